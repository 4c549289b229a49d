"""Build a labelled rig (skeleton, skin weights, regions, muscles) on any landmarked head.

Orvalho, Zacur & Susin 2008, §2 describe the generic rig's layers (skin, 44 landmarks, skeleton,
muscles, attributes) but not how they were made: an artist modelled them. Here
every layer is a rule on the contract landmarks (``spec/landmarks.md``), so the
same definitions work on the default head and on any other landmarked head.
Muscles follow Lee, Terzopoulos & Waters 1995, §5 (linear muscles with width and
falloff) and Bibliowicz 2005, §4.2 (a joint from an origin under the skin to an
insertion on the skin); a sphincter (``kind`` "sphincter") is an elliptical ring on the skin
after Waters 1987 (centre and lateral point; :mod:`autobones.geometry.ring`), and a sheet (``kind``
"sheet", mentalis) an elliptical patch given the same way.

Everything is computed in the head's canonical frame (:func:`autobones.orient.detect_frame`:
+Y up, +Z front, +X subject's left, head sizes) and returned in the input frame
and units. Distances in the rules are in centimetres of an adult face, measured
with the face unit ``fu`` = distance between the outer eye corners (ex-ex,
about 9.3 cm): ``CM = fu / 9.3``.

Skeleton (parents neck -> head -> {jaw, eye_l, eye_r})
    head  pivot at the occiput-C1 centre of rotation: 22.5 mm posterior and 22.6 mm
          inferior of the tragions' midpoint (the ear canals'; Chancey, Ottaviano, Myers &
          Nightingale 2007), on the midline, scaled by ex-ex / 90 mm; tail 85% of the way
          to the vertex.
    neck  from a neck-slice centroid (half the pivot-menton height below the menton,
          kept above the mesh bottom) up to the head pivot.
    jaw   pivot at the condyles: 12 mm anterior of the tragions' midpoint at its height
          (the condyle sits 10-15 mm in front of the ear canal), scaled the same way, on the
          midline; tail 85% of the way to the chin (mean of pogonion and menton).
    eye_s centre = midpoint of exocanthion and endocanthion pushed 1.15 cm back (an
          eyeball radius); tail 0.8 cm in front of it.
    Every joint is pulled toward the head's inside if its generalized winding number
    is below 1/2.

Skin weights (``weights``, also the field ``skin_weights``)
    jaw   product of three smooth steps: below the mouth plane (stomion, gonion_l,
          gonion_r; 0.8 cm wide, centred 0.5 mm below it), and (1 cm wide) above the jaw-line plane (menton, gonions) lowered by
          0.6 cm (so the menton and the skin under the chin are in), and in front of
          the ramus plane (jaw pivot, gonions); then heat-diffused over the surface
          (time (0.25 cm)^2) so the transition is smooth.
    eyes  1 on mesh components that are eyeballs (a separate small component whose
          centroid is within 1.5 cm of an eye centre); skin-only heads have closed
          lids on the default head, so the eye bones rotate eyeballs only and eye
          weights are 0 on the skin.
    head/neck  the rest (1 - jaw - eye) split at the neck plane (through 0.8 cm under the menton
               and the skull base behind), smoothly over 3 cm, then diffused.

Regions (field ``region``, classes in :data:`REGIONS`), first rule that holds wins
    ears     within an ellipse in the side (y, z) plane: height 1.24 ear lengths (superaurale-
             subaurale), depth 0.72 ear lengths, centred 0.32 ear lengths behind the tragion
             at mid-ear height; and lateral (|x| > 0.85 |x_tragion|)
    lips     within an ellipse centred at the stomion: half-width |x_cheilion| + 0.3 cm,
             from 0.2 cm below labiale inferius to 0.2 cm above labiale superius; front
    nose     y from subnasale - 0.15 cm to nasion, |x| below a width going from
             alare + 0.3 cm at the nose base to 0.6 endocanthion at the nasion; front
    eyelids  ellipse around each eye: corners + 0.4 cm, palpebrale +- 0.7 cm
    brow     band from the eyelid top to 1 cm above the highest brow point, out to
             brow_outer + 0.6 cm; front
    forehead above the brow band up to 3 cm above frontotemporale, |x| < ft + 1 cm; front
    chin     jaw weight > 1/2 and |x| < 0.9 |x_cheilion|, below the lips
    jaw      jaw weight > 1/2, or within 1.5 cm of a gonion (the jaw angle lies on the
             jaw weight's border planes)
    cheeks   in front of the ears (z > tragion + 0.3 cm), between the mouth/jaw and the eyes
    neck     below the neck plane (0.8 cm under the menton to the skull base behind)
    scalp    everything else
``depth_group``: face / middle / back of :func:`autobones.placement.segment.segment_head`.
``face_half``: upper / lower of the mouth plane (stomion, gonions).

Muscles: see ``generic_rig/muscles.json`` (``units`` there): origin and
insertion are landmark combinations, insertion snapped to the skin, origin
snapped then pushed inward by its depth; field ``muscle/<name>`` is Lee et al.'s force
profile: sin(pi/2 e^kappa) along the muscle (fading out within 25% past the
insertion) times 0.5 (cos(pi (w / width)^falloff) + 1) across it.
"""
from __future__ import annotations

