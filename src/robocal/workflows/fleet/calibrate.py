"""``robocal fleet calibrate``: every robot of a fleet file calibrated on Dask.

::

    r = run_fleet_calibration("plant.toml", "out", client=client, db="history.sqlite")

writes ``out/<id>/`` per robot (the files ``robocal calibrate`` writes, the same result.json, plus
``fleet_inputs.json``: the robot's input hash), ``out/summary.json`` (every robot: ``status`` ``ok``
or ``failed`` with its ``reason``), ``out/summary.html`` and ``out/summary.svg`` (accuracy before and
after per robot, outliers flagged). Entries the fleet file could not describe are failed rows too;
one bad robot never stops the others. See :mod:`robocal.workflows.fleet.robot` for one robot.

Each robot is calibrated on its own (its own inputs, outputs, hash and history cycle). On a
cluster, by default, each worker thread runs one long task that takes the next robot nobody has
taken yet until none is left (:func:`robocal.workflows.fleet.cluster.run_pulled`; the claims are
files in a temporary folder in ``out_dir``): a 100-pose calibration takes ~20-30 ms, and a Dask
task per robot or per few robots cost the scheduler and the client ~2-4 ms of CPU each, on the
cores the workers need (benchmarks/bench_fleet.py). The workers finish within one robot of each
other. With ``per_task`` the robots go in fixed groups instead, one task each (:func:`task_groups`).
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ...io.atomic import atomic_write_text
from ...io.fleet_file import read_fleet
from .cluster import run_pulled, run_tasks
from .robot import calibrate_entries, calibrate_entry, failed_row
from ..outputs import ensure_writable_dir

__all__ = ["SUMMARY_FORMAT", "OUTLIER_Z", "flag_outliers", "task_groups", "run_fleet_calibration"]

SUMMARY_FORMAT = "robocal-fleet-summary/1"
#: Modified z-score above which a robot's accuracy after calibration is an outlier (Iglewicz and
#: Hoaglin 1993: z = 0.6745 (x - median) / MAD, flag z > 3.5).
OUTLIER_Z = 3.5
_OUTLIER_RULE = (f"accuracy after calibration with a modified z-score 0.6745 (x - median) / MAD above {OUTLIER_Z} "
                 "among the robots that finished (Iglewicz and Hoaglin), at least 5 of them")


def _after(row):
    v = row.get("holdout_rms_after_mm")
    return v if v is not None else row.get("rms_after_mm")


def flag_outliers(rows) -> list:
    """Set ``row["outlier"]`` (bool) on every row: the robot's accuracy after calibration is far
    worse than the fleet's (modified z-score above :data:`OUTLIER_Z`; needs 5 finished robots)."""
    vals = [(i, _after(r)) for i, r in enumerate(rows) if r["status"] == "ok" and _after(r) is not None]
    for r in rows:
        r["outlier"] = False
    if len(vals) < 5:
        return rows
    x = np.array([v for _, v in vals], dtype=float)
    med = float(np.median(x))
    mad = float(np.median(np.abs(x - med)))
    if mad <= 0:
        return rows
    z = 0.6745 * (x - med) / mad
    for (i, _), zi in zip(vals, z):
        rows[i]["outlier"] = bool(zi > OUTLIER_Z)
        rows[i]["outlier_z"] = round(float(zi), 2)
    return rows


def _lost(entry, exc) -> dict:
    """The row of a task that never returned (a worker died, the cluster went away)."""
    return failed_row(entry.id, f"the task did not finish on the cluster: {type(exc).__name__}: {exc}")


def task_groups(entries, per_task: int) -> list:
    """``entries`` cut into consecutive groups of ``per_task`` robots (>= 1), one Dask task each."""
    if int(per_task) < 1:
        raise ValueError(f"robots per task must be at least 1, got {per_task}")
    entries = list(entries)
    return [entries[i:i + int(per_task)] for i in range(0, len(entries), int(per_task))]


def _check_outputs_are_not_inputs(fleet, out_dir) -> None:
    """Before any work: no file the run writes (the summaries, each robot's folder's files) is one of
    its inputs (the fleet file, a robot's measurements, robot file or cell file), even though a run
    may resume into ``out_dir``
    (:class:`~robocal.io.output_paths.OutputIsInputError`, one ``Error:`` line naming both)."""
    from ...io.output_paths import check_not_inputs
    from ..calibration.calibrate import OUTPUT_FILES
    from .robot import STAMP_FILE

    join = os.path.join  # plain strings: ~10 paths per robot
    out = os.fspath(out_dir)
    outputs = [join(out, n) for n in ("summary.json", "summary.html", "summary.svg")]
    inputs = {"FLEET.toml": fleet.path}
    names = (*OUTPUT_FILES.values(), STAMP_FILE)
    fresh = not os.path.isdir(out)
    for e in fleet.entries:
        if not fresh and os.path.isdir(join(out, e.id)):  # no folder, no file in it (one stat, not ~10)
            outputs += [join(out, e.id, n) for n in names]
        inputs[f"robot {e.id!r} measurements"] = e.measurements
        if e.model_is_file:
            inputs[f"robot {e.id!r} model"] = e.model
        if e.cell and Path(e.cell).is_file():
            inputs[f"robot {e.id!r} cell"] = e.cell
    check_not_inputs(outputs, inputs)


