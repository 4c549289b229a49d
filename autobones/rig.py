"""The Rig: a mesh with its skeleton, skin weights and labels, and how it is saved."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Optional

import numpy as np

from .errors import AutobonesError
from .io.atomic import check_destination, replace_all, temp_beside
from .io.jsonable import strict_dumps
from .io.gltf import write_glb
from .placement.segment import LABEL_NAMES
from .skeleton import Skeleton


def sidecar_paths(glb_path):
    """``x.glb`` or ``x.rig.glb`` -> (``x.rig.json``, ``x.weights.npz``)."""
    base = os.fspath(glb_path)
    if base.lower().endswith(".glb"):
        base = base[:-4]
    if base.endswith(".rig"):
        base = base[:-4]
    return base + ".rig.json", base + ".weights.npz"


def rig_outputs(path):
    """The three files :meth:`Rig.save` writes for ``path``: the glb and its sidecars
    (:func:`sidecar_paths`); AutobonesError when ``path`` does not name a .glb."""
    if not path.lower().endswith(".glb"):
        raise AutobonesError(f"{path}: the output must be a .glb file")
    return [path, *sidecar_paths(path)]


# what a ``.rig.json`` says it is (``format``); readers refuse anything else
SIDECAR_FORMAT = "autobones-rig/1"
# largest ARKit shape weight ``pose`` takes: ARKit's range is 0..1, an animator may overdrive a shape
# (1.5); a negative weight turns a shape inside out (jawOpen=-5 sank the chin into the skull)
ARKIT_MAX_WEIGHT = 2.0

# Sidecar keys beyond the Rig's own (bones, labels, frame...), in the order they are written:
# one order for every pipeline, so the JSON text does not depend on which one filled them
# (keys of ``Rig.other`` go just before ``expressions``, which ``save`` writes last).
SIDECAR_KEYS = ("source", "muscles", "landmarks", "landmark_confidence", "landmarks_dropped", "landmarks_flagged",
                "field_labels", "reliable_fraction", "facial_bone_partner", "neck_height_canonical", "batch",
                "arkit", "expressions")


def sidecar_attributes(doc):
    """Sidecar keys beyond the Rig's own -> keyword arguments of :class:`Rig`.

    ``doc`` is a dict holding some of :data:`SIDECAR_KEYS` (JSON values: lists, dicts,
    numbers); ``landmarks`` become (3,) float64 arrays, anything else is kept as given and
    keys the Rig does not know go to ``other`` (a newer version's sidecar survives a round trip).
    """
    kwargs = {k: doc[k] for k in SIDECAR_KEYS if k in doc}
    if kwargs.get("landmarks") is not None:
        kwargs["landmarks"] = {n: np.asarray(v, dtype=np.float64) for n, v in kwargs["landmarks"].items()}
    other = {k: v for k, v in doc.items() if k not in SIDECAR_KEYS}
    if other:
        kwargs["other"] = other
    return kwargs


@dataclass
class Rig:
    """A rigged head, everything in the input mesh's own frame and units.

    Attributes
    ----------
    vertices : (n, 3) float
        The input vertices, unchanged and in input order.
    faces : (m, 3) int
        The input triangles.
    skeleton : Skeleton
        Bones (``neck``, ``head``, ``face_00``...).
    weights : (n, b) float
        Skin weights, rows summing to 1, columns in skeleton order.
    labels : (n,) int8
        Depth group per vertex: 0 face, 1 middle, 2 back.
    facial_mask : (n,) bool
        Vertices the facial bones were clustered on.
    frame : orient.Frame
        Detected (or given) canonical frame.
    options : dict
        Options the rig was made with.
    timings : dict
        Seconds per pipeline stage.
    segmentation : segment.HeadSegmentation or None
        The depth grouping with its full merge tree: ``rig.segmentation.groups(4)``
        cuts it at another group count (the bone-placement method of ``place``: average-linkage
        grouping, k-means facial bones).
    fields : dict of str -> (n,) or (n, k) array
        Attribute fields carried onto the vertices (``transfer``); saved in the npz
        as ``field/<name>``.
    source : str or None
        Base name of the input file (None for arrays); written to the sidecar always.

    The attributes below are None when the pipeline that made the rig has none (then the
    sidecar has no such key); each is saved under its own name in the sidecar.

    muscles : list of dict or None
        ``transfer``: each with ``name``, ``type``, ``side``, ``origin`` and ``insertion``
        (3-lists, input frame and units), ``width`` (mesh units), ``width_canonical``
        (head sizes) and the definition's other keys (JSON values).
    landmarks : dict str -> (3,) float64 or None
        ``transfer``: the head's validated landmarks, input frame and units.
    landmark_confidence : dict str -> float or None
        Automatic landmarks: confidence in [0, 1] per name.
    landmarks_dropped, landmarks_flagged : list of str or None
        Automatic landmarks: names dropped as unreliable; names the refinement flagged.
    field_labels : dict str -> list of str or None
        Class names of the integer fields: ``fields[name] == i`` means ``field_labels[name][i]``.
    reliable_fraction : float or None
        ``transfer``: fraction of the head's vertices that copied their fields (the rest were inpainted).
    facial_bone_partner : list of int or None
        ``place``: index of each facial bone's mirror partner (-1: on the midline).
    neck_height_canonical : float or None
        ``place`` without landmarks: height of the neck cut in the canonical frame (head sizes).
    batch : dict or None
        ``autobones batch``: ``{"options": ..., "options_hash": ...}``.
    arkit : dict or None
        The ARKit shape record (``transfer(..., arkit=True)``; :func:`autobones.arkit.targets.arkit_targets`):
        names, source, method, per-shape triangles turned over at weight 1.
    expressions : dict or None
        A loaded rig's expression record (:meth:`expression_record`; ``definitions`` inside).
    arkit_targets : dict str -> (n, 3) float or None
        The 52 ARKit displacement fields (input frame and units), written as glTF morph targets
        named as ARKit does and read back from the glb by ``load_rig``; not in the sidecar.
    other : dict
        Sidecar keys of a loaded rig that this version does not know, written back unchanged.
    """

    vertices: np.ndarray
    faces: np.ndarray
    skeleton: Skeleton
    weights: np.ndarray
    labels: np.ndarray
    facial_mask: np.ndarray
    frame: object
    options: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    segmentation: object = None
    fields: dict = field(default_factory=dict)
    source: Optional[str] = None
    muscles: Optional[list] = None
    landmarks: Optional[dict] = None
    landmark_confidence: Optional[dict] = None
    landmarks_dropped: Optional[list] = None
    landmarks_flagged: Optional[list] = None
    field_labels: Optional[dict] = None
    reliable_fraction: Optional[float] = None
    facial_bone_partner: Optional[list] = None
    neck_height_canonical: Optional[float] = None
    batch: Optional[dict] = None
    arkit: Optional[dict] = None
    expressions: Optional[dict] = None
    arkit_targets: Optional[dict] = None
    other: dict = field(default_factory=dict)

    def sidecar_extra(self):
        """The sidecar's keys beyond the Rig's own, as JSON values (:data:`SIDECAR_KEYS` order)."""
        out = {"source": self.source}
        for key in SIDECAR_KEYS[1:-1]:
            value = getattr(self, key)
            if value is not None:
                out[key] = value
        if self.landmarks is not None:
            out["landmarks"] = {n: np.asarray(v).tolist() for n, v in self.landmarks.items()}
        out.update(self.other)
        if self.expressions is not None:  # last, where ``save`` puts a new record
            out["expressions"] = self.expressions
        return out

    @property
    def extra(self):
        """Read-only view of :meth:`sidecar_extra` (older code read ``rig.extra['muscles']``;
        use the attributes: ``rig.muscles``, ``rig.landmarks``, ``rig.field_labels``...)."""
        return MappingProxyType(self.sidecar_extra())

    def sidecar(self):
        """The JSON sidecar as a dict."""
        from .version import __version__

        return {
            "format": SIDECAR_FORMAT,
            "autobones_version": __version__,
            "options": self.options,
            "frame": self.frame.to_dict(),
            "vertex_count": int(len(self.vertices)),
            "bones": self.skeleton.to_list(),
            "label_names": list(LABEL_NAMES),
            "labels": self.labels.astype(int).tolist(),
            "facial_mask": np.flatnonzero(self.facial_mask).tolist(),
            **({} if self.segmentation is None else {
                # the last merges of the depth tree: a large jump before a count says that
                # many groups are natural for this head
                "depth_merge_distances": self.segmentation.linkage[-8:, 2][::-1].tolist()}),
            **self.sidecar_extra(),
        }

    def muscle_markers(self):
        """glTF marker nodes for the muscles: origins ride the skull (``head``), insertions the
        bone that dominates the skin where they attach."""
        muscles = self.muscles or []
        if not muscles:
            return []
        from scipy.spatial import cKDTree

        names = self.skeleton.names
        skull = "head" if "head" in names else names[0]
        ins = np.array([m["insertion"] for m in muscles], dtype=np.float64)
        _, nearest = cKDTree(self.vertices).query(ins)
        out = []
        for m, v in zip(muscles, nearest):
            out.append((f"muscle/{m['name']}/origin", skull, m["origin"]))
            out.append((f"muscle/{m['name']}/insertion", names[int(np.argmax(self.weights[v]))], m["insertion"]))
        return out

    def expression_model(self, definitions=None):
        """The :class:`autobones.expressions.ExpressionModel` of this rig (built on first use and
        kept; needs the muscles of ``transfer``). ``definitions`` (path or dict) builds it again with
        those; ``pose`` and ``save`` then use it. None: the model already built, else one with the
        definitions a loaded rig's sidecar kept (``expressions['definitions']``), else
        ``generic_rig/expressions.json``."""
        from .expressions.model import ExpressionModel

        cached = self.__dict__.get("_expression_model")
        if definitions is None:
            if cached is not None:
                return cached
            definitions = (self.expressions or {}).get("definitions")
        if cached is None or cached.definitions is not definitions:
            cached = ExpressionModel(definitions).fit(self)
            self.__dict__["_expression_model"] = cached
        return cached

    def pose(self, au=None, expression=None, muscles=None, jaw_deg=0.0, eyelids=None, gaze=None, look_at=None,
             head_deg=None, neck_deg=None, arkit=None, tissue=False, layer="auto"):
        """Posed vertices (n, 3), input frame and units: FACS action units (``au={12: 0.8}``,
        ``"12L"`` for one side), an emotion (``expression="happiness"``), muscle contractions,
        jaw opening in degrees, eyelids, eye gaze and head/neck rotations; see
        :meth:`autobones.expressions.ExpressionModel.pose`. All zero: the vertices, exactly.

        ``arkit={"jawOpen": 0.6}``: ARKit shape weights (rigs made with ``arkit=True``). Their
        displacements add on top of everything else, unrotated: alone they give exactly what a
        glTF player gives (rest + sum of weight x target); mixed with AUs, the jaw or head/eye
        turns, both act and nothing wins (an AU jaw opening plus ``jawOpen`` opens twice; glTF
        players would also turn the targets with the bones).

        ``layer``: what poses the AUs the definitions' ``au_arkit`` table maps (AU12 -> mouthSmile,
        AU26/27 -> jawOpen, ...; emotions expand to their AUs first). ``"shapes"``: the head's own ARKit
        shapes (:mod:`autobones.expressions.au_shapes`: each mapped shape at the AU's intensity, ``"12L"``
        only the subject's left shape, AUs sharing a shape take the largest, not the sum; added unturned
        by head/neck and without the tissue pass); AutobonesError on a rig without ARKit shapes.
        ``"muscles"``: the muscle model, exactly as before the layer existed. ``"auto"`` (default):
        shapes where the rig has them, else muscles. Unmapped AUs, muscles, jaw, eyelids, gaze,
        head/neck and tissue always use the muscle model.

        A rig without muscles (``place``'s) poses ``head_deg`` and ``neck_deg`` alone, by its bones
        (:meth:`turn_bones`); anything else raises AutobonesError.

        ``tissue=True``: the skin refined by the layered soft tissue's equilibrium (Lee,
        Terzopoulos & Waters 1995; :mod:`autobones.expressions.tissue`): skin over shortening
        muscles bulges, the tissue keeps its volume and stays off the skull.

        Examples
        --------
        >>> import numpy as np
        >>> import autobones
        >>> from autobones import samples
        >>> rig = autobones.transfer(samples.path("robot.obj"), samples.path("robot.landmarks.json"), arkit=True)
        >>> smile = rig.pose(au={12: 0.8, 6: 0.4}, jaw_deg=10)
        >>> smile.shape == rig.vertices.shape, bool(np.abs(smile - rig.vertices).max() > 0)
        (True, True)
        >>> np.array_equal(rig.pose(), rig.vertices)     # all zero: the vertices, exactly
        True
        >>> blink = rig.pose(arkit={"eyeBlinkLeft": 1.0})
        >>> rig.pose(expression="hapiness")
        Traceback (most recent call last):
        ...
        autobones.errors.AutobonesError: unknown expression 'hapiness'; known: surprise, fear, happiness, sadness, disgust, anger
        """
        from .expressions import au_shapes

        offset = self.arkit_offset(arkit)
        if au_shapes.resolve_layer(layer, bool(self.arkit_targets)) == "shapes" and (au or expression):
            doc = self._expression_definitions()
            weights, rest = au_shapes.split_mix(au_shapes.au_mix(au, expression, doc["expressions"]),
                                                au_shapes.table_of(doc), self.arkit_targets)
            au, expression = rest or None, None
            if weights:
                shapes = au_shapes.shape_displacement(weights, self.arkit_targets, len(self.vertices))
                offset = shapes if offset is None else offset + shapes
        only_arkit = (au is None and expression is None and muscles is None and not jaw_deg and eyelids is None
                      and gaze is None and look_at is None and head_deg is None and neck_deg is None)
        if offset is not None and only_arkit:  # no model needed (a rig without muscles poses too)
            base = np.asarray(self.vertices, dtype=np.float64)
        elif not self.muscles and self.only_turns(au, expression, muscles, jaw_deg, eyelids, gaze, look_at, tissue):
            base = self.turn_bones(head_deg, neck_deg)   # a `place` rig: its bones, no skin/muscle model
        else:
            base = self.expression_model().pose(au=au, expression=expression, muscles=muscles, jaw_deg=jaw_deg,
                                                eyelids=eyelids, gaze=gaze, look_at=look_at, head_deg=head_deg,
                                                neck_deg=neck_deg, tissue=tissue)
        return base if offset is None else base + offset

    @staticmethod
    def only_turns(au, expression, muscles, jaw_deg, eyelids, gaze, look_at, tissue):
        """True when no control of :meth:`pose` but the head and neck turns is given: what a rig without
        muscles can pose (:meth:`turn_bones`)."""
        return (au is None and expression is None and muscles is None and not jaw_deg and eyelids is None
                and gaze is None and look_at is None and not tissue)

    def turn_bones(self, head_deg=None, neck_deg=None, axes=None):
        """Vertices (n, 3), input frame and units, with the ``head`` and ``neck`` bones turned by
        (pitch, yaw, roll) degrees about the head's left, up and front (:attr:`autobones.orient.Frame.turn_axes`:
        a ``transfer`` rig's landmarks' anatomical axes) at their joints and every bone under them carried
        along, by linear blend skinning with the rig's own weights (what a glTF player does): how any rig,
        ``place``'s included, turns. All zero: the vertices, exactly. ``axes``: (3, 3) rows left, up,
        front the angles are about instead."""
        from .expressions.bones import blend_bones, bone_transforms

        R = self.frame.turn_axes if axes is None else np.asarray(axes, dtype=np.float64)
        origin, size = self.frame.origin, self.frame.size
        V = np.asarray(self.vertices, dtype=np.float64)
        C = (V - origin) @ R.T / size
        pivots = (np.asarray(self.skeleton.heads, dtype=np.float64) - origin) @ R.T / size
        moves = bone_transforms(list(self.skeleton.names), pivots, 0.0, None, None, head_deg, neck_deg,
                                parents=list(self.skeleton.parents))
        if not moves:
            return V.copy()
        d = blend_bones(np.zeros_like(C), C, np.asarray(self.weights, dtype=np.float64), moves)
        return (C + d) * size @ R + origin

    def _expression_definitions(self):
        """The definitions ``pose`` uses: the built model's, else the sidecar's, else the packaged ones."""
        from .expressions.definitions import load_expressions

        model = self.__dict__.get("_expression_model")
        return model.doc_ if model is not None else load_expressions((self.expressions or {}).get("definitions"))

    def arkit_offset(self, weights):
        """Sum of ``weight * target`` (n, 3) of the ARKit shapes ``weights`` (dict name -> float in
        [0, :data:`ARKIT_MAX_WEIGHT`]), or None when there are none; AutobonesError for a name the rig
        has no target for or a weight outside that range."""
        if weights is None or (isinstance(weights, dict) and not weights):
            return None
        if not isinstance(weights, dict):
            raise AutobonesError(f"arkit: expected a dict shape name -> weight, not {type(weights).__name__}")
        targets = self.arkit_targets or {}
        if not targets:
            raise AutobonesError("this rig has no ARKit shapes; make it with autobones transfer HEAD --arkit "
                                 "(or autobones.transfer(..., arkit=True))")
        out = np.zeros((len(self.vertices), 3))
        for name, w in weights.items():
            if name not in targets:
                close = [n for n in targets if n.lower() == str(name).lower()]
                raise AutobonesError(f"unknown ARKit shape {name!r}"
                                     + (f" (did you mean {close[0]!r}?)" if close else
                                        f"; the rig has {', '.join(list(targets)[:6])}, ... ({len(targets)})"))
            try:
                w = float(w)
            except (TypeError, ValueError):
                raise AutobonesError(f"ARKit shape {name}: weight {w!r} is not a number") from None
            if not np.isfinite(w):
                raise AutobonesError(f"ARKit shape {name}: weight {w} is not finite")
            if not 0.0 <= w <= ARKIT_MAX_WEIGHT:
                raise AutobonesError(f"ARKit shape {name}: weight {w:g} is outside [0, {ARKIT_MAX_WEIGHT:g}] "
                                     "(ARKit's own range is 0..1; above 1 overdrives the shape)")
            out += w * np.asarray(targets[name], dtype=np.float64)
        return out

    def expression_record(self, targets=(), skipped=(), tissue=False):
        """The sidecar's ``expressions`` entry (rigs with muscles; None otherwise): the definitions
        the model poses with (``format``, their ``sha256``, the whole ``definitions``) and the morph
        targets written to the glb (``name``, ``au``, the AU's ``label``, ``max_displacement`` in
        mesh units), those ``skipped`` as all zero on this head, and whether the targets carry the
        ``tissue`` pass."""
        if not self.muscles:
            return None
        from .expressions.model import load_expressions
        from .expressions.morph_targets import definitions_digest

        model = self.__dict__.get("_expression_model")
        doc = model.doc_ if model is not None else load_expressions(
            (self.expressions or {}).get("definitions"))
        aus = doc.get("action_units", {})
        return {"format": doc.get("format"), "sha256": definitions_digest(doc),
                "morph_targets": [{"name": name, "au": name[2:], "label": aus.get(name[2:].rstrip("LR"), {}).get("name"),
                                   "max_displacement": float(np.linalg.norm(d, axis=1).max())}
                                  for name, d in targets],
                "morph_targets_skipped": list(skipped), "morph_targets_tissue": bool(tissue), "definitions": doc}

    def save(self, path, expressions=False, tissue=False):
        """Write ``path`` (.glb), its ``.rig.json`` sidecar and ``.weights.npz``.

        All three are written to temporary files in the target folder first and
        renamed only when every one is complete, so a failure leaves no partial
        output. Returns the three paths.

        Parameters
        ----------
        path : str
            Output ``.glb``; the sidecars go beside it (:func:`sidecar_paths`).
        expressions : bool, "sides" or sequence of AU keys
            Also write FACS action units as glTF morph targets (``AU12``..., each the
            displacement at intensity 1 from the neutral mesh, computed on this head by
            :meth:`expression_model`; see :mod:`autobones.expressions.morph_targets`). True: one per AU of
            the definitions, both sides; ``"sides"``: also ``AU12L``/``AU12R``; a list: those.
            Needs the muscles of ``transfer``. ``tissue=True`` refines each target by the
            layered tissue (:meth:`pose` with ``tissue=True``). Rigs with muscles always record the
            expression definitions in the sidecar (``expressions``), so a loaded rig
            poses any mix the same way.
        """
        from .arguments import path_argument

        path = path_argument(path, "path")
        targets = rig_outputs(path)
        json_path, npz_path = targets[1:]
        for target in targets:  # every destination before any work: the message names the file in the way
            check_destination(target, "the rig")
        morphs, skipped = [], []
        if expressions is not False and expressions is not None:
            from .expressions.morph_targets import au_morph_targets

            morphs, skipped = au_morph_targets(self.expression_model(), expressions, tissue=tissue)
        elif tissue:
            raise AutobonesError("tissue=True refines the AU morph targets: it needs expressions=True")
        record = self.expression_record(morphs, skipped, tissue=tissue)
        if self.arkit_targets:  # after the AUs: named as ARKit does (mesh.extras.targetNames)
            morphs = list(morphs) + list(self.arkit_targets.items())
        side = self.sidecar()
        if record is not None:
            side["expressions"] = record
        temps = []
        try:
            try:
                for target in targets:
                    fd, tmp = temp_beside(target, suffix=os.path.splitext(target)[1])
                    os.close(fd)
                    temps.append(tmp)
                write_glb(temps[0], self.vertices, self.faces, self.skeleton, self.weights,
                          extras={"autobones": {"sidecar": os.path.basename(json_path)}},
                          markers=self.muscle_markers(), morph_targets=morphs,
                          axes=self.frame.turn_axes)  # the joints' roll from the head's own axes
                with open(temps[1], "w") as fh:
                    fh.write(strict_dumps(side, indent=1))  # strict JSON: an undefined value is null, never NaN
                with open(temps[2], "wb") as fh:
                    # the glb has float32 positions: the exact input vertices are kept here (load_rig)
                    np.savez_compressed(fh, weights=self.weights.astype(np.float32),
                                        bone_names=np.array(self.skeleton.names),
                                        vertices=np.asarray(self.vertices, dtype=np.float64),
                                        **{f"field/{k}": v for k, v in self.fields.items()})
            except OSError as exc:
                raise AutobonesError(f"{path}: cannot write ({exc.strerror or exc})") from exc
            replace_all(zip(temps, targets), "the rig")  # all three or none, the file at fault named
        finally:
            for tmp in temps:
                if os.path.exists(tmp):
                    os.remove(tmp)
        return targets