import logging
import os

import numpy as np

from ..errors import AutobonesError, counted
from ..io.files import read_json
from ..geometry.laplacian import diffuse, laplacian
from ..geometry.ring import RING_KINDS, ring_frame, ring_profile
from ..geometry.smooth import step
from ..geometry.topology import mesh_parts
from ..skeleton import Skeleton
from ..labelled_rig import LabelledRig
from .anatomy import anatomical_joints

log = logging.getLogger(__name__)


BONES = ("neck", "head", "jaw", "eye_l", "eye_r")
REGIONS = ("scalp", "forehead", "brow", "eyelids", "nose", "cheeks", "lips", "chin", "jaw", "ears", "neck")
DEPTH_GROUPS = ("face", "middle", "back")
FACE_HALVES = ("upper", "lower")

#: Landmarks the skeleton, weights and regions need.
SKELETON_NAMES = (
    "vertex", "opisthocranion", "nasion", "subnasale", "labiale_superius", "stomion",
    "labiale_inferius", "pogonion", "menton",
    "exocanthion_l", "exocanthion_r", "endocanthion_l", "endocanthion_r",
    "palpebrale_superius_l", "palpebrale_superius_r", "palpebrale_inferius_l", "palpebrale_inferius_r",
    "brow_inner_l", "brow_inner_r", "brow_middle_l", "brow_middle_r", "brow_outer_l", "brow_outer_r",
    "alare_l", "alare_r", "cheilion_l", "cheilion_r", "gonion_l", "gonion_r",
    "tragion_l", "tragion_r", "superaurale_l", "superaurale_r", "subaurale_l", "subaurale_r",
    "frontotemporale_l", "frontotemporale_r",
)
ADULT_EX_EX_CM = 9.3


def load_muscle_definitions(path=None):
    """The muscle list of a muscles JSON file (default: ``generic_rig/muscles.json``)."""
    if path is None:
        from ..generic_rig import muscles_path

        path = muscles_path()
    path = os.fspath(path)
    try:
        doc = read_json(path, "rig", "muscle definitions")
        return list(doc["muscles"])
    except AutobonesError:  # read_json's own message, naming the file
        raise
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise AutobonesError(f"{path}: cannot read the muscle definitions ({exc})") from None


def required_landmarks(muscles=None):
    """Sorted names build_rig needs for the skeleton, regions and the given muscle definitions."""
    if muscles is None:
        muscles = load_muscle_definitions()
    names = set(SKELETON_NAMES)
    for m in muscles:
        names.update(m["origin"])
        names.update(m["insertion"])
    return sorted(names)


# ---------------------------------------------------------------------------------------------


