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
from ..errors import InputError

import json
import math
import warnings
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ..calib import solve
from ..calib.solve import NotConvergedWarning
from ..calib.outputs import corrected_joint_targets, json_ready, result_to_dict
from ..calib.sanity import calibration_verdict
from ..calib.uncertainty import predicted_point_std
from ..calib.validation import train_holdout_split
from ..io.atomic import atomic_write_text
from ..io.measurements import read_measurements
from ..io.targets import read_targets, write_corrected_targets
from ..metrics import error_statistics
from ..robots import load_robot, save_robot
from .calibrate_swarm import check_method, convergence_plots, identify, swarm_record
from .calibrate_setup import build_problems, split_by_ids, tool_frame_summary
from .outputs import check_outputs_free, ensure_writable_dir, staged_outputs
from .progress import solver_progress

__all__ = ["CalibrationInputError", "OUTPUT_FILES", "output_paths", "split_poses", "select_free", "run_calibration",
           "run_correct"]

OUTPUT_FILES = {"result": "result.json", "robot": "calibrated_robot.toml", "urdf": "calibrated_robot.urdf",
                "report": "report.html"}


class CalibrationInputError(InputError):
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
                    overwrite: bool = False, progress=None, method: str = "lm", rotation_weight: float | None = None,
                    prior=None, train_ids=(), holdout_ids=(), measurements=None, use_orientation: bool = True,
                    max_iterations: int = 50, report: bool = True, force: bool = False,
                    drop_duplicates: bool = False, particles: int = 20, generations: int = 2000,
                    swarm_progress=None, elastic: str | None = None, payload=None) -> dict:
    """Calibrate ``robot`` from the measurement file ``data``; write the results into ``out_dir``.

    robot: shipped robot name or robot file path (the nominal model). data: a
    ``robocal-measurements/1`` CSV file. free / free_all / fix: see :func:`select_free`. holdout:
    fraction of poses held out for validation (a seeded random split, ``seed``); 0 disables it.
    loss: ``linear``, ``huber`` or ``cauchy`` (robust, per pose). sigma_mm: measurement noise per
    coordinate [mm] (weights and absolute uncertainty; default: estimated from the residuals).
    tool: initial target point (3,) [mm] in the flange frame (default origin).
    progress(step, total, text): called between steps (and about once a second inside a long
    solve). report: write ``report.html`` (False for batch runs: the plots cost more than the
    solve). drop_duplicates: drop repeated poses (else an error); the dropped ones are listed in
    the notes.

    6-D (files with orientation, unless ``use_orientation`` is false): positions and orientations
    are fitted with a 6-DoF tool frame; rotation_weight [mm per rad] (default
    :data:`~robocal.workflows.calibrate_setup.DEFAULT_ROTATION_WEIGHT`). prior: ``(sigma_mm,
    sigma_deg)`` of a weak Gaussian prior on the geometry around nominal. train_ids /
    holdout_ids: a given protocol (pose ids, :func:`~robocal.workflows.calibrate_setup.split_by_ids`)
    instead of the seeded split. measurements: an already read :class:`~robocal.io.Measurements`
    (``data`` then only names it). max_iterations: of the solver; a solve that stops there is
    reported (``result["solver"]["warning"]``, ``NotConvergedWarning``). method: ``lm``, ``svd``,
    ``ipso`` or ``ipso+lm`` (:mod:`robocal.workflows.calibrate_swarm`: particles, generations,
    ``swarm_progress(generation, best_f)``; ``seed`` seeds the swarm too). elastic: ``"joint"``
    identifies a torsional compliance per joint under gravity together with the geometry (the
    robot file's mass model if it has one, else lumped gravity parameters; docs/elastic.md);
    payload: a :class:`~robocal.calib.elastic.Payload` (or ``KG@x,y,z`` text) carried during the
    measurements.

    Nothing is written when an output file exists and ``overwrite`` is false (``FileExistsError``
    naming the file, checked before any work); the files are written into a temporary folder and
    moved into place together (:mod:`robocal.workflows.outputs`). The sanity gates
    (:mod:`robocal.calib.sanity`) give ``status`` and ``reasons`` in result.json; a failed result
    writes no calibrated robot files unless ``force``. Returns a dict with ``result`` (the JSON
    dict), ``files``, ``notes``, ``verdict``, ``convergence_warnings`` and the solver objects.
    """
    step = progress or (lambda i, n, text: None)
    total = 6 if report else 5
    out = Path(out_dir)
    names = [n for k, n in OUTPUT_FILES.items() if report or k != "report"]
    _check_options(out, names, overwrite, loss, sigma_mm, method)
    nominal = load_robot(robot)
    from .calibrate_elastic import elastic_option, parse_payload

    if isinstance(payload, str):
        payload = parse_payload(payload)
    elastic_model = elastic_option(nominal, elastic, payload)
    if measurements is None:
        size_mb = Path(data).stat().st_size / 1e6 if Path(data).is_file() else 0.0
        if size_mb > 10.0:  # a large file takes seconds to read: say so (small files stay silent on errors)
            step(1, total, f"reading {data} ({size_mb:.0f} MB)")
        measurements = read_measurements(data, robot=nominal, check_limits=True, drop_duplicates=drop_duplicates)
    meas = measurements
    ensure_writable_dir(out)
    free_names = select_free(nominal, free, free_all, fix)
    train, hold, split_notes, protocol = _split(meas, data, free_names, use_orientation, holdout, seed,
                                                train_ids, holdout_ids)
    step(1, total, f"read {meas.n_poses} poses of {nominal.name} from {data}: {len(train)} to calibrate, "
                   f"{len(hold)} held out ({protocol})")
    setup = build_problems(nominal, meas, train, free_names=free_names, sigma_mm=sigma_mm, tool=tool,
                           use_orientation=use_orientation, rotation_weight=rotation_weight, prior=prior,
                           elastic=elastic_model)
    swarm = {"seed": seed, "particles": particles, "generations": generations, "progress": swarm_progress}
    res0, result, convergence_warnings = _solve(setup, step, total, len(train), len(free_names), meas.n_targets,
                                                loss, method, max_iterations, swarm)
    step(4, total, f"validating on {len(hold)} held-out pose(s)")
    validation = _validate(setup, res0, result, meas, hold)
    step(4, total, f"predicted uncertainty at the {meas.n_poses} measured poses")
    accuracy = _accuracy_map(setup["problem"], result, meas)
    verdict = calibration_verdict(
        robot=nominal.name, rms_before_mm=res0.rms_after, rms_after_mm=result.rms_after, sigma_mm=sigma_mm,
        holdout_before_mm=validation["before"]["rms"] if validation else None,
        holdout_after_mm=validation["after"]["rms"] if validation else None,
        parameters=(nominal.params.names, nominal.params.units, nominal.params.values, result.state.params))
    write_robot = verdict.ok or force
    step(5, total, "writing result.json" + (", calibrated robot (TOML, URDF)" if write_robot else
                                            " (FAILED the sanity gates: no calibrated robot file)"))
    notes = list(split_notes) + list(setup["notes"])
    if "dropped_duplicates" in meas.metadata:
        notes.insert(0, f"dropped duplicate poses: {meas.metadata['dropped_duplicates']}")
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    metadata = {
        "robot": str(robot), "measurements": str(data), "n_poses_file": meas.n_poses,
        "n_poses_calibration": int(len(train)), "n_poses_holdout": int(len(hold)), "holdout_fraction": holdout,
        "seed": seed, "loss": loss, "sigma_mm": sigma_mm, "method": method, "free": free_names,
        "fixed_by_option": list(fix), "initial_target_mm": [0.0, 0.0, 0.0] if tool is None else [float(v) for v in tool],
        "targets": list(meas.targets), "instrument": meas.metadata.get("instrument"),
        "frame": meas.metadata.get("frame"), "written": stamp, "measurement_kind": setup["description"],
        "rotation_weight_mm_per_rad": setup["rotation_weight"],
        "prior_sigma_mm_deg": None if prior is None else [float(v) for v in prior],
        "split": protocol, "max_iterations": max_iterations, "elastic": elastic,
    }
    rdict = _result_dict(setup, nominal, res0, result, meas, train, validation, accuracy, metadata, convergence_warnings)
    rdict["status"], rdict["reasons"], rdict["sanity_checks"] = verdict.status, list(verdict.reasons), verdict.checks
    elastic_out = None
    if elastic_model is not None:
        from .calibrate_elastic import elastic_summary, torque_plot, with_elastic

        rdict["elastic"] = json_ready(elastic_summary(setup["problem"], result))
        elastic_out = (lambda m: with_elastic(m, setup["problem"], result),
                       (lambda: torque_plot(setup["problem"], res0, result)) if report else None)
    if report:
        step(6, total, "writing report.html; moving the outputs into place together")
    with staged_outputs(out, names, overwrite) as stage:
        files = _write_outputs(output_paths(stage), rdict, result, nominal, meas, data, train, validation, stamp,
                               list(setup["problem"].targets), accuracy, write_robot, notes, report,
                               elastic=elastic_out)
    files = {k: out / p.name for k, p in files.items()}
    return {"result": rdict, "files": files, "notes": notes, "calibration_result": result,
            "problem": setup["problem"], "verdict": verdict, "six_d": bool(setup["six_d"]),
            "description": setup["description"], "convergence_warnings": convergence_warnings}


