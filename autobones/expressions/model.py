"""Facial expressions on a transferred rig: the skin/muscle model of Bibliowicz 2005 (§4.2), FACS action units.

The deformation chain of Bibliowicz 2005 (Figure 4.21), rebuilt procedurally on any head from
what ``autobones.transfer`` carries onto it (muscle joints, the muscle influence fields, regions,
skeleton and skin weights, landmarks). :meth:`ExpressionModel.fit` builds one sub-model after the
other, each a pure function in its own module:

0. the skin surface (``surface.py``): the mesh welded for graph operations, the skin, normals,
   the Laplacian; the mouth line (``mouth.py``) that splits the lips.
1. muscles (``muscles.py``, ``wires.py``): every muscle joint pulls one wire that runs along the
   skin over the muscle; each wire control vertex is point-constrained to a weighted average of
   locators riding its own muscle (the force profile of Lee, Terzopoulos & Waters 1995 along
   it), the neighbouring muscles whose influence fields cover it, and a rest locator. The
   constraint weights do not depend on the contractions, so the skin displacement is a fixed
   linear map of the contraction vector: one (n, 3) basis field per muscle. The sphincters
   (``sphincters.py``: orbicularis oris and oculi, which Bibliowicz leaves out) have no wire: each
   draws the skin inside its ring toward the ring's centre (Waters 1987), linear too.
2. skull non-penetration (``skull.py``): a skin point may sink along its rest normal by at most
   the soft-tissue thickness of its region.
3. creases (``creases.py``): frontalis contractions press horizontal furrows into the forehead,
   corrugator ones vertical furrows between the brows.
4. eyelids (``lids.py``: four lid joints turning about the eye pivots; lashes and eye shells
   follow the lid skin they touch), the jaw (``jaw.py``: its weight sharpened across the mouth
   line, spread under the chin; ``mouth_parts.py``: teeth, gums and tongue ride the jaw below the
   occlusal plane and the skull above it), head, neck and eyes by linear blend skinning
   (``bones.py``).
5. unfolding (``unfold.py``, beyond the cited methods): skin triangles the lids or jaw turn over
   are relaxed, and what stays folded moves as one piece with the skin around it.

Stages 1 and 3 are linear in the contractions (``muscle_basis_``), stage 2 is a clamp that only
acts where the skin would sink into the skull, stage 4 is a rotation per vertex, stage 5 acts
only where triangles turn over: a fit can search the contraction vector, jaw angle and lid
amounts directly (:meth:`ExpressionModel.pose_parameters`), and for fixed jaw and lids the pose
is an affine map of the contractions away from the clamp and folds
(:meth:`ExpressionModel.linear_pose`).

What the model needs comes through ``transfer`` and is saved with the rig: the skeleton and skin
weights, the muscles (origins, insertions, ``width_canonical``), the landmarks (stomion,
cheilions, palpebrale points, exocanthions, menton; missing ones fall back to the muscles and
eye bones) and the region label names (all three read by :func:`rig_inputs.rig_inputs`),
``rig.fields`` (``muscle/<name>``, ``region``), ``rig.frame``. Fitting is deterministic.

Everything is computed in the head's canonical frame (+Y up, +Z front, +X the subject's left,
head sizes) and returned in the input frame and units. Lengths in ``generic_rig/expressions.json``
are in face units (fu = the exocanthion distance of that head), so the same numbers give each
head its own expression; :func:`definitions.model_parameters` resolves them.
"""
from __future__ import annotations

import numpy as np

from ..arguments import MAX_ANGLE, float_array, intensity_mixes, pose_angles, real
from ..errors import AutobonesError, counted
from ..geometry.mouth_parts import inner_mouth_parts, mouth_part_weights
from ..geometry.winding import outward_faces
from .bones import blend_bones, bone_transforms, turn_jaw, turn_lids
from .creases import crease_fields
from .definitions import load_expressions, model_parameters, muscle_types, parse_au_key
from .jaw import jaw_glide, jaw_weights
from .lids import (LIDS, attach_hinge_share, attach_lid_weights, lid_attachments, lid_hinges, lid_weights,
                   margin_release, ride_lids)