def build_rig(V, F, landmarks, muscles=None, frame=None):
    """Build the labelled rig of a head from its landmarks.

    Parameters
    ----------
    V : (n, 3) float
        Skin vertices in the mesh's own frame and units (any axes, any unit).
    F : (m, 3) int
        Triangles; a closed head works best (joints are kept inside by winding number).
    landmarks : mapping str -> (3,) float
        Contract landmarks in the same frame; every name of :func:`required_landmarks`
        must be present.
    muscles : list of dict, str path, or None
        Muscle definitions (the ``muscles`` list of ``generic_rig/muscles.json``, or a
        path to such a file); default the generic rig's.
    frame : autobones.orient.Frame or None
        The head's canonical frame; detected when None.

    Returns
    -------
    LabelledRig
        In the input frame and units; fields ``skin_weights``, ``jaw_weight``, ``region``,
        ``depth_group``, ``face_half`` and ``muscle/<name>``.
    """
    import igl

    from ..io.mesh import check_mesh
    from ..orient import detect_frame

    V, F = check_mesh(np.asarray(V, dtype=np.float64), np.asarray(F), name="build_rig mesh")
    if muscles is None or isinstance(muscles, (str, os.PathLike)):
        muscles = load_muscle_definitions(muscles)
    need = required_landmarks(muscles)
    missing = [k for k in need if k not in landmarks]
    if missing:
        raise AutobonesError(
            f"build_rig: {counted(len(missing), 'landmark')} missing: {', '.join(missing)}; the skeleton, "
            f"regions and muscles need {counted(len(need), 'contract name')} (autobones.rig_building.build.required_landmarks())")
    if frame is None:
        frame = detect_frame(V, F)
    Vc = frame.to_canonical(V)
    L = {k: frame.to_canonical(np.asarray(v, dtype=np.float64).reshape(1, 3))[0] for k, v in landmarks.items()}
    _check_sides(L)
    fu = float(np.linalg.norm(L["exocanthion_l"] - L["exocanthion_r"]))
    cm = fu / ADULT_EX_EX_CM
    Fi = np.ascontiguousarray(F, dtype=np.int64)
    Vq = np.ascontiguousarray(Vc)

    def wn(P):
        return igl.fast_winding_number(Vq, Fi, np.ascontiguousarray(np.atleast_2d(P), dtype=np.float64))

    skel_c, jaw0, eyes = _skeleton(Vc, L, cm, wn)
    W, jaw, below_mouth = _skin_weights(Vc, F, L, cm, jaw0, eyes)

    # --- regions -----------------------------------------------------------------------------
    from ..placement.segment import segment_head

    region = _regions(Vc, L, cm, jaw, below_mouth, jaw0)
    seg = segment_head(Vc, F)
    face_half = (below_mouth > 0).astype(np.int8)

    fields = {"skin_weights": W, "jaw_weight": jaw, "region": region,
              "depth_group": seg.labels.astype(np.int8), "face_half": face_half}
    out_muscles = _place_muscles(muscles, L, Vc, F, fu, cm, wn, frame, fields)

    skel = skel_c.transformed(frame.from_canonical)
    return LabelledRig(
        vertices=V, faces=F, landmarks={k: np.asarray(v, dtype=np.float64) for k, v in landmarks.items()},
        skeleton=skel, weights=W, fields=fields,
        labels={"region": list(REGIONS), "depth_group": list(DEPTH_GROUPS), "face_half": list(FACE_HALVES)},
        muscles=out_muscles,
        units="input mesh units",
        frame="input mesh frame; canonical frame (+Y up, +Z front, +X subject's left, head sizes) in info",
        info={"canonical_frame": frame.to_dict(), "face_unit": fu * frame.size,
              "bones": "neck -> head -> {jaw, eye_l, eye_r}; eye bones rotate eyeballs only",
              "seeds": "004 §2 (layers), 001 §5 (muscles), 000 §4.2 (muscle joints)"})


# ---------------------------------------------------------------------------------------------
# helpers (canonical frame)


