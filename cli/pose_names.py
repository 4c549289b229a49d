"""``pose``'s names checked against the rig before its skin/muscle model is built (which takes seconds)."""
from __future__ import annotations


def check_pose_names(rig, definitions, expression, au, muscles, eyelids, arkit, shapes=False):
    """AutobonesError for the first unknown expression, action unit, muscle, eyelid or ARKit name.

    ``definitions`` is the dict pose will use (None: the rig's sidecar's, else the built-in ones).
    ``shapes``: the AUs go through the rig's ARKit shapes, so the AUs the ``au_arkit`` table maps are
    known too (AU16, AU45 have no muscle definition).
    The messages are the model's own, so a name is refused the same way before or after the build.
    """
    from autobones.errors import AutobonesError
    from autobones.expressions.definitions import load_expressions, parse_au_key
    from autobones.expressions.lids import LIDS

    doc = definitions if definitions is not None else (rig.expressions or {}).get("definitions")
    doc = load_expressions(doc)
    known = doc["expressions"]
    for name in expression:
        if name not in known:
            raise AutobonesError(f"unknown expression {name!r}; known: {', '.join(known)}")
    units = doc["action_units"]
    if shapes:
        from autobones.expressions.au_shapes import mapped_aus, table_of

        units = {**dict.fromkeys(mapped_aus(table_of(doc))), **units}
    for key in au:
        base = parse_au_key(key)[1]
        if base not in units:
            raise AutobonesError(f"unknown action unit {key!r}; defined: {', '.join(sorted(units, key=int))}")
    names = {m["name"] for m in rig.muscles or []} | {m.get("type") for m in rig.muscles or []}
    for m in muscles:
        if m not in names:
            raise AutobonesError(f"unknown muscle {m!r}; the rig has: {', '.join(m['name'] for m in rig.muscles or [])}")
    for part in eyelids:
        if not any(p == part or p.split("_")[0] == part for p in LIDS):
            raise AutobonesError(f"unknown eyelid {part!r}; use upper, lower or one of {', '.join(LIDS)}")
    if arkit:  # the rig's own check: a sum of its stored targets, no model
        rig.arkit_offset(arkit)
