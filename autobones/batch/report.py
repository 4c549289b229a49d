"""The batch report (``batch_report.json``): records as the report shows them, writing it, the summary table."""
from __future__ import annotations

import os

from ..io.atomic import write_text_atomic
from ..io.jsonable import strict_dumps

REPORT_NAME = "batch_report.json"
REPORT_FORMAT = "autobones-batch-report/1"

STATUSES = ("ok", "failed", "skipped")


def public_record(record, inp, out, options):
    """A record as the report shows it: paths relative to the folders, error naming the file."""
    rec = dict(record)
    rec.setdefault("options", options)
    rel_in = os.path.relpath(record["input"], inp).replace(os.sep, "/")
    rec["input"] = rel_in
    rec["output"] = os.path.relpath(record["output"], out).replace(os.sep, "/")
    if rec.get("landmarks") and rec["landmarks"] != "detected":
        rec["landmarks"] = os.path.relpath(rec["landmarks"], inp).replace(os.sep, "/")
    rec.pop("pid", None)
    err = rec.get("error")
    if err:
        err = err.replace(record["input"], rel_in).replace(inp + os.sep, "")
        base = os.path.basename(record["input"])
        if err.startswith(base + ":") and not err.startswith(rel_in):
            err = rel_in + err[len(base):]
        elif not err.startswith(rel_in):
            err = f"{rel_in}: {err}"
        rec["error"] = err
    return rec


def write_report(path, report):
    """Write the report as JSON through a temporary file renamed into place."""
    write_text_atomic(path, strict_dumps(report, indent=1) + "\n", "the batch report")


def summary_table(report):
    """The end-of-batch table as text: one row per status with count and time, then the total."""
    rows = []
    for s in STATUSES:
        files = [f for f in report["files"] if f["status"] == s]
        secs = sum(f.get("seconds") or 0.0 for f in files)
        rows.append((s, str(len(files)), f"{secs:.1f} s"))
    rows.append(("total", str(len(report["files"])), f"{report['seconds']:.1f} s wall"))
    w = [max(len(r[k]) for r in rows + [("status", "files", "time")]) for k in range(3)]
    line = f"{'status':<{w[0]}}  {'files':>{w[1]}}  {'time':>{w[2]}}"
    out = [line, "-" * len(line)]
    for i, r in enumerate(rows):
        if i == len(rows) - 1:
            out.append("-" * len(line))
        out.append(f"{r[0]:<{w[0]}}  {r[1]:>{w[1]}}  {r[2]:>{w[2]}}")
    return "\n".join(out)