def _skeleton(Vc, L, cm, wn):
    """Canonical-frame skeleton (module doc): (Skeleton, jaw pivot (3,), {side: (eye centre, eye tail)})."""
    # --- skeleton --------------------------------------------------------------------------
    head0, jaw0 = anatomical_joints(L)
    head1 = head0 + 0.85 * (L["vertex"] - head0)
    head1[0] = 0.0
    chin = 0.5 * (L["pogonion"] + L["menton"])
    jaw1 = jaw0 + 0.85 * (chin - jaw0)
    bottom = Vc[:, 1].min()
    y_root = max(L["menton"][1] - 0.5 * (head0[1] - L["menton"][1]), bottom + 1.0 * cm)
    ring = np.abs(Vc[:, 1] - y_root) < 1.0 * cm
    neck0 = np.array([0.0, y_root, Vc[ring, 2].mean() if ring.any() else head0[2]])
    eyes = {}
    for s in ("l", "r"):
        c = 0.5 * (L[f"exocanthion_{s}"] + L[f"endocanthion_{s}"]) - np.array([0.0, 0.0, 1.15 * cm])
        eyes[s] = (c, c + np.array([0.0, 0.0, 0.8 * cm]))
    centre = 0.5 * (head0 + head1)
    joints = {"head0": head0, "head1": head1, "jaw0": jaw0, "jaw1": jaw1, "neck0": neck0}
    for k in joints:
        joints[k] = _pull_inside(wn, joints[k], centre)
    heads = np.array([joints["neck0"], joints["head0"], joints["jaw0"], eyes["l"][0], eyes["r"][0]])
    tails = np.array([joints["head0"], joints["head1"], joints["jaw1"], eyes["l"][1], eyes["r"][1]])
    skel_c = Skeleton(list(BONES), [-1, 0, 1, 1, 1], heads, tails)
    return skel_c, jaw0, eyes


def _skin_weights(Vc, F, L, cm, jaw0, eyes):
    """Skin weights (n, 5) in :data:`BONES` order (module doc), the jaw weight (n,) and the signed
    distance below the mouth plane (n,), canonical frame."""
    # --- jaw weight --------------------------------------------------------------------------
    go_l, go_r = L["gonion_l"], L["gonion_r"]
    up_n = _plane_normal(L["stomion"], go_l, go_r, toward=np.array([0.0, -1.0, 0.0]))
    low_n = _plane_normal(L["menton"], go_l, go_r, toward=np.array([0.0, 1.0, 0.0]))
    ramus_n = _plane_normal(jaw0, go_l, go_r, toward=np.array([0.0, 0.0, 1.0]))
    below_mouth = (Vc - L["stomion"]) @ up_n
    above_jawline = (Vc - L["menton"]) @ low_n
    front_of_ramus = (Vc - jaw0) @ ramus_n
    raw = (step(below_mouth, 0.05 * cm, 0.8 * cm) * step(above_jawline, -0.6 * cm, cm)
           * step(front_of_ramus, 0.0, cm))
    lap = laplacian(Vc, F)
    jaw = np.clip(diffuse(raw, *lap, t=(0.25 * cm) ** 2), 0.0, 1.0)

    # --- eyes: separate eyeball components ---------------------------------------------------
    comp = mesh_parts(len(Vc), F)
    eye_w = {s: np.zeros(len(Vc)) for s in ("l", "r")}
    main = np.bincount(comp).argmax()
    for c in np.unique(comp):
        if c == main:
            continue
        idx = comp == c
        cen = Vc[idx].mean(axis=0)
        for s in ("l", "r"):
            if np.linalg.norm(cen - eyes[s][0]) < 1.5 * cm:
                eye_w[s][idx] = 1.0
    eye_any = eye_w["l"] + eye_w["r"]
    jaw = jaw * (1.0 - eye_any)

    # neck: the skin below the neck plane, fading over 3 cm across it (bone heat alone gave the
    # face to the neck bone, whose top sits nearer the lips than the head bone does)
    neck_w = np.clip(diffuse(step(-_above_neck_plane(Vc, L, cm), 0.0, 3.0 * cm), *lap, t=(0.5 * cm) ** 2), 0.0, 1.0)
    rest = 1.0 - jaw - eye_any
    W = np.column_stack([neck_w * rest, (1.0 - neck_w) * rest, jaw, eye_w["l"], eye_w["r"]])
    W = np.clip(W, 0.0, None)
    W /= W.sum(axis=1, keepdims=True)
    return W, jaw, below_mouth


