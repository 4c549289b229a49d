"""The copies of a head and the checks of ``benchmarks/zoo.py`` (issue #31): measures that need no ground truth.

Each ``check_*`` function takes a rig (or two) and the head's reference geometry and returns a
:class:`Result`: ``ok``, ``fail`` with the failing figure (``"up 47°"``, ``"chin 0.01"``), ``na``
with the reason, or (set by the harness) ``error`` / ``refused``. Figures are in the units the issue
states them in: degrees, jaw weight, share of the peak motion, ex-ex (exocanthion distance) units.
"""
from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from autobones.arkit.folds import ON_TOP, folded_triangles
from autobones.arkit.lids import eye_sides, gap_closure
from autobones.geometry.closest import closest_points
from autobones.geometry.topology import used_vertices, weld_by_size
from autobones.io.landmark_names import mirror_name
from autobones.rig_transfer.jaw import MAX_JUMP, face_unit, lip_line_edges

ROOT = Path(__file__).resolve().parents[1]
VALIDATOR_DIR = ROOT / "tools" / "gltf-validator"

ROTATIONS = 6              # random rotations (scipy, seed 31)
REMESH_OFF = 0.02          # head sizes: a subdivided vertex further off the surface left it (remesh)
FRAME_DEG = 30.0           # check 1: front / up within this of the landmarks'
DRIFT = 1e-6               # check 1: frame of a rotated / scaled copy vs the as-is one (rotation entries)
JAW_ON, JAW_OFF = 0.9, 0.1  # check 2
TURN_DEG, BASE_SHARE, BASE_MAX = 15.0, 0.05, 0.01  # check 3
MIDLINE, C1_MAX = 0.02, 0.15  # check 4 (ex-ex units)
C1_MM = (22.5, 22.6)       # occiput-C1 centre: posterior, inferior of the tragions' midpoint (Chancey 2007)
EXEX_MM = 90.0
SUM_TOL = 1e-6             # check 5
CORR_MAX = 0.01            # check 6: p95 of the displacement, ex-ex units
BLINK_MIN = 0.9            # check 7

JAW_PROBES = (("pogonion", "chin", True), ("menton", "chin", True), ("labiale_inferius", "lip", True),
              ("pronasale", "nose", False), ("nasion", "nasion", False), ("vertex", "vertex", False))


# ------------------------------------------------------------------------------------- copies of a head
@dataclass
class Variant:
    name: str
    V: np.ndarray
    F: np.ndarray
    lm: dict = None            # what transfer is given (jittered / snapped), variant frame
    truth: dict = None         # the head's landmarks in the variant's frame (what checks measure against)
    R: np.ndarray = field(default_factory=lambda: np.eye(3))   # x' = s R x
    s: float = 1.0
    core: np.ndarray = None    # the head's own vertices (not the stray triangle)
    snap: bool = False         # remeshed: mapped back by closest point

    def back(self, P):
        return np.asarray(P) @ self.R / self.s


def rotations():
    from scipy.spatial.transform import Rotation

    return Rotation.random(ROTATIONS, random_state=31).as_matrix()


def remesh(V, F):
    """Another tessellation of the same surface: one Loop subdivision (libigl), then quadric decimation
    back to ``len(F)`` triangles. Welded by position first where that leaves every edge on at most two
    triangles (Loop's boundary rule shrank the robot's unwelded faces apart, and the copy had cracks its
    head has not; welded, ICT's parts touch along 108 edges, on which libigl's Loop crashes). Where the
    mesh is not manifold, or Loop's stencils leave the surface (a vertex more than ``REMESH_OFF`` head
    sizes off it: trimesh's Loop, used until 2026-12-07, threw the SMPL woman's, the ogre's, the beast's,
    the falcon's, James' and the robot's 0.2-0.5), a midpoint subdivision instead."""
    import fast_simplification
    import igl
    import trimesh

    V, F = np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)
    Vw, Fw = compact(*weld_by_size(V, F)[:2])
    manifold = igl.is_edge_manifold(Fw)[0]   # no edge on more than two triangles
    if manifold:
        V, F = Vw, Fw
    else:
        manifold = igl.is_edge_manifold(F)[0]
    size = float(np.ptp(V[used_vertices(F, len(V))], axis=0).max())
    Vs = Fs = None
    if manifold:
        Vs, Fs = igl.loop(V, F)
        if np.linalg.norm(Vs - closest_points(Vs, V, F)[0], axis=1).max() > REMESH_OFF * size:
            Vs = Fs = None
    if Vs is None:
        Vs, Fs = trimesh.remesh.subdivide(V, F)
    return compact(*fast_simplification.simplify(Vs, Fs, target_count=len(F)))


