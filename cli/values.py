"""Option values: numbers, seeds, NAME=VALUE pairs, comma-separated vectors."""
from __future__ import annotations


def number(text, what):
    """``text`` as a finite float; ``what`` names the option in the error."""
    from autobones.errors import AutobonesError

    try:
        v = float(text)
    except (TypeError, ValueError):
        raise AutobonesError(f"{what}: {text!r} is not a number") from None
    if v != v or v in (float("inf"), float("-inf")):
        raise AutobonesError(f"{what}: {text!r} is not a finite number")
    return v


def seed(text, what="--seed"):
    """``text`` as a seed: a whole number >= 0 (numpy's generators take no other)."""
    from autobones.placement.facial_bones import check_seed
    from autobones.errors import AutobonesError

    try:
        v = int(str(text).strip())
    except ValueError:
        raise AutobonesError(f"{what} {text!r}: the seed must be a whole number >= 0 (e.g. 0, 1, 42)") from None
    return check_seed(v, what)


def pairs(items, option, default=None):
    """``["12=0.8", "6"]`` -> ``{"12": 0.8, "6": default}``; values summed when a key repeats."""
    from autobones.errors import AutobonesError

    out = {}
    for item in items:
        key, eq, value = item.partition("=")
        key = key.strip()
        if not key:
            raise AutobonesError(f"{option} {item!r}: expected NAME=VALUE")
        if not eq and default is None:
            raise AutobonesError(f"{option} {item!r}: expected NAME=VALUE (e.g. {option} upper=1)")
        out[key] = out.get(key, 0.0) + (number(value, f"{option} {item}") if eq else default)
    return out


def vector(text, n, option):
    """``"1,-2"`` -> ``[1.0, -2.0]`` (exactly ``n`` numbers); None stays None."""
    from autobones.errors import AutobonesError

    if text is None:
        return None
    parts = [p for p in text.replace(" ", "").split(",")]
    if len(parts) != n:
        raise AutobonesError(f"{option} {text!r}: expected {n} comma-separated numbers")
    return [number(p, f"{option} {text}") for p in parts]
