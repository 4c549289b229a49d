"""The per-file job of a batch: its options, its output names, and :func:`rig_one`."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import socket
import time
import traceback

from ..errors import AutobonesError
from ..io.atomic import replace_all
from ..orient import close_front

PARTIAL_SUFFIX = ".partial"

#: The glb's suffix, as ``place`` and ``transfer`` name theirs: ``INPUT/a/b.obj`` -> ``OUT/a/b.rig.glb``.
OUTPUT_SUFFIX = ".rig.glb"

#: Landmark files looked for beside ``NAME.ext`` in transfer mode, first found wins.
LANDMARK_SUFFIXES = (".landmarks.json", ".pp", ".pts", ".ljson")


# ---------------------------------------------------------------------------------------------
# options and naming

def make_options(transfer=False, density="medium", rig=None, random_state=0, expressions=False, arkit=False,
                 symmetric="auto", tissue=False, expression_fit=True):
    """The per-file options as a plain JSON-able dict (what :func:`rig_one` takes).

    ``density`` is ignored (None) for a transfer; ``rig`` is made absolute so the
    options mean the same thing on every worker. ``expressions`` (transfer only: True or
    ``"sides"``) adds AU morph targets to each glb (``Rig.save``); the key is present only
    when set, so other batches keep their options hash. ``arkit`` (transfer only) adds the 52
    ARKit shapes (``transfer(..., arkit=True)``), the same way, and so does ``symmetric`` (transfer
    only) when not ``"auto"`` (``transfer(..., symmetric=...)``). ``tissue`` (with ``expressions``)
    refines the morph targets by the layered tissue (``Rig.save(..., tissue=True)``), present only
    when set; ``expression_fit`` False (transfer only) fits the neutral generic skin
    (``transfer(..., expression_fit=False)``), present only when off.
    """
    from ..placement.facial_bones import DENSITIES, bone_count

    if transfer and tissue and not expressions:
        raise AutobonesError("--tissue refines the AU morph targets: add --expressions")
    if transfer:
        return {"mode": "transfer", "density": None,
                "rig": None if rig is None else os.path.abspath(os.fspath(rig)), "random_state": None,
                **({"expressions": expressions} if expressions else {}), **({"arkit": True} if arkit else {}),
                **({"symmetric": symmetric} if symmetric != "auto" else {}), **({"tissue": True} if tissue else {}),
                **({} if expression_fit else {"expression_fit": False})}
    if tissue:
        raise AutobonesError("--tissue refines the AU morph targets of a transfer: add --transfer --expressions")
    if not expression_fit:
        raise AutobonesError("--no-expression-fit chooses how a transfer's correspondence is fitted, which place "
                             "does not use; add --transfer")
    if symmetric != "auto":
        raise AutobonesError("--symmetric chooses how a transfer's correspondence is fitted, which place does not "
                             "use; add --transfer")
    if arkit:
        raise AutobonesError("--arkit needs landmarks and a transfer, which place does not use; add --transfer")
    if expressions:
        raise AutobonesError("--expressions needs muscles, which place does not make; add --transfer")
    if rig is not None:
        raise AutobonesError("--rig is only used with --transfer")
    n = bone_count(density)  # refuse a bad density once, before any file is touched
    named = isinstance(density, str) and density.strip().lower() in DENSITIES
    d = density.strip().lower() if named else n
    return {"mode": "place", "density": d, "rig": None, "random_state": int(random_state)}


def options_hash(options):
    """sha256 (16 hex digits) of the options and the autobones version: what makes outputs comparable."""
    from ..version import __version__

    text = json.dumps({"options": options, "autobones_version": __version__}, sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def output_for(rel):
    """The glb a mesh ``rel`` (relative to the input folder) is rigged into, relative to the output folder:
    ``a/b.obj`` -> ``a/b.rig.glb``, the name ``place`` and ``transfer`` give by default."""
    return os.path.splitext(rel)[0] + OUTPUT_SUFFIX


def legacy_output(glb_path):
    """``x.rig.glb`` -> ``x.glb``: the name batches before the ``.rig.glb`` rule gave the glb (same sidecars)."""
    glb_path = os.fspath(glb_path)
    return glb_path[:-len(OUTPUT_SUFFIX)] + ".glb" if glb_path.endswith(OUTPUT_SUFFIX) else None


def output_paths(glb_path):
    """``x.rig.glb`` -> (``x.rig.glb``, ``x.rig.json``, ``x.weights.npz``), as :meth:`Rig.save` names them."""
    from ..rig import sidecar_paths

    return (os.fspath(glb_path), *sidecar_paths(glb_path))


def landmarks_for(mesh_path):
    """The landmark file beside ``DIR/NAME.ext`` (``NAME.landmarks.json``, ``.pp``, ``.pts``,
    ``.ljson``; the first that exists), or None."""
    stem = os.path.splitext(os.fspath(mesh_path))[0]
    for suffix in LANDMARK_SUFFIXES:
        if os.path.isfile(stem + suffix):
            return stem + suffix
    return None


def partial_dir(glb_path):
    """The hidden folder ``DIR/.NAME.rig.glb.partial`` a job saves into before renaming its outputs."""
    folder, name = os.path.split(os.fspath(glb_path))
    return os.path.join(folder, f".{name}{PARTIAL_SUFFIX}")


def refuse_inside_input(paths, input_root, input_files=()):
    """AutobonesError when one of ``paths``, resolved (every symbolic link on the way, the last
    one included), lies inside the folder ``input_root`` or is one of ``input_files`` (resolved too).

    A link in the output tree (``OUT/sub -> INPUT/sub``, ``OUT/a.rig.glb -> INPUT/a.glb``) would
    otherwise put outputs, temporaries included, inside the input, or a rig over its own mesh.
    """
    root = os.path.realpath(os.fspath(input_root))
    files = {os.path.realpath(os.fspath(f)) for f in input_files}
    for path in paths:
        path = os.fspath(path)
        real = os.path.realpath(path)
        if real == root or real.startswith(root.rstrip(os.sep) + os.sep) or real in files:
            where = f"the input file {real}" if real in files else f"{real}, inside the input folder {root}"
            raise AutobonesError(f"{path}: resolves (through a symbolic link) to {where}; outputs are never "
                                 "written inside the input folder: remove the link or choose another output folder")


def one_line(text, limit=500):
    """``text`` with its whitespace runs made single spaces, cut to ``limit`` characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


