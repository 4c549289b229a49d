"""``autobones`` command line. Parses arguments, calls the library, prints one line per result.

Errors a user can fix (bad file, bad option) print as one line on stderr with
exit code 2; ``--debug`` shows the traceback instead.
"""
from __future__ import annotations

import logging
import sys
import warnings

from .commands import COMMANDS
from .parser import build_parser

EXIT_USER_ERROR = 2


def _axis_values(argv):
    """argparse reads ``--front -y`` (or ``--head -10,0,0``) as two options; join such pairs as ``--front=-y``."""
    out, i = [], 0
    while i < len(argv):
        if i + 1 < len(argv) and (
                (argv[i] in ("--up", "--front") and argv[i + 1].lower() in ("-x", "-y", "-z"))
                # pose's vectors: ``--head -10,0,0`` (argparse takes only plain numbers for negative values)
                or (argv[i] in ("--gaze", "--look-at", "--head", "--neck", "--jaw") and argv[i + 1][:2] in
                    {"-" + c for c in "0123456789."})):
            out.append(f"{argv[i]}={argv[i + 1]}")
            i += 2
        else:
            out.append(argv[i])
            i += 1
    return out


def main(argv=None):
    parser = build_parser()
    args, extra = parser.parse_known_args(_axis_values(sys.argv[1:] if argv is None else list(argv)))
    if extra:  # as parse_args would, but with the command's own name and --help in the hint
        parser.command_parsers.get(args.command, parser).error(f"unrecognized arguments: {' '.join(extra)}")
    if args.version:
        import autobones

        print(f"autobones {autobones.__version__}")
        return 0
    if not args.command:  # an error like any other: one line on stderr (the full help is --help's, on stdout)
        print(f"autobones: error: no command given; one of {', '.join(COMMANDS)} (see autobones --help)",
              file=sys.stderr)
        return EXIT_USER_ERROR
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2),
                        format="autobones: %(message)s", stream=sys.stderr)
    from autobones.errors import AutobonesError

    # Warnings (numpy's RuntimeWarnings on a hostile mesh) are held until the command ends: after a
    # result they are shown as before; before a one-line error they would break the one line, and the
    # error says what is wrong, so they are dropped (--debug shows them with the traceback).
    with warnings.catch_warnings(record=True) as held:
        warnings.simplefilter("default")
        try:
            code = COMMANDS[args.command](args)
        except AutobonesError as exc:
            if args.debug:
                _show(held)
                raise
            print(f"autobones {args.command}: error: {one_line(exc)}", file=sys.stderr)
            return EXIT_USER_ERROR
        except KeyboardInterrupt:
            print("autobones: interrupted", file=sys.stderr)
            return 130
    _show(held)
    return code


def one_line(exc):
    """The message of ``exc`` as one line: a newline or other control character (in a file name, say)
    written as its escape, so the line stays one line and the name stays readable."""
    text = str(exc)
    return "".join(c if c >= " " and c != "\x7f" else repr(c)[1:-1] for c in text)


def _show(held):
    """Issue the held warnings again, where they were raised, through the caller's own filters."""
    for w in held:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)


if __name__ == "__main__":
    sys.exit(main())
