"""`robocal calibrate` and `robocal correct`: file-to-file calibration workflows.

``run_calibration`` reads a robot and a measurement file, splits the poses (seeded) into a
calibration and a held-out set, identifies the kinematic parameters, base frame and target
points, validates on the held-out poses and writes into one folder:

* ``result.json``            every number (:func:`robocal.calib.outputs.result_to_dict` + validation)
* ``calibrated_robot.toml``  the calibrated robot (``robocal-robot/1``; its base is the robot in the
                             measurement instrument's frame)
* ``calibrated_robot.urdf``  the same as URDF (skipped, with a note, when a joint coupling cannot be
                             expressed in URDF)
* ``report.html``            self-contained report with plots

"Before" numbers are the nominal kinematics with the best-fit base frame and target points (a
first solve with the geometry held nominal), so they measure what calibration of the robot itself
gains, not the unknown placement of the instrument.

``run_correct`` turns Cartesian targets into corrected joint targets with a calibrated robot.

Target files (``robocal-targets/1``) and the corrected targets (``robocal-corrected-targets/1``) are
read and written by :mod:`robocal.io.targets`.
"""

from __future__ import annotations

import json
import math
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ..calib import CalibrationProblem, Target, solve
from ..calib.outputs import corrected_joint_targets, json_ready, result_to_dict
from ..calib.sanity import calibration_verdict
from ..calib.uncertainty import predicted_point_std
from ..calib.validation import train_holdout_split
from ..io.atomic import atomic_write_text
from ..io.measurements import read_measurements
from ..io.targets import read_targets, write_corrected_targets
from ..metrics import error_statistics
from ..robots import load_robot, save_robot
from .outputs import check_outputs_free, ensure_writable_dir, staged_outputs
from .progress import solver_progress

__all__ = ["CalibrationInputError", "OUTPUT_FILES", "output_paths", "split_poses", "select_free", "run_calibration",
           "run_correct"]

OUTPUT_FILES = {"result": "result.json", "robot": "calibrated_robot.toml", "urdf": "calibrated_robot.urdf",
                "report": "report.html"}


class CalibrationInputError(ValueError):
    """The inputs of a calibration cannot work (too few poses, unknown parameter names, ...)."""


def output_paths(out_dir) -> dict:
    out = Path(out_dir)
    return {k: out / v for k, v in OUTPUT_FILES.items()}


def split_poses(n: int, holdout: float, seed: int):
    """Seeded split of ``n`` poses: (train indices, held-out indices), both sorted
    (:func:`robocal.calib.validation.train_holdout_split` with a clear error for a bad fraction)."""
    if not 0.0 <= holdout < 1.0:
        raise CalibrationInputError(f"--holdout must be a fraction in [0, 1), got {holdout}")
    return train_holdout_split(n, holdout, seed)


def select_free(model, free=None, free_all: bool = False, fix=()) -> list:
    """Names of the parameters to identify: the model's free ones (robot file ``fixed`` lists
    respected), or ``free`` (names), or all with ``free_all``; minus ``fix``."""
    names = list(model.params.names)

    def check(ns, what):
        for n in ns:
            try:
                model.params.index(n)
            except KeyError as exc:
                raise CalibrationInputError(f"{what}: {exc.args[0]} (robot {model.name})") from None

    if free and free_all:
        raise CalibrationInputError("give either --free or --free-all, not both")
    if free_all:
        sel = names
    elif free:
        check(free, "--free")
        sel = [n for n in names if n in set(free)]
    else:
        sel = [n for n, f in zip(names, model.params.free) if f]
    check(fix, "--fix")
    return [n for n in sel if n not in set(fix)]


def _point_errors(pred, measured):
    """Per-point error magnitudes (N, K) (NaN where not measured)."""
    return np.linalg.norm(measured - pred, axis=-1)


def _per_point(errors_before, errors_after, pose_ids, targets):
    mask = np.isfinite(errors_after)
    pi, ki = np.nonzero(mask)
    return {"pose": [pose_ids[i] for i in pi], "target": [targets[k] for k in ki],
            "before": errors_before[mask], "after": errors_after[mask]}


