"""A symmetric correspondence on a symmetric head: mirror partners land on mirror points.

Beyond the papers we implement (Orvalho, Zacur & Susin 2008 fit each generic vertex on its
own): on a smooth, symmetric head nothing in the fit's data term tells a point on one side
how far it may slide toward the other, so the correspondence drifts across the midline and
every expression carried by it comes out lopsided (the goat's smile, issue #16).

When the generic rig's skin and the head are both mirror-symmetric about the planes of their
own landmarks, the fit keeps its solution symmetric: after every least-squares solve each
generic vertex is averaged with the mirror image of its mirror partner's fitted point,

    x_i <- (x_i + S_t(sum_k b_ik x_k)) / 2,

``S_t`` the reflection through the head's landmark plane and ``b_i`` the barycentric
coordinates of the closest point of the generic surface to vertex i's reflection through the
generic's own plane (a permutation on an exactly symmetric mesh). The landmarks are left as
given: the fit pulls each side toward its own, and the averaging meets them halfway when a
hand-placed pair is a few percent of ex-ex off (the goat's: 2.2 % mean; making the pairs mirror
images first was measured and did worse there, benchmarks/symmetry.py). The final stick onto
the head keeps whatever asymmetry its surface has.

Symmetric means, by default, that the head's landmark pairs are mirror images of each other
(within :data:`MAX_LANDMARK_MISMATCH`: a symmetric face wearing a one-sided smile is not
symmetric) and that the reflected surfaces lie on themselves: the 75th percentile of the distance
from an area-uniform sample's mirror image to the surface at most :data:`MAX_ASYMMETRY` of ex-ex
(measured with 1000 samples: the robot and ICT 0.0 %, menpo3d's template 0.5 %, the goat 1.8 %;
real scans 3.7-4.3 % (james), 6.3 % (LeePerrySmith), 6.5 % (demosthenes), whose own asymmetry
the correspondence must follow). Landmark pairs: the robot and ICT 0.0 %; the goat's hand-placed
pairs 3.6 %, menpo3d template's 9.8 %, james's published ones 4.8 %, automatic ones on the scans
2.6-4.5 % (largest pair, ex-ex units); so ``auto`` keeps the goat out; ``symmetric="on"`` forces
it. With automatic landmarks ``transfer`` leaves ``auto`` off: even on the exactly symmetric default
head their pairs are 1.6 % apart and their plane a degree off.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import AutobonesError
from ..geometry.closest import closest_points
from ..geometry.sample import sample_surface
from ..io.landmark_names import mirror_name
from ..landmarks.refine import symmetry_plane
from ..orient import reflect

#: Largest surface asymmetry (75th percentile of the mirrored sample's distance to the surface, in
#: ex-ex units) of a head the correspondence is kept symmetric on.
MAX_ASYMMETRY = 0.025

#: A generic vertex whose reflection lies further than this (ex-ex units) from the generic surface
#: has no mirror partner and is left as fitted.
MAX_PARTNER = 0.01

#: Largest mirror mismatch of a bilateral landmark pair (ex-ex units) on a head the correspondence is
#: kept symmetric on: a symmetric face wearing a one-sided expression is not (ICT's mouthSmile_L moves
#: cheilion_l 17-18 % of ex-ex off its partner's mirror image, browInnerUp_L the inner brow 4 %,
#: eyeBlink_L the outer eye corner 1.1-1.2 %; its neutral, jawOpen and mouthPucker heads 0.0 %)
MAX_LANDMARK_MISMATCH = 0.01

# 1000 points: few enough that a scan's closest points take its near-triangle path, not a full AABB tree
SAMPLES = 1000
MODES = ("auto", "on", "off")


def surface_asymmetry(V, F, plane, unit, samples=SAMPLES):
    """How far a mesh is from its own mirror image, at an area-uniform sample of its surface.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    plane : ((3,) float, float)
        Unit normal and offset, ``normal . x = offset``, mesh units.
    unit : float
        Length to measure in (mesh units), e.g. the outer-eye-corner distance.
    samples : int
        Sample size (seed 0).

    Returns
    -------
    (samples,) float64
        Distance from each sample point's mirror image to the surface, in ``unit``.
    """
    P, _, _ = sample_surface(V, F, samples, seed=0)
    return np.sqrt(closest_points(reflect(P, *plane), V, F)[3]) / unit


def mirror_operator(V, F, plane, tol):
    """Each vertex's mirror partner on the surface, as barycentric rows.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    plane : ((3,) float, float)
        The mesh's mirror plane (unit normal, offset), mesh units.
    tol : float
        A vertex whose reflection lies further than this (mesh units) from the surface has no partner.

    Returns
    -------
    M : (n, n) scipy.sparse.csr_matrix
        Row i: the barycentric coordinates, on its triangle's three vertices, of the closest
        surface point to vertex i's reflection (0 for a vertex without a partner).
    has : (n,) bool
        Vertices with a partner.
    """
    n = len(V)
    _, face, bary, d2 = closest_points(reflect(V, *plane), V, F)
    has = np.sqrt(d2) <= tol
    rows = np.repeat(np.arange(n), 3)
    M = sp.csr_matrix(((bary * has[:, None]).ravel(), (rows, np.asarray(F)[face].ravel())), shape=(n, n))
    return M, has


class Symmetry:
    """Whether and how a transfer keeps its correspondence symmetric (see the module doc).

    Parameters
    ----------
    mode : {"auto", "on", "off"}
        ``auto``: when the head's landmark pairs are mirror images (within ``landmark_tolerance``)
        and both surfaces are symmetric about their landmark planes (:data:`MAX_ASYMMETRY`);
        ``on``: always (an error when the landmarks have no pair); ``off``: never.
    landmark_tolerance : float
        Largest mirror mismatch of a landmark pair, ex-ex units, for ``auto``; 0 turns ``auto``
        off (automatic landmarks: their mirror plane is tilted by up to a degree, and symmetrising
        about it put the default head's correspondence 1.9 / 4.0 % of ex-ex off its own).

    Attributes (after :meth:`fit`)
    ----------
    applied_ : bool
    source_plane_, target_plane_ : ((3,) float, float)
        Mirror planes of the generic rig's landmarks (its frame) and the head's (its frame).
    record_ : dict
        What the rig's sidecar keeps: ``mode``, ``applied``, the head's largest landmark pair
        mismatch and the two surface asymmetries (ex-ex units).
    """

    def __init__(self, mode="auto", landmark_tolerance=MAX_LANDMARK_MISMATCH):
        self.mode = mode
        self.landmark_tolerance = landmark_tolerance

    def fit(self, V_src, F_src, lm_src, V, F, lm):
        """Decide on the generic skin ``(V_src, F_src)`` with landmarks ``lm_src`` and the head
        ``(V, F)`` with landmarks ``lm`` (dicts, each mesh's own frame); returns self."""
        if self.mode not in MODES:
            raise AutobonesError(f"symmetric must be one of {', '.join(MODES)}, got {self.mode!r}")
        pairs = [n for n in lm if n.endswith("_l") and mirror_name(n) in lm and n in lm_src and mirror_name(n) in lm_src]
        self.applied_, self.record_ = False, {"mode": self.mode, "applied": False}
        if self.mode == "off" or not pairs:
            if self.mode == "on":
                raise AutobonesError("--symmetric on needs at least one left/right landmark pair shared with the rig")
            return self
        plane = symmetry_plane(lm)
        unit_s = _exex(lm_src, V_src)
        unit_t = _exex(lm, V)
        mismatch = max(float(np.linalg.norm(reflect(np.asarray(lm[n], dtype=np.float64), *plane)
                                            - np.asarray(lm[mirror_name(n)]))) for n in pairs) / unit_t
        self.record_["landmark_mismatch"] = round(mismatch, 5)
        self.unit_s_ = unit_s
        if self.mode == "auto" and (self.landmark_tolerance <= 0 or mismatch > self.landmark_tolerance):
            # a one-sided expression, loosely placed or automatic landmarks: the surfaces need no look
            self.record_["reason"] = ("automatic landmarks" if self.landmark_tolerance <= 0 else
                                      "the landmark pairs are no mirror images")
            return self
        self.source_plane_, self.target_plane_ = symmetry_plane(lm_src), plane
        asym_s = float(np.percentile(surface_asymmetry(V_src, F_src, self.source_plane_, unit_s), 75))
        asym_t = float(np.percentile(surface_asymmetry(V, F, self.target_plane_, unit_t), 75))
        self.record_.update(source_asymmetry=round(asym_s, 5), head_asymmetry=round(asym_t, 5))
        self.applied_ = self.mode == "on" or (asym_s <= MAX_ASYMMETRY and asym_t <= MAX_ASYMMETRY)
        self.record_["applied"] = bool(self.applied_)
        return self

    def partners(self, V_src, F_src):
        """(n,) int64: each generic vertex's mirror partner (the vertex nearest its reflection's closest
        surface point), or None when not applied."""
        if not self.applied_:
            return None
        M, has = mirror_operator(V_src, F_src, self.source_plane_, MAX_PARTNER * self.unit_s_)
        out = np.asarray(M.argmax(axis=1)).ravel()
        return np.where(has, out, np.arange(len(V_src)))

    def fit_option(self):
        """``symmetry=`` of :func:`autobones.rig_transfer.correspondence.fit_surface`, or None."""
        if not self.applied_:
            return None
        return {"source_plane": self.source_plane_, "target_plane": self.target_plane_,
                "partner_tol": MAX_PARTNER * self.unit_s_}


def _exex(lm, V):
    """The outer-eye-corner distance of landmarks ``lm``, or a tenth of the mesh's extent without them."""
    if "exocanthion_l" in lm and "exocanthion_r" in lm:
        d = float(np.linalg.norm(np.asarray(lm["exocanthion_l"]) - np.asarray(lm["exocanthion_r"])))
        if d > 0:
            return d
    return 0.1 * float(np.ptp(np.asarray(V), axis=0).max())


def symmetrize(X, M, has, plane):
    """One symmetrising step of the fit: ``X`` (n, 3) fitted points (head frame), ``M``, ``has`` from
    :func:`mirror_operator`, ``plane`` the head's. Returns (n, 3); rows without a partner unchanged."""
    out = X.copy()
    out[has] = 0.5 * (X[has] + reflect(M[has] @ X, *plane))
    return out