# ---------------------------------------------------------------------------------------------
# the per-file job

def rig_one(input_path, output_path, options, input_root=None):
    """Rig one mesh and write its glb and sidecars atomically; never raises for a bad file.

    Parameters
    ----------
    input_path : str
        Mesh file (absolute, so workers elsewhere read the same file).
    output_path : str
        Target glb (``NAME.rig.glb`` in a batch); the sidecars go beside it. Parent folders are created.
    options : dict
        From :func:`make_options`: ``mode`` ('place' or 'transfer'), ``density``,
        ``rig``, ``random_state``. In transfer mode the landmarks are the file
        :func:`landmarks_for` finds beside the mesh.
    input_root : str, optional
        The batch's input folder: the outputs are resolved again just before they are
        written and refused if a symbolic link made since the plan leads them inside it.

    Returns
    -------
    dict
        ``input``, ``output``, ``status`` ('ok' or 'failed'), ``error`` (one line,
        None when ok), ``error_type``, ``seconds``, ``timings`` (per stage),
        ``vertices``, ``bones``, ``options_hash``, ``landmarks``, ``host``, ``pid``;
        ``traceback`` for an unexpected exception (a bug, not a bad file).

    The result depends only on the arguments and the files' contents: BLAS runs on
    one thread in every engine so a rig is the same bit for bit wherever it is made.
    """
    t0 = time.perf_counter()
    h = options_hash(options)
    record = {"input": input_path, "output": output_path, "status": "failed", "error": None,
              "error_type": None, "seconds": 0.0, "timings": {}, "vertices": None, "bones": None,
              "options_hash": h, "landmarks": None, "host": socket.gethostname(), "pid": os.getpid()}
    partial = partial_dir(output_path)
    try:
        for target in output_paths(output_path):  # before the work: a folder in the way names itself
            if os.path.isdir(target):
                raise AutobonesError(f"{target}: a folder of that name is in the way of the rig; move it")
        with _one_blas_thread():
            rig = _make_rig(input_path, options, record)
        close = close_front(rig.frame)
        if close:   # a front told from the back by a small margin: the rig to look at among hundreds
            record.setdefault("warnings", []).append({"kind": "front a close call", "text": close})
        rig.batch = {"options": options, "options_hash": h}
        _save_atomically(rig, output_path, partial, options.get("expressions", False), options.get("tissue", False),
                         input_root)
        record.update(status="ok", timings={k: round(float(v), 4) for k, v in rig.timings.items()},
                      vertices=int(len(rig.vertices)), bones=int(len(rig.skeleton)))
    except AutobonesError as exc:
        record.update(error=one_line(str(exc)), error_type="AutobonesError")
    except Exception as exc:  # a batch never dies on one file: record the bug and go on
        record.update(error=one_line(f"{type(exc).__name__}: {exc}"), error_type=type(exc).__name__,
                      traceback=traceback.format_exc())
    finally:
        if os.path.isdir(partial):
            shutil.rmtree(partial, ignore_errors=True)
    record["seconds"] = round(time.perf_counter() - t0, 4)
    return record