def _check_options(out: Path, names, overwrite, loss, sigma_mm, method) -> None:
    if out.exists() and not out.is_dir():
        raise CalibrationInputError(f"{out}: exists and is not a folder")
    check_outputs_free(out, names, overwrite)
    if loss not in ("linear", "huber", "cauchy"):
        raise CalibrationInputError(f"--loss must be linear, huber or cauchy, got {loss!r}")
    check_method(method, loss)
    if sigma_mm is not None and not (math.isfinite(sigma_mm) and sigma_mm > 0):
        raise CalibrationInputError(f"--sigma must be a positive number of mm, got {sigma_mm}")


def _split(meas, data, free_names, use_orientation, holdout, seed, train_ids, holdout_ids):
    """Calibration and held-out pose indices, notes and the protocol's name; a clear error when the
    calibration poses cannot determine the unknowns."""
    N, K = meas.n_poses, meas.n_targets
    split_notes = []
    if train_ids or holdout_ids:
        train, hold, split_notes = split_by_ids(meas.pose_ids, train_ids, holdout_ids)
    else:
        train, hold = split_poses(N, holdout, seed)
    six_d = use_orientation and meas.rotations is not None
    rows = 3 * K + (3 if six_d else 0)
    n_unknowns = len(free_names) + 6 + 3 * K + (3 if six_d else 0)
    n_res = rows * len(train)
    if n_res < n_unknowns or len(train) < 3:
        need = max(3, math.ceil(n_unknowns / rows))
        raise CalibrationInputError(
            f"{data}: too few poses: {len(train)} calibration pose(s) ({N} in the file, {len(hold)} held out) give "
            f"{n_res} residuals for {n_unknowns} unknowns ({len(free_names)} parameters, base frame, {K} target "
            f"point(s)); at least {need} calibration poses are needed, 3-5 times that for a useful result")
    protocol = "given pose ids" if (train_ids or holdout_ids) else f"seed {seed}"
    return train, hold, split_notes, protocol


