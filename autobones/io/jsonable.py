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
