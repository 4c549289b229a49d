"""What the commands show while they work: stage lines with ``-v``, a ticking line on a terminal otherwise."""
from __future__ import annotations

import sys
import threading
from contextlib import contextmanager


@contextmanager
def progress(args, what):
    """Show ``autobones CMD: WHAT 0:04`` on stderr, its clock ticking, while the block runs.

    Only when stderr is a terminal (a pipe or a log file gets nothing, so scripts and the tests read
    clean output) and without ``-v`` (whose stage lines say the same and would break the line). The
    line is removed when the block ends; the command's result line follows as usual. The steps
    wrapped here give no count to make a bar of (a model build, Blender, one solve), so it is a clock.
    """
    if getattr(args, "verbose", 0) or not sys.stderr.isatty():
        yield
        return
    import shutil

    from tqdm import tqdm

    size = shutil.get_terminal_size((100, 24))  # a terminal of unknown size reports 0 x 0: tqdm would hide the line
    bar = tqdm(total=None, desc=f"autobones {args.command}: {what}", bar_format="{desc} {elapsed}",
               file=sys.stderr, leave=False, ncols=min(size.columns or 100, 120), nrows=max(size.lines, 2))
    stop = threading.Event()

    def tick():  # tqdm redraws only on update(); the step itself never calls back
        while not stop.wait(0.5):
            bar.refresh()

    ticker = threading.Thread(target=tick, daemon=True)
    ticker.start()
    try:
        yield
    finally:
        stop.set()
        ticker.join()
        bar.close()


def stopwatch():
    """The package's stage clock: ``lap(stage)`` logs ``stage  0.42 s``, shown by ``-v``."""
    from autobones.timing import Stopwatch

    return Stopwatch()