def _place_muscles(muscles, L, Vc, F, fu, cm, wn, frame, fields):
    """Muscles of the definitions on the head, in the input frame (``width`` in mesh units);
    adds each one's influence (n,) to ``fields`` as ``muscle/<name>``."""
    out_muscles = []
    for m in muscles:
        mm, infl = _muscle(m, L, Vc, F, fu, cm, wn)
        fields["muscle/" + m["name"]] = infl
        mm["origin"] = frame.from_canonical(mm["origin"][None])[0]
        mm["insertion"] = frame.from_canonical(mm["insertion"][None])[0]
        mm["width"] = mm["width_canonical"] * frame.size
        mm["origin_depth_length"] = mm["origin_depth_canonical"] * frame.size
        out_muscles.append(mm)
    return out_muscles


def _check_sides(L):
    bad = [f"{b}_l/_r" for b in ("exocanthion", "tragion", "gonion", "cheilion")
           if not L[f"{b}_l"][0] > L[f"{b}_r"][0]]
    if bad:
        raise AutobonesError(f"build_rig: left and right landmarks look swapped ({', '.join(bad)}): "
                             f"_l is the subject's own left, on the viewer's right in a frontal picture")


def _pull_inside(wn, p, anchor, steps=20):
    if wn(p)[0] > 0.5:
        return p
    t = np.linspace(1.0, 0.0, steps + 1)
    Q = anchor + t[:, None] * (p - anchor)
    ok = np.flatnonzero(wn(Q) > 0.5)
    return Q[ok[0]] if len(ok) else p


def _above_neck_plane(Vc, L, cm):
    """Signed distance (canonical units) above the neck plane: the plane containing the x axis
    through 0.8 cm under the menton and the skull base behind (opisthocranion depth, 2 cm under
    the tragions)."""
    tr = 0.5 * (L["tragion_l"] + L["tragion_r"])
    a = L["menton"] + np.array([0.0, -0.8 * cm, 0.0])
    b = np.array([0.0, tr[1] - 2.0 * cm, L["opisthocranion"][2]])
    d = b - a
    nrm = np.array([0.0, d[2], -d[1]])
    nrm = (nrm if nrm[1] > 0 else -nrm) / np.linalg.norm(nrm)
    return (Vc - a) @ nrm


def _plane_normal(a, b, c, toward):
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    return n if n @ toward >= 0 else -n


