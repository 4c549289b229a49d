"""The accuracy part of ``benchmarks/landmarks.py``: the detector configurations measured in one run
(MediaPipe's ablations, dlib's 68-point predictor), the error against the published landmarks, and the
tables per head, per name and per configuration."""
from __future__ import annotations

import time

import numpy as np

import autobones.landmarks.detect as detect_mod
from autobones.errors import AutobonesError
from autobones.io.landmarks import IBUG68, NAMES
from autobones.landmarks.detect import LandmarkDetector
from autobones.orient import detect_frame

from landmarks_timing import run_config

FRONT = ((0.0, 0.0),)


# ---------------------------------------------------------------------------
# dlib's 68-point predictor, as a detector for the same pipeline


class Dlib68:
    """dlib's 68-point shape predictor as a detector: image (H, W, 3) uint8 -> (68, 2) pixels or None.

    The face box comes from dlib's HOG frontal face detector (upsampled once); when it
    finds nothing, from the CNN (MMOD) detector. Both models and the predictor come from
    ``face-recognition-models``. ``points`` is the contract's iBUG-68 table (palpebrale
    = mean of the two lid points, stomion = mean of 62 and 66). dlib's part positions are
    whole pixels (its pixel centres are at integers, as in :mod:`autobones.render`).
    """

    points = IBUG68

    def __init__(self, upsample=1):
        import dlib
        import face_recognition_models as models

        self.upsample = upsample
        self.hog = dlib.get_frontal_face_detector()
        self.cnn = dlib.cnn_face_detection_model_v1(models.cnn_face_detector_model_location())
        self.predictor = dlib.shape_predictor(models.pose_predictor_model_location())
        self.calls = {"hog": 0, "cnn": 0, "none": 0}

    def __call__(self, image):
        image = np.ascontiguousarray(image)
        rects = list(self.hog(image, self.upsample))
        if rects:
            self.calls["hog"] += 1
        else:
            rects = [d.rect for d in self.cnn(image, self.upsample)]
            self.calls["cnn" if rects else "none"] += 1
        if not rects:
            return None
        box = max(rects, key=lambda r: r.width() * r.height())
        shape = self.predictor(image, box)
        return np.array([[p.x, p.y] for p in shape.parts()], dtype=np.float64)


# ---------------------------------------------------------------------------


def errors(found, truth):
    """name -> error in % of the published ex-ex, over names in both."""
    unit = np.linalg.norm(truth["exocanthion_l"] - truth["exocanthion_r"])
    return {n: 100 * float(np.linalg.norm(np.asarray(found[n]) - truth[n])) / unit
            for n in NAMES if n in found and n in truth}


def fmt_names(d, limit=4):
    if not d:
        return "-"
    names = list(d)
    return ", ".join(names[:limit]) + (f" +{len(names) - limit}" if len(names) > limit else "")


def detector_configs(mesh, with_dlib):
    """([(name, detector, LandmarkDetector options)], dlib's detector or None). Each detector's model is
    loaded by a discarded warm-up detection on ``mesh`` first, so that no head's time includes the load."""
    mediapipe = detect_mod.MediaPipeFaceMesh()
    t0 = time.perf_counter()
    LandmarkDetector(detector=mediapipe).detect(*mesh)
    print(f"warm-up (MediaPipe model load + one detection, discarded): {time.perf_counter() - t0:.2f} s")
    configs = [("default", mediapipe, {}), ("front only", mediapipe, {"views": FRONT}),
               ("no refine", mediapipe, {"refine": False}),
               ("front, no refine", mediapipe, {"views": FRONT, "refine": False})]
    dlib_det = None
    if with_dlib:
        try:
            dlib_det = Dlib68()
        except ImportError as exc:
            print(f"--dlib: cannot import dlib / face_recognition_models ({exc}); skipped")
        if dlib_det is not None:
            t0 = time.perf_counter()
            LandmarkDetector(detector=dlib_det).detect(*mesh)
            print(f"warm-up (dlib models load + one detection, discarded): {time.perf_counter() - t0:.2f} s")
            configs += [("dlib", dlib_det, {}), ("dlib front only", dlib_det, {"views": FRONT}),
                        ("dlib front, no refine", dlib_det, {"views": FRONT, "refine": False})]
    return configs, dlib_det


def measure_accuracy(configs, heads, meshes, truth, size):
    """(config, head) -> {"lm", "err", "time", "stages", "frame"} or {"failed": why}. Each head's frame is
    found once and shared by every configuration, so they differ only in what they configure."""
    res = {}
    for h in heads:
        t0 = time.perf_counter()
        frame = detect_frame(*meshes[h])
        t_frame = time.perf_counter() - t0
        for cname, det, opts in configs:
            try:
                lm, total, st = run_config(det, meshes[h], frame, size=size, **opts)
            except AutobonesError as exc:
                res[cname, h] = {"failed": str(exc)}
                print(f"  {cname:22s} {h:17s} FAILED: {exc}", flush=True)
                continue
            e = errors(lm, truth[h])
            res[cname, h] = {"lm": lm, "err": e, "time": total, "stages": st, "frame": t_frame}
            worst = max(e, key=e.get)
            print(f"  {cname:22s} {h:17s} mean {np.mean(list(e.values())):5.2f}%  max {e[worst]:5.2f}% ({worst})  "
                  f"{len(e)} scored, dropped {fmt_names(lm.dropped)}, flagged {fmt_names(lm.flagged)}  "
                  f"{total:.2f} s", flush=True)
    return res


