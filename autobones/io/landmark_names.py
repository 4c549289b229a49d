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
