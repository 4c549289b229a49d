"""Rebuild ``autobones/landmarks/assist_calibration.json``: where the assistant reads each name off the
built-in generic skin (:mod:`autobones.landmarks.assist_calibration`).

Run from the repository root with the shared data set beside it (``../shared/data``):
``python tools/calibrate_assist.py``. Every landmarked human head (benchmarks/landmarks_assist.py's list:
ICT, menpo3d, Lee Perry-Smith, the zoo's two SMPL heads) is fitted from its five assisted names, its other
landmarks are pulled back to the generic's rest skin, and the family-weighted means are stored.
"""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))


def main():
    import landmarks_assist as la

    from autobones.landmarks.assist import generic_skin
    from autobones.landmarks.assist_calibration import CALIBRATION_PATH, calibrate, write_reading

    samples = la.human_samples()
    g, _ = generic_skin()
    reading, counts = calibrate([(f, p) for _, f, p in samples], g.vertices, g.faces)
    write_reading(CALIBRATION_PATH, reading, counts, [h for h, _, _ in samples])
    print(f"wrote {CALIBRATION_PATH}: {len(reading)} names from {len(samples)} heads")


if __name__ == "__main__":
    main()
