"""What ``autobones view PATH`` shows: one rig, or a batch output folder, read (never written) as JSON facts.

Beyond the seeds (issue #17): the viewer reads what ``place``, ``transfer`` and ``batch`` write. A rig is
``x.rig.glb`` (or any ``x.glb``) with ``x.rig.json`` and ``x.weights.npz`` beside it
(:mod:`autobones.io.rig_files`); a batch folder is what ``autobones batch`` writes, ``batch_report.json``
and the rigs under it, ``NAME.rig.glb`` (``NAME.glb`` from batches before that name;
:mod:`autobones.batch.report`). Everything here returns plain dicts and lists ready for JSON; paths in
them are relative to the folder served, '/'-separated. Coordinates are the rig's input frame and units.
"""
from __future__ import annotations

import json
import os
import struct
import zipfile
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from ..batch.report import REPORT_FORMAT, REPORT_NAME, STATUSES
from ..errors import AutobonesError
from ..geometry.ring import RING_KINDS
from ..io.files import read_json, shown as shown_name
from ..io.rig_files import load_rig
from ..orient import Frame, close_front
from ..rig import SIDECAR_FORMAT, sidecar_paths



@dataclass
class Site:
    """The folder served and what its page shows.

    Attributes
    ----------
    root : str
        Real path of the folder served; nothing outside it is read.
    mode : str
        ``'rig'`` (one rig) or ``'batch'`` (a folder of rigs, with or without a batch report).
    rig : str or None
        ``'rig'`` mode: the rig's glb, relative to ``root``.
    report : dict or None
        ``'batch'`` mode: the parsed ``batch_report.json`` (None when the folder has none).
    rigs : list of str
        ``'batch'`` mode without a report: every autobones glb found under ``root``.
    briefs : dict
        Cache of what each batch card shows from its rig's sidecar (:func:`batch_listing`).
    """

    root: str
    mode: str
    rig: Optional[str] = None
    report: Optional[dict] = None
    rigs: list = field(default_factory=list)
    briefs: dict = field(default_factory=dict, repr=False)  # glb -> (file sizes and times, card facts)


def open_site(path):
    """The :class:`Site` of ``path``: an autobones ``.glb`` (with its sidecars) or a folder of rigs.

    Raises
    ------
    AutobonesError
        ``path`` does not exist; a file that is not a rig written by autobones (or whose sidecars
        are missing or do not match); a folder with no batch report and no autobones rig under it;
        an unreadable batch report.
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise AutobonesError(f"{path}: no such file or folder (give a rig .glb or a batch output folder)")
    real = os.path.realpath(path)
    if os.path.isfile(real):
        if not real.lower().endswith(".glb"):
            raise AutobonesError(f"{path}: not a .glb; give a rig written by autobones (x.glb with x.rig.json "
                                 "and x.weights.npz beside it) or a batch output folder")
        load_rig(real)  # the same checks as everywhere: autobones glb, sidecars present and matching
        return Site(root=os.path.dirname(real), mode="rig", rig=os.path.basename(real))
    report = _read_report(real, path)
    rigs = [] if report is not None else find_rigs(real)
    if report is None and not rigs:
        raise AutobonesError(f"{path}: no {REPORT_NAME} and no rig written by autobones in this folder; give a "
                             "folder written by `autobones batch` or a rig .glb")
    if report is not None and not report["files"]:
        raise AutobonesError(f"{path}: its {REPORT_NAME} lists no files; nothing to show")
    return Site(root=real, mode="batch", report=report, rigs=rigs)


def _read_report(root, shown):
    p = os.path.join(root, REPORT_NAME)
    if not os.path.isfile(p):
        return None
    try:
        rep = read_json(p, "sidecar", "batch report")  # a regular file, bounded in size and depth
        if not isinstance(rep, dict) or rep.get("format") != REPORT_FORMAT or not isinstance(rep.get("files"), list):
            raise ValueError(f"format {rep.get('format') if isinstance(rep, dict) else None!r}, "
                             f"expected {REPORT_FORMAT!r}")
    except AutobonesError as exc:  # named as the folder was given
        raise AutobonesError(f"{os.path.join(shown, REPORT_NAME)}: "
                             f"{str(exc).removeprefix(shown_name(p) + ': ')}") from None
    except (OSError, ValueError) as exc:
        raise AutobonesError(f"{os.path.join(shown, REPORT_NAME)}: not a readable batch report "
                             f"({type(exc).__name__}: {exc})") from None
    return rep


def glb_generator(path):
    """The ``asset.generator`` of a binary glTF file, reading only its header and JSON chunk.

    Returns None when the file is not a readable glb (a listing must not fail on one bad file).
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(20)
            if len(head) < 20 or head[:4] != b"glTF":
                return None
            length, kind = struct.unpack_from("<I4s", head, 12)
            if kind != b"JSON" or length > 64 << 20:
                return None
            doc = json.loads(fh.read(length))
        return (doc.get("asset") or {}).get("generator")
    except (OSError, ValueError, AttributeError, struct.error, RecursionError):  # nested 100k deep: not a rig
        return None


