"""Facial expressions on a transferred rig: seed 000 §4.2's skin/muscle model, FACS action units.

The deformation chain of seed 000 (Figure 4.21), rebuilt procedurally on any head
from what ``autobones.transfer`` carries onto it (muscle joints, the muscle
influence fields, regions, skeleton and skin weights, landmarks):

1. muscles (``muscles.py``, ``wire.py``): every muscle joint pulls one wire that
   runs along the skin over the muscle (from part way up the muscle to just past
   its insertion). Each wire control vertex is point-constrained to a weighted
   average of locators: its muscle's locator (weight 001's force profile along the
   muscle; frontalis, whose origin is the galea aponeurotica, scales about a point a
   quarter of the way down and carries the scalp above with it), the locators of
   the neighbouring muscles whose influence fields cover it (weight: that field
   times ``cross_talk``) and one unparented rest locator.
   The point-constraint weights do not depend on the contractions, so the skin
   displacement is a fixed linear map of the contraction vector: one (n, 3) basis
   field per muscle. Where wires overlap, their dropoffs are normalised to sum to
   at most 1, so contractions on one skin patch blend and damp instead of adding.
   The mouth line (cheilion_r - stomion - cheilion_l) cuts the influence of a
   wire on the upper lip off the lower lip and vice versa.
2. skull non-penetration: a skin point may sink along its rest normal by at most
   the soft-tissue thickness of its region (the offset skull surface, taken
   locally parallel to the skin).
3. creases: frontalis contractions press horizontal furrows into the forehead,
   corrugator ones vertical furrows between the brows.
4. eyelids (four lid joints rotating about the eye pivots, weights built from
   the palpebral landmarks, fading to the fixed medial eye corner and past the looser
   lateral one) and bone movements: the
   jaw turns each vertex about its pivot by its jaw weight times the angle, that
   weight sharpened across the mouth line (so the jaw opens the lower lip only; the cut
   fades out toward the mouth corners, where the lips join) and spread under the chin
   (so the skin there stretches); head and neck
   rotations blend by the rig's skin weights (linear blend skinning); eyeballs
   gaze through their eye bones (yaw/pitch, or an aim point). Separate small parts on
   the lids follow the skin where they touch it (a row of lashes turns as one piece
   with its margin, an eye-occlusion shell stretches between both lids); the mouth's
   separate inner parts (teeth, gums, tongue) ride the jaw below the occlusal plane
   and the skull above it, teeth whole, gums and tongue split at the lower crowns,
   nothing behind the jaw joint (the pharynx).
5. unfolding (beyond the seeds): skin triangles the lids or jaw turn over are relaxed
   (the displacement replaced by its neighbours' mean under the intrinsic Laplacian's
   weights, locally; each relaxed patch is kept only where it leaves less skin folded);
   what that leaves folded (slivers where the surface itself folds sharply, as in the mouth
   corners' commissure) moves as one piece with the rigid or affine motion of the skin
   around it (:meth:`ExpressionModel._rigid_patches`).

Stages 1 and 3 are linear in the contractions (``muscle_basis_``), stage 2 is a
clamp that only acts where the skin would sink into the skull, stage 4 is a
rotation per vertex, stage 5 acts only where triangles turn over: a fit can search
the contraction vector, jaw angle and lid amounts directly
(:meth:`ExpressionModel.pose_parameters`), and for fixed jaw and lids the pose is an
affine map of the contractions away from the clamp and folds
(:meth:`ExpressionModel.linear_pose`).

What the model needs comes through ``transfer`` and is saved with the rig: the
skeleton and skin weights, ``rig.extra['muscles']`` (origins, insertions,
``width_canonical``), ``rig.extra['landmarks']`` (stomion, cheilions, palpebrale
points, exocanthions, menton; missing ones fall back to the muscles and eye
bones), ``rig.fields`` (``muscle/<name>``, ``region``), ``rig.frame``. Fitting
is deterministic and takes under a second on a 27k-vertex head; posing takes
a few milliseconds.

Everything is computed in the head's canonical frame (+Y up, +Z front, +X the
subject's left, head sizes) and returned in the input frame and units. Lengths in
``generic_rig/expressions.json`` are in face units (fu = the exocanthion
distance of that head), so the same numbers give each head its own expression.
"""
from __future__ import annotations

import json
import os

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import AutobonesError
from ..geometry.laplacian import diffuse, factor_spd, laplacian
from ..geometry.normals import vertex_normals
from ..geometry.smooth import ramp
from ..geometry.topology import mesh_parts, weld
from .muscles import muscles_from_rig
from .wires import wire_weights

REGIONS_DEFAULT = ("scalp", "forehead", "brow", "eyelids", "nose", "cheeks", "lips", "chin", "jaw", "ears", "neck")
LIDS = ("upper_l", "upper_r", "lower_l", "lower_r")


def load_expressions(path=None):
    """The expression definitions (default ``generic_rig/expressions.json``) as a dict."""
    if path is None:
        from ..generic_rig import expressions_path

        path = expressions_path()
    if isinstance(path, dict):
        return path
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
        for key in ("model", "muscle_types", "action_units", "expressions"):
            doc[key]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise AutobonesError(f"{path}: cannot read the expression definitions ({exc})") from None
    return doc


def _rot(axis, deg):
    """(3, 3) right-handed rotation about canonical axis 0/1/2 by ``deg`` degrees."""
    a = np.radians(float(deg))
    c, s = np.cos(a), np.sin(a)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def _euler(deg):
    """(pitch, yaw, roll) degrees about canonical +X, +Y, +Z -> R = Rz Ry Rx."""
    p, y, r = (list(np.ravel(deg).astype(float)) + [0.0, 0.0, 0.0])[:3]
    return _rot(2, r) @ _rot(1, y) @ _rot(0, p)


def _align(a, b):
    """Smallest rotation taking unit vector ``a`` to unit vector ``b``."""
    v, c = np.cross(a, b), float(a @ b)
    if c < -0.999999:
        return _rot(1, 180.0)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def x_turn(P, angle):
    """Displacement (m, 3) of points ``P`` (m, 3), relative to a pivot, turned by ``angle``
    (radians, scalar or (m,)) about the canonical +X axis (the lid and jaw joints' axis)."""
    ca, sa = np.cos(angle), np.sin(angle)
    return np.c_[np.zeros(len(P)), (ca - 1.0) * P[:, 1] - sa * P[:, 2], sa * P[:, 1] + (ca - 1.0) * P[:, 2]]