from .mouth import mouth_corners, mouth_line
from .muscles import check_muscle_kinds, influence_fields, muscles_from_rig
from .rig_inputs import rig_inputs
from .skull import REGIONS_DEFAULT, skull_clamp, slide_over_bone, tissue_thickness
from .sphincters import is_sphincter
from .surface import skin_surface
from .unfold import flipped_faces
from .unfold import unfold as unfold_folds
from .wires import muscle_basis

__all__ = ["ExpressionModel", "LIDS", "face_unit", "flipped_faces", "load_expressions"]


def face_unit(landmarks, eyes):
    """The face unit (head sizes): the exocanthion distance, else 1.48 times the eye pivots'.

    ``landmarks`` and ``eyes`` (side -> eye pivot) hold canonical (3,) points. Raises
    AutobonesError when neither is there.
    """
    if "exocanthion_l" in landmarks and "exocanthion_r" in landmarks:
        return float(np.linalg.norm(landmarks["exocanthion_l"] - landmarks["exocanthion_r"]))
    if len(eyes) == 2:
        return 1.48 * float(np.linalg.norm(eyes["l"] - eyes["r"]))
    raise AutobonesError("expressions: the rig has neither exocanthion landmarks nor both eye bones "
                         "to measure the face by")


class ExpressionModel:
    """The skin/muscle model of Bibliowicz 2005 with FACS action units, built on one transferred rig.

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
    lid_hinges_ : tuple
        Where the lids hinge on the line through the eye corners: points (2, 3), unit axes
        (2, 3), closing angles (2,) degrees, the hinge's share of each vertex's turn (n,), which
        lid joints hinge (4,) bool (:func:`lids.lid_hinges`).
    face_unit_ : float
        Exocanthion distance in head sizes.
    params_ : dict
        The resolved model parameters (:func:`definitions.model_parameters`).
    surface_ : SkinSurface
        The welded skin and its operators (:mod:`surface`).

    Example
    -------
    >>> model = ExpressionModel().fit(autobones.transfer("head.obj", landmarks="head.landmarks.json"))
    >>> V = model.pose(au={12: 0.8, 6: 0.4}, jaw_deg=10)
    """

    def __init__(self, definitions=None):
        self.definitions = definitions

    # ------------------------------------------------------------------------------ build
    def fit(self, rig):
        """Build the skin, wires, locators, constraints, creases, lids and jaw weights on ``rig``
        (a transferred :class:`autobones.rig.Rig`, or any object with its attributes)."""
        missing = [a for a in ("vertices", "faces", "frame", "skeleton", "weights") if not hasattr(rig, a)]
        if missing:  # rig=42: one line naming the argument, not an AttributeError inside
            raise AutobonesError(f"rig: expected an autobones Rig (autobones.transfer or load_rig), not "
                                 f"{type(rig).__name__} (it has no {missing[0]})")
        self.doc_ = load_expressions(self.definitions)
        p = self.params_ = model_parameters(self.doc_)
        types = muscle_types(self.doc_)
        inputs = rig_inputs(rig)
        frame = self.frame_ = rig.frame
        # head, neck and gaze angles are about the head's anatomical axes where the canonical frame leans
        axes = getattr(frame, "axes", None)
        self.turn_basis_ = None if axes is None else np.asarray(axes, dtype=np.float64) @ frame.rotation.T
        self.vertices_ = np.asarray(rig.vertices, dtype=np.float64)
        V = self.canonical_ = frame.to_canonical(self.vertices_)
        # the skull lies under the skin along its normals: a rig of a head written inside out keeps the
        # file's triangles (geometry.winding), so the model turns them outward for itself
        F = outward_faces(V, rig.faces)[0]
        names = self.bones_ = list(rig.skeleton.names)
        self.pivots_ = frame.to_canonical(rig.skeleton.heads)
        W = np.asarray(rig.weights, dtype=np.float64)
        mj = self.joints_ = muscles_from_rig(rig).transformed(frame.to_canonical, 1.0 / float(frame.size))
        for t in sorted(set(mj.types) & set(types)):
            if not is_sphincter(types[t]) and not {"wire", "dropoff"} <= set(types[t]):
                raise AutobonesError(f"expression definitions: muscle type {t!r} needs 'wire' and 'dropoff' "
                                     "(a linear muscle), or a 'sphincter' or 'sheet' entry")
        check_muscle_kinds(rig.muscles, types)
        self.muscle_names_ = list(mj.names)
        L = {kk: frame.to_canonical(np.asarray(v, dtype=np.float64).reshape(1, 3))[0]
             for kk, v in inputs.landmarks.items()}
        eyes = {s: self.pivots_[names.index(f"eye_{s}")] for s in "lr" if f"eye_{s}" in names}
        fu = self.face_unit_ = face_unit(L, eyes)
        eye_cols = [W[:, names.index(f"eye_{s}")] for s in "lr" if f"eye_{s}" in names]
        eye_w = sum(eye_cols, np.zeros(len(V)))

        surf = self.surface_ = skin_surface(V, F, eye_cols, p["skull_smoothing_passes"])
        skin = self.skin_ = surf.skin
        N = self.normals_ = surf.normals
        self.skull_normals_ = surf.skull_normals
        centre = self.pivots_[names.index("head")] if "head" in names else V.mean(axis=0)
        corners = mouth_corners(L, dict(zip(mj.names, mj.insertions)), V, skin, fu)
        mouth = mouth_line(V, N, skin, corners, centre, fu, p["lips"])
        self.mouth_ = {"zone": mouth.zone, "upper": mouth.upper, "signed": mouth.signed, "stomion": mouth.stomion,
                       "inward": mouth.inward}

        infl = influence_fields(rig.fields, mj.names, len(V))
        G, self.wires_ = muscle_basis(V, skin, mj, infl, types, mouth, fu, p, surf)
        self.shortening_ = np.array([float(types[t]["shortening"]) if t in types else 0.0 for t in mj.types])
        labels = self.region_labels_ = list(inputs.field_labels.get("region", REGIONS_DEFAULT))
        region = rig.fields.get("region")
        self.region_ = None if region is None else np.asarray(region).reshape(len(V)).astype(np.int64)
        self.thickness_ = tissue_thickness(rig.fields.get("region"), labels, p["skull"], fu, surf)
        self.clamp_ = skull_clamp(mouth)
        slide = np.array([t in types and bool(types[t]["slide"]) for t in mj.types], dtype=bool)
        G = slide_over_bone(G, slide, self.clamp_, self.thickness_, surf.skull_normals, p["slide_thickness"], fu)
        creases = crease_fields(V, N, skin, infl, mj.types, mj.insertions, mouth.stomion[0], fu, p["creases"])

        lid = p["eyelids"]
        with surf.sharing_factors():  # the lid weights and the hinges' share diffuse over the same time
            lw, self.lid_close_deg_, self.lid_pivots_ = lid_weights(V, F, skin, L, eyes, fu, lid, surf)
            hp, ha, hc, share, hinged = lid_hinges(V, skin, L, eyes, fu, lid, surf)
        self.lid_lower_range_ = float(lid["lower_range"])
        self.attached_, source, parts = lid_attachments(V, skin, surf.part, eye_w, lw.max(axis=0), fu,
                                                        lid["attached_part_size"])
        self.lid_weights_ = attach_lid_weights(lw, self.attached_, source, parts)
        self.lid_hinges_ = (hp, ha, hc, attach_hinge_share(share, lw, self.attached_, source, parts), hinged)
        self.muscle_basis_, self.crease_basis_ = ride_lids(G, creases, margin_release(lw, lid["margin_hold"]),
                                                           self.attached_, source)

        Wj = jaw_weights(W, names, V, skin, mouth, L.get("menton"), fu, p, surf)
        self.mouth_parts_ = np.zeros(0, dtype=np.int64)   # vertices of the mouth's inner parts
        if "jaw" in names:
            mp = p["mouth_parts"]
            found = inner_mouth_parts(V, surf.part, ~skin & ~self.attached_ & (eye_w < 0.5), mouth.stomion, fu,
                                      mp["reach"], mp["rigid_size"])
            Wj, self.mouth_parts_ = mouth_part_weights(
                Wj, names.index("jaw"), names.index("head") if "head" in names else None, V, found, mouth.stomion,
                self.pivots_[names.index("jaw")], fu, mp["band"], mp["pharynx"])
        self.jaw_weights_ = Wj
        self.jaw_glide_ = jaw_glide(p["jaw_glide"], fu)
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
        au, expression, muscles, eyelids = intensity_mixes(au, expression, muscles, eyelids)
        c = np.zeros(len(self.muscle_names_))
        lids = np.zeros(4)
        jaw = real(jaw_deg, "jaw_deg", -MAX_ANGLE / 2, MAX_ANGLE / 2)  # a jaw opens less than a right angle
        mix = {}
        if expression is not None:
            ex = {expression: 1.0} if isinstance(expression, str) else dict(expression)
            for name, a in ex.items():
                if name not in self.expressions:
                    raise AutobonesError(f"unknown expression {name!r}; known: {', '.join(self.expressions)}")
                for k_, v in self.expressions[name]["au"].items():
                    mix[str(k_)] = mix.get(str(k_), 0.0) + float(a) * float(v)
        for k_, v in (au or {}).items():
            key = parse_au_key(k_)[0]
            mix[key] = mix.get(key, 0.0) + float(v)
        for key, a in mix.items():
            _, key, side = parse_au_key(key)
            if key not in self.action_units:
                raise AutobonesError(f"unknown action unit {key!r}; defined: "
                                     f"{', '.join(sorted(self.action_units, key=int))}")
            if not np.isfinite(a):
                raise AutobonesError(f"action unit {key}: intensity {a} is not a finite number")
            d = self.action_units[key]
            for m, v in d.get("muscles", {}).items():
                if m not in self.joints_.names and m not in self.joints_.types and m in self.doc_["muscle_types"]:
                    continue   # a rig transferred before this muscle type joined the generic rig
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
        const, R = self._bone_frames(jaw_deg, eyelids)
        G = self.muscle_basis_.copy()
        for i, K in self.crease_basis_.items():
            G[i] += K
        A = np.einsum("nij,knj->kni", R, G)
        rot, size = self.frame_.rotation, self.frame_.size
        return (A * size) @ rot, self.vertices_ + (const * size) @ rot

    # ------------------------------------------------------------------------------ posing
    def pose(self, au=None, expression=None, muscles=None, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None,
             head_deg=None, neck_deg=None, tissue=False):
        """Posed vertices for AUs / an expression / muscle contractions plus bone controls.

        Parameters
        ----------
        au, expression, muscles, jaw_deg, eyelids
            See :meth:`parameters`.
        gaze : (yaw_deg, pitch_deg), optional
            Both eyes turned toward the subject's left (yaw > 0) and up (pitch > 0).
        look_at : (3,) float, optional
            A point in the input frame and units both eyes aim at (the aim control of Bibliowicz 2005;
            the eyes keep their rest divergence).
        head_deg, neck_deg : (pitch, yaw, roll) degrees, optional
            Rotations about the canonical +X (pitch > 0 nods down), +Y (yaw > 0 turns to
            the subject's left) and +Z axes at the head / neck pivots.
        tissue : bool
            Refine the skin by the layered tissue's equilibrium (:meth:`tissue`; Lee, Terzopoulos
            & Waters 1995): skin over shortening muscles bulges, the tissue keeps its volume and
            stays off the skull. The first such pose builds and factorises the tissue (about a
            second on a 27k-vertex head).

        Returns
        -------
        (n, 3) float
            Vertices in the input frame and units; exactly ``rig.vertices`` when every
            parameter is 0.
        """
        p = self.parameters(au=au, expression=expression, muscles=muscles, jaw_deg=jaw_deg, eyelids=eyelids)
        return self.pose_parameters(p["contractions"], jaw_deg=p["jaw_deg"], eyelids=p["eyelids"], gaze=gaze,
                                    look_at=look_at, head_deg=head_deg, neck_deg=neck_deg, tissue=tissue)

    def pose_parameters(self, contractions, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None, head_deg=None,
                        neck_deg=None, tissue=False):
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
        gaze, look_at, head_deg, neck_deg, tissue
            See :meth:`pose`.

        Returns
        -------
        (n, 3) float
            Vertices in the input frame and units.
        """
        self._check()
        gaze, look_at, head_deg, neck_deg = pose_angles(gaze, look_at, head_deg, neck_deg)
        c = float_array(np.reshape(contractions, -1) if np.ndim(contractions) else contractions, "contractions",
                        (None,))
        if c.shape != (len(self.muscle_names_),):
            raise AutobonesError(f"contractions: expected {counted(len(self.muscle_names_), 'value')}, got {c.shape}")
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
        bones = (jaw_deg, eyelids, gaze, look_at, head_deg, neck_deg)
        d = self._bones(d, *bones, unfold=True)
        if tissue and np.any(d):  # rest is its own equilibrium: left exact
            d = self._tissue_pass(d, bones)
        return self.vertices_ + (d * self.frame_.size) @ self.frame_.rotation

    def _bone_frames(self, *bones):
        """The bones' motion at every vertex for fixed bone parameters ``bones`` (as :meth:`_bones`
        takes them after ``d``): ``const`` (n, 3) and ``R`` (n, 3, 3), canonical, so that a rest
        vertex displaced by ``u`` goes to ``V + const + R @ u`` (no unfolding)."""
        n = len(self.canonical_)
        const = self._bones(np.zeros((n, 3)), *bones)
        R = np.stack([self._bones(np.tile(np.eye(3)[a], (n, 1)), *bones) - const for a in range(3)],
                     axis=2)                                             # (n, 3, 3): column a = image of e_a
        return const, R

    def tissue(self):
        """The layered tissue under this head's skin (:class:`~autobones.expressions.tissue.TissueModel`),
        built and factorised on first use, then reused by every pose with ``tissue=True``."""
        self._check()
        if getattr(self, "tissue_", None) is None:
            from .tissue import TissueModel

            self.tissue_ = TissueModel().fit(self)
        return self.tissue_

    def _tissue_pass(self, d, bones):
        """Canonical displacement ``d`` (n, 3) after the tissue's equilibrium under it
        (:meth:`tissue`); ``bones`` the bone parameters as :meth:`_bones` takes them."""
        tissue = self.tissue()
        surf = self.surface_
        const, R = self._bone_frames(*bones)
        first = surf.first
        wire = (self.canonical_ + d)[first]
        skin, self.tissue_info_ = tissue.refine(wire, const[first], R[first])
        moved = self.skin_ & np.any(skin != wire, axis=1)[surf.index]
        d = d.copy()
        d[moved] = skin[surf.index[moved]] - self.canonical_[moved]
        return d

    def _bones(self, d, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None, head_deg=None, neck_deg=None,
               unfold=False):
        """Stage 4 on the canonical (n, 3) muscle-stage displacement ``d``: the lids, jaw, head,
        neck and eyes (:mod:`bones`). Returns the canonical displacement (n, 3), head sizes. For
        fixed bone parameters and ``unfold`` False it is affine in ``d`` per vertex (a rotation
        plus a translation); ``unfold`` relaxes skin the lids and jaw fold over (:mod:`unfold`)."""
        V = self.canonical_
        lids = np.zeros(4) if eyelids is None else np.asarray(eyelids, dtype=np.float64).reshape(4)
        d = turn_lids(d, V, lids, self.lid_weights_, self.lid_close_deg_, self.lid_lower_range_, self.lid_pivots_,
                      getattr(self, "lid_hinges_", None))
        if jaw_deg:
            if "jaw" not in self.bones_:
                raise AutobonesError("jaw_deg: the rig has no 'jaw' bone")
            j = self.bones_.index("jaw")
            d = turn_jaw(d, V, jaw_deg, self.jaw_weights_[:, j], self.pivots_[j], self.jaw_glide_)
        if unfold and (jaw_deg or np.any(lids)):
            d = unfold_folds(d, V, self.surface_, float(self.params_["unfold_reach"]) * self.face_unit_)
        if look_at is not None:
            look_at = self.frame_.to_canonical(np.asarray(look_at, dtype=np.float64).reshape(1, 3))[0]
        moves = bone_transforms(self.bones_, self.pivots_, 0.0, gaze, look_at, head_deg, neck_deg,
                                basis=self.turn_basis_)
        return blend_bones(d, V, self.jaw_weights_, moves)
