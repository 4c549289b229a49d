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
        self.parents = np.asarray(self.parents, dtype=np.int64)
        self.heads = np.asarray(self.heads, dtype=np.float64)
        self.tails = np.asarray(self.tails, dtype=np.float64)
        b = len(self.names)
        assert len(set(self.names)) == b, "bone names must be unique"
        assert self.parents.shape == (b,) and self.heads.shape == (b, 3) and self.tails.shape == (b, 3)
        assert all(p < i for i, p in enumerate(self.parents)), "parents must come before children"

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

    def to_list(self):
        return [
            {"name": n, "parent": (self.names[p] if p >= 0 else None),
             "head": h.tolist(), "tail": t.tolist()}
            for n, p, h, t in zip(self.names, self.parents, self.heads, self.tails)
        ]