def compact(V, F):
    keep = np.unique(F)
    remap = -np.ones(len(V), dtype=np.int64)
    remap[keep] = np.arange(len(keep))
    return np.asarray(V, dtype=np.float64)[keep], remap[F]


def decimate(V, F, vertices=5000):
    import fast_simplification

    return compact(*fast_simplification.simplify(V, F, target_count=2 * vertices))


def snapped(lm, V, F):
    if lm is None:
        return None
    names = list(lm)
    C = closest_points(np.array([lm[n] for n in names]), V, F)[0]
    return dict(zip(names, C))


def _with_holes(name, V, F, lm, seed, count=12, radius=0.03):
    """The copy of (V, F) with ``count`` disks of ``radius`` head sizes cut out of its surface, centred
    on random vertices at least three radii from every landmark; unused vertices stay (core)."""
    rng = np.random.default_rng(seed)
    used = used_vertices(F, len(V))
    r = radius * float(np.ptp(V[used], axis=0).max())
    far = used
    if lm:
        d = np.min([np.linalg.norm(V[used] - p, axis=1) for p in lm.values()], axis=0)
        far = used[d > 3 * r]
    centres = V[rng.choice(far, size=min(count, len(far)), replace=False)]
    C = V[F].mean(axis=1)
    gone = np.zeros(len(F), dtype=bool)
    for c in centres:
        gone |= np.linalg.norm(C - c, axis=1) < r
    return Variant(name, V, F[~gone], lm, lm, core=np.isin(np.arange(len(V)), F[~gone]))


def _cut_behind_ears(name, V, F, lm, behind=0.3):
    """The copy of (V, F) cut by a plane across the landmarks' front ``behind`` ex-ex behind the tragions'
    midpoint (else that far in front of the opisthocranion): a bust or trophy cut behind the ears, an
    animal's head cut across a level neck. Transfer is given the landmarks still on the surface (within
    0.02 ex-ex); None without landmarks to place the cut."""
    ref = landmark_frame(V, F, lm) if lm else None
    ears = bool(lm) and "tragion_l" in lm and "tragion_r" in lm
    if ref is None or not (ears or "opisthocranion" in lm):
        return None
    u = unit(lm, V)
    if ears:
        at = 0.5 * (lm["tragion_l"] + lm["tragion_r"]) - behind * u * ref["front"]
    else:
        at = lm["opisthocranion"] + behind * u * ref["front"]
    return _kept_side(name, V, F, lm, at, ref["front"], u)


def _kept_side(name, V, F, lm, at, normal, u):
    """The copy of (V, F) with every triangle wholly on the ``normal`` side of the plane through ``at``,
    given the landmarks still on its surface (within 0.02 of ex-ex ``u``)."""
    Vc, Fc = compact(V, F[((V - at) @ normal > 0)[F].all(axis=1)])
    names = list(lm)
    C = closest_points(np.array([lm[n] for n in names]), Vc, Fc)[0]
    kept = {n: lm[n] for n, c in zip(names, C) if np.linalg.norm(c - lm[n]) <= 0.02 * u}
    return Variant(name, Vc, Fc, kept, lm, core=np.ones(len(Vc), dtype=bool))


def _cut_under_chin(name, V, F, lm, under=0.05):
    """The copy of (V, F) cropped level with the chin: every triangle wholly above a plane across the
    landmarks' up ``under`` ex-ex below the menton (else the pogonion) kept, as a face scan or a bust is
    often cropped; transfer is given the landmarks still on the surface. None without a chin to cut at."""
    ref = landmark_frame(V, F, lm) if lm else None
    chin = None if ref is None else lm.get("menton", lm.get("pogonion"))
    if chin is None:
        return None
    u = unit(lm, V)
    return _kept_side(name, V, F, lm, chin - under * u * ref["up"], ref["up"], u)