def run_calibration(robot, data, out_dir, *, free=None, free_all: bool = False, fix=(), holdout: float = 0.2,
                    seed: int = 0, loss: str = "linear", sigma_mm: float | None = None, tool=None,
                    overwrite: bool = False, progress=None, method: str = "lm", force: bool = False,
                    drop_duplicates: bool = False) -> dict:
    """Calibrate ``robot`` from the measurement file ``data``; write the results into ``out_dir``.

    robot: shipped robot name or robot file path (the nominal model). data: a
    ``robocal-measurements/1`` file of that robot. free / free_all / fix: parameter selection
    (:func:`select_free`). holdout, seed: fraction of poses held out for validation and the seed
    of the split. loss: ``linear``, ``huber`` or ``cauchy`` (robust, per pose). sigma_mm:
    measurement noise per coordinate [mm] (weights and absolute uncertainty; default: estimated
    from the residuals). tool: initial target point (3,) [mm] in the flange frame (default origin).
    progress(step, total, text): called between steps. drop_duplicates: drop repeated poses (else an
    error); the dropped ones are listed in the notes.

    Nothing is written when an output file exists and ``overwrite`` is false (``FileExistsError``
    naming the file, checked before any work); the files are written into a temporary folder and
    moved into place together (:mod:`robocal.workflows.outputs`). The sanity gates
    (:mod:`robocal.calib.sanity`) give ``status`` and ``reasons`` in result.json; a failed result
    writes no calibrated robot files unless ``force``. Returns a dict with ``result`` (the JSON
    dict), ``files``, ``notes`` and ``verdict``.
    """
    step = progress or (lambda i, n, text: None)
    total = 6
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise CalibrationInputError(f"{out}: exists and is not a folder")
    check_outputs_free(out, OUTPUT_FILES.values(), overwrite)
    if loss not in ("linear", "huber", "cauchy"):
        raise CalibrationInputError(f"--loss must be linear, huber or cauchy, got {loss!r}")
    if sigma_mm is not None and not (math.isfinite(sigma_mm) and sigma_mm > 0):
        raise CalibrationInputError(f"--sigma must be a positive number of mm, got {sigma_mm}")

    nominal = load_robot(robot)
    size_mb = Path(data).stat().st_size / 1e6 if Path(data).is_file() else 0.0
    if size_mb > 10.0:  # a large file takes seconds to read: say so (small files stay silent on errors)
        step(1, total, f"reading {data} ({size_mb:.0f} MB)")
    meas = read_measurements(data, robot=nominal, check_limits=True, drop_duplicates=drop_duplicates)
    ensure_writable_dir(out)
    free_names = select_free(nominal, free, free_all, fix)
    N, K = meas.n_poses, meas.n_targets
    train, hold = split_poses(N, holdout, seed)
    n_unknowns = len(free_names) + 6 + 3 * K
    n_res = 3 * K * len(train)
    if n_res < n_unknowns or len(train) < 3:
        need = max(3, math.ceil(n_unknowns / (3 * K)))
        raise CalibrationInputError(
            f"{data}: too few poses: {len(train)} calibration pose(s) ({N} in the file, {len(hold)} held out) give "
            f"{n_res} residuals for {n_unknowns} unknowns ({len(free_names)} parameters, base frame, {K} target "
            f"point(s)); at least {need} calibration poses are needed, 3-5 times that for a useful result")
    step(1, total, f"read {N} poses of {nominal.name} from {data}: {len(train)} to calibrate, {len(hold)} held out "
                   f"(seed {seed})")
    point0 = (0.0, 0.0, 0.0) if tool is None else tuple(float(v) for v in tool)
    targets = [Target(t, point=point0) for t in meas.targets]
    pose_ids = list(meas.pose_ids)
    q_tr, p_tr = meas.joints[train], meas.points[train]

    step(2, total, f"initial base frame and target point(s) with the nominal geometry ({len(train)} poses)")
    problem0 = CalibrationProblem(nominal, q_tr, targets, p_tr, free=[], base_initial="fit", point_sigma_mm=sigma_mm)
    res0 = solve(problem0, loss=loss, method=method, progress=solver_progress(step, 2, total))

    step(3, total, f"identifying {len(free_names)} parameter(s) + base + {K} target point(s) ({loss} loss)")
    problem = CalibrationProblem(nominal, q_tr, targets, p_tr, free=free_names, base_initial="fit",
                                 point_sigma_mm=sigma_mm)
    result = solve(problem, loss=loss, method=method, state0=res0.state, progress=solver_progress(step, 3, total))

    step(4, total, f"validating on {len(hold)} held-out pose(s)")
    validation = None
    if len(hold):
        q_h, p_h = meas.joints[hold], meas.points[hold]
        e_before = _point_errors(problem0.predict_points(res0.state, q=q_h, stations=np.zeros(len(hold), int)), p_h)
        e_after = _point_errors(problem.predict_points(result.state, q=q_h, stations=np.zeros(len(hold), int)), p_h)
        ok = np.isfinite(e_after)
        validation = {
            "n_poses": int(len(hold)), "pose_ids": [pose_ids[i] for i in hold],
            "before": error_statistics(e_before[ok]), "after": error_statistics(e_after[ok]),
            "per_point": _per_point(e_before, e_after, [pose_ids[i] for i in hold], meas.targets),
        }
    # predicted uncertainty over every pose of the file (accuracy map)
    step(4, total, f"predicted uncertainty at the {N} measured poses")
    std_pts = predicted_point_std(problem, result, meas.joints)  # (N, K)
    base_model = result.model.replace(T_world_base=np.eye(4))
    positions = base_model.fk(meas.joints)[:, :3, 3]
    accuracy = {
        "quantity": "predicted position uncertainty (1 std, sqrt of the trace of J Cov J^T) of the targets in the "
                    "instrument frame, largest over the targets of each pose",
        "pose_ids": pose_ids, "flange_position_base_mm": positions, "predicted_std_mm": std_pts.max(axis=1),
        "statistics": error_statistics(std_pts.max(axis=1)),
    }

    verdict = calibration_verdict(
        robot=nominal.name, rms_before_mm=res0.rms_after, rms_after_mm=result.rms_after, sigma_mm=sigma_mm,
        holdout_before_mm=validation["before"]["rms"] if validation else None,
        holdout_after_mm=validation["after"]["rms"] if validation else None,
        parameters=(nominal.params.names, nominal.params.units, nominal.params.values, result.state.params))
    write_robot = verdict.ok or force
    step(5, total, "writing result.json" + (", calibrated robot (TOML, URDF)" if write_robot else
                                            " (FAILED the sanity gates: no calibrated robot file)"))
    notes = ([f"dropped duplicate poses: {meas.metadata['dropped_duplicates']}"]
             if "dropped_duplicates" in meas.metadata else [])
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    metadata = {
        "robot": str(robot), "measurements": str(data), "n_poses_file": N, "n_poses_calibration": int(len(train)),
        "n_poses_holdout": int(len(hold)), "holdout_fraction": holdout, "seed": seed, "loss": loss,
        "sigma_mm": sigma_mm, "method": method, "free": free_names, "fixed_by_option": list(fix),
        "initial_target_mm": list(point0), "targets": list(meas.targets), "instrument": meas.metadata.get("instrument"),
        "frame": meas.metadata.get("frame"), "written": stamp,
    }
    rdict = result_to_dict(result, problem, nominal=nominal, pose_ids=[pose_ids[i] for i in train],
                           validation=json_ready(validation) if validation else None, metadata=metadata)
    rdict["baseline"] = json_ready({
        "description": "nominal geometry with best-fit base frame and target point(s) (the 'before' state)",
        "iterations": res0.iterations, "converged": res0.converged, "reason": res0.reason,
        "rms_mm": res0.rms_after, "T_instrument_base": res0.state.bases[0], "targets_mm": res0.state.targets})
    rdict["accuracy_map"] = json_ready(accuracy)
    rdict["status"], rdict["reasons"], rdict["sanity_checks"] = verdict.status, list(verdict.reasons), verdict.checks
    step(6, total, "writing report.html; moving the outputs into place together")
    with staged_outputs(out, OUTPUT_FILES.values(), overwrite) as stage:
        files = _write_outputs(output_paths(stage), rdict, result, nominal, meas, data, train, N, validation, stamp,
                               targets, positions, accuracy, write_robot, notes)
    files = {k: out / p.name for k, p in files.items()}
    return {"result": rdict, "files": files, "notes": notes, "calibration_result": result, "problem": problem,
            "verdict": verdict}


