"""The tests to mark slow, from a measured run: reads ``pytest --durations=0`` output on stdin and prints
the node ids whose setup and call together took at least ``--over`` seconds (tests/slow_tests.txt).

    python -m pytest -q --durations=0 | python tools/slow_tests.py --over 2 > tests/slow_tests.txt

tests/conftest.py marks the listed tests ``slow``, so ``pytest -m "not slow"`` is the few-minute run.
"""
import argparse
import re
import sys
from datetime import date


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--over", type=float, default=2.0, help="seconds (setup + call) from which a test is slow")
    args = ap.parse_args()
    spent = {}
    for line in sys.stdin:
        m = re.match(r"\s*([\d.]+)s (setup|call|teardown)\s+(\S+)", line)
        if m:
            spent[m.group(3)] = spent.get(m.group(3), 0.0) + float(m.group(1))
    slow = sorted(n for n, t in spent.items() if t >= args.over)
    print(f"# tests whose setup + call took >= {args.over:g} s in a full run measured {date.today()}; made by "
          "tools/slow_tests.py, read by tests/conftest.py (marks them slow)")
    print("\n".join(slow))


if __name__ == "__main__":
    main()