def make_variant(name, V, F, lm, seed):
    """The copy ``name`` of the head (V, F) with landmarks ``lm`` (or None); None when it does not apply."""
    core = np.ones(len(V), dtype=bool)
    if name == "as-is":
        return Variant(name, V, F, lm, lm, core=core)
    if name.startswith("rot") or name.startswith("x"):
        R = rotations()[int(name[3:]) - 1] if name.startswith("rot") else np.eye(3)
        s = 1.0 if name.startswith("rot") else float(name[1:])
        tl = None if lm is None else {n: s * (R @ p) for n, p in lm.items()}
        return Variant(name, s * V @ R.T, F, tl, tl, R=R, s=s, core=core)
    if name in ("remesh", "dec5k"):
        if name == "dec5k" and len(V) <= 5000:
            return None
        Vn, Fn = remesh(V, F) if name == "remesh" else decimate(V, F)
        return Variant(name, Vn, Fn, snapped(lm, Vn, Fn), lm, core=np.ones(len(Vn), dtype=bool), snap=True)
    if name == "flip":  # every triangle wound the other way: normals point in (a negative-scale export)
        return Variant(name, V, F[:, ::-1].copy(), lm, lm, core=core)
    if name == "mirror":  # the head's mirror image (another head), written with outward normals
        M = np.diag([-1.0, 1.0, 1.0])
        tl = None if lm is None else {mirror_name(n): M @ p for n, p in lm.items()}
        return Variant(name, V @ M, F[:, ::-1].copy(), tl, tl, R=M, core=core)
    if name == "holes":  # a scan's missing patches: 12 disks of 0.03 head sizes, away from the landmarks
        return _with_holes(name, V, F, lm, seed)
    if name == "backcut":  # cut across the face's front behind the ears (a bust's or a trophy's cut)
        return _cut_behind_ears(name, V, F, lm)
    if name == "chincut":  # cropped level with the chin (a face scan's or a bust's crop): no neck
        return _cut_under_chin(name, V, F, lm)
    if name == "stray":
        size = float(np.ptp(V, axis=0).max())
        p = V.mean(axis=0) + 10 * size * np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
        tri = p + 0.02 * size * np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
        Vn = np.vstack([V, tri])
        Fn = np.vstack([F, len(V) + np.arange(3)[None]])
        return Variant(name, Vn, Fn, lm, lm, core=np.r_[core, np.zeros(3, dtype=bool)])
    if name == "jitter":
        if lm is None:
            return None
        rng = np.random.default_rng(seed)
        u = unit(lm, V)
        step = rng.normal(size=(len(lm), 3))
        step *= 0.01 * u / np.linalg.norm(step, axis=1, keepdims=True)
        moved = snapped({n: p + d for (n, p), d in zip(lm.items(), step)}, V, F)
        return Variant(name, V, F, moved, lm, core=core)
    raise ValueError(name)


# ------------------------------------------------------------------------------------- results
@dataclass
class Result:
    status: str                # ok, fail, na, error, refused
    text: str = ""             # the failing figure or the reason
    severity: float = 0.0      # how far past the bound (ranks failures over variants)
    notes: list = None         # [(rig label, full message)] of refusals and errors

    def __post_init__(self):
        self.text = self.text or self.status
        self.notes = list(self.notes or [])

    @staticmethod
    def of(fails, ok_text="ok"):
        """``fails`` [(text, severity)]: ok when empty, else the worst first (all figures joined)."""
        if not fails:
            return Result("ok", ok_text)
        fails = sorted(fails, key=lambda f: -f[1])
        return Result("fail", ", ".join(t for t, _ in fails), fails[0][1])


def na(reason):
    return Result("na", f"n/a: {reason}")


def unit(lm, V):
    """ex-ex in mesh units (the exocanthion distance; a quarter of the bbox diagonal without it)."""
    return face_unit(V, lm or {})


