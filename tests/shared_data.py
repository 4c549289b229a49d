"""Paths to the third-party test meshes carried in tests/data, and small synthetic meshes for tests.

The meshes are stored compactly in ``tests/data/<family>/meshes.npz`` (one topology stored once per
family, vertices float32 where that is bit-exact after writing; see ``tests/data/LICENSES.md``) and
written out on first use as real files (``.obj`` / binary ``.ply``, same names as in the shared data
set) into a per-user cache folder keyed by the content of the store. Loading a written file gives
exactly the arrays of the original file: ``tests/data/make_test_data.py`` checks that when it builds
the store. Landmark files (``*.landmarks.json``) are copied as they are, beside their meshes.
"""
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
STORE = ROOT / "tests" / "data"


def _cache_dir():
    h = hashlib.sha256(Path(__file__).read_bytes())
    for f in sorted(STORE.glob("*/*")):
        if f.is_file():
            h.update(f.relative_to(STORE).as_posix().encode() + b"\0" + f.read_bytes())
    user = str(os.getuid()) if hasattr(os, "getuid") else "user"
    return Path(tempfile.gettempdir()) / f"autobones-test-data-{user}-{h.hexdigest()[:16]}"


# Materialised copies of tests/data: <DATA>/<family>/<file>, the layout of the shared data set.
DATA = _cache_dir()


def data(rel):
    """Path of a test mesh or landmark file (e.g. ``"ict/identity000.obj"``), written on first use.

    Fails (never skips) when ``rel`` is not in tests/data.
    """
    family, name = rel.split("/")
    path = DATA / family / name
    if not path.is_file():
        src = STORE / family / name
        if name.endswith(".json"):
            assert src.is_file(), f"missing test file {src}: add it with tests/data/make_test_data.py"
            _atomic_write(path, src.read_bytes())
        else:
            store = STORE / family / "meshes.npz"
            assert store.is_file(), f"missing test mesh store {store}: see tests/data/make_test_data.py"
            with np.load(store) as z:
                assert f"{name}/vertices" in z.files, \
                    f"missing test mesh {rel} in {store}: add it with tests/data/make_test_data.py"
                _atomic_write(path, mesh_bytes(z, name, f"{family}/{name}"))
        # the landmark files of the family sit beside its meshes, as in the shared data set
        for lm in (STORE / family).glob("*.landmarks.json"):
            if not (DATA / family / lm.name).is_file():
                _atomic_write(DATA / family / lm.name, lm.read_bytes())
    return path


def landmark_files():
    """Every ``<family>/*.landmarks.json`` of tests/data, written out beside its mesh; sorted paths."""
    out = []
    for lm in sorted(STORE.glob("*/*.landmarks.json")):
        stem = lm.name[: -len(".landmarks.json")]
        with np.load(lm.parent / "meshes.npz") as z:
            mesh = next(f"{stem}{e}" for e in (".obj", ".ply") if f"{stem}{e}/vertices" in z.files)
        data(f"{lm.parent.name}/{mesh}")
        out.append(data(f"{lm.parent.name}/{lm.name}"))
    return sorted(out)


def _atomic_write(path, content):
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(content)
        os.chmod(tmp, 0o444)  # read-only, like the shared data set: a test must not change its inputs
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def mesh_bytes(z, name, rel=None):
    """The file ``name`` of an open ``meshes.npz`` as bytes (OBJ text or binary little-endian PLY).

    OBJ vertices are written with the shortest decimal that reads back as the stored value (float32
    values: numpy's shortest float32 repr, which for the 6-7 significant digits of the original
    files is the original decimal, so reading it as float64 gives the original float64 exactly);
    faces are written as the original polygons, in the original order (no texture indices).
    """
    V = z[f"{name}/vertices"]
    if name.endswith(".ply"):
        F = z[f"{name}/faces"].astype("<i4")
        rgba = z[f"{name}/rgba"] if f"{name}/rgba" in z.files else None
        head = ["ply", "format binary_little_endian 1.0"]
        head += [f"comment {c}" for c in z[f"{name}/comments"].tolist()] if f"{name}/comments" in z.files else []
        head += [f"element vertex {len(V)}", "property float x", "property float y", "property float z"]
        fields = [("xyz", "<f4", (3,))]
        if rgba is not None:
            head += [f"property uchar {c}" for c in ("red", "green", "blue", "alpha")[: rgba.shape[1]]]
            fields.append(("rgba", "u1", (rgba.shape[1],)))
        head += [f"element face {len(F)}", "property list uchar int vertex_indices", "end_header"]
        verts = np.empty(len(V), dtype=fields)
        verts["xyz"] = V
        if rgba is not None:
            verts["rgba"] = rgba
        faces = np.empty(len(F), dtype=[("n", "u1"), ("idx", "<i4", (3,))])
        faces["n"] = 3
        faces["idx"] = F
        return ("\n".join(head) + "\n").encode("ascii") + verts.tobytes() + faces.tobytes()
    topo = str(z[f"{name}/topology"])
    sizes, index = z[f"{topo}/sizes"], z[f"{topo}/index"].astype(np.int64) + 1
    fmt = str if V.dtype == np.float32 else (lambda x: repr(float(x)))
    lines = [f"# {rel or name}: written by tests/shared_data.py from tests/data (source, licence: tests/data/LICENSES.md)"]
    lines += [f"v {fmt(x)} {fmt(y)} {fmt(w)}" for x, y, w in V]
    ends = np.cumsum(sizes)
    flat = index.tolist()
    lines += ["f " + " ".join(map(str, flat[e - n:e])) for n, e in zip(sizes.tolist(), ends.tolist())]
    return ("\n".join(lines) + "\n").encode("ascii")