def _regions(Vc, L, cm, jaw, below_mouth, jaw0):
    R = {name: i for i, name in enumerate(REGIONS)}
    x, y, z = Vc[:, 0], Vc[:, 1], Vc[:, 2]
    ax = np.abs(x)
    lab = np.full(len(Vc), -1, dtype=np.int8)

    def put(mask, name):
        m = mask & (lab < 0)
        lab[m] = R[name]

    sym = lambda b: 0.5 * (np.abs(L[f"{b}_l"]) + np.abs(L[f"{b}_r"]))  # noqa: E731  |x|, y, z
    tr, sa, sba = sym("tragion"), sym("superaurale"), sym("subaurale")
    ex, en, ch, al = sym("exocanthion"), sym("endocanthion"), sym("cheilion"), sym("alare")
    ps, pi = sym("palpebrale_superius"), sym("palpebrale_inferius")
    bo, ft = sym("brow_outer"), sym("frontotemporale")
    brow_top = max(sym("brow_inner")[1], sym("brow_middle")[1], bo[1]) + 1.0 * cm
    face_front = z > tr[2] + 0.3 * cm
    # ears: ellipse in the side plane behind the tragion: height 1.24 ear lengths (sa-sba),
    # depth 0.72 ear lengths, centred 0.32 ear lengths behind the tragion
    ear_len = np.linalg.norm(sa[1:] - sba[1:])
    ec = np.array([0.5 * (sa[1] + sba[1]), tr[2] - 0.32 * ear_len])
    ear = (((y - ec[0]) / (0.62 * ear_len)) ** 2 + ((z - ec[1]) / (0.36 * ear_len)) ** 2 < 1) & (ax > 0.85 * tr[0])
    put(ear, "ears")
    # lips
    sto = L["stomion"]
    hw = ch[0] + 0.3 * cm
    top = L["labiale_superius"][1] + 0.2 * cm - sto[1]
    bot = sto[1] - (L["labiale_inferius"][1] - 0.2 * cm)
    v = np.where(y >= sto[1], (y - sto[1]) / top, (sto[1] - y) / bot)
    put(((x / hw) ** 2 + v ** 2 < 1) & (z > ch[2] - 1.0 * cm), "lips")
    # nose
    sn, na = L["subnasale"], L["nasion"]
    f = np.clip((y - sn[1]) / max(na[1] - sn[1], 1e-9), 0, 1)
    nose_w = (al[0] + 0.3 * cm) * (1 - f) + 0.6 * en[0] * f
    put((y > sn[1] - 0.15 * cm) & (y < na[1]) & (ax < nose_w) & (z > en[2] - 0.5 * cm), "nose")
    # eyelids
    ecx, ecy = 0.5 * (ex[0] + en[0]), 0.5 * (ps[1] + pi[1])
    ehw = 0.5 * (ex[0] - en[0]) + 0.4 * cm
    eht = ps[1] + 0.7 * cm - ecy
    ehb = ecy - (pi[1] - 0.7 * cm)
    ev = np.where(y >= ecy, (y - ecy) / eht, (ecy - y) / ehb)
    put((((ax - ecx) / ehw) ** 2 + ev ** 2 < 1) & (z > ex[2] - 1.0 * cm), "eyelids")
    # brow band and forehead
    lid_top = ps[1] + 0.7 * cm
    put((y >= min(lid_top, sym("brow_inner")[1] - 0.5 * cm)) & (y < brow_top) & (ax < bo[0] + 0.6 * cm)
        & face_front, "brow")
    put((y >= brow_top) & (y < ft[1] + 3.0 * cm) & (ax < ft[0] + 1.0 * cm) & (z > ft[2] - 1.0 * cm), "forehead")
    # chin and jaw
    put((jaw > 0.5) & (ax < 0.9 * ch[0]) & (y < L["labiale_inferius"][1]), "chin")
    # the jaw angle sits on the border planes of the jaw weight (they pass through the gonions):
    # skin within 1.5 cm of a gonion is jaw too
    near_go = np.minimum(np.linalg.norm(Vc - L["gonion_l"], axis=1), np.linalg.norm(Vc - L["gonion_r"], axis=1))
    put((jaw > 0.5) | ((near_go < 1.5 * cm) & (below_mouth > -0.5 * cm)), "jaw")
    # neck: below the plane (containing the x axis) through 0.8 cm under the menton and the
    # skull base behind (opisthocranion depth, 2 cm under the tragions)
    neck = _above_neck_plane(Vc, L, cm) < 0
    # cheeks: face in front of the ears between the jaw/mouth and the eyes
    put(face_front & (y < lid_top) & (y > L["menton"][1]) & ~neck, "cheeks")
    put(neck, "neck")
    put(np.ones(len(Vc), bool), "scalp")
    return lab


def _combo(weights, L, what):
    w = np.array(list(weights.values()), dtype=np.float64)
    if abs(w.sum() - 1.0) > 1e-6:
        raise AutobonesError(f"muscle definition: {what} weights sum to {w.sum():g}, not 1 "
                             f"(an affine combination of landmarks)")
    return sum(float(c) * L[k] for k, c in weights.items())