def run_fleet_calibration(fleet_file, out_dir, *, client=None, db=None, report: bool = True, progress=None,
                          per_task: int | None = None, allow_unconverged: bool = False) -> dict:
    """Calibrate every robot of ``fleet_file`` into ``out_dir`` (see the module docstring).

    client: a ``distributed.Client`` (:func:`robocal.workflows.fleet.cluster.fleet_client`), or
    None for a plain loop in this process. db: the history database (path or URL) every result
    is recorded in (None: not recorded). report: each robot's report.html (the plots take longer
    than the solve). progress(done, total, row): after each robot (on a cluster, in batches at most
    every half second). per_task: robots per Dask task in fixed groups (:func:`task_groups`);
    default: every worker thread takes robots one by one. A robot whose fit did not converge gets ``status: "not
    converged"`` (no robot file, no history record) unless ``allow_unconverged`` (or the fleet file's
    ``allow_unconverged`` option).

    Returns ``{"summary": dict written to summary.json, "files": {...}}``.
    """
    t0 = time.perf_counter()
    fleet = read_fleet(fleet_file)
    _check_outputs_are_not_inputs(fleet, out_dir)
    out = ensure_writable_dir(out_dir)
    entries = fleet.entries
    if allow_unconverged:
        entries = [dataclasses.replace(e, options={**e.options, "allow_unconverged": True}) for e in entries]
    db_target = str(db) if db is not None else None
    if db_target is not None:  # reachable, and its tables made once, before the workers write
        from ...store import PASSWORD_ENV, HistoryStore, strip_credentials, url_password

        secret = url_password(db_target)
        if client is not None and secret is not None and not _workers_are_local(client):
            raise ValueError(_PASSWORD_IN_URL)  # tasks never carry a password
        HistoryStore.open(db_target).close()
        if client is not None and secret is not None:
            os.environ[PASSWORD_ENV] = secret  # in-process workers read it where they open the database
            db_target = strip_credentials(db_target)
    done = [0]

    def robot_done(_finished, _total, row):
        done[0] += 1
        if progress is not None:
            progress(done[0], len(entries), row)

    settings = {"out_dir": str(out.resolve()), "db": db_target, "report": report}
    if client is not None and per_task is None:  # the workers take the robots one by one
        rows = run_pulled(client, calibrate_entry, entries, claims_parent=out, progress=robot_done,
                          on_error=_lost, key_prefix="calibrate", **settings)
    else:  # fixed groups, one Dask task each (or a loop in this process)
        groups = task_groups(entries, per_task or 1)
        keys = [f"calibrate-{g[0].id}-{g[0].index}" + (f"-to-{g[-1].id}-{g[-1].index}" if len(g) > 1 else "")
                for g in groups]

        def group_done(_finished, _total, group_rows):
            for row in group_rows:
                robot_done(None, None, row)

        results = run_tasks(client, calibrate_entries, groups, keys=keys, progress=group_done,
                            on_error=lambda group, exc: [_lost(e, exc) for e in group], **settings)
        rows = [row for group_rows in results for row in group_rows]
    for e, row in zip(entries, rows):
        row["index"] = e.index
    rows += [failed_row(p.label(), p.reason, index=p.index, stage="fleet file") for p in fleet.problems]
    rows.sort(key=lambda r: r["index"])
    flag_outliers(rows)
    counts = {"robots": len(rows), "ok": sum(r["status"] == "ok" for r in rows),
              "failed": sum(r["status"] == "failed" for r in rows),
              "not_converged": sum(r["status"] == "not converged" for r in rows), "skipped": sum(bool(r.get("skipped")) for r in rows),
              "outliers": sum(r["outlier"] for r in rows)}
    summary = {"format": SUMMARY_FORMAT, "fleet": str(fleet.path), "written": _now(), "counts": counts,
               "history": _display_db(db_target), "outlier_rule": _OUTLIER_RULE,
               "wall_seconds": round(time.perf_counter() - t0, 3), "robots": rows}
    files = {"summary": atomic_write_text(out / "summary.json", json.dumps(summary, indent=2) + "\n", overwrite=True)}
    from ...report.fleet_summary import plot_fleet_accuracy, write_fleet_summary_html

    svg = plot_fleet_accuracy(rows, f"{Path(fleet_file).name}: accuracy per robot before/after calibration")
    files["html"] = write_fleet_summary_html(out / "summary.html", summary, svg, "summary.svg")
    files["plot"] = out / "summary.svg"
    return {"summary": summary, "files": files}


def _workers_are_local(client) -> bool:
    """True when every worker of ``client`` runs in this process (a threads-only local cluster)."""
    try:
        return all(str(w).startswith("inproc://") for w in client.scheduler_info().get("workers", {}))
    except Exception:  # noqa: BLE001 - any doubt: not local
        return False


_PASSWORD_IN_URL = ("the history database URL carries a password, which would travel to the Dask workers in the "
                    "tasks: give the URL without it and set ROBOCAL_DB_PASSWORD (or ROBOCAL_DB_PASSWORD_FILE, a file "
                    "readable on every worker) where the workers run")


def _now() -> str:
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _display_db(db):
    if db is None:
        return None
    from ...store import redact_url

    return redact_url(db)
