"""Held-out heads for the frame check (#31 check 1): heads cut from Debian's assimp test models.

    apt-get install assimp-testmodels assimp-utils      # the models, and the `assimp` converter
    python benchmarks/assimp_heads.py [--rotations 6]

Not in ``../shared`` and in no project file: five characters of assimp's test set (a woman's and a man's
body, the COLLADA rubber duck, the Wuson bison, a game dwarf in a horned helmet), converted by
``assimp export`` and cut at the neck by a plane across each model's own up (or, for the bison, across
its body) at a height read off its cross-sections. Their truth is the frame each was modelled in (up and
front, checked on pictures), so the check needs no landmarks: ``place``'s up and front within 30 degrees
of it, as is and turned at random. Licences: the Debian package's copyright (BSD-3-clause for assimp's
test models; HUMAN.blend "redistribution and reuse allowed"): research test data, never in the package.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import autobones
import zoo_checks as zc   # benchmarks/ is the script's folder, first on the path

MODELS = Path("/usr/share/assimp/models")
# name -> (model, cut axis, sign (the head's end), share of the extent kept from that end, true up, front)
HEADS = {
    "woman": ("Collada/human.zae", 1, 1.0, 0.145, (0, 1, 0), (0, 0, 1)),
    "man": ("BLEND/HUMAN.blend", 2, 1.0, 0.14, (0, 0, 1), (0, -1, 0)),
    "duck": ("Collada/duck.dae", 1, 1.0, 0.42, (0, 1, 0), (1, 0, 0)),
    "bison": ("OBJ/WusonOBJ.obj", 2, -1.0, 0.19, (0, 1, 0), (0, 0, -1)),
    "dwarf": ("COB/dwarf.cob", 2, 1.0, 0.30, (0, 0, 1), (0, 1, 0)),
}


def head_of(model, axis, sign, share, folder):
    """(V, F): the model converted to OBJ by ``assimp export`` and cut by a plane across ``axis``, keeping
    the triangles within ``share`` of its extent from its ``sign`` end."""
    obj = folder / (Path(model).stem + ".obj")
    subprocess.run(["assimp", "export", str(MODELS / model), str(obj), "-ptv", "-tri"], check=True,
                   capture_output=True)
    V, F = autobones.load_mesh(obj)
    h = sign * V[:, axis]
    F = F[(h[F] >= h.max() - share * np.ptp(h)).all(axis=1)]
    used = np.unique(F)
    index = np.full(len(V), -1)
    index[used] = np.arange(len(used))
    return V[used], index[F]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rotations", type=int, default=6, help="random turns of each head (seed 31)")
    args = ap.parse_args(argv)
    if not MODELS.is_dir() or shutil.which("assimp") is None:
        sys.exit("needs Debian's assimp-testmodels and assimp-utils: apt-get install assimp-testmodels assimp-utils")
    turns = [np.eye(3)] + list(Rotation.random(args.rotations, random_state=31).as_matrix())
    print("| head | vertices | up, front off (deg), as is | worst of the turned copies | verdict |")
    print("|---|---:|---|---|---|")
    passed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, (model, axis, sign, share, up, front) in HEADS.items():
            V, F = head_of(model, axis, sign, share, Path(tmp))
            offs = []
            for R in turns:
                rig = autobones.place((V @ R.T, F), density="sparse")
                got = rig.frame.rotation @ R      # the frame's up and front rows, back in the model's axes
                offs.append((zc.angle(got[1], up), zc.angle(got[2], front)))
            ok = all(max(o) <= 30 for o in offs)
            passed += ok
            worst = max(offs[1:], key=max)
            print(f"| {name} | {len(V)} | {offs[0][0]:.0f}, {offs[0][1]:.0f} | {worst[0]:.0f}, {worst[1]:.0f} | "
                  f"{'ok' if ok else 'wrong'} |")
    print(f"\n{passed} / {len(HEADS)} heads within 30 degrees in every copy ({len(turns)} copies each)")


if __name__ == "__main__":
    main()