def _make_rig(input_path, options, record):
    import autobones

    mode = options.get("mode")
    if mode == "place":
        return autobones.place(input_path, density=options["density"], random_state=options["random_state"])
    if mode == "transfer":
        # a mesh without a landmark file beside it gets automatic landmarks (human faces)
        lm = landmarks_for(input_path)
        if lm is not None:
            record["landmarks"] = lm
        rig = autobones.transfer(input_path, lm, rig=options.get("rig"), arkit=bool(options.get("arkit")),
                                 symmetric=options.get("symmetric", "auto"),
                                 expression_fit=options.get("expression_fit", True))
        if lm is None:  # only once they were found: a file that failed to load had none detected
            record["landmarks"] = "detected"
        return rig
    raise AutobonesError(f"unknown batch mode {mode!r}; use 'place' or 'transfer'")


class _one_blas_thread:
    def __enter__(self):
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:  # without it, the engines' own settings apply
            self._limits = None
        else:
            self._limits = threadpool_limits(limits=1)
        return self

    def __exit__(self, *exc):
        if self._limits is not None:
            self._limits.restore_original_limits()
        return False


def _save_atomically(rig, output_path, partial, expressions=False, tissue=False, input_root=None):
    """Save into ``partial``, then rename glb, npz and last the sidecar (the commit mark) into place."""
    from .workers import dask_task_cancelled, exit_if_orphaned

    folder = os.path.dirname(os.path.abspath(output_path))
    if input_root is not None:  # the plan checked; a link made since must not lead us into the input
        refuse_inside_input((partial, *output_paths(output_path)), input_root)
    try:
        os.makedirs(folder, exist_ok=True)
        if os.path.isdir(partial):
            shutil.rmtree(partial)
        os.mkdir(partial)
    except OSError as exc:
        raise AutobonesError(f"{output_path}: cannot create the output folder ({exc.strerror or exc})") from exc
    staged = rig.save(os.path.join(partial, os.path.basename(output_path)), expressions=expressions, tissue=tissue)
    glb, js, npz = output_paths(output_path)
    # all three or none (a failed rename puts back what was there), the sidecar last: it marks the file done;
    # never by an orphan: a worker whose batch was killed leaves the .partial folder for the next run
    exit_if_orphaned()
    if dask_task_cancelled():
        raise AutobonesError(f"{output_path}: the batch that asked for this file is gone (the Dask task was "
                             "cancelled); nothing renamed")
    replace_all(((staged[0], glb), (staged[2], npz), (staged[1], js)), "the rig")
    try:
        os.rmdir(partial)
    except OSError as exc:
        raise AutobonesError(f"{output_path}: cannot write ({exc.strerror or exc})") from exc