def _norm(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def angle(a, b):
    return float(np.degrees(np.arccos(np.clip(_norm(a) @ _norm(b), -1.0, 1.0))))


def landmark_frame(V, F, lm):
    """The landmarks' own frame: dict ``front``, ``up``, ``left`` (unit (3,)), or None.

    front: opisthocranion (else the tragions' midpoint, else the mesh centroid) -> pronasale; up:
    menton (else pogonion) -> vertex (else nasion), made orthogonal to front; left = up x front."""
    if lm is None or "pronasale" not in lm:
        return None
    if "opisthocranion" in lm:
        back = lm["opisthocranion"]
    elif "tragion_l" in lm and "tragion_r" in lm:
        back = 0.5 * (lm["tragion_l"] + lm["tragion_r"])
    else:
        back = V[used_vertices(F, len(V))].mean(axis=0)
    top = lm.get("vertex", lm.get("nasion"))
    bottom = lm.get("menton", lm.get("pogonion"))
    if top is None or bottom is None:
        return None
    front = _norm(lm["pronasale"] - back)
    up = top - bottom
    up = _norm(up - (up @ front) * front)
    return {"front": front, "up": up, "left": np.cross(up, front)}


def mirror_plane(lm, ref):
    """(point, normal) of the landmarks' midplane: normal from the left-right pairs (else the frame's
    left), through the mean of the pairs' midpoints and the midline landmarks."""
    pairs = [(lm[n], lm[n[:-2] + "_r"]) for n in lm if n.endswith("_l") and n[:-2] + "_r" in lm]
    normal = _norm(sum(a - b for a, b in pairs)) if pairs else ref["left"]
    mids = [0.5 * (a + b) for a, b in pairs] + [p for n, p in lm.items() if not n.endswith(("_l", "_r"))]
    return np.mean(mids, axis=0), normal


# ------------------------------------------------------------------------------------- check 1
def check_frame(rig, ref):
    """The rig's detected front / up against the landmarks' (``ref`` in the variant's frame)."""
    if ref is None:
        return na("no landmark frame")
    fails = []
    for name, row in (("front", 2), ("up", 1)):
        deg = angle(rig.frame.rotation[row], ref[name])
        if deg > FRAME_DEG:
            fails.append((f"{name} {deg:.0f}°", deg / FRAME_DEG))
    return Result.of(fails)


def frame_drift(rotation, rotation0, R):
    """Largest difference (entries, degrees) between the frame of a copy turned by ``R`` (3, 3),
    mapped back, and the as-is frame ``rotation0``."""
    back = np.asarray(rotation) @ R          # rows r' = R r  ->  r = R^T r'
    entries = float(np.abs(back - rotation0).max())
    return entries, max(angle(a, b) for a, b in zip(back, rotation0))


# ------------------------------------------------------------------------------------- check 2
def family(skeleton, name):
    """Indices of bone ``name`` and all its descendants."""
    out = [skeleton.names.index(name)]
    for i, p in enumerate(skeleton.parents):
        if p in out:
            out.append(i)
    return out


def check_jaw(rig, lm, given=None):
    """Jaw weight at the chin / lower lip (>= 0.9) and nose / nasion / vertex (<= 0.1); edges off the
    lip line whose jaw weight steps by more than 0.3 (as ``benchmarks/jaw_weights.py`` measures). The
    lip line is the one the landmarks the rig was made from give (``given``, default ``lm``): on a
    remeshed copy the true landmarks lie off its surface, and the lip line through them misses the
    copy's own lip edges (ICT decimated: 8 edges counted as jumps that are the lips' own)."""
    if "jaw" not in rig.skeleton.names:
        return Result("fail", "no jaw bone", 1.0)
    V, F = rig.vertices, rig.faces
    jaw = rig.weights[:, family(rig.skeleton, "jaw")].sum(axis=1)
    fails = {}
    for name, label, on in JAW_PROBES:
        if name not in lm:
            continue
        w = float(jaw[np.argmin(np.linalg.norm(V - lm[name], axis=1))])
        bad = (JAW_ON - w) / JAW_ON if on else (w - JAW_OFF) / (1 - JAW_OFF)
        if bad > 0 and bad >= fails.get(label, (None, 0))[1]:
            fails[label] = (f"{label} {w:.2f}", bad)
    E, on_line = lip_line_edges(V, F, lm if given is None else given)
    jump = np.abs(jaw[E[:, 0]] - jaw[E[:, 1]])[~on_line]
    if len(jump) and jump.max() > MAX_JUMP:
        fails["jump"] = (f"jump {jump.max():.2f} x{int((jump > MAX_JUMP).sum())}",
                         (jump.max() - MAX_JUMP) / (1 - MAX_JUMP))
    return Result.of(list(fails.values()))


# ------------------------------------------------------------------------------------- check 3
def head_turn_motion(rig, deg=TURN_DEG):
    """Per-vertex displacement (n,) of a ``deg`` yaw of the ``head`` bone (and its children) about
    the rig's own up at the head joint (``Rig.turn_bones``: the head's axes, a transferred rig's
    anatomical ones), linear blend skinning (what ``pose --head 0,deg,0`` and a glTF player do with
    the skin weights)."""
    return np.linalg.norm(rig.turn_bones(head_deg=(0.0, float(deg), 0.0)) - np.asarray(rig.vertices), axis=1)


def chin_height(lm, up):
    """Height along ``up`` of the lowest chin landmark (menton, pogonion), or None."""
    h = [float(lm[n] @ up) for n in ("menton", "pogonion") if lm and n in lm]
    return min(h) if h else None


def check_neck_base(rig, up, core, chin=None):
    """The lowest 5% of the vertices and the lowest 5% of the height (along ``up``, over the ``core``
    vertices) move at most 1% of the peak motion on a 15° head turn. The vertex share stops below the
    ``chin`` height when given: on a head whose face is far denser than its neck (ICT) 5% of the
    vertices reach above the chin, which must follow the head."""
    if "head" not in rig.skeleton.names:
        return Result("fail", "no head bone", 1.0)
    d = head_turn_motion(rig)[core]
    h = rig.vertices[core] @ up
    peak = float(d.max())
    if not peak > 0:
        return Result("fail", "head turn moves nothing", 1.0)
    lo_count = h <= np.quantile(h, BASE_SHARE)
    if chin is not None and (lo_count & (h < chin)).any():
        lo_count &= h < chin
    lo_height = h <= h.min() + BASE_SHARE * np.ptp(h)
    fails = []
    for label, zone in (("base", lo_count), ("base(h)", lo_height)):
        share = float(d[zone].max()) / peak
        if share > BASE_MAX:
            fails.append((f"{label} {share:.1%}", share / BASE_MAX))
    return Result.of(fails)


# ------------------------------------------------------------------------------------- check 4
def c1_centre(tragion, u, ref):
    """The occiput-C1 centre of rotation (Chancey et al. 2007) from the tragions' midpoint ``tragion``
    (3,): ``C1_MM`` behind and below it along the landmark frame ``ref``, millimetres scaled by the
    head's ex-ex ``u`` / ``EXEX_MM``."""
    return tragion + (u / EXEX_MM) * (-C1_MM[0] * ref["front"] - C1_MM[1] * ref["up"])


def check_pivot(rig, lm, ref, core, human):
    """The head joint behind the gonions' line, below the tragions, above the neck's base, on the
    midline; on human heads with tragions its distance to the occiput-C1 centre (issue #32)."""
    if ref is None or lm is None:
        return na("no landmark frame")
    if "head" not in rig.skeleton.names:
        return Result("fail", "no head bone", 1.0)
    j = rig.skeleton.heads[rig.skeleton.names.index("head")]
    u = unit(lm, rig.vertices)
    pair = lambda n: 0.5 * (lm[n + "_l"] + lm[n + "_r"]) if n + "_l" in lm and n + "_r" in lm else None  # noqa: E731
    gonion, tragion = pair("gonion"), pair("tragion")
    fails = []
    if gonion is not None:
        d = float((j - gonion) @ ref["front"]) / u
        if d > 0:
            fails.append((f"fwd of gonions {d:.3f}", 1 + d))
    if tragion is not None:
        d = float((j - tragion) @ ref["up"]) / u
        if d > 0:
            fails.append((f"above tragions {d:.3f}", 1 + d))
    d = float(j @ ref["up"] - (rig.vertices[core] @ ref["up"]).min()) / u
    if d < 0:
        fails.append((f"below base {-d:.3f}", 1 - d))
    p, n = mirror_plane(lm, ref)
    d = abs(float((j - p) @ n)) / u
    if d > MIDLINE:
        fails.append((f"off midline {d:.3f}", d / MIDLINE))
    if human and tragion is not None and "exocanthion_l" in lm:
        d = float(np.linalg.norm(j - c1_centre(tragion, u, ref))) / u
        if d > C1_MAX:
            fails.append((f"C1 {d:.2f}", d / C1_MAX))
    return Result.of(fails)


# ------------------------------------------------------------------------------------- check 5
def check_weights(rig):
    """Every vertex weighted, rows summing to 1 (1e-6), nothing NaN."""
    W = np.asarray(rig.weights, dtype=np.float64)
    fails = []
    bad = ~np.isfinite(W).all(axis=1)
    if bad.any():
        fails.append((f"NaN {int(bad.sum())}", 10.0))
    W = np.where(np.isfinite(W), W, 0.0)
    empty = int((W.max(axis=1) <= 0).sum())
    if empty:
        fails.append((f"unweighted {empty}", 5.0))
    off = float(np.abs(W.sum(axis=1) - 1.0).max())
    if off > SUM_TOL:
        fails.append((f"sum {off:.1e}", 1 + off))
    if (W < 0).any():
        fails.append((f"negative {W.min():.1e}", 2.0))
    return Result.of(fails)


def validator_installed():
    return shutil.which("node") is not None and (VALIDATOR_DIR / "node_modules" / "gltf-validator").is_dir()


def check_gltf(path):
    """The Khronos glTF validator's errors on ``path`` (as ``tests/test_gltf_clients.py`` runs it)."""
    if not validator_installed():
        return na("validator not installed")
    out = subprocess.run(["node", str(VALIDATOR_DIR / "validate.js"), str(path)], capture_output=True,
                         text=True, timeout=300)
    if out.returncode != 0:
        return Result("error", f"error: validator exit {out.returncode}: {out.stderr.strip()[:80]}")
    issues = json.loads(out.stdout)["issues"]
    if issues["numErrors"]:
        codes = sorted({m["code"] for m in issues["messages"] if m["severity"] == 0})
        return Result("fail", f"{issues['numErrors']} errors ({', '.join(codes[:2])})", 1.0 + issues["numErrors"])
    return Result("ok")


# ------------------------------------------------------------------------------------- check 6
def correspondence_offset(P, P0, ok, V0, F0, back, snap):
    """p95 and max distance (mesh units, as-is frame) between each reliable generic vertex's point on a
    copy ``P`` mapped back by ``back`` (and by closest point onto the as-is head when ``snap``) and its
    point ``P0`` on the as-is head."""
    Q = back(P[ok])
    if snap:
        Q = closest_points(Q, V0, F0)[0]
    d = np.linalg.norm(Q - P0[ok], axis=1)
    return float(np.quantile(d, 0.95)), float(d.max())


def check_correspondence(p95_unit):
    """``p95_unit``: the p95 offset in ex-ex units."""
    if p95_unit > CORR_MAX:
        return Result("fail", f"p95 {p95_unit:.1%}", p95_unit / CORR_MAX)
    return Result("ok")


# ------------------------------------------------------------------------------------- check 7
def check_arkit(rig, lm, up):
    """No triangle turned over by any ARKit shape at weight 1 (``mouthClose`` on top of ``jawOpen``);
    ``eyeBlinkLeft`` closes >= 90% of the left lid gap (:func:`autobones.arkit.lids.gap_closure`'s
    ``margins``: from the upper margin at palpebrale superius to the lower margin across from it)."""
    targets = rig.arkit_targets or {}
    if not targets:
        return Result("fail", "no ARKit shapes", 1.0)
    V, F = rig.vertices, rig.faces
    fails, folds = [], {}
    for name, D in targets.items():
        base = targets.get(ON_TOP.get(name))
        k = int(folded_triangles(V, F, np.asarray(D), base=None if base is None else np.asarray(base)).sum())
        if k:
            folds[name] = k
    if folds:
        worst = max(folds, key=folds.get)
        fails.append((f"folds {sum(folds.values())} ({worst} {folds[worst]}"
                      + (f" +{len(folds) - 1} shapes)" if len(folds) > 1 else ")"), 1.0 + sum(folds.values())))
    if "l" in eye_sides(lm) and "eyeBlinkLeft" in targets:
        # the upper margin's way to the lower margin across from it (``points``, to the lower landmark,
        # also counts the two landmarks' offset along the eye, which no closing removes)
        closed = gap_closure(V, F, targets["eyeBlinkLeft"], lm, "l", up)["margins"]
        if closed < BLINK_MIN:
            fails.append((f"blink {closed:.0%}", 1 + BLINK_MIN - closed))
        elif not fails:
            return Result("ok", f"ok (blink {closed:.0%})")
    elif not fails:
        return Result("ok", "ok (no lid landmarks)")
    return Result.of(fails)