def _solve(setup, step, total, n_train, n_free, K, loss, method, max_iterations, swarm):
    """The baseline (nominal geometry, best-fit base and targets) and the calibration; the
    convergence warnings of the calibration (list of str)."""
    step(2, total, f"initial base frame and target point(s) with the nominal geometry ({n_train} poses; "
                   f"{setup['description']})")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotConvergedWarning)  # the baseline only starts the real solve
        res0 = solve(setup["problem0"], loss=loss, method="svd" if method == "svd" else "lm",
                     max_iterations=max_iterations, progress=solver_progress(step, 2, total))
    step(3, total, f"identifying {n_free} parameter(s) + base + {K} target point(s) ({loss} loss)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NotConvergedWarning)
        start = res0.state
        if getattr(setup["problem"], "deflection", None) is not None:  # the baseline has no elastic blocks
            start = start._replace(**{b.name: b.initial for b in setup["problem"].deflection.blocks})
        if method in ("lm", "svd"):
            result = solve(setup["problem"], loss=loss, method=method, state0=start,
                           max_iterations=max_iterations, progress=solver_progress(step, 3, total))
        else:
            result = identify(setup["problem"], start, method=method, loss=loss, max_iterations=max_iterations,
                              **swarm)
    if start is not res0.state:
        _before_is_the_baseline(result, res0)
    return res0, result, [str(w.message) for w in caught if issubclass(w.category, NotConvergedWarning)]


def _before_is_the_baseline(result, res0) -> None:
    """An elastic solve starts from the baseline plus the compliance and gravity blocks' initial
    values, which already deflect the robot (with lumped gravity one compliance is held at a
    nonzero value to fix the scale): its own "before" would be that arbitrary start. Report the
    rigid baseline (nominal geometry, best-fit base and targets) as "before" instead, as on the
    rigid path, when the two problems' residuals have the same layout."""
    if (np.shape(result.residuals_before) == np.shape(res0.residuals_after)
            and np.shape(result.point_errors_before) == np.shape(res0.point_errors_after)):
        result.residuals_before = res0.residuals_after
        result.point_errors_before = res0.point_errors_after


def _validate(setup, res0, result, meas, hold):
    """Held-out position errors before/after (statistics and per point), or None without held-out poses."""
    if not len(hold):
        return None
    pose_ids = list(meas.pose_ids)
    q_h, p_h = meas.joints[hold], meas.points[hold]
    stations = np.zeros(len(hold), int)
    e_before = _point_errors(setup["problem0"].predict_points(res0.state, q=q_h, stations=stations), p_h)
    e_after = _point_errors(setup["problem"].predict_points(result.state, q=q_h, stations=stations), p_h)
    ok = np.isfinite(e_after)
    return {
        "n_poses": int(len(hold)), "pose_ids": [pose_ids[i] for i in hold],
        "before": error_statistics(e_before[ok]), "after": error_statistics(e_after[ok]),
        "per_point": _per_point(e_before, e_after, [pose_ids[i] for i in hold], meas.targets),
    }


def _accuracy_map(problem, result, meas) -> dict:
    """Predicted uncertainty over every pose of the file (the report's accuracy map)."""
    std_pts = predicted_point_std(problem, result, meas.joints)  # (N, K)
    base_model = result.model.replace(T_world_base=np.eye(4))
    positions = base_model.fk(meas.joints)[:, :3, 3]
    return {
        "quantity": "predicted position uncertainty (1 std, sqrt of the trace of J Cov J^T) of the targets in the "
                    "instrument frame, largest over the targets of each pose",
        "pose_ids": list(meas.pose_ids), "flange_position_base_mm": positions,
        "predicted_std_mm": std_pts.max(axis=1), "statistics": error_statistics(std_pts.max(axis=1)),
    }


def _result_dict(setup, nominal, res0, result, meas, train, validation, accuracy, metadata,
                 convergence_warnings) -> dict:
    pose_ids = list(meas.pose_ids)
    problem = setup["problem"]
    rdict = result_to_dict(result, problem, nominal=nominal, pose_ids=[pose_ids[i] for i in train],
                           validation=json_ready(validation) if validation else None, metadata=metadata)
    rdict["baseline"] = json_ready({
        "description": "nominal geometry with best-fit base frame and target point(s) (the 'before' state)",
        "iterations": res0.iterations, "converged": res0.converged, "reason": res0.reason,
        "rms_mm": res0.rms_after, "T_instrument_base": res0.state.bases[0], "targets_mm": res0.state.targets})
    rdict["accuracy_map"] = json_ready(accuracy)
    rdict["six_d"] = bool(setup["six_d"])
    rdict["tool_frame"] = json_ready(tool_frame_summary(result, problem))
    swarm_record(rdict, result, metadata["method"])
    if convergence_warnings:
        rdict["solver"]["warning"] = convergence_warnings[-1]
    return rdict


def _write_outputs(paths, rdict, result, nominal, meas, data, train, validation, stamp, targets, accuracy,
                   write_robot, notes, report, elastic=None) -> dict:
    """Write result.json, the calibrated robot (TOML, URDF; only with ``write_robot``) and the
    report (with ``report``) into ``paths`` (a staging folder); returns {kind: path}. elastic:
    None or (function adding the ``[elastic]`` section to the model, function giving the report's
    torque plots or None)."""
    if not write_robot:
        notes.append("calibrated_robot.toml/.urdf not written: the result FAILED the sanity gates "
                     "(pass --force to write them anyway)")
    N = meas.n_poses
    calibrated = result.model.replace(
        title=f"{nominal.title or nominal.name} (calibrated)",
        source=f"robocal calibrate of {Path(str(data)).name} ({len(train)} poses, {stamp}) from nominal: "
               f"{nominal.source}")
    if elastic is not None:
        calibrated = elastic[0](calibrated)
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
    if not report:
        return files
    from ..report.html import write_report

    amap = {"positions_mm": accuracy["flange_position_base_mm"], "values_mm": accuracy["predicted_std_mm"],
            "label": "predicted position std [mm]",
            "title": f"{nominal.name}: predicted uncertainty of the calibrated model at the measured poses",
            "note": "Flange positions in the robot base frame, coloured by the predicted 1-std position uncertainty "
                    "(J Cov J^T over the identified variables, base frame included)."}
    files["report"] = write_report(paths["report"], rdict, accuracy_map=amap,
                                   title=f"Calibration of {nominal.name} from {Path(str(data)).name}",
                                   extra_plots={**convergence_plots(result),
                                                **(elastic[1]() if elastic is not None and elastic[1] else {})})
    return files


# ---------------------------------------------------------------------------------------------
# corrected joint targets
# ---------------------------------------------------------------------------------------------



def deflection_of(calibrated, payload=None):
    """``reach(model, q)``: the poses a calibrated robot with an ``[elastic]`` section really reaches
    under ``payload`` (a :class:`~robocal.calib.elastic.Payload` or ``KG@x,y,z`` text); None
    without that section."""
    from .calibrate_elastic import parse_payload

    desc = calibrated.extra.get("elastic")
    if isinstance(payload, str):
        payload = parse_payload(payload)
    if desc is None:
        if payload is not None:
            raise CalibrationInputError(f"{calibrated.extra.get('origin', calibrated.name)}: --payload needs a robot "
                                        "file with an [elastic] section (robocal calibrate --elastic joint)")
        return None
    load = None if payload is None else (calibrated.end_effectors[0].name, payload.mass, payload.com)
    return lambda model, q: desc.reached_poses(model, q, load)


def run_correct(robot_file, targets_file, out_file, *, nominal=None, frame=None, overwrite: bool = False,
                payload=None) -> dict:
    """Corrected joint targets for the targets in ``targets_file`` with the calibrated robot
    ``robot_file``; writes ``out_file`` (CSV, ``robocal-corrected-targets/1``).

    nominal: the nominal robot (name or file) the controller runs; default the robot named in the
    calibrated file (``name``). frame: overrides the targets file's ``frame``.

    Output columns: ``name``, the corrected joints (controller joint names, in the file's
    ``angle_unit``; prismatic in ``length_unit``), the filtered Cartesian target to send to a
    nominal-model controller in the robot base frame (``x, y, z`` and orientation columns in the
    input's convention, ``quaternion`` if it had none), ``converged``, ``status``,
    ``position_error_mm``, ``rotation_error_deg`` (of the calibrated model at the joints).
    A robot file with an ``[elastic]`` section: the joint deflection under gravity and ``payload``
    (``KG@x,y,z`` or a :class:`~robocal.calib.elastic.Payload`) is compensated (docs/elastic.md).
    """
    from ..io.output_paths import check_outputs

    out_file = Path(out_file)
    check_outputs(out_file, {"the robot file": robot_file, "the targets": targets_file, "--nominal": nominal},
                  overwrite=overwrite)
    calibrated = load_robot(robot_file)
    nominal_model = load_robot(nominal if nominal is not None else calibrated.name)
    if tuple(nominal_model.controller_joints) != tuple(calibrated.controller_joints):
        raise CalibrationInputError(f"nominal robot {nominal_model.name} has joints "
                                    f"{list(nominal_model.controller_joints)}, the calibrated robot "
                                    f"{list(calibrated.controller_joints)}")
    tg = read_targets(targets_file, calibrated)
    fr = frame or tg["frame"]
    targets = tg["positions"]
    corr = corrected_joint_targets(calibrated, nominal_model, targets, tg["rotations"], q_seed=tg["q_seed"], frame=fr,
                                   reach=deflection_of(calibrated, payload))
    write_corrected_targets(out_file, corr, calibrated, tg["names"], robot=str(robot_file), nominal=nominal_model.name,
                            targets=f"{targets_file} (frame {fr})", length_unit=tg["length_unit"],
                            angle_unit=tg["angle_unit"], orientation=tg["orientation"], overwrite=overwrite)
    return {"corrected": corr, "file": out_file, "names": tg["names"], "frame": fr, "nominal": nominal_model.name}