class ExpressionModel:
    """Seed 000's skin/muscle model with FACS action units, built on one transferred rig.

    Parameters
    ----------
    definitions : str, dict or None
        Expression definitions (``generic_rig/expressions.json`` when None).

    Attributes (after :meth:`fit`)
    ----------
    muscle_names_ : list of str
        Order of the contraction vector.
    muscle_basis_ : (k, n, 3) float
        Canonical-frame skin displacement of each muscle at contraction 1 (before
        skull non-penetration); the muscle stage is ``tensordot(c, muscle_basis_, 1)``.
    crease_basis_ : dict int -> (n, 3) float
        Canonical crease displacement per unit contraction of the muscles that crease.
    jaw_weights_ : (n, b) float
        The rig's skin weights with the jaw column sharpened across the mouth line.
    skin_ : (n,) bool
        Vertices the muscles and eyelids move (the largest part, not eyeballs).
    lid_weights_ : (4, n) float
        Upper/lower lid joint weights, order :data:`LIDS`.
    lid_close_deg_ : (2,) float
        Angle (degrees) that brings each upper lid margin to its lower lid (l, r).
    face_unit_ : float
        Exocanthion distance in head sizes.

    Example
    -------
    >>> model = ExpressionModel().fit(autobones.transfer("head.obj", landmarks="head.landmarks.json"))
    >>> V = model.pose(au={12: 0.8, 6: 0.4}, jaw_deg=10)
    """

    def __init__(self, definitions=None):
        self.definitions = definitions

    # ------------------------------------------------------------------------------ build
    def fit(self, rig):
        """Build wires, locators, constraints, lids and jaw weights on ``rig`` (a transferred
        :class:`autobones.rig.Rig`, or any object with its attributes)."""
        doc = load_expressions(self.definitions)
        self.doc_ = doc
        frame = rig.frame
        self.frame_ = frame
        V = np.asarray(rig.vertices, dtype=np.float64)
        F = np.asarray(rig.faces, dtype=np.int64)
        self.vertices_ = V
        n = len(V)
        Vc = frame.to_canonical(V)
        self.canonical_ = Vc
        names = list(rig.skeleton.names)
        self.bones_ = names
        self.pivots_ = frame.to_canonical(rig.skeleton.heads)
        W = np.asarray(rig.weights, dtype=np.float64)
        mj = muscles_from_rig(rig).transformed(frame.to_canonical, 1.0 / float(frame.size))
        self.joints_ = mj
        self.muscle_names_ = list(mj.names)
        k = len(mj)
        L = {kk: frame.to_canonical(np.asarray(v, dtype=np.float64).reshape(1, 3))[0]
             for kk, v in (rig.extra.get("landmarks") or {}).items()}
        eyes = {s: self.pivots_[names.index(f"eye_{s}")] for s in "lr" if f"eye_{s}" in names}
        if "exocanthion_l" in L and "exocanthion_r" in L:
            fu = float(np.linalg.norm(L["exocanthion_l"] - L["exocanthion_r"]))
        elif len(eyes) == 2:
            fu = 1.48 * float(np.linalg.norm(eyes["l"] - eyes["r"]))
        else:
            raise AutobonesError("expressions: the rig has neither exocanthion landmarks nor both eye bones "
                                 "to measure the face by")
        self.face_unit_ = fu
        model = doc["model"]

        # every graph operation runs on the mesh welded by position (unwelded heads, UV seams),
        # per-vertex results are read back through ``index``
        # (only when the mesh falls apart without it: welding would also join eyelashes, eye
        # occlusion shells and teeth that touch the skin)
        face_area = 0.5 * np.linalg.norm(np.cross(Vc[F[:, 1]] - Vc[F[:, 0]], Vc[F[:, 2]] - Vc[F[:, 0]]), axis=1)
        part0 = mesh_parts(n, F)
        if np.bincount(part0[F[:, 0]], weights=face_area, minlength=n).max() >= 0.2 * face_area.sum():
            Vw, Fw, index = Vc, F, np.arange(n)
        else:
            Vw, Fw, index = weld(Vc, F, 1e-9 * max(float(np.ptp(Vc, axis=0).max()), 1e-300))
        nw = len(Vw)
        first = np.zeros(nw, dtype=np.int64)
        first[index] = np.arange(n)
        self._weld = (index, first)

        # skin: the welded part with the largest area, minus anything bound to an eye bone
        part_w = mesh_parts(nw, Fw)
        area = 0.5 * np.linalg.norm(np.cross(Vw[Fw[:, 1]] - Vw[Fw[:, 0]], Vw[Fw[:, 2]] - Vw[Fw[:, 0]]), axis=1)
        part = part_w[index]
        skin = part == int(np.argmax(np.bincount(part_w[Fw[:, 0]], weights=area, minlength=nw)))
        for s in "lr":
            if f"eye_{s}" in names:
                skin &= W[:, names.index(f"eye_{s}")] < 0.5
        self.skin_ = skin
        Nw = vertex_normals(Vw, Fw)
        N = Nw[index]
        self.normals_ = N
        # the offset skull is smooth: its directions are the skin normals smoothed over ~1 cm
        E0 = np.concatenate([Fw[:, [0, 1]], Fw[:, [1, 2]], Fw[:, [2, 0]]])
        A0 = sp.csr_matrix((np.ones(2 * len(E0)), (np.r_[E0[:, 0], E0[:, 1]], np.r_[E0[:, 1], E0[:, 0]])), shape=(nw, nw))
        skin_w = np.zeros(nw, dtype=bool)
        skin_w[index[skin]] = True
        Fs = Fw[skin_w[Fw].all(axis=1)]
        a_s = 0.5 * np.linalg.norm(np.cross(Vw[Fs[:, 1]] - Vw[Fs[:, 0]], Vw[Fs[:, 2]] - Vw[Fs[:, 0]]), axis=1)
        Fs = Fs[a_s > 1e-9 * max(float(np.median(a_s)) if len(a_s) else 0.0, 1e-300)]
        n0 = np.cross(Vw[Fs[:, 1]] - Vw[Fs[:, 0]], Vw[Fs[:, 2]] - Vw[Fs[:, 0]])
        self._unfold_mesh = (A0.tocsr(), skin_w, Fs, n0, 0.5 * np.linalg.norm(n0, axis=1))
        Ns = Nw.copy()
        for _ in range(int(model.get("skull_smoothing_passes", 10))):
            Ns = A0 @ Ns + Ns
        Ns /= np.maximum(np.linalg.norm(Ns, axis=1, keepdims=True), 1e-300)
        self.skull_normals_ = Ns[index]
        skin_idx = np.flatnonzero(skin)
        tree = cKDTree(Vc[skin_idx])

        def snap(P):
            return skin_idx[tree.query(np.atleast_2d(P))[1]]

        # --- the mouth line and its zone ---------------------------------------------------
        ins = {nm: mj.insertions[i] for i, nm in enumerate(mj.names)}
        ch_l = L.get("cheilion_l", ins.get("buccinator_l"))
        ch_r = L.get("cheilion_r", ins.get("buccinator_r"))
        if ch_l is None or ch_r is None:
            raise AutobonesError("expressions: the rig has no cheilion landmarks or buccinator muscles "
                                 "to find the mouth corners by")
        st = L.get("stomion")
        if st is None:
            mid = 0.5 * (ch_l + ch_r)
            near = skin & (np.abs(Vc[:, 0] - mid[0]) < 0.05 * fu) & (np.abs(Vc[:, 1] - mid[1]) < 0.1 * fu)
            st = Vc[np.flatnonzero(near)[np.argmax(Vc[near, 2])]] if near.any() else mid
        lips = model["lips"]
        xs = np.array([ch_r[0], st[0], ch_l[0]])
        order = np.argsort(xs)
        y_line = np.interp(Vc[:, 0], xs[order], np.array([ch_r[1], st[1], ch_l[1]])[order])
        # in the mouth groove the lip surfaces face each other: a downward normal is the upper
        # lip's underside, an upward one the lower lip's top, whatever the straight line says
        s_mouth = Vc[:, 1] - y_line - float(lips.get("normal_bias", 0.03)) * fu * N[:, 1]
        hw = 0.5 * abs(ch_l[0] - ch_r[0])
        dx = np.abs(Vc[:, 0] - st[0])
        z_ch = 0.5 * (ch_l[2] + ch_r[2])
        zh = float(lips["zone_height"]) * fu
        zone = (ramp(dx, float(lips["zone_half_width"]) * hw, 0.75 * hw) * ramp(np.abs(s_mouth), zh, 0.6 * zh)
                * ramp(Vc[:, 2], z_ch - 0.4 * fu, z_ch - 0.3 * fu) * skin)
        # the mouth's lining (skin behind the lips facing into the head, e.g. ICT's mouth sock)
        # splits by the same line, over its whole depth and height
        centre = self.pivots_[names.index("head")] if "head" in names else Vc.mean(axis=0)
        inward = (N * (Vc - centre)).sum(axis=1) < 0
        lining = inward & skin
        lining_zone = (ramp(dx, float(lips["zone_half_width"]) * hw, 0.75 * hw) * ramp(np.abs(s_mouth), 4.0 * zh, 3.0 * zh)
                       * ramp(Vc[:, 2], z_ch - 1.2 * fu, z_ch - 0.8 * fu))
        zone = np.where(lining, np.maximum(zone, lining_zone), zone)
        cut = float(lips["cut_width"]) * fu
        cut = cut * (1.0 + 4.0 * np.clip(dx / hw, 0.0, 1.2) ** 4)   # softer toward the corners
        upper = ramp(s_mouth, -0.5 * cut, 0.5 * cut)
        self.mouth_ = {"zone": zone, "upper": upper, "signed": s_mouth, "stomion": st}

        # --- wires, locators, point constraints ---------------------------------------------
        types = doc["muscle_types"]
        rest_w = float(model["rest_weight"])
        cross = float(model["cross_talk"])
        cvs = int(model["cvs"])
        infl = np.zeros((k, n))
        for i, nm in enumerate(mj.names):
            f = rig.fields.get(f"muscle/{nm}")
            if f is not None:
                infl[i] = np.asarray(f, dtype=np.float64).reshape(n)
        G = np.zeros((k, n, 3))
        all_tree = cKDTree(Vc)
        total = np.zeros(n)
        self.wires_ = []
        for i, nm in enumerate(mj.names):
            spec = types.get(mj.types[i])
            if spec is None:
                continue
            o, ip = mj.origins[i], mj.insertions[i]
            o_skin = Vc[snap(o)[0]]
            t = np.linspace(float(spec["wire"][0]), float(spec["wire"][1]), cvs)
            cv_idx = snap(o_skin[None] + t[:, None] * (ip - o_skin)[None])
            Q = Vc[cv_idx]
            # which lip the wire belongs to: its insertion inside the mouth zone's width
            ins_dx = abs(ip[0] - st[0])
            ins_s = ip[1] - np.interp(ip[0], xs[order], np.array([ch_r[1], st[1], ch_l[1]])[order])
            if ins_dx < 0.9 * hw and abs(ins_s) > float(lips["cut_width"]) * fu:
                gate = 1.0 - zone * ((1.0 - upper) if ins_s > 0 else upper)
                side = "upper" if ins_s > 0 else "lower"
            else:
                gate, side = None, "both"
            d0 = float(spec["dropoff"]) * mj.widths[i]
            Wm = wire_weights(Vc, Q, d0, gate=skin * (1.0 if gate is None else gate), tree=all_tree)
            # point constraint per control vertex: own locator (001 profile), neighbours, rest
            prof = np.where(t <= 1.0, np.sin(0.5 * np.pi * np.clip(t, 0, 1) ** 0.48),
                            np.cos(0.5 * np.pi * np.clip((t - 1.0) / 0.25, 0.0, 1.0)))
            if "galea" in spec:
                # the aponeurosis above the muscle is pulled along as one sheet: its own locator
                # weighs fully from the wire's start over the galea down to the anchor
                prof = np.where(t < float(spec["galea"]["anchor"]), 1.0, prof)
            cw = cross * infl[:, cv_idx].T                                   # (cvs, k)
            cw[:, i] = prof
            for j2 in range(k):                                   # neighbours pull from their own side only
                if j2 != i and mj.sides[j2] != mj.sides[i] and "m" not in (mj.sides[j2], mj.sides[i]):
                    cw[:, j2] = 0.0
            cw = cw / (rest_w + cw.sum(axis=1, keepdims=True))
            for j2 in np.flatnonzero(cw.max(axis=0) > 0):
                sh = float(types.get(mj.types[j2], {}).get("shortening", 0.0))
                if sh == 0.0:
                    continue
                # frontalis, on the galea: the scalp slides down toward a raised brow
                anchor = types.get(mj.types[j2], {}).get("galea", {}).get("anchor")
                d = mj.locator_displacements(Q, j2, anchor=anchor) * (sh * cw[:, j2:j2 + 1])
                G[j2] += Wm @ d
            total += np.asarray(Wm.sum(axis=1)).ravel()
            self.wires_.append({"muscle": nm, "base": Q, "vertices": cv_idx, "dropoff": d0, "side": side})
        # smooth the muscle fields by heat diffusion over ~1 mm of skin (implicit step with the
        # intrinsic Laplacian, edges across the mouth line removed): a wire's dropoff varies faster
        # than the tiny triangles of mouth and eye corners can follow without folding
        Lp, M = laplacian(Vw, Fw)
        self._laplacian = (Lp, M)
        # unfolding averages over the intrinsic (Delaunay) Laplacian's non-negative weights: a
        # plain neighbour mean drags the tiny triangles of mouth corners along with big ones
        Wu = (sp.diags(Lp.diagonal()) - Lp).tocsr()
        Wu.data = np.maximum(Wu.data, 0.0)
        Wu.eliminate_zeros()
        self._unfold_weights = (Wu, np.asarray(Wu.sum(axis=1)).ravel())
        t_s = (float(model.get("smoothing", 0.012)) * fu) ** 2
        if t_s > 0:
            C = Lp.tocoo()
            off = C.row != C.col
            # an edge across the mouth line conducts less the more it lies in the mouth zone
            zw, uw, sw = zone[first], upper[first], skin[first]
            conduct = (1.0 - np.minimum(zw[C.row], zw[C.col]) * np.abs(uw[C.row] - uw[C.col])) * (sw[C.row] & sw[C.col])
            keep = off & (conduct > 0)
            Loff = sp.csr_matrix((C.data[keep] * conduct[keep], (C.row[keep], C.col[keep])), shape=(nw, nw))
            Lc = Loff - sp.diags(np.asarray(Loff.sum(axis=1)).ravel())
            # muscles whose wire pulls one lip are smoothed with the cut, the corner muscles (wires
            # on both lips) without it
            sides = {w["muscle"]: w["side"] for w in self.wires_}
            both = np.array([sides.get(nm, "both") == "both" for nm in mj.names])
            for sel, lap_ in ((~both, Lc), (both, Lp)):
                if not sel.any():
                    continue
                solve = factor_spd(M + t_s * lap_)
                flat = G[sel][:, first].transpose(1, 0, 2).reshape(nw, -1)
                flat = solve(np.asarray(M @ flat))[index]
                G[sel] = flat.reshape(n, int(sel.sum()), 3).transpose(1, 0, 2)
        if bool(model.get("normalise_overlaps", False)):
            G *= (1.0 / np.maximum(total, 1.0))[None, :, None]
        self.muscle_basis_ = G
        self.shortening_ = np.array([float(types.get(t_, {}).get("shortening", 0.0)) for t_ in mj.types])

        # --- skull: soft-tissue thickness per region ----------------------------------------
        skull = model["skull"]
        thick = np.full(n, float(skull["default"]) * fu)
        region = rig.fields.get("region")
        if region is not None:
            labels = list((rig.extra.get("field_labels") or {}).get("region", REGIONS_DEFAULT))
            region = np.asarray(region).reshape(n).astype(np.int64)
            for r_i, r_name in enumerate(labels):
                if r_name in skull:
                    thick[region == r_i] = float(skull[r_name]) * fu
        # the offset skull is smooth: region thicknesses blend over ~1 cm of skin
        self.thickness_ = diffuse(thick[first], Lp, M, t=(float(skull.get("blend", 0.1)) * fu) ** 2)[index]
        # the offset skull lies under outward-facing skin only: not under the lips (the inner lip
        # surfaces face each other) nor under skin whose normal points into the head
        self.clamp_ = (zone < 0.05) & ~inward
        # muscles over bone (type option "slide"): where the skull lies close under outward skin
        # (soft tissue at most ``slide_thickness`` fu) the skin slides over it, so the part of
        # the field along the skull normal (toward a deep origin) is dropped
        over_bone = self.clamp_ * ramp(self.thickness_, 1.5 * float(model.get("slide_thickness", 0.04)) * fu,
                                        float(model.get("slide_thickness", 0.04)) * fu)
        Ns_ = self.skull_normals_
        for i, ty in enumerate(mj.types):
            if bool(types.get(ty, {}).get("slide", False)):
                G_i = self.muscle_basis_[i]
                G_i -= (over_bone * (G_i * Ns_).sum(axis=1))[:, None] * Ns_

        # --- creases ---------------------------------------------------------------------------
        cr = model["creases"]
        self.crease_basis_ = {}
        for i, ty in enumerate(mj.types):
            if ty.startswith("frontalis"):
                lam, amp = float(cr["forehead_wavelength"]) * fu, float(cr["forehead_amplitude"]) * fu
                phase = (Vc[:, 1] - mj.insertions[i][1]) / lam
                furrow = 0.5 * (1.0 - np.cos(2.0 * np.pi * phase)) * (phase > 0.5)
            elif ty in ("corrugator", "lateral_corrugator"):
                lam, amp = float(cr["glabella_wavelength"]) * fu, float(cr["glabella_amplitude"]) * fu
                furrow = 0.5 * (1.0 + np.cos(2.0 * np.pi * (Vc[:, 0] - st[0]) / lam)) * (np.abs(Vc[:, 0] - st[0]) < lam)
            else:
                continue
            K = -(amp * infl[i] * furrow * skin)[:, None] * N
            if np.any(K):
                self.crease_basis_[i] = K

        # --- eyelids ---------------------------------------------------------------------------
        lid = model["eyelids"]
        self.lid_weights_ = np.zeros((4, n))
        self.lid_close_deg_ = np.zeros(2)
        self.lid_pivots_ = np.zeros((2, 3))
        # open lids: the fissure's midpoint lies in a hole of the skin, far from its surface
        import igl

        skinF = F[skin[F].all(axis=1)]
        mids = []
        for s in "lr":
            nm_ = [f"palpebrale_superius_{s}", f"palpebrale_inferius_{s}"]
            mids.append(0.5 * (L[nm_[0]] + L[nm_[1]]) if all(x in L for x in nm_) else Vc.mean(axis=0))
        mid_gap = np.sqrt(igl.point_mesh_squared_distance(np.array(mids), np.ascontiguousarray(Vc),
                                                          np.ascontiguousarray(skinF))[0]) if len(skinF) else np.zeros(2)
        for e, s in enumerate("lr"):
            c = eyes.get(s)
            if c is None:
                continue
            need = [f"{b}_{s}" for b in ("exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius")]
            if all(nm_ in L for nm_ in need):
                ex, en, ps, pi = (L[nm_] for nm_ in need)
            else:
                sign = 1.0 if s == "l" else -1.0
                ex, en = c + [sign * 0.15 * fu, 0, 0.08 * fu], c + [-sign * 0.15 * fu, 0, 0.08 * fu]
                ps, pi = c + [0, 0.05 * fu, 0.12 * fu], c + [0, -0.01 * fu, 0.12 * fu]
            mid = 0.5 * (ps + pi)
            gap = max(float(np.linalg.norm(ps - pi)), 1e-3 * fu)
            xo = np.array([en[0], mid[0], ex[0]])
            oo = np.argsort(xo)
            y_f = np.interp(Vc[:, 0], xo[oo], np.array([en[1], mid[1], ex[1]])[oo])
            s_f = Vc[:, 1] - y_f
            a = float(lid["width_margin"]) * 0.5 * abs(ex[0] - en[0])
            cx = 0.5 * (ex[0] + en[0])
            depth = float(lid.get("depth", 0.02)) * fu
            front = ramp(Vc[:, 2], c[2] - depth, c[2] + 0.04 * fu)
            ru = np.sqrt(((Vc[:, 0] - cx) / a) ** 2 + (s_f / (float(lid["upper_height"]) * fu)) ** 2)
            rl = np.sqrt(((Vc[:, 0] - cx) / a) ** 2 + (s_f / (float(lid["lower_height"]) * fu)) ** 2)
            is_open = mid_gap[e] > 0.25 * gap
            if is_open:
                up_step, low_step = ramp(s_f, 0.0, 0.15 * gap), ramp(-s_f, 0.0, 0.15 * gap)
            else:  # closed lids (one surface across the fissure): spread so nothing folds over
                up_step, low_step = ramp(s_f, -0.5 * gap, 1.5 * gap), ramp(-s_f, -0.5 * gap, 1.5 * gap)
            # the fissure opens as 1 - u^2 between the corners, so the lid joints turn less there
            u = (Vc[:, 0] - cx) / (0.5 * abs(ex[0] - en[0]))
            # the medial canthus is tied to bone, the lateral one is looser: toward (and past) the
            # outer corner the lids keep turning over ``lateral_reach`` half fissure widths
            u = np.where(u * np.sign(ex[0] - en[0]) > 0, u / float(lid.get("lateral_reach", 1.0)), u)
            h = np.clip(1.0 - u * u, 0.0, 1.0) ** float(lid.get("corner_exponent", 1.0))
            # above the margin the upper lid turns as one sheet: the corners hold the margin only,
            # so their hold fades over ``corner_release`` fissure heights up the lid
            rel = float(lid.get("corner_release", 0.0))
            h_up = 1.0 - (1.0 - h) * (1.0 - ramp(s_f, 0.0, rel * gap)) if rel > 0 else h
            self.lid_weights_[e] = ramp(ru, 1.0, 0.55) * up_step * front * skin * h_up
            self.lid_weights_[2 + e] = ramp(rl, 1.0, 0.55) * low_step * front * skin * h
            phi = lambda p: np.arctan2(p[1] - c[1], p[2] - c[2])  # noqa: E731
            self.lid_close_deg_[e] = np.degrees(phi(ps) - phi(pi))
            self.lid_pivots_[e] = c
        self.lid_lower_range_ = float(lid["lower_range"])
        # smoothed like the muscle fields, but wider: a lid joint turns its skin by the full closing
        # angle, so a weight that changes within a few of the eye corners' tiny triangles folds them
        t_l = (float(lid.get("smoothing", model.get("smoothing", 0.012))) * fu) ** 2
        if t_l > 0:
            lw = diffuse(self.lid_weights_[:, first].T, Lp, M, t=t_l)[index].T
            # diffusion reaches the whole skin with vanishing weights: the lids keep their own area
            self.lid_weights_ = np.where(lw > 1e-3, np.clip(lw, 0.0, 1.0), 0.0) * skin
        # the lid margins ride the eyeball: the muscles around (frontalis, zygomatics) stretch the
        # lids' skin but leave the margins to the lid joints
        hold = float(lid.get("margin_hold", 0.85)) * self.lid_weights_.max(axis=0)
        self.muscle_basis_ *= (1.0 - hold)[None, :, None]
        for i in list(self.crease_basis_):
            self.crease_basis_[i] = self.crease_basis_[i] * (1.0 - hold)[:, None]
        # small separate parts on the lids (eyelashes, eye-occlusion / tear-line shells) are held
        # where they touch the skin: each of their vertices follows the skin under the nearest of
        # its part's touching vertices (its lid joints and muscle fields), so a lash turns whole
        # with the margin it grows from (its tip, nearest the lid skin above, would lag) and a
        # shell across the fissure closes with both lids
        self.attached_ = np.zeros(n, dtype=bool)
        eye_w = sum((W[:, names.index(f"eye_{s}")] for s in "lr" if f"eye_{s}" in names), np.zeros(n))
        d_skin, near = tree.query(Vc)
        near = skin_idx[near]
        lid_any = self.lid_weights_.max(axis=0)
        att = float(lid.get("attached_part_size", 0.5)) * fu
        on_lids = []                                        # (rows, touching rows) per part
        for p_ in np.unique(part[~skin]):
            rows = np.flatnonzero((part == p_) & ~skin)
            if (eye_w[rows].mean() >= 0.5 or np.ptp(Vc[rows], axis=0).max() > att
                    or d_skin[rows].min() > 0.01 * fu or lid_any[near[rows]].max() < 0.1):
                continue
            self.attached_[rows] = True
            roots = rows[d_skin[rows] <= d_skin[rows].min() + 0.01 * fu]
            near[rows] = near[roots[cKDTree(Vc[roots]).query(Vc[rows])[1]]]
            on_lids.append((rows, roots))
        rows = np.flatnonzero(self.attached_)
        self.lid_weights_[:, rows] = self.lid_weights_[:, near[rows]]
        # a part rooted on one lid only (a row of lashes on its tarsal plate) turns as one piece
        # with the margin, corners included; a part rooted on both (a shell across the
        # fissure) stretches between them
        for part_rows, roots in on_lids:
            rw = self.lid_weights_[:, roots]
            on_upper = np.mean(rw[:2].max(axis=0) >= rw[2:].max(axis=0))
            if on_upper >= 0.9 or on_upper <= 0.1:
                self.lid_weights_[:, part_rows] = rw.max(axis=1)[:, None]
        self.muscle_basis_[:, rows] = self.muscle_basis_[:, near[rows]]
        for i in list(self.crease_basis_):
            self.crease_basis_[i][rows] = self.crease_basis_[i][near[rows]]

        # --- jaw weights sharpened across the mouth line -------------------------------------
        Wj = W.copy()
        self.mouth_parts_ = np.zeros(0, dtype=np.int64)   # vertices of the mouth's inner parts
        if "jaw" in names:
            j = names.index("jaw")
            # under the chin the jaw swings toward the neck: spread its weight there so the skin
            # stretches instead of folding (heat diffusion, as build_rig smooths it)
            spread = float(model.get("jaw_spread", 0.15)) * fu
            jaw_s = (np.clip(diffuse(W[first, j], *self._laplacian, t=spread ** 2), 0.0, 1.0)[index]
                     if spread > 0 else W[:, j])
            below = ramp(s_mouth, 0.0, -0.1 * fu) * skin
            jaw_b = (1.0 - below) * W[:, j] + below * jaw_s
            # beside the mouth the cheek is one sheet from the cheekbone to the mandible: lateral of
            # the mouth corners it stretches as the jaw opens, the jaw weight diffusing up into it
            cheek = float(model.get("cheek_spread", 0.0)) * fu
            if cheek > 0:
                jaw_c = np.clip(diffuse(W[first, j], *self._laplacian, t=cheek ** 2), 0.0, 1.0)[index]
                lateral = ramp(dx, 0.8 * hw, 1.1 * hw) * skin * (1.0 - below)
                jaw_b = np.where(lateral > 0, np.maximum(jaw_b, lateral * jaw_c + (1.0 - lateral) * jaw_b), jaw_b)
            # under the chin the opening jaw swings back toward the neck: the skin there follows it
            # less and less from the menton back, so it stretches instead of folding into the neck
            men = L.get("menton")
            if men is not None:
                under = ramp(Vc[:, 1], men[1] + float(model.get("under_chin_height", 0.15)) * fu, men[1]) * skin
                fade = ramp(Vc[:, 2], men[2] - float(model.get("under_chin_depth", 0.6)) * fu, men[2])
                jaw_b = jaw_b * (1.0 - under * (1.0 - fade))
            # the lips join at the corners, where tiny triangles bridge the upper lip (hanging over
            # the lower) and the lower lip: any step in the jaw weight there turns them over, so the
            # cut grows from nothing at the cheilions to full half the mouth's half-width in (full
            # only at the stomion pinned the corners, a V-shaped opening; nearer the corners the
            # mouth's lining folds at AU26 and the unfolding moves a wide patch of it)
            zone_j = zone * ramp(dx, hw, 0.5 * hw)
            jaw_new = (1.0 - zone_j) * jaw_b + zone_j * (1.0 - upper)
            others = np.delete(np.arange(W.shape[1]), j)
            rest = W[:, others].sum(axis=1)
            want = 1.0 - jaw_new
            scale = np.where(rest > 1e-12, want / np.maximum(rest, 1e-12), 0.0)
            Wj[:, others] = W[:, others] * scale[:, None]
            if "head" in names:
                h = names.index("head")
                Wj[:, h] += np.where(rest > 1e-12, 0.0, want)
            Wj[:, j] = jaw_new
            # the mouth's separate inner parts (teeth, gums, tongue) are carried by the mandible
            # below the occlusal plane and by the skull above it (taken level through the
            # stomion): a small part (a tooth) rides one bone by its centre; a large one (gums
            # with the tongue) splits vertex by vertex over a narrow band at the crowns of the lower
            # teeth, when there are any (the lower gums and the tongue lie within the lower dental
            # arch, up to its crowns), and behind the jaw joint stays with the skull (the pharynx)
            mouth = model.get("mouth_parts", {})
            reach = float(mouth.get("reach", 0.9)) * fu
            band = float(mouth.get("band", 0.03)) * fu
            rigid = float(mouth.get("rigid_size", 0.5)) * fu
            inner = ~skin & ~self.attached_ & (eye_w < 0.5)
            found = []                                     # (rows, centre, small)
            for p_ in np.unique(part[inner]):
                rows = np.flatnonzero((part == p_) & inner)
                cen = Vc[rows].mean(axis=0)
                if np.linalg.norm(cen - st) <= reach and cen[2] <= st[2]:
                    found.append((rows, cen, np.ptp(Vc[rows], axis=0).max() <= rigid))
            # (a lower crown stands at most a little above the lips' line: a small part reaching
            # higher is not a lower tooth)
            tops = [Vc[rows, 1].max() - st[1] for rows, cen, sm in found if sm and cen[1] < st[1]]
            level = st[1] + max([t_ for t_ in tops if t_ <= 0.1 * fu], default=0.0)
            # behind the jaw joint: the pharynx, fixed to the skull (held fully from pharynx fu behind
            # the joint, free from twice that in front: a sharper step turns the tongue's triangles
            # over at the joint as the jaw opens)
            ph = float(mouth.get("pharynx", 0.1)) * fu
            front = ramp(Vc[:, 2] - self.pivots_[j][2], -ph, 2.0 * ph)
            for rows, cen, sm in found:
                y = np.full(len(rows), cen[1] - st[1]) if sm else Vc[rows, 1] - level
                jw = ramp(y, band, -band) * front[rows]
                Wj[rows] = 0.0
                Wj[rows, j] = jw
                if "head" in names:
                    Wj[rows, names.index("head")] = 1.0 - jw
                self.mouth_parts_ = np.union1d(self.mouth_parts_, rows)
        self.jaw_weights_ = Wj
        down, forward = (list(model.get("jaw_glide", [0.0, 0.0])) + [0.0, 0.0])[:2]
        self.jaw_glide_ = np.array([0.0, -float(down), float(forward)]) * fu
        return self

    # ------------------------------------------------------------------------------ parameters
    def _check(self):
        if not hasattr(self, "muscle_basis_"):
            raise AutobonesError("ExpressionModel: call fit(rig) before posing")

    @property
    def action_units(self):
        """AU number (str) -> definition, as in the data file."""
        return self.doc_["action_units"]

    @property
    def expressions(self):
        """Emotion prototype name -> definition."""
        return self.doc_["expressions"]

    def parameters(self, au=None, expression=None, muscles=None, jaw_deg=0.0, eyelids=None):
        """The model's own parameters for a mix of AUs, an expression and direct muscle values.

        Parameters
        ----------
        au : dict, optional
            AU -> intensity (usually 0..1); keys ``12``, ``"12"``, ``"AU12"``, and
            ``"12L"`` / ``"12R"`` for one side (the subject's left / right).
        expression : str or dict, optional
            An emotion prototype (``"happiness"``...) at intensity 1, or name -> intensity.
        muscles : dict, optional
            Muscle name (``zygomaticus_major_l``) or type (both sides) -> contraction,
            added to what the AUs give.
        jaw_deg : float
            Extra jaw opening, degrees.
        eyelids : dict, optional
            ``upper``/``lower`` (both eyes) or ``upper_l``... -> amount (upper 1 closes).

        Returns
        -------
        dict
            ``contractions`` (k,) float in :attr:`muscle_names_` order, ``jaw_deg`` float,
            ``eyelids`` (4,) float in :data:`LIDS` order.
        """
        self._check()
        c = np.zeros(len(self.muscle_names_))
        lids = np.zeros(4)
        jaw = float(jaw_deg)
        mix = {}
        if expression is not None:
            ex = {expression: 1.0} if isinstance(expression, str) else dict(expression)
            for name, a in ex.items():
                if name not in self.expressions:
                    raise AutobonesError(f"unknown expression {name!r}; known: {', '.join(self.expressions)}")
                for k_, v in self.expressions[name]["au"].items():
                    mix[str(k_)] = mix.get(str(k_), 0.0) + float(a) * float(v)
        for k_, v in (au or {}).items():
            key = str(k_).upper().removeprefix("AU")
            mix[key] = mix.get(key, 0.0) + float(v)
        for key, a in mix.items():
            side = None
            if key[-1:] in ("L", "R"):
                key, side = key[:-1], key[-1].lower()
            if key not in self.action_units:
                raise AutobonesError(f"unknown action unit {key!r}; defined: "
                                     f"{', '.join(sorted(self.action_units, key=int))}")
            if not np.isfinite(a):
                raise AutobonesError(f"action unit {key}: intensity {a} is not a finite number")
            d = self.action_units[key]
            for m, v in d.get("muscles", {}).items():
                c += a * float(v) * self._muscle_mask(m, side)
            jaw += a * float(d.get("jaw_deg", 0.0)) * (1.0 if side is None else 0.5)
            for part, v in d.get("eyelids", {}).items():
                lids += a * float(v) * self._lid_mask(part, side)
        for m, v in (muscles or {}).items():
            c += float(v) * self._muscle_mask(m, None)
        for part, v in (eyelids or {}).items():
            lids += float(v) * self._lid_mask(part, None)
        if not (np.isfinite(c).all() and np.isfinite(lids).all() and np.isfinite(jaw)):
            raise AutobonesError("expression parameters must be finite numbers")
        return {"contractions": c, "jaw_deg": jaw, "eyelids": lids}

    def _muscle_mask(self, m, side):
        mj = self.joints_
        if m in mj.names:
            mask = np.array([n == m for n in mj.names], dtype=np.float64)
        else:
            mask = np.array([t == m for t in mj.types], dtype=np.float64)
            if not mask.any():
                raise AutobonesError(f"unknown muscle {m!r}; the rig has: {', '.join(mj.names)}")
        if side is not None:
            mask *= np.array([s == side for s in mj.sides], dtype=np.float64)
        return mask

    def _lid_mask(self, part, side):
        names = [p for p in LIDS if p == part or p.split("_")[0] == part]
        if not names:
            raise AutobonesError(f"unknown eyelid {part!r}; use upper, lower or one of {', '.join(LIDS)}")
        if side is not None:
            names = [p for p in names if p.endswith("_" + side)]
        return np.array([float(p in names) for p in LIDS])

    def muscle_fields(self):
        """(k, n, 3) skin displacement per unit contraction of each muscle, input frame and units
        (before the skull clamp, creases and bones): the linear part of the model, for fitting."""
        self._check()
        return (self.muscle_basis_ * self.frame_.size) @ self.frame_.rotation

    def linear_pose(self, jaw_deg=0.0, eyelids=None):
        """The pose as an affine map of the contractions for fixed jaw and lids (for fitting).

        Parameters
        ----------
        jaw_deg : float
            Jaw opening, degrees.
        eyelids : (4,) float, optional
            Lid amounts in :data:`LIDS` order.

        Returns
        -------
        A : (k, n, 3) float
            Displacement per unit contraction (muscle fields and creases carried by the lid
            and jaw rotations), input frame and units.
        b : (n, 3) float
            The posed vertices at zero contraction, input frame and units.

        ``b + tensordot(c, A, 1)`` equals ``pose_parameters(c, jaw_deg, eyelids)`` wherever the
        skull clamp does not act (the lid and jaw stages are a fixed rotation per vertex).
        """
        self._check()
        n = len(self.canonical_)
        const = self._bones(np.zeros((n, 3)), jaw_deg, eyelids)
        R = np.stack([self._bones(np.tile(np.eye(3)[a], (n, 1)), jaw_deg, eyelids) - const for a in range(3)],
                     axis=2)                                             # (n, 3, 3): column a = image of e_a
        G = self.muscle_basis_.copy()
        for i, K in self.crease_basis_.items():
            G[i] += K
        A = np.einsum("nij,knj->kni", R, G)
        rot, size = self.frame_.rotation, self.frame_.size
        return (A * size) @ rot, self.vertices_ + (const * size) @ rot

    # ------------------------------------------------------------------------------ posing
    def pose(self, au=None, expression=None, muscles=None, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None,
             head_deg=None, neck_deg=None):
        """Posed vertices for AUs / an expression / muscle contractions plus bone controls.

        Parameters
        ----------
        au, expression, muscles, jaw_deg, eyelids
            See :meth:`parameters`.
        gaze : (yaw_deg, pitch_deg), optional
            Both eyes turned toward the subject's left (yaw > 0) and up (pitch > 0).
        look_at : (3,) float, optional
            A point in the input frame and units both eyes aim at (000's aim control;
            the eyes keep their rest divergence).
        head_deg, neck_deg : (pitch, yaw, roll) degrees, optional
            Rotations about the canonical +X (pitch > 0 nods down), +Y (yaw > 0 turns to
            the subject's left) and +Z axes at the head / neck pivots.

        Returns
        -------
        (n, 3) float
            Vertices in the input frame and units; exactly ``rig.vertices`` when every
            parameter is 0.
        """
        p = self.parameters(au=au, expression=expression, muscles=muscles, jaw_deg=jaw_deg, eyelids=eyelids)
        return self.pose_parameters(p["contractions"], jaw_deg=p["jaw_deg"], eyelids=p["eyelids"], gaze=gaze,
                                    look_at=look_at, head_deg=head_deg, neck_deg=neck_deg)

    def pose_parameters(self, contractions, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None, head_deg=None,
                        neck_deg=None):
        """Posed vertices from the raw parameter vector (what a fit searches over).

        Parameters
        ----------
        contractions : (k,) float
            Muscle contractions in :attr:`muscle_names_` order (1 = the muscle type's
            ``shortening``).
        jaw_deg : float
            Jaw opening, degrees.
        eyelids : (4,) float, optional
            Lid amounts in :data:`LIDS` order.
        gaze, look_at, head_deg, neck_deg
            See :meth:`pose`.

        Returns
        -------
        (n, 3) float
            Vertices in the input frame and units.
        """
        self._check()
        c = np.asarray(contractions, dtype=np.float64).reshape(-1)
        if c.shape != (len(self.muscle_names_),):
            raise AutobonesError(f"contractions: expected {len(self.muscle_names_)} values, got {c.shape}")
        Vc = self.canonical_
        d = np.tensordot(c, self.muscle_basis_, axes=1) if np.any(c) else np.zeros_like(Vc)
        # skull non-penetration: sink at most the soft-tissue thickness along the rest normal
        if np.any(c):
            Ns = self.skull_normals_
            depth = (d * Ns).sum(axis=1)
            over = -self.thickness_ - depth
            hit = (over > 0) & self.clamp_
            d[hit] += over[hit, None] * Ns[hit]
            for i, K in self.crease_basis_.items():
                if c[i] != 0:
                    d += c[i] * K
        return self.vertices_ + (self._bones(d, jaw_deg, eyelids, gaze, look_at, head_deg, neck_deg, unfold=True)
                                 * self.frame_.size) @ self.frame_.rotation

    def _unfold(self, d, rounds=40, passes=8):
        """Relax the canonical displacement ``d`` (n, 3) where skin triangles turned over.

        Beyond the seeds: a wide jaw opening turns each vertex by its own angle, and where the
        jaw weight changes fast (under the chin, the mouth corners) neighbouring skin can swing
        past each other. Skin cannot fold through itself, so around every skin triangle whose
        normal turned by more than 90 degrees (and the two rings of vertices about it) the
        displacement is replaced by its neighbours' mean, weighted by the intrinsic Laplacian
        (Jacobi passes, the ring outside held), the region growing (never farther than
        ``unfold_reach`` fu from the first folds; each round relaxing only its part within
        ``unfold_reach`` of the folds left, so skin whose folds are undone is not smoothed on
        while others persist) until nothing is turned over, ``rounds`` run out or eight rounds
        in a row leave no less folded area; the state with the least folded area (rest area of
        the turned triangles) is kept, and of it each connected relaxed patch only where it
        leaves less folded area than before (never more anywhere). What still folds then moves
        as one piece with the skin around it (:meth:`_rigid_patches`). Vertices away from folds
        keep their displacement exactly.
        """
        A, skin_w, Fs, n0, area = self._unfold_mesh
        Wu, wdeg = self._unfold_weights
        index, first = self._weld
        Vw = self.canonical_[first]
        dw = d[first].copy()
        touched = np.zeros(len(Vw), dtype=bool)
        grow = np.zeros(len(Vw), dtype=bool)
        faces = np.arange(len(Fs))                # faces whose vertices may have moved
        last, stale, allowed = None, 0, None
        reach = float(self.doc_["model"].get("unfold_reach", 0.25)) * self.face_unit_
        for _ in range(rounds):
            bad = faces[_turned(Vw + dw, Fs[faces], n0[faces])]
            amount = float(area[bad].sum())
            if last is None or amount < last:       # keep the state with the least folded area
                best, best_touched = dw.copy(), touched.copy()
            if not len(bad):
                break
            # stop when relaxing no longer helps (a fold the mean cannot undo)
            stale = stale + 1 if last is not None and amount >= last else 0
            last = amount if last is None else min(last, amount)
            if stale >= 8:
                break
            grow[Fs[bad].ravel()] = True
            if allowed is None:   # the relaxation stays within ``reach`` of the first folds
                seeds = np.unique(Fs[bad].ravel())
                near = cKDTree(Vw[seeds]).query(Vw, distance_upper_bound=reach)[0]
                allowed = np.isfinite(near) & skin_w
            for _ring in range(2):
                grow |= (A @ grow.astype(np.float64)) > 0
            grow &= allowed
            # only skin within ``reach`` of the folds left now relaxes further: where folds are
            # undone (under the chin) the skin is not dragged on toward the harmonic fill while
            # folds elsewhere (the mouth corners) persist
            G = np.flatnonzero(grow)
            near_now = cKDTree(Vw[np.unique(Fs[bad].ravel())]).query(Vw[G], distance_upper_bound=reach)[0]
            active = np.zeros(len(Vw), dtype=bool)
            active[G[np.isfinite(near_now)]] = True
            touched |= active
            rows = np.flatnonzero(active)
            faces = np.flatnonzero(grow[Fs].any(axis=1))
            rows = rows[wdeg[rows] > 0]
            Wr = Wu[rows]
            for _p in range(passes):
                dw[rows] = (Wr @ dw) / np.maximum(wdeg[rows], 1e-300)[:, None]
        if not best_touched.any():
            best, rigid = self._rigid_patches(Vw, d[first].copy())
            if not rigid.any():
                return d
            out = d.copy()
            out[rigid[index]] = best[index[rigid[index]]]
            return out
        # each separate relaxed patch is kept only where it leaves less skin folded than before
        # (a patch grown around a few slivers must not fold their larger neighbours instead)
        T = np.flatnonzero(best_touched)
        n_c, lab = connected_components(A[T][:, T], directed=False)
        comp = np.full(len(Vw), n_c)
        comp[T] = lab
        face_c = comp[Fs].min(axis=1)              # a face touches at most one patch
        before, after = (np.bincount(face_c, weights=area * _turned(Vw + q, Fs, n0), minlength=n_c + 1)
                         for q in (d[first], best))
        undo = np.flatnonzero(after[:n_c] >= before[:n_c])
        if len(undo):
            back = np.isin(comp, undo)
            best[back] = d[first][back]
            best_touched &= ~back
        best, rigid = self._rigid_patches(Vw, best)
        best_touched |= rigid
        out = d.copy()
        moved = best_touched[index]
        out[moved] = best[index[moved]]
        return out

    def _rigid_patches(self, Vw, dw, rings=6, sweeps=12):
        """Move what relaxation left folded as one piece (welded displacement ``dw``).

        Slivers where the surface itself folds sharply (the mouth corners' commissure, where the
        upper lip overhangs the lower one; the mouth's lining between the lips) stay turned over
        under any averaging of the displacement. Each connected cluster of still-folded
        triangles is grown ring by ring; its vertices take the rigid motion (rotation and
        translation, least squares), or else the orientation-preserving affine map, that best
        fits the displacement of the ring of vertices around it, so the cluster turns and
        stretches only as its surroundings do, the next ``feather`` rings blending back to their
        own displacement. The first candidate that leaves no triangle about the cluster folded
        is kept (else the one removing the most folded area, if any; never beyond
        ``unfold_reach`` fu of the cluster); sweeps repeat while they change anything. Returns
        the displacement and the vertices moved.
        """
        moved = np.zeros(len(Vw), dtype=bool)
        for _ in range(sweeps):
            dw, m = self._rigid_sweep(Vw, dw, rings)
            if not m.any():
                break
            moved |= m
        return dw, moved

    def _rigid_sweep(self, Vw, dw, rings, feathers=(0, 1, 2, 4)):
        """One sweep of :meth:`_rigid_patches` over the clusters folded now."""
        A, skin_w, Fs, n0, area = self._unfold_mesh
        moved = np.zeros(len(Vw), dtype=bool)
        bad = np.flatnonzero(_turned(Vw + dw, Fs, n0))
        if not len(bad):
            return dw, moved
        reach = float(self.doc_["model"].get("unfold_reach", 0.25)) * self.face_unit_

        def grow(mask):
            return (((A @ mask.astype(np.float64)) > 0) | mask) & skin_w

        V_bad = np.unique(Fs[bad].ravel())
        n_c, lab = connected_components(A[V_bad][:, V_bad], directed=False)
        for c in range(n_c):
            seed = V_bad[lab == c]
            core = np.zeros(len(Vw), dtype=bool)
            core[seed] = True
            centre = Vw[seed].mean(axis=0)
            best_gain, best_q, done = 0.0, None, False
            for _r in range(rings):
                shells = [core]
                for _f in range(max(feathers) + 1):
                    shells.append(grow(shells[-1]))
                ring = shells[1] & ~core
                R_ = np.flatnonzero(ring)
                if len(R_) < 3 or np.linalg.norm(Vw[R_] - centre, axis=1).max() > reach:
                    break
                X = Vw[R_]
                Y = X + dw[R_]
                mx, my = X.mean(axis=0), Y.mean(axis=0)
                U, _s, Vt = np.linalg.svd((X - mx).T @ (Y - my))
                D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
                maps = [(U @ D @ Vt).T]                      # y ~ M (x - mx) + my
                if len(R_) >= 4:
                    Aff = np.linalg.lstsq(X - mx, Y - my, rcond=None)[0].T
                    if np.linalg.det(Aff) > 0:
                        maps.append(Aff)
                for fe in feathers:
                    near = shells[fe + 1]
                    local = np.flatnonzero(near[Fs].any(axis=1))
                    before = float((area[local] * _turned(Vw + dw, Fs[local], n0[local])).sum())
                    alpha = np.zeros(len(Vw))
                    for k in range(fe + 1):      # 1 on the core, fading over the feather rings
                        alpha[shells[k] & (alpha == 0)] = 1.0 - k / (fe + 1.0)
                    rows = np.flatnonzero(alpha > 0)
                    for Mm in maps:
                        q = dw.copy()
                        target = (Vw[rows] - mx) @ Mm.T + my - Vw[rows]
                        q[rows] = alpha[rows, None] * target + (1.0 - alpha[rows, None]) * dw[rows]
                        amount = float((area[local] * _turned(Vw + q, Fs[local], n0[local])).sum())
                        if before - amount > best_gain:
                            best_gain, best_q = before - amount, (rows, q[rows])
                        if amount == 0.0 and before > 0.0:
                            done = True
                            break
                    if done:
                        break
                if done:
                    break
                core = shells[1]
            if best_q is not None:
                dw[best_q[0]] = best_q[1]
                moved[best_q[0]] = True
        return dw, moved

    def _bones(self, d, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None, head_deg=None, neck_deg=None,
               unfold=False):
        """Stage 4 on the canonical (n, 3) muscle-stage displacement ``d``: the lids, jaw, head,
        neck and eyes. Returns the canonical displacement (n, 3), head sizes. For fixed bone
        parameters and ``unfold`` False it is affine in ``d`` per vertex (a rotation plus a
        translation); ``unfold`` relaxes skin the lids and jaw fold over (:meth:`_unfold`)."""
        Vc = self.canonical_
        d = np.array(d, dtype=np.float64)
        # eyelids: four lid joints rotating about the eye pivots (canonical +X axis)
        lids = np.zeros(4) if eyelids is None else np.asarray(eyelids, dtype=np.float64).reshape(4)
        for q in np.flatnonzero(lids):
            e = q % 2
            w = self.lid_weights_[q]
            rows = np.flatnonzero(w > 0)
            if len(rows) == 0:
                continue
            ang = np.radians(self.lid_close_deg_[e]) * lids[q] * w[rows]
            if q >= 2:
                ang = -self.lid_lower_range_ * ang
            d[rows] += x_turn(Vc[rows] + d[rows] - self.lid_pivots_[e], ang)
        # bones: neck -> head -> {jaw, eyes}, linear blend skinning with the sharpened jaw weights
        # the jaw turns each vertex about its pivot by its weight times the angle (blending the
        # angle, not the positions: linear blending would pull half-weighted skin under the chin
        # toward the pivot, into the neck); then the head carries it
        W = self.jaw_weights_
        if jaw_deg:
            if "jaw" not in self.bones_:
                raise AutobonesError("jaw_deg: the rig has no 'jaw' bone")
            j = self.bones_.index("jaw")
            rows = np.flatnonzero(W[:, j] > 0)
            ang = np.radians(float(jaw_deg)) * W[rows, j]
            d[rows] += x_turn(Vc[rows] + d[rows] - self.pivots_[j], ang)
            # the condyle glides down and forward along the articular eminence as the jaw opens
            glide = self.jaw_glide_ * float(jaw_deg)
            if np.any(glide):
                d[rows] += W[rows, j, None] * glide[None, :]
        if unfold and (jaw_deg or np.any(lids)):
            d = self._unfold(d)
        R = self._bone_transforms(0.0, gaze, look_at, head_deg, neck_deg)
        if R:
            P = Vc + d
            for b, (Rb, tb) in R.items():
                w = W[:, b]
                rows = np.flatnonzero(w != 0)
                if len(rows):
                    d[rows] += w[rows, None] * (P[rows] @ (Rb - np.eye(3)).T + tb)
        return d

    def _bone_transforms(self, jaw_deg, gaze, look_at, head_deg, neck_deg):
        """World transforms (R, t) of the bones that move, canonical frame: x -> R x + t."""
        names, piv = self.bones_, self.pivots_
        moves = {}

        def local(name, R):
            c = piv[names.index(name)]
            return R, c - R @ c

        def need(name, what):
            if name not in names:
                raise AutobonesError(f"{what}: the rig has no {name!r} bone")

        world = {}
        base = (np.eye(3), np.zeros(3))
        if neck_deg is not None and np.any(np.asarray(neck_deg, dtype=float)):
            need("neck", "neck_deg")
            base = local("neck", _euler(neck_deg))
            world["neck"] = base
        if head_deg is not None and np.any(np.asarray(head_deg, dtype=float)):
            need("head", "head_deg")
            Rh, th = local("head", _euler(head_deg))
            base = (base[0] @ Rh, base[0] @ th + base[1])
        if "head" in names and (np.any(base[0] != np.eye(3)) or np.any(base[1])):
            world["head"] = base
        if jaw_deg:
            need("jaw", "jaw_deg")
            Rj, tj = local("jaw", _rot(0, jaw_deg))
            world["jaw"] = (base[0] @ Rj, base[0] @ tj + base[1])
        elif "jaw" in names and "head" in world:
            world["jaw"] = base
        for s in "lr":
            eye = f"eye_{s}"
            Re = None
            if look_at is not None:
                need(eye, "look_at")
                tgt = self.frame_.to_canonical(np.asarray(look_at, dtype=np.float64).reshape(1, 3))[0]
                # the target is given in the posed world: bring it into the head's rest frame
                tgt = base[0].T @ (tgt - base[1])
                dvec = tgt - piv[names.index(eye)]
                Re = _align(np.array([0.0, 0.0, 1.0]), dvec / max(np.linalg.norm(dvec), 1e-300))
            elif gaze is not None and np.any(np.asarray(gaze, dtype=float)):
                need(eye, "gaze")
                yaw, pitch = (list(np.ravel(gaze).astype(float)) + [0.0])[:2]
                Re = _rot(1, yaw) @ _rot(0, -pitch)
            if Re is not None:
                Rl, tl = local(eye, Re)
                world[eye] = (base[0] @ Rl, base[0] @ tl + base[1])
            elif eye in names and "head" in world:
                world[eye] = base
        for name, T in world.items():
            moves[names.index(name)] = T
        return moves


def flipped_faces(V0, V1, F, min_area=0.0):
    """Boolean (m,): triangles whose normal turned by more than 90 degrees from ``V0`` to ``V1``.

    ``V0``, ``V1`` (n, 3) rest and posed vertices, ``F`` (m, 3); triangles whose rest area is
    not above ``min_area`` (units of V0 squared; degenerate ones at the default 0) never count.
    """
    n0 = np.cross(V0[F[:, 1]] - V0[F[:, 0]], V0[F[:, 2]] - V0[F[:, 0]])
    return (0.5 * np.linalg.norm(n0, axis=1) > min_area) & _turned(V1, F, n0)


def _turned(P, F, n0):
    """(m,) bool: triangles ``F`` at positions ``P`` whose normal turned from the rest normals
    ``n0`` (m, 3) by over 90 degrees."""
    return (n0 * np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])).sum(axis=1) <= 0