def _write_outputs(paths, rdict, result, nominal, meas, data, train, N, validation, stamp, targets, positions,
                   accuracy, write_robot, notes) -> dict:
    """Write result.json, the calibrated robot (TOML, URDF; only with ``write_robot``) and the
    report into ``paths`` (a staging folder); returns {kind: path}."""
    if not write_robot:
        notes.append("calibrated_robot.toml/.urdf not written: the result FAILED the sanity gates "
                     "(pass --force to write them anyway)")

    calibrated = result.model.replace(
        title=f"{nominal.title or nominal.name} (calibrated)",
        source=f"robocal calibrate of {Path(str(data)).name} ({len(train)} poses, {stamp}) from nominal: "
               f"{nominal.source}")
    comment = (f"Calibrated by robocal from {data} ({len(train)} of {N} poses; held-out RMS "
               + (f"{validation['before']['rms']:.4f} -> {validation['after']['rms']:.4f} mm" if validation else "n/a")
               + ").\n[base] is the robot base in the measurement instrument's frame "
               f"({meas.metadata.get('frame') or 'instrument'}). Identified target points (flange frame, mm): "
               + "; ".join(f"{t.name} = [{', '.join(f'{v:.4f}' for v in result.state.targets[k])}]"
                           for k, t in enumerate(targets))
               + ".\nAll numbers with uncertainties: result.json.")
    files = {}
    from ..io.urdf import UrdfError, write_urdf

    if write_robot:
        files["robot"] = save_robot(calibrated, paths["robot"], comment=comment)
        try:
            files["urdf"] = write_urdf(calibrated, paths["urdf"])
        except UrdfError as exc:  # a stale URDF of an earlier run is removed by staged_outputs
            notes.append(f"calibrated_robot.urdf not written: {exc}")
    rdict["notes"] = notes
    text = json.dumps(rdict, indent=2, allow_nan=False) + "\n"
    files["result"] = atomic_write_text(paths["result"], text)

    from ..report.html import write_report

    amap = {"positions_mm": positions, "values_mm": accuracy["predicted_std_mm"],
            "label": "predicted position std [mm]",
            "title": f"{nominal.name}: predicted uncertainty of the calibrated model at the measured poses",
            "note": "Flange positions in the robot base frame, coloured by the predicted 1-std position uncertainty "
                    "(J Cov J^T over the identified variables, base frame included)."}
    files["report"] = write_report(paths["report"], rdict, accuracy_map=amap,
                                   title=f"Calibration of {nominal.name} from {Path(str(data)).name}")
    return files