def find_rigs(root):
    """Every glb written by autobones under ``root`` (recursively, hidden names skipped), relative, sorted.

    ``x.glb`` and ``x.rig.glb`` share the sidecars ``x.rig.json`` and ``x.weights.npz``: with both
    there (an older batch's name beside the one batches write now), only ``x.rig.glb`` is listed.
    """
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        names = set(files)
        for name in sorted(files):
            if name.startswith(".") or not name.lower().endswith(".glb"):
                continue
            p = os.path.join(folder, name)
            if not name.lower().endswith(".rig.glb") and name[:-4] + ".rig.glb" in names \
                    and glb_generator(os.path.join(folder, name[:-4] + ".rig.glb")) == "autobones":
                continue  # x.glb beside x.rig.glb: the sidecars are the newer rig's
            if glb_generator(p) == "autobones":
                found.append(os.path.relpath(p, root).replace(os.sep, "/"))
    return found


def read_sidecar(glb_path):
    """The ``.rig.json`` sidecar of ``glb_path`` as a dict; AutobonesError when missing or unreadable."""
    json_path = sidecar_paths(glb_path)[0]
    try:
        meta = read_json(json_path, "sidecar")  # a regular file, bounded in size and depth
    except AutobonesError as exc:  # named as the listing names it, by the file's base name
        raise AutobonesError(f"{os.path.basename(json_path)}: cannot read the sidecar "
                             f"({str(exc).removeprefix(shown_name(json_path) + ': ')})") from None
    except (OSError, ValueError) as exc:
        raise AutobonesError(f"{os.path.basename(json_path)}: cannot read the sidecar ({type(exc).__name__}: "
                             f"{exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != SIDECAR_FORMAT:
        raise AutobonesError(f"{os.path.basename(json_path)}: not an autobones sidecar")
    return meta


def rig_warnings(meta, record=None):
    """What a reviewer should look at in a rig: a list of ``{"kind", "text"}``.

    Only what the rig files or the batch record say, no thresholds of our own: landmarks dropped
    or flagged by the automatic detector, morph targets not written, ARKit shapes whose triangles
    turn over (the sidecar's ``arkit.flipped_triangles``, which ``transfer`` also logs as a warning),
    a front told from the back by a small margin (the sidecar's ``frame.front_check``, which ``place``
    logs), and a ``warnings`` list in the batch record when a newer batch writes one (each kind once).
    """
    out = []
    meta = meta or {}
    if meta.get("landmarks_dropped"):
        out.append({"kind": "landmarks dropped",
                    "text": "landmarks dropped as unreliable: " + ", ".join(map(str, meta["landmarks_dropped"]))})
    if meta.get("landmarks_flagged"):
        out.append({"kind": "landmarks flagged",
                    "text": "landmarks to check: " + ", ".join(map(str, meta["landmarks_flagged"]))})
    skipped = (meta.get("expressions") or {}).get("morph_targets_skipped")
    if skipped:
        out.append({"kind": "morph targets skipped",
                    "text": "morph targets not written: " + ", ".join(map(str, skipped))})
    flipped = (meta.get("arkit") or {}).get("flipped_triangles")
    if isinstance(flipped, dict) and any(flipped.values()):
        bad = ", ".join(f"{k} ({v})" for k, v in flipped.items() if v)
        out.append({"kind": "ARKit triangles turned over",
                    "text": f"ARKit shapes with triangles turned over at weight 1: {bad}"})
    close = _close_front(meta.get("frame"))
    if close:
        out.append({"kind": "front a close call", "text": close})
    for w in (record or {}).get("warnings") or []:
        if isinstance(w, dict):
            if w.get("kind") == "front a close call" and close:
                continue   # the batch record repeats what the sidecar keeps
            out.append({"kind": str(w.get("kind", "warning")), "text": str(w.get("text", w))})
        else:
            out.append({"kind": str(w).split(":")[0][:40], "text": str(w)})
    return out


def _close_front(frame):
    """:func:`autobones.orient.close_front` of a sidecar's ``frame`` dict, or None (a clear front, none
    recorded, or a frame that does not read)."""
    if not isinstance(frame, dict) or not (frame.get("front_check") or {}).get("close"):
        return None
    try:
        return close_front(Frame.from_dict(frame))
    except (KeyError, TypeError, ValueError):
        return None


def rig_facts(root, rel, record=None):
    """Everything the rig page shows beside the 3-D view, from the sidecar (and the batch record).

    Parameters
    ----------
    root : str
        The folder served.
    rel : str
        The rig's glb, relative to ``root``.
    record : dict or None
        The rig's record in the batch report, for its status, timings and seconds.

    Returns
    -------
    dict
        ``path``, ``source``, ``command``, ``vertices``, ``bones`` (name, parent, head, tail),
        ``frame`` (up, front, rotation (3, 3) rows = canonical +X, +Y, +Z in the input frame, origin,
        head_size, symmetry_error), ``muscles`` (name, type, kind, origin, insertion, ``segments``:
        (s, 2, 3) rest-pose line segments picturing it, the file's frame), ``landmarks``
        ({name: [x, y, z]}), ``landmarks_source``, ``morph_targets`` (names and labels), ``options``,
        ``status``, ``seconds``, ``timings`` (seconds per stage; only batch records keep them),
        ``warnings`` (:func:`rig_warnings`).
    """
    glb = os.path.join(root, rel)
    meta = read_sidecar(glb)
    opts = meta.get("options") or {}
    record = record or {}
    morphs = (meta.get("expressions") or {}).get("morph_targets") or []
    return {
        "path": rel,
        "source": meta.get("source"),
        "command": opts.get("command"),
        "autobones_version": meta.get("autobones_version"),
        "vertices": meta.get("vertex_count"),
        "bones": [{"name": b["name"], "parent": b.get("parent"), "head": b.get("head"), "tail": b.get("tail")}
                  for b in meta.get("bones") or []],
        "frame": meta.get("frame"),
        "muscles": _muscles(meta),
        "landmarks": meta.get("landmarks") or {},
        "landmarks_source": opts.get("landmarks_source"),
        "reliable_fraction": meta.get("reliable_fraction"),
        "morph_targets": [{"name": m.get("name"), "label": m.get("label")} for m in morphs],
        "options": opts,
        "status": record.get("status"),
        "input": record.get("input"),
        "seconds": record.get("seconds"),
        "timings": record.get("timings") or {},
        "warnings": rig_warnings(meta, record),
    }


def _muscles(meta):
    """The sidecar's muscles for the page: name, type, kind, origin, insertion and ``segments``, the
    rest-pose lines that picture each (:func:`autobones.render.muscle_segments`: a linear muscle's
    origin -> insertion, a sphincter's ring, a sheet's outline) in the file's frame. A muscle whose
    ellipse cannot be drawn from the sidecar (no frame, a malformed reach) is pictured by its two ends."""
    from ..render import muscle_segments

    try:
        frame = Frame.from_dict(meta.get("frame"))
    except (KeyError, TypeError, ValueError):
        frame = None
    out = []
    for m in meta.get("muscles") or []:
        ends = [m.get("origin"), m.get("insertion")]
        seg = [ends] if all(e is not None for e in ends) else []
        if frame is not None and m.get("kind") in RING_KINDS and seg:
            try:
                S = muscle_segments([m], to_frame=frame.to_canonical)
                seg = frame.from_canonical(S.reshape(-1, 3)).reshape(-1, 2, 3).tolist()
            except (AutobonesError, KeyError, TypeError, ValueError):
                pass
        out.append({"name": m.get("name"), "type": m.get("type"), "kind": m.get("kind", "linear"),
                    "origin": m.get("origin"), "insertion": m.get("insertion"), "segments": seg})
    return out


def batch_listing(site):
    """The batch page's data: the report's summary and one entry per file.

    Returns
    -------
    dict
        ``summary`` (counts per status, seconds, finished, engine, options; None without a report)
        and ``files``: each with ``input``, ``output`` (the glb, relative to the folder), ``status``
        ('ok', 'failed', 'skipped'), ``error`` (one line), ``reason``, ``seconds``, ``vertices``,
        ``bones``, ``landmarks``, ``viewable`` (the glb and its sidecar exist), ``warnings``.
    """
    if site.report is None:
        records = [{"input": None, "output": r, "status": "ok"} for r in site.rigs]
        summary = None
    else:
        rep = site.report
        records = [f for f in rep["files"] if isinstance(f, dict)]
        summary = {k: rep.get(k) for k in ("counts", "seconds", "finished", "engine", "jobs", "options",
                                           "autobones_version")}
    files = []
    for rec in records:
        out = str(rec.get("output") or "")
        entry = {k: rec.get(k) for k in ("input", "status", "error", "reason", "seconds", "vertices", "bones",
                                         "landmarks")}
        entry["output"] = out
        entry["status"] = entry["status"] if entry["status"] in STATUSES else "failed"
        glb = os.path.realpath(os.path.join(site.root, out)) if out else None
        inside = glb is not None and glb.startswith(site.root + os.sep)
        brief = _sidecar_brief(site, glb) if inside and entry["status"] != "failed" else None
        entry["viewable"] = brief is not None
        said = list(brief["warnings"]) if brief else []
        # the record's own (a close call on the front is in the sidecar too: said once)
        entry["warnings"] = said + [w for w in rig_warnings(None, rec) if w["kind"] not in {v["kind"] for v in said}]
        if entry["status"] != "failed" and brief is None:
            entry["warnings"].append({"kind": "rig files missing",
                                      "text": "the glb or its sidecar is missing or unreadable"})
        if brief is not None:
            entry["vertices"] = entry["vertices"] or brief["vertices"]
            entry["bones"] = entry["bones"] or brief["bones"]
            entry.update(source=brief["source"], morph_targets=brief["morph_targets"], muscles=brief["muscles"])
        files.append(entry)
    return {"summary": summary, "files": files}


def _sidecar_brief(site, glb):
    """What a batch card shows from one rig's sidecar, None when the glb or sidecar is missing or unreadable.

    Kept on the site by the files' sizes and times: a sidecar of a million-vertex rig is megabytes of
    JSON, and the batch page is read again each time the user comes back to it.
    """
    side = sidecar_paths(glb)[0]
    try:
        key = tuple((os.stat(p).st_size, os.stat(p).st_mtime_ns) for p in (glb, side))
    except OSError:
        return None
    hit = site.briefs.get(glb)
    if hit is not None and hit[0] == key:
        return hit[1]
    try:
        meta = read_sidecar(glb)
    except AutobonesError:
        return None
    brief = {"warnings": rig_warnings(meta), "vertices": meta.get("vertex_count"),
             "bones": len(meta.get("bones") or []), "source": meta.get("source"),
             "morph_targets": len((meta.get("expressions") or {}).get("morph_targets") or []),
             "muscles": len(meta.get("muscles") or [])}
    site.briefs[glb] = (key, brief)
    return brief


def batch_record(site, rel):
    """The batch report's record of the rig ``rel`` (relative glb path), or None."""
    if site.report is None:
        return None
    for rec in site.report["files"]:
        if isinstance(rec, dict) and rec.get("output") == rel:
            return rec
    return None


def bone_weights(glb_path, bone):
    """Column ``bone`` of the full weight matrix in ``x.weights.npz``: (n,) float32, every influence.

    The glb keeps only the 4 largest influences per vertex; this is the matrix the rig was made with.
    AutobonesError when the npz is missing or unreadable or has no such bone.
    """
    npz = sidecar_paths(glb_path)[1]
    try:
        with np.load(npz, allow_pickle=False) as z:
            names = [str(s) for s in z["bone_names"]]
            if bone not in names:
                raise AutobonesError(f"{os.path.basename(npz)}: no bone {bone!r} (bones: {', '.join(names[:8])}...)")
            return np.asarray(z["weights"][:, names.index(bone)], dtype=np.float32)
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        raise AutobonesError(f"{os.path.basename(npz)}: cannot read the weights ({type(exc).__name__}: {exc})") from None
