"""A USD stage to a file and back: the write (``.usda``, ``.usdc``/``.usd``, ``.usdz``), usd-core's errors
while writing as one line, and USD's own validation of the written file (``autobones.export.usd``
builds the stage)."""
from __future__ import annotations

import contextlib
import os
import tempfile

from ..errors import AutobonesError

INSTALL = "USD export needs usd-core: pip install 'autobones[usd]' (or pip install usd-core)"


def pxr_modules():
    """usd-core's modules (Gf, Sdf, Tf, Usd, UsdGeom, UsdSkel, Vt); AutobonesError saying how to install it."""
    try:
        from pxr import Gf, Sdf, Tf, Usd, UsdGeom, UsdSkel, Vt
    except ImportError:
        raise AutobonesError(INSTALL) from None
    return Gf, Sdf, Tf, Usd, UsdGeom, UsdSkel, Vt


def validate_stage(stage_or_path):
    """USD's own checks on a stage or a file: every validator registered with ``pxr.UsdValidation``,
    the framework that replaced ``UsdUtils.ComplianceChecker`` (usd-core 26.11 has no compliance
    checker); a release without the framework's ``ValidationContext`` runs the compliance checker.

    Returns
    -------
    list of (str, str, str)
        (``"Error"``/``"Warn"``/``"Info"``, error name, message) per finding; empty when clean.
    """
    Usd = pxr_modules()[3]
    try:
        from pxr import UsdValidation

        UsdValidation.ValidationContext  # noqa: B018 (usd-core >= 25.02)
    except (ImportError, AttributeError):  # older usd-core: the compliance checker usdchecker ran then
        from pxr import UsdUtils

        path = stage_or_path if isinstance(stage_or_path, (str, os.PathLike)) else \
            stage_or_path.GetRootLayer().realPath
        checker = UsdUtils.ComplianceChecker(skipARKitRootLayerCheck=True)
        checker.CheckCompliance(os.fspath(path))
        return ([("Error", "compliance", m) for m in checker.GetErrors() + checker.GetFailedChecks()]
                + [("Warn", "compliance", m) for m in checker.GetWarnings()])
    stage = Usd.Stage.Open(os.fspath(stage_or_path)) if isinstance(stage_or_path, (str, os.PathLike)) \
        else stage_or_path
    registry = UsdValidation.ValidationRegistry()
    ctx = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    out = []
    for e in ctx.Validate(stage):
        if e.HasNoError():
            continue
        out.append((e.GetType().displayName if hasattr(e.GetType(), "displayName") else str(e.GetType()),
                    str(e.GetName()), str(e.GetMessage())))
    return out


def export_stage(stage, tmp, out_path, ext):
    """Write ``stage`` to the temporary ``tmp`` (``out_path``'s format)."""
    if ext == ".usdz":
        from pxr import UsdUtils

        with tempfile.TemporaryDirectory(prefix="autobones-usdz-") as work:
            inner = os.path.join(work, os.path.splitext(os.path.basename(out_path))[0] + ".usdc")
            if not stage.GetRootLayer().Export(inner):
                raise AutobonesError(f"{out_path}: usd-core could not write the stage")
            os.remove(tmp)  # the packager refuses to replace a file
            if not UsdUtils.CreateNewUsdzPackage(inner, tmp):
                raise AutobonesError(f"{out_path}: usd-core could not write the .usdz package")
    elif not stage.GetRootLayer().Export(tmp, args={"format": "usda" if ext == ".usda" else "usdc"}):
        raise AutobonesError(f"{out_path}: usd-core could not write the stage")


@contextlib.contextmanager
def usd_errors(out_path):
    """USD's errors while writing ``out_path`` as one AutobonesError line. Without a ``Tf.Error.Mark``
    usd-core prints each error itself (a full disk: thousands of lines as the check then read the
    truncated file) and carries on; under one, the first error raises ``Tf.ErrorException`` here."""
    from pxr import Tf

    mark = Tf.Error.Mark()
    mark.SetMark()
    try:
        yield
    except Tf.ErrorException as exc:
        text = " ".join(str(exc).split())
        why = "no space left on device" if "No space left" in text else text.split(" : ")[-1][:160] or "an error"
        raise AutobonesError(f"{out_path}: usd-core could not write it ({why.strip(chr(39))})") from None
    except OSError as exc:
        raise AutobonesError(f"{out_path}: cannot write the USD file ({exc.strerror or exc})") from None
    finally:
        mark.Clear()
