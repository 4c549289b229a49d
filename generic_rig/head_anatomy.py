"""Key anatomical points of the built-in default head (a data table).

Frame: metres, +Y up, +Z out of the face, +X toward the subject's own LEFT
ear; x = 0 is the mid-sagittal (symmetry) plane, y = 0 the height of menton,
z = 0 the coronal plane through the ear canals.  Landmark names follow
Farkas (1994), *Anthropometry of the Head and Face*.

The values are measured on the built mesh (``build_default_head.py
--measure``, see ``head_measure.py``), not typed in by hand: surface points
are snapped to the mesh; ``eye_centre`` is the centre of the closed-lid /
eyeball bulge, inside the head.  Re-run ``--measure`` after changing the shape
in ``head_field.py`` and paste its table here.
"""

from __future__ import annotations

# "_l" = the subject's left (+x); midline points have x = 0.  The "_r"
# entries are added below as exact mirror images (x -> -x).
ANATOMY: dict[str, tuple[float, float, float]] = {
    "pronasale": (0.0000, 0.0829, 0.1075),
    "glabella": (0.0000, 0.1367, 0.0946),
    "nasion": (0.0000, 0.1201, 0.0913),
    "subnasale": (0.0000, 0.0691, 0.0908),
    "stomion": (0.0000, 0.0478, 0.0896),
    "labrale_superius": (0.0000, 0.0535, 0.0928),
    "labrale_inferius": (0.0000, 0.0413, 0.0914),
    "pogonion": (0.0000, 0.0150, 0.0837),
    "menton": (0.0000, 0.0004, 0.0700),
    "vertex": (0.0000, 0.2260, -0.0020),
    "opisthocranion": (0.0000, 0.1430, -0.0964),
    "exocanthion_l": (0.0464, 0.1142, 0.0631),
    "endocanthion_l": (0.0166, 0.1118, 0.0688),
    "eye_centre_l": (0.0315, 0.1130, 0.0575),
    "cheilion_l": (0.0264, 0.0484, 0.0718),
    "alare_l": (0.0211, 0.0720, 0.0839),
    "zygion_l": (0.0689, 0.1000, 0.0149),
    "gonion_l": (0.0551, 0.0198, -0.0103),
    "tragion_l": (0.0710, 0.1061, -0.0031),
    "superaurale_l": (0.0768, 0.1329, -0.0246),
    "subaurale_l": (0.0680, 0.0718, -0.0078),
}
# "+ 0.0" turns -0.0 into 0.0, so printed tables never show "-0.0000"
ANATOMY.update({k[:-2] + "_r": (-v[0] + 0.0, v[1], v[2])
                for k, v in list(ANATOMY.items()) if k.endswith("_l")})
