"""Planning a batch: the meshes under the input folder and, for each, run, skip (up to date) or fail (refused)."""
from __future__ import annotations

import os
from dataclasses import dataclass, field

from ..errors import AutobonesError
from ..io.files import read_json
from ..io.atomic import BACKUP_SUFFIX
from ..io.mesh import SUPPORTED
from .jobs import (PARTIAL_SUFFIX, landmarks_for, legacy_output, options_hash, output_for, output_paths, partial_dir,
                   refuse_inside_input)
from .report import REPORT_NAME


@dataclass
class Item:
    """One mesh of the batch: what to do with it and, when skipped or refused, why."""

    input: str           # absolute
    rel: str             # relative to the input folder, '/' separated
    output: str          # absolute NAME.rig.glb
    action: str = "run"  # run | skip | fail
    reason: str | None = None
    record: dict = field(default_factory=dict)
    stale: tuple = ()    # what an older batch left under the old name NAME.glb: removed once rigged again


def check_folders(input_dir, output_dir):
    """Absolute (input, output) folders; refuse a missing input or overlapping folders."""
    inp = os.path.realpath(os.fspath(input_dir))
    out = os.path.realpath(os.fspath(output_dir))
    if not os.path.isdir(inp):
        raise AutobonesError(f"{input_dir}: no such folder")
    if os.path.exists(out) and not os.path.isdir(out):
        raise AutobonesError(f"{output_dir}: exists and is not a folder")
    if out == inp:
        raise AutobonesError(f"{output_dir}: the output folder is the input folder; outputs are never "
                             f"written inside the input, choose another folder")
    if out.startswith(inp + os.sep):
        raise AutobonesError(f"{output_dir}: the output folder is inside the input folder {input_dir}; "
                             f"outputs are never written inside the input, choose a folder outside it")
    if inp.startswith(out + os.sep):
        raise AutobonesError(f"{input_dir}: the input folder is inside the output folder {output_dir}; "
                             f"its outputs would land inside the input, choose separate folders")
    return inp, out


def find_meshes(input_dir, output_dir=None):
    """Mesh files under ``input_dir``, recursively, sorted by relative path.

    Only :data:`autobones.io.mesh.SUPPORTED` extensions; hidden files and folders
    (a leading dot), ``output_dir`` (should it sit inside) and rigs autobones wrote (a
    ``.glb`` with its ``.rig.json`` beside it: ``place`` run in the folder before) are left
    out; symbolic links to folders are not followed.
    """
    from ..rig import sidecar_paths

    inp = os.path.realpath(os.fspath(input_dir))
    skip = os.path.realpath(os.fspath(output_dir)) if output_dir is not None else None
    found = []
    for root, dirs, files in os.walk(inp):
        dirs[:] = sorted(d for d in dirs if not d.startswith(".")
                         and os.path.realpath(os.path.join(root, d)) != skip)
        for name in sorted(files):
            if name.startswith(".") or os.path.splitext(name)[1].lower() not in SUPPORTED:
                continue
            path = os.path.join(root, name)
            ours = name.lower().endswith(".glb") and os.path.isfile(sidecar_paths(path)[0])  # a rig, not a head
            if os.path.isfile(path) and not ours:
                found.append(path)
    return sorted(found, key=lambda p: os.path.relpath(p, inp).replace(os.sep, "/"))