# ---------------------------------------------------------------------------------------------
# corrected joint targets
# ---------------------------------------------------------------------------------------------



def run_correct(robot_file, targets_file, out_file, *, nominal=None, frame=None, overwrite: bool = False) -> dict:
    """Corrected joint targets for the targets in ``targets_file`` with the calibrated robot
    ``robot_file``; writes ``out_file`` (CSV, ``robocal-corrected-targets/1``).

    nominal: the nominal robot (name or file) the controller runs; default the robot named in the
    calibrated file (``name``). frame: overrides the targets file's ``frame``.

    Output columns: ``name``, the corrected joints (controller joint names, in the file's
    ``angle_unit``; prismatic in ``length_unit``), the filtered Cartesian target to send to a
    nominal-model controller in the robot base frame (``x, y, z`` and orientation columns in the
    input's convention, ``quaternion`` if it had none), ``converged``, ``status``,
    ``position_error_mm``, ``rotation_error_deg`` (of the calibrated model at the joints).
    """
    out_file = Path(out_file)
    if out_file.exists() and not overwrite:
        raise FileExistsError(f"{out_file}: output file exists; pass --overwrite to replace it")
    calibrated = load_robot(robot_file)
    nominal_model = load_robot(nominal if nominal is not None else calibrated.name)
    if tuple(nominal_model.controller_joints) != tuple(calibrated.controller_joints):
        raise CalibrationInputError(f"nominal robot {nominal_model.name} has joints "
                                    f"{list(nominal_model.controller_joints)}, the calibrated robot "
                                    f"{list(calibrated.controller_joints)}")
    tg = read_targets(targets_file, calibrated)
    fr = frame or tg["frame"]
    targets = tg["positions"]
    corr = corrected_joint_targets(calibrated, nominal_model, targets, tg["rotations"], q_seed=tg["q_seed"], frame=fr)
    write_corrected_targets(out_file, corr, calibrated, tg["names"], robot=str(robot_file), nominal=nominal_model.name,
                            targets=f"{targets_file} (frame {fr})", length_unit=tg["length_unit"],
                            angle_unit=tg["angle_unit"], orientation=tg["orientation"], overwrite=overwrite)
    return {"corrected": corr, "file": out_file, "names": tg["names"], "frame": fr, "nominal": nominal_model.name}
