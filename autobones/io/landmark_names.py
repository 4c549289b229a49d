"""The landmark contract's names (``spec/landmarks.md``): 12 midline, 16 bilateral pairs, 44 in all.

Orvalho, Zacur & Susin 2008 (§2) tag the generic rig with 44 anthropometric landmarks; this
module names them and fixes their order. ``_l`` is the subject's own left (+X in the
canonical head frame), ``_r`` the right.
"""
from __future__ import annotations

#: Midline names, top of the head to the chin then around (spec order).
MIDLINE = (
    "vertex", "opisthocranion", "glabella", "nasion", "pronasale", "subnasale",
    "labiale_superius", "stomion", "labiale_inferius", "sublabiale", "pogonion", "menton",
)

#: Bilateral base names; each exists as ``NAME_l`` (subject's left) and ``NAME_r``.
BILATERAL = (
    "exocanthion", "endocanthion", "palpebrale_superius", "palpebrale_inferius",
    "brow_inner", "brow_middle", "brow_outer", "alare", "crista_philtri", "cheilion",
    "zygion", "gonion", "tragion", "superaurale", "subaurale", "frontotemporale",
)

#: The 44 contract names in their fixed order: the 12 midline names, then for
#: each bilateral base name in :data:`BILATERAL` order ``NAME_l`` then ``NAME_r``.
NAMES = MIDLINE + tuple(f"{base}_{side}" for base in BILATERAL for side in ("l", "r"))

#: Contract name -> its position in :data:`NAMES`.
NAME_INDEX = {name: i for i, name in enumerate(NAMES)}


def mirror_name(name):
    """The same landmark on the other side: ``'x_l'`` <-> ``'x_r'``; a midline name is itself.

    Raises ``ValueError`` for a name outside :data:`NAMES`.
    """
    if name not in NAME_INDEX:
        raise ValueError(f"{name!r} is not a landmark name of the contract")
    if name in MIDLINE:
        return name
    return name[:-1] + ("r" if name.endswith("_l") else "l")


#: Where each name goes (``spec/landmarks.md``), by midline or bilateral base name.
WHERE = {
    "vertex": "top of the head, highest midline point of the skull in upright pose",
    "opisthocranion": "back of the head, most posterior midline point",
    "glabella": "smooth prominence between the eyebrows",
    "nasion": "deepest point of the nasal bridge, between the eyes",
    "pronasale": "nose tip, most anterior point of the nose (a muzzle tip on an animal)",
    "subnasale": "where the base of the nose meets the upper lip",
    "labiale_superius": "midpoint of the upper lip's vermilion border",
    "stomion": "midpoint of the line where the lips meet",
    "labiale_inferius": "midpoint of the lower lip's vermilion border",
    "sublabiale": "deepest point of the crease between lower lip and chin",
    "pogonion": "most anterior point of the chin",
    "menton": "lowest point of the chin",
    "exocanthion": "outer corner of the eye",
    "endocanthion": "inner corner of the eye",
    "palpebrale_superius": "highest point of the upper eyelid margin",
    "palpebrale_inferius": "lowest point of the lower eyelid margin",
    "brow_inner": "inner (medial) end of the eyebrow",
    "brow_middle": "highest point of the eyebrow",
    "brow_outer": "outer (lateral) end of the eyebrow",
    "alare": "outer end of the nostril base, where the nose wing meets the cheek",
    "crista_philtri": "peak of the upper lip (Cupid's bow)",
    "cheilion": "corner of the mouth",
    "zygion": "most lateral point of the cheekbone",
    "gonion": "angle of the jaw",
    "tragion": "notch above the tragus of the ear",
    "superaurale": "highest point of the ear",
    "subaurale": "lowest point of the earlobe",
    "frontotemporale": "temple: most medial point of the temporal ridge on the forehead",
}

#: The 44 names by part of the head, for a list a person works down: (group, names in contract order).
GROUPS = (
    ("midline", MIDLINE),
    ("eyes and brows", tuple(f"{b}_{s}" for b in ("exocanthion", "endocanthion", "palpebrale_superius",
                                                   "palpebrale_inferius", "brow_inner", "brow_middle", "brow_outer",
                                                   "frontotemporale") for s in "lr")),
    ("nose", ("alare_l", "alare_r")),
    ("mouth", tuple(f"{b}_{s}" for b in ("crista_philtri", "cheilion") for s in "lr")),
    ("jaw and cheeks", tuple(f"{b}_{s}" for b in ("zygion", "gonion") for s in "lr")),
    ("ears", tuple(f"{b}_{s}" for b in ("tragion", "superaurale", "subaurale") for s in "lr")),
)


def where(name):
    """Where ``name`` goes on the head, one line (the spec's table; ``_l``/``_r`` say the subject's side)."""
    if name in MIDLINE:
        return WHERE[name]
    side = "subject's left" if name.endswith("_l") else "subject's right"
    return f"{WHERE[name[:-2]]} ({side})"