def flat_grid(n=21, half=1.0, z=0.0):
    """A flat ``n x n`` grid of side ``2 half`` at height ``z`` facing +Z: V (n*n, 3), F int64."""
    x, y = np.meshgrid(np.linspace(-half, half, n), np.linspace(-half, half, n))
    V = np.c_[x.ravel(), y.ravel(), np.full(n * n, float(z))]
    a = (np.arange(n - 1)[None, :] + n * np.arange(n - 1)[:, None]).ravel()
    F = np.r_[np.c_[a, a + 1, a + n + 1], np.c_[a, a + n + 1, a + n]]
    return V, F.astype(np.int64)


def icosphere(subdivisions=3, radius=1.0):
    import trimesh

    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(m.vertices), np.asarray(m.faces)


BLENDER_SCRIPT = ROOT / "tests" / "blender_check.py"
BLENDER_INSTALL = "install it with: apt-get install blender python3-numpy (or bash tools/test-setup.sh)"


def long_snout(V, F, lm, k):
    """The head with everything in front of its eye corners stretched by ``1 + k`` along its front
    axis (the landmarks' frame), the landmarks moved with it: a long-snouted animal's proportions on
    a human's mesh. Returns (V, landmarks)."""
    from autobones.orient import frame_from_landmarks

    frame = frame_from_landmarks(V, F, lm)
    eyes = [lm[n] for n in ("exocanthion_l", "exocanthion_r", "endocanthion_l", "endocanthion_r") if n in lm]
    z0 = frame.to_canonical(np.array(eyes))[:, 2].mean()

    def stretch(P):
        Q = frame.to_canonical(np.asarray(P, dtype=np.float64))
        Q[:, 2] += k * np.maximum(Q[:, 2] - z0, 0.0)
        return frame.from_canonical(Q)

    return stretch(V), {n: stretch(np.asarray(p)[None])[0] for n, p in lm.items()}


def run_blender_check(glb, report_path):
    """Run tests/blender_check.py on ``glb`` in headless Blender; return its JSON report.

    Fails (never skips) when Blender or its numpy is missing.
    """
    import json
    import subprocess

    import pytest

    blender = shutil.which("blender")
    if blender is None:
        pytest.fail(f"blender is not on PATH; {BLENDER_INSTALL}")
    cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "-P", str(BLENDER_SCRIPT), "--", str(glb), str(report_path)]
    # Blender's embedded (system) Python locates its standard library from the first
    # python3.X on PATH: a pyenv or virtualenv interpreter running pytest would hijack
    # it and hide the system numpy the glTF importer needs. Put Blender's own folder first.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONHOME", "PYTHONPATH")}
    env["PATH"] = os.path.dirname(os.path.realpath(blender)) + os.pathsep + env.get("PATH", "")
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    log = (out.stdout + out.stderr)[-3000:]
    if "No module named 'numpy'" in log:
        pytest.fail(f"Blender's Python has no numpy, which its glTF importer needs; {BLENDER_INSTALL}\n{log}")
    assert out.returncode == 0 and os.path.exists(report_path), f"{' '.join(cmd)} failed:\n{log}"
    with open(report_path) as fh:
        return json.load(fh)
