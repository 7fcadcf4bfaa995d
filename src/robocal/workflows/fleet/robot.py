"""One robot of ``robocal fleet calibrate``: the task a Dask worker runs.

:func:`calibrate_entry` is self-contained (a fleet entry and a few settings in, one summary row
out) so that it can run on any worker that sees the input files and the output folder:

1. the content hash of the inputs (:func:`input_digest`: measurement file bytes, robot file bytes
   or library name, id, tool, cell, options, report flag, robocal version); when
   ``<out>/<id>/fleet_inputs.json`` holds the same hash for a finished robot, the robot is skipped
   (a crashed overnight run resumes instead of restarting);
2. :func:`robocal.workflows.calibration.calibrate.run_calibration`, exactly as ``robocal calibrate`` runs it
   (same ``result.json``, calibrated robot files, report) into ``<out>/<id>/``;
3. the result recorded in the history database (one ``geometric_calibration`` cycle per robot; a
   cycle with this input hash already there is not recorded twice);
4. ``fleet_inputs.json`` written last (through a temporary file): only a robot whose every step
   finished counts as done.

Any error becomes the row's ``status: failed`` with the reason; nothing raises out of the task.
"""

from __future__ import annotations

import functools
import hashlib
import json
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

from ..convergence import Convergence
from ...io.atomic import atomic_write_text
from ...io.fleet_file import FleetEntry

__all__ = ["STAMP_FILE", "input_digest", "calibrate_entry", "calibrate_entries", "failed_row", "record_calibration"]

#: Per-robot marker of a finished robot: its input hash and summary row.
STAMP_FILE = "fleet_inputs.json"


@functools.lru_cache(maxsize=1)
def _robocal_version() -> str:
    """The installed robocal version (looked up once per process: importlib.metadata scans the
    installed distributions, ~2 ms of every robot's task before)."""
    try:
        return version("robocal")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        return "unknown"


def _file_sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def input_digest(entry: FleetEntry, report: bool) -> str:
    """SHA-256 (hex) of everything that decides a robot's result (see the module docstring)."""
    desc = {
        "id": entry.id, "model": Path(entry.model).name if entry.model_is_file else entry.model,
        "model_sha256": _file_sha256(entry.model) if entry.model_is_file else None,
        "measurements_sha256": _file_sha256(entry.measurements), "tool": entry.tool, "cell": entry.cell,
        "options": entry.options, "report": bool(report), "robocal": _robocal_version(),
    }
    return hashlib.sha256(json.dumps(desc, sort_keys=True).encode()).hexdigest()


def failed_row(entry_id, reason: str, **extra) -> dict:
    """A summary row for a robot that did not finish."""
    return {"id": entry_id, "status": "failed", "reason": reason, **extra}


def _stamp(robot_dir: Path):
    try:
        return json.loads((robot_dir / STAMP_FILE).read_text())
    except (OSError, ValueError):
        return None


def _finished(robot_dir: Path, digest: str):
    """The stored row when ``robot_dir`` holds a finished robot with inputs ``digest``, else None."""
    stamp = _stamp(robot_dir)
    if not stamp or stamp.get("input_sha256") != digest or not (robot_dir / "result.json").is_file():
        return None
    return stamp.get("row")


def _row(entry, rdict, digest, seconds) -> dict:
    res, val = rdict["residuals"], rdict.get("validation")
    ok = rdict["status"] != "failed"
    conv = Convergence.from_dict(rdict.get("convergence"))
    unconverged = ok and not conv.may_write_model(entry.options.get("allow_unconverged", False))
    status = "failed" if not ok else ("not converged" if unconverged else "ok")
    reason = {"ok": None, "failed": "the result failed the sanity gates: " + "; ".join(rdict["reasons"]),
              "not converged": conv.warning() if unconverged else None}[status]
    row = {"id": entry.id, "status": status, "reason": reason,
           "model": rdict["robot"] if isinstance(rdict.get("robot"), str) else entry.model, "cell": entry.cell,
           "measurements": str(entry.measurements), "n_poses": rdict["metadata"]["n_poses_file"],
           "sanity": rdict["status"], "rms_before_mm": res["before"]["rms"], "rms_after_mm": res["after"]["rms"],
           "holdout_rms_before_mm": val["before"]["rms"] if val else None,
           "holdout_rms_after_mm": val["after"]["rms"] if val else None,
           "converged": conv.converged,
           "result": f"{entry.id}/result.json", "input_sha256": digest, "seconds": round(seconds, 3)}
    return row


