"""The bone hierarchy: names, parents and rest positions."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Skeleton:
    """Bones as plain arrays.

    Attributes
    ----------
    names : list of str
        Unique bone names (glTF joint names).
    parents : (b,) int
        Parent index of each bone, -1 for the root; parents come before children.
    heads, tails : (b, 3) float
        Rest positions of each bone's start (its pivot) and end, in the frame
        and units of the mesh they rig.
    """

    names: list
    parents: np.ndarray
    heads: np.ndarray
    tails: np.ndarray

    def __post_init__(self):
        # checked, not asserted: a public type (issue #33), and asserts vanish under python -O
        from .arguments import float_array, index_array
        from .errors import AutobonesError

        if not isinstance(self.names, (list, tuple)) or not all(isinstance(n, str) for n in self.names):
            raise AutobonesError("names: expected a list of bone names (str)")
        b = len(self.names)
        if len(set(self.names)) != b:
            raise AutobonesError("names: bone names must be unique")
        parents = np.asarray(self.parents)
        if parents.dtype.kind not in "iuf" or parents.shape != (b,):
            raise AutobonesError(f"parents: expected {b} bone indices (-1: a root), got {parents.dtype} {parents.shape}")
        self.parents = index_array(parents + 1, "parents", (b,), b + 1) - 1  # -1..b-1, shifted to 0..b
        self.heads = float_array(self.heads, "heads", (b, 3))
        self.tails = float_array(self.tails, "tails", (b, 3))
        if not all(p < i for i, p in enumerate(self.parents)):
            raise AutobonesError("parents: each bone's parent must come before it (-1: a root)")

    def __len__(self):
        return len(self.names)

    @property
    def segments(self):
        """(b, 2, 3) heads and tails."""
        return np.stack([self.heads, self.tails], axis=1)

    def index(self, name):
        return self.names.index(name)

    def transformed(self, fn):
        """A copy with ``fn`` ((k, 3) -> (k, 3)) applied to heads and tails."""
        return Skeleton(list(self.names), self.parents.copy(), fn(self.heads), fn(self.tails))

    def aimed(self, name, direction):
        """A copy whose bone ``name`` points along ``direction`` (3,): its tail moved about its head,
        the bone's length kept (an exported joint's +Y runs head -> tail, so this sets the axis a DCC
        turns the bone about)."""
        from .errors import AutobonesError

        d = np.asarray(direction, dtype=np.float64)
        if d.shape != (3,) or not np.isfinite(d).all() or not np.linalg.norm(d) > 0:
            raise AutobonesError(f"direction: expected a nonzero finite 3-vector, got {direction!r}")
        i = self.index(name)
        tails = self.tails.copy()
        tails[i] = self.heads[i] + np.linalg.norm(self.tails[i] - self.heads[i]) * d / np.linalg.norm(d)
        return Skeleton(list(self.names), self.parents.copy(), self.heads.copy(), tails)

    def to_list(self):
        return [
            {"name": n, "parent": (self.names[p] if p >= 0 else None),
             "head": h.tolist(), "tail": t.tolist()}
            for n, p, h, t in zip(self.names, self.parents, self.heads, self.tails)
        ]
