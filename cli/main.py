"""``autobones`` command line. Parses arguments, calls the library, prints one line per result.

Errors a user can fix (bad file, bad option) print as one line on stderr with
exit code 2; ``--debug`` shows the traceback instead.
"""
from __future__ import annotations

import logging
import sys

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
    args = parser.parse_args(_axis_values(sys.argv[1:] if argv is None else list(argv)))
    if args.version:
        import autobones

        print(f"autobones {autobones.__version__}")
        return 0
    if not args.command:
        parser.print_help()
        return EXIT_USER_ERROR
    logging.basicConfig(level=logging.WARNING - 10 * min(args.verbose, 2),
                        format="autobones: %(message)s", stream=sys.stderr)
    from autobones.errors import AutobonesError

    try:
        return COMMANDS[args.command](args)
    except AutobonesError as exc:
        if args.debug:
            raise
        print(f"autobones {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print("autobones: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