def record_calibration(db, entry: FleetEntry, rdict: dict, meas, digest: str) -> int | None:
    """Record one robot's calibration in the history database ``db`` (path or URL) as a
    ``geometric_calibration`` cycle: the measured points with their joints, the estimated parameters
    (change from nominal, value, std) and the accuracy before/after; ``meta`` holds the input hash.
    Returns the cycle id (the existing one when a cycle with this hash is already recorded)."""
    from ...store import HistoryStore, UnknownRobotError

    with HistoryStore.open(db) as store:
        try:
            for c in reversed(store.cycles(entry.id, kind="geometric_calibration", status="committed")):
                if c.meta.get("input_sha256") == digest:
                    return c.id
        except UnknownRobotError:
            pass
        meta = {"source": "robocal fleet calibrate", "input_sha256": digest, "cell": entry.cell,
                "measurements": str(entry.measurements), "result": f"{entry.id}/result.json",
                "sanity": rdict["status"]}
        params = [p for p in rdict["model_parameters"] if p["estimated"]]
        with store.cycle(entry.id, "geometric_calibration", meta=meta, robot_model=rdict["robot"],
                         notes=f"robocal fleet calibrate ({rdict['metadata']['n_poses_calibration']} poses)") as c:
            for k, name in enumerate(meas.targets):
                ok = np.all(np.isfinite(meas.points[:, k]), axis=1)
                if ok.any():
                    c.add_measurements(meas.joints[ok], meas.points[ok, k], pose_index=np.nonzero(ok)[0],
                                       target=name, sensor=meas.metadata.get("instrument") or "instrument")
            if params:
                c.add_parameters([p["name"] for p in params], [p["change"] for p in params],
                                 units=[p["unit"] for p in params], values=[p["calibrated"] for p in params],
                                 std=[p["std"] for p in params])
            c.add_metric("residual_rms_before", rdict["residuals"]["before"]["rms"], "mm")
            c.add_metric("residual_rms_after", rdict["residuals"]["after"]["rms"], "mm")
            val = rdict.get("validation")
            if val:
                c.add_metric("holdout_rms_before", val["before"]["rms"], "mm")
                c.add_metric("holdout_rms_after", val["after"]["rms"], "mm")
        return c.id


def _calibrate(entry: FleetEntry, robot_dir: Path, report: bool):
    """run_calibration as ``robocal calibrate`` runs it, and the measurements it read."""
    from ...io.measurements import read_measurements
    from ...robots import load_robot
    from ..calibration.calibrate import run_calibration

    opts = dict(entry.options)
    nominal = load_robot(entry.model)
    meas = read_measurements(entry.measurements, robot=nominal, check_limits=True,
                             drop_duplicates=opts.get("drop_duplicates", False))
    r = run_calibration(entry.model, entry.measurements, robot_dir, overwrite=True, report=report, tool=entry.tool,
                        measurements=meas, **opts)
    return r, meas


def calibrate_entry(entry: FleetEntry, out_dir, *, db=None, report: bool = True) -> dict:
    """Calibrate one fleet robot into ``out_dir/<id>/`` (see the module docstring); the summary row."""
    from ...io.output_paths import PathEscapeError, path_under

    t0 = time.perf_counter()
    try:
        robot_dir = path_under(out_dir, entry.id)  # the id is validated by the fleet file reader; checked again
    except PathEscapeError as exc:
        return failed_row(entry.id, str(exc))
    try:
        digest = input_digest(entry, report)
    except OSError as exc:
        return failed_row(entry.id, f"cannot read the inputs: {exc}")
    done = _finished(robot_dir, digest)
    if done is not None:
        return {**done, "skipped": True}
    try:
        r, meas = _calibrate(entry, robot_dir, report)
    except Exception as exc:  # one bad robot never stops the others: its reason goes to the summary
        return failed_row(entry.id, f"{type(exc).__name__}: {exc}" if not isinstance(exc, (ValueError, OSError, KeyError))
                          else str(exc).strip("'\""), input_sha256=digest)
    rdict = r["result"]
    row = _row(entry, rdict, digest, time.perf_counter() - t0)
    if db is not None and row["status"] == "ok":  # no history of a fit that did not converge
        try:
            row["history_cycle"] = record_calibration(db, entry, rdict, meas, digest)
        except Exception as exc:  # the calibration stands; the robot is retried next run
            return {**row, "status": "failed", "reason": f"history database: {exc}"}
    row["seconds"] = round(time.perf_counter() - t0, 3)
    # the results above were written durably; the marker need not be (lost in a power cut, the
    # robot is only calibrated again), which spares each robot one fsync (~10 ms on a VM disk)
    atomic_write_text(robot_dir / STAMP_FILE, json.dumps({"input_sha256": digest, "row": row}, indent=2) + "\n",
                      overwrite=True, durable=False)
    return {**row, "skipped": False}


def calibrate_entries(entries, out_dir, *, db=None, report: bool = True) -> list:
    """:func:`calibrate_entry` for each of a few robots, one after the other: the Dask task of a
    group of robots (one row per robot, in order; each robot still fails alone)."""
    return [calibrate_entry(e, out_dir, db=db, report=report) for e in entries]
