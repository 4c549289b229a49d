"""Plain JSON values from nested containers of numpy arrays and scalars."""
from __future__ import annotations

import numpy as np


def jsonable(x):
    """``x`` with every dict key a str, tuples as lists, arrays as nested lists and numpy
    scalars as Python numbers (what ``json.dump`` accepts); other values unchanged."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    return x


def finite_or_null(x):
    """``x`` with every NaN or infinite float (Python or numpy) replaced by None, recursively
    through dicts, lists and tuples; every other value, finite floats included, is returned
    as it is (the JSON text of a finite document does not change)."""
    if isinstance(x, dict):
        return {k: finite_or_null(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite_or_null(v) for v in x]
    if isinstance(x, (float, np.floating)) and not np.isfinite(x):
        return None
    return x


def strict_dumps(doc, **kwargs):
    """``json.dumps`` of ``doc`` as strict JSON: a value that is undefined (NaN, infinite) is
    written as null, never as the ``NaN``/``Infinity`` tokens that ``JSON.parse`` and other
    strict readers reject (``allow_nan=False`` makes any one left over an error, not a file)."""
    import json

    return json.dumps(finite_or_null(doc), allow_nan=False, **kwargs)