def _muscle(m, L, Vc, F, fu, cm, wn):
    import igl

    Fi = np.ascontiguousarray(F, dtype=np.int64)
    o0 = _combo(m["origin"], L, f"{m['name']} origin")
    i0 = _combo(m["insertion"], L, f"{m['name']} insertion")
    _, fid, C = igl.point_mesh_squared_distance(np.array([o0, i0]), np.ascontiguousarray(Vc), Fi)
    o_skin, ins = C[0], C[1]
    if m.get("kind") in RING_KINDS:
        return _ring(m, o_skin, ins, Vc)
    tri = Vc[F[fid[0]]]
    n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    n /= max(np.linalg.norm(n), 1e-300)
    depth = float(m.get("origin_depth", 0.1)) * fu
    rule = m.get("origin_rule", "normal")
    if rule == "scale_to_centre":
        centre = 0.5 * (0.5 * (L["tragion_l"] + L["tragion_r"]) + 0.5 * (L["vertex"] + L["menton"]))
        origin = centre + float(m.get("scale", 0.95)) * (o_skin - centre)
    else:
        cand = [o_skin - depth * n, o_skin + depth * n]
        w = wn(np.array(cand))
        origin = cand[int(np.argmax(w))]
    # influence: Lee, Terzopoulos & Waters 1995's length and width ratios
    axis = ins - origin
    length = np.linalg.norm(axis)
    u = axis / length
    p = (Vc - origin) @ u
    e = p / length
    perp = np.linalg.norm(Vc - origin - p[:, None] * u, axis=1)
    width = float(m["width"]) * fu
    kappa = float(m.get("length_exponent", 0.48))
    ec = np.clip(e, 0.0, 1.0)
    along = np.where(e < 0, 0.0, np.sin(0.5 * np.pi * ec ** kappa))
    past = np.clip((e - 1.0) / 0.25, 0.0, 1.0)
    along = np.where(e > 1.0, np.cos(0.5 * np.pi * past), along)
    r = np.clip(perp / width, 0.0, 1.0)
    across = np.where(perp < width, 0.5 * (np.cos(np.pi * r ** float(m.get("falloff", 1.8))) + 1.0), 0.0)
    infl = np.clip(along * across, 0.0, 1.0)
    return _placed(m, origin, ins, width, depth, bool(wn(origin)[0] > 0.5)), infl.astype(np.float64)


def _ring(m, centre, lateral, Vc):
    """A sphincter or sheet muscle (``kind`` "sphincter" / "sheet"): origin = the ellipse's centre on
    the skin, insertion = its lateral point on the skin; influence = the ellipse's profile
    (:func:`ring_profile`)."""
    axes, half = ring_frame(centre, lateral)
    hole = m.get("hole")
    try:
        _, infl = ring_profile(Vc, centre, axes, half, m["reach"], core=float(m.get("core", 0.3)),
                               hole=None if hole is None else (float(hole[0]), float(hole[1])),
                               split=m.get("split"), depth=float(m.get("depth", 0.6)))
    except AutobonesError as exc:
        raise AutobonesError(f"muscle definition {m['name']}: {exc}") from None
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise AutobonesError(f"muscle definition {m['name']}: incomplete {m.get('kind')} ({exc!r})") from None
    return _placed(m, centre, lateral, half, 0.0, False), infl


def _placed(m, origin, insertion, width, depth, inside):
    """The muscle definition ``m`` as placed on a head: its other keys, the landmark combinations
    it was placed by, and the canonical ``origin``, ``insertion``, ``width_canonical``,
    ``origin_depth_canonical`` and ``inside`` (its origin inside the head)."""
    out = {k: v for k, v in m.items() if k not in ("origin", "insertion")}
    out.update({"origin_definition": dict(m["origin"]), "insertion_definition": dict(m["insertion"]),
                "origin": origin, "insertion": insertion, "width_canonical": width,
                "origin_depth_canonical": depth, "inside": inside})
    return out