def pooled(res, heads, cname):
    """Every head x name error of configuration ``cname``."""
    rows = [res[cname, h] for h in heads if "err" in res.get((cname, h), {})]
    return [v for r in rows for v in r["err"].values()]


def per_name(res, heads, cname):
    """name -> (mean over heads, (max, its head), heads) of configuration ``cname``."""
    out = {}
    for n in NAMES:
        v = [(res[cname, h]["err"][n], h) for h in heads
             if "err" in res.get((cname, h), {}) and n in res[cname, h]["err"]]
        if v:
            out[n] = (np.mean([x for x, _ in v]), max(v), len(v))
    return out


def print_accuracy(res, heads, meshes, cols, dlib_det):
    """The three accuracy tables of configurations ``cols`` (default first)."""
    print_per_head(res, heads, meshes)
    names_table = {c: per_name(res, heads, c) for c in cols}
    print_per_name(res, heads, cols, names_table)
    print_per_config(res, heads, cols, names_table)
    if dlib_det is not None:
        print(f"\n(dlib face boxes: {dlib_det.calls['hog']} pictures by HOG, {dlib_det.calls['cnn']} by the CNN "
              f"fallback, {dlib_det.calls['none']} with no face)")


def print_per_head(res, heads, meshes):
    print("\n## Accuracy per head (default: 5 views, refinement; % of the published ex-ex)\n")
    print("| head | vertices | scored | mean % | max % (name) | dropped | flagged | frame s | render s | 2-D s "
          "| refine s | other s | detect s | frame + detect s |")
    print("|---|---:|---:|---:|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for h in heads:
        r = res["default", h]
        if "err" not in r:
            print(f"| {h} | {len(meshes[h][0]):,} | 0 | - | failed: {r['failed'][:60]} | | | | | | | | | |")
            continue
        e, st = r["err"], r["stages"]
        worst = max(e, key=e.get)
        other = r["time"] - sum(st.values())
        print(f"| {h} | {len(meshes[h][0]):,} | {len(e)} | {np.mean(list(e.values())):.2f} | {e[worst]:.2f} ({worst}) "
              f"| {fmt_names(r['lm'].dropped)} | {fmt_names(r['lm'].flagged)} | {r['frame']:.2f} | {st['render']:.2f} "
              f"| {st['2-D']:.2f} | {st['refine']:.2f} | {other:.2f} | {r['time']:.2f} "
              f"| {r['frame'] + r['time']:.2f} |")


def print_per_name(res, heads, cols, names_table):
    print("\n## Accuracy per name (mean over heads, % of ex-ex; default also max over heads)\n")
    nheads = {c: sum("err" in res[c, h] for h in heads) for c in cols}
    print("| name | heads | default mean | default max (head) | " + " | ".join(
        f"{c} mean" + (f" ({nheads[c]} of {len(heads)} heads)" if nheads[c] < len(heads) else "")
        for c in cols[1:]) + " |")
    print("|---|---:|---:|---|" + "---:|" * (len(cols) - 1))
    for n in NAMES:
        if n not in names_table["default"]:
            continue
        m, (mx, mh), k = names_table["default"][n]
        rest = " | ".join(f"{names_table[c][n][0]:.2f}" if n in names_table[c] else "-" for c in cols[1:])
        print(f"| {n} | {k} | {m:.2f} | {mx:.2f} ({mh}) | {rest} |")


def print_per_config(res, heads, cols, names_table):
    print("\n## Accuracy per configuration (same run)\n")
    print("| configuration | " + " | ".join(heads) + " | heads | pooled mean % | ratio to default (same heads) "
          "| worst name (mean) | head x name > 8 % | dropped (total) | flagged (total) | median s | mean <= 3 % "
          "| every name <= 8 % |")
    print("|---|" + "---:|" * len(heads) + "---:|---:|---:|---|---:|---:|---:|---:|---|---|")
    for c in cols:
        pm = pooled(res, heads, c)
        if not pm:
            print(f"| {c} | " + " | ".join("fail" for _ in heads) + " | 0 | - | - | - | - | - | - | - | - | - |")
            continue
        pn = names_table[c]
        wn = max(pn, key=lambda n: pn[n][0])
        per_head = " | ".join(f"{np.mean(list(res[c, h]['err'].values())):.2f}" if "err" in res[c, h] else "fail"
                              for h in heads)
        ok = [res[c, h] for h in heads if "err" in res[c, h]]
        # the ratio compares like with like: only the heads both this configuration and default scored
        same = [h for h in heads if "err" in res[c, h] and "err" in res["default", h]]
        base = np.mean([v for h in same for v in res["default", h]["err"].values()]) if same else np.nan
        mine = np.mean([v for h in same for v in res[c, h]["err"].values()]) if same else np.nan
        drop = sum(len(r["lm"].dropped) for r in ok)
        flag = sum(len(r["lm"].flagged) for r in ok)
        secs = np.median([r["time"] for r in ok])
        every = all(v[0] <= 8.0 for v in pn.values())
        print(f"| {c} | {per_head} | {len(ok)} | {np.mean(pm):.2f} | {mine / base:.2f} | {wn} {pn[wn][0]:.2f} "
              f"| {sum(v > 8 for v in pm)} of {len(pm)} | {drop} | {flag} | {secs:.2f} "
              f"| {'MET' if np.mean(pm) <= 3 else 'NOT MET'} ({np.mean(pm):.2f}) "
              f"| {'MET' if every else 'NOT MET'} (worst {pn[wn][0]:.2f}) |")