def plan(input_dir, output_dir, options, force=False):
    """One :class:`Item` per mesh, with ``action`` run, skip (up to date) or fail (refused).

    Refused: two inputs that would write the same output (``a.obj`` and ``a.ply``),
    and, without ``force``, outputs that exist but are older than the input or were
    made with other options. AutobonesError, before anything is written, when a symbolic
    link in the output tree leads any output inside the input folder or onto an input.

    The glb is ``OUT/REL/NAME.rig.glb``, as ``place`` and ``transfer`` name theirs. Batches before
    this rule wrote ``NAME.glb`` beside the same sidecars: such a file is rigged again once (even
    when up to date), and the old glb (and an old ``.NAME.glb.partial`` folder) removed once the new
    one is written (``Item.stale``).
    """
    inp, out = check_folders(input_dir, output_dir)
    h = options_hash(options)
    items = []
    for path in find_meshes(inp, out):
        rel = os.path.relpath(path, inp)
        glb = os.path.join(out, output_for(rel))
        items.append(Item(input=path, rel=rel.replace(os.sep, "/"), output=glb))
    # every path the batch writes, resolved: the planned names, their .partial folders, the report
    written = [p for it in items for p in (*output_paths(it.output), partial_dir(it.output))]
    sources = [it.input for it in items] + [lm for lm in map(landmarks_for, (it.input for it in items)) if lm]
    refuse_inside_input(written + [os.path.join(out, REPORT_NAME)], inp, sources)
    owners = {}
    for it in items:
        for target in output_paths(it.output):
            owners.setdefault(target.lower(), []).append(it)
    for it in items:
        clash = sorted({o.rel for target in output_paths(it.output) for o in owners[target.lower()]} - {it.rel})
        if clash:
            it.action, it.reason = "fail", (f"{it.rel}: {', '.join(clash)} would write the same output "
                                            f"{os.path.relpath(it.output, out)}; rename one of them")
    for it in items:
        if it.action == "run":
            old = legacy_output(it.output)  # never another's output: ``a.rig.obj``'s old name is ``a.obj``'s new one
            old = None if old is None or old.lower() in owners else old
            it.action, it.reason, it.stale = _state(it, options, h, force, old)
    refuse_inside_input([p for it in items for p in it.stale], inp, sources)  # and what it removes
    return items


def _state(it, options, h, force, old=None):
    """(action, reason, stale) of a file not refused for a clash; ``old`` its glb's name before ``.rig.glb``."""
    targets = output_paths(it.output)
    present = [os.path.exists(t) for t in targets]
    # an older batch's glb beside the sidecars (the new glb absent): the three files it wrote, judged so
    renamed = old is not None and not present[0] and any(present[1:]) and os.path.isfile(old)
    old_partial = old is not None and os.path.isdir(partial_dir(old))
    stale = ((old,) if renamed else ()) + ((partial_dir(old),) if old_partial else ())
    if os.path.isdir(partial_dir(it.output)) or old_partial:
        return "run", "interrupted", stale
    if not any(present):
        return "run", None, stale
    if renamed:
        targets, present = (old, *targets[1:]), [True, *present[1:]]
    why = None
    if not all(present):
        why = "some of its outputs exist (" + ", ".join(os.path.basename(t) for t, p in zip(targets, present) if p) + ")"
    else:
        recorded = _recorded_hash(targets[1])
        sources = [it.input]
        if options.get("mode") == "transfer":
            lm = landmarks_for(it.input)
            sources += [lm] if lm else []
        newest_in = max(os.stat(s).st_mtime_ns for s in sources)
        oldest_out = min(os.stat(t).st_mtime_ns for t in targets)
        if recorded is None:
            why = "its outputs exist but were not written by autobones batch"
        elif recorded != h:
            why = "its outputs were made with other options or another autobones version"
        elif oldest_out < newest_in:
            why = "its outputs are older than the input"
        elif renamed:
            return "run", (f"renamed: an older batch named it {os.path.basename(old)}; rigged again as "
                           f"{os.path.basename(it.output)}"), stale
        else:
            return "skip", "up to date", ()
    if force:
        return "run", f"overwritten: {why}", stale
    return "fail", f"{it.rel}: {why}; pass --force to overwrite", ()


def _recorded_hash(sidecar):
    try:
        return read_json(sidecar, "sidecar").get("batch", {}).get("options_hash")
    except (OSError, ValueError, AttributeError, AutobonesError):  # unreadable: not ours, so never skipped
        return None


def clean_stale_temps(out):
    """Remove what an interrupted run left behind: Rig.save's ``.autobones-*`` temporaries, the
    backups of a group rename (``*.autobones-old``) and a half-written report. ``.partial`` folders are kept: they mark files to redo."""
    for root, dirs, files in os.walk(out):
        dirs[:] = [d for d in dirs if not d.endswith(PARTIAL_SUFFIX)]
        for name in files:
            if (name.startswith(".autobones-") or name.startswith(".batch_report-")
                    or (name.startswith(".") and name.endswith(BACKUP_SUFFIX))):
                try:
                    os.unlink(os.path.join(root, name))
                except OSError:
                    pass
