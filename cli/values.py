"""Option values of ``autobones pose``: numbers, NAME=VALUE pairs, comma-separated vectors."""
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
