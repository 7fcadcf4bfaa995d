"""`robocal calibrate` and `robocal correct`: file-to-file calibration workflows.

``run_calibration`` reads a robot and a measurement file, splits the poses (seeded) into a
calibration and a held-out set, identifies the kinematic parameters, base frame and target
points, validates on the held-out poses and writes into one folder:

* ``result.json``            every number (:func:`robocal.calib.outputs.result_to_dict` + validation)
                             except the per-pose arrays, whose files it names (its size does not grow
                             with the pose count)
* ``residuals.csv``          position error of every measured point before/after (calibration and
                             held-out poses): ``set,pose_id,target,error_before_mm,error_after_mm``
* ``accuracy_map.csv``       predicted position std at every pose of the file:
                             ``pose_id,flange_x_mm,flange_y_mm,flange_z_mm,predicted_std_mm``
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
from ...errors import InputError

import json
import math
import warnings
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ...calib import solve
from ...calib.solve import NotConvergedWarning, not_converged_message
from ...calib.outputs import corrected_joint_targets, json_ready, result_to_dict
from ...calib.sanity import Verdict, calibration_verdict
from ...calib.uncertainty import predicted_point_std
from ...calib.validation import train_holdout_split
from ...io.atomic import atomic_write_text
from ...io.measurements import read_measurements
from ...io.targets import read_targets, write_corrected_targets
from ...metrics import error_statistics
from ...robots import load_robot, save_robot
from .calibrate_swarm import check_method, convergence_plots, identify, swarm_record
from .calibrate_setup import build_problems, split_by_ids, tool_frame_summary
from ..convergence import Convergence
from ..outputs import check_output_folder, check_outputs_free, ensure_writable_dir, staged_outputs
from ..progress import solver_progress

__all__ = ["CalibrationInputError", "OUTPUT_FILES", "output_paths", "split_poses", "select_free", "run_calibration",
           "compute_calibration", "write_calibration", "check_calibration_outputs", "calibrated_model", "run_correct"]

OUTPUT_FILES = {"result": "result.json", "robot": "calibrated_robot.toml", "urdf": "calibrated_robot.urdf",
                "report": "report.html", "residuals": "residuals.csv", "accuracy": "accuracy_map.csv"}


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


def select_free(model, free=None, free_all: bool = False, fix=(), frames_only: bool = False) -> list:
    """Names of the parameters to identify: the model's free ones (robot file ``fixed`` lists
    respected), or ``free`` (names), or all with ``free_all``; minus ``fix``. ``frames_only``: none
    (the geometry held, only the base / instrument and tool frames are fitted); it excludes the
    other options. An empty ``free`` list (``--free ""``) is an error, not "the default"."""
    names = list(model.params.names)
    if frames_only:
        if free or free_all or fix:
            raise CalibrationInputError("--frames-only holds the whole geometry: give no --free, --free-all or --fix")
        return []
    if free is not None and not isinstance(free, str) and len(free) == 0:
        raise CalibrationInputError("--free names no parameter; name some (e.g. --free a2,theta3), leave --free out "
                                    "for the default set, or pass --frames-only to fit only the base and tool frames")

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
                    max_iterations: int = 1000, report: bool = True, force: bool = False,
                    drop_duplicates: bool = False, particles: int = 20, generations: int = 2000,
                    swarm_progress=None, elastic: str | None = None, payload=None,
                    allow_unconverged: bool = False, frames_only: bool = False) -> dict:
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
    :data:`~robocal.workflows.calibration.calibrate_setup.DEFAULT_ROTATION_WEIGHT`). prior: ``(sigma_mm,
    sigma_deg)`` of a weak Gaussian prior on the geometry around nominal. train_ids /
    holdout_ids: a given protocol (pose ids, :func:`~robocal.workflows.calibration.calibrate_setup.split_by_ids`)
    instead of the seeded split. measurements: an already read :class:`~robocal.io.Measurements`
    (``data`` then only names it). max_iterations: of the solver; a solve that stops there is
    reported (``result["solver"]["warning"]``, ``NotConvergedWarning``). method: ``lm``, ``svd``,
    ``ipso`` or ``ipso+lm`` (:mod:`robocal.workflows.calibration.calibrate_swarm`: particles, generations,
    ``swarm_progress(generation, best_f)``; ``seed`` seeds the swarm too). elastic: ``"joint"``
    identifies a torsional compliance per joint under gravity together with the geometry (the
    robot file's mass model if it has one, else lumped gravity parameters; docs/elastic.md);
    payload: a :class:`~robocal.calib.elastic.Payload` (or ``KG@x,y,z`` text) carried during the
    measurements. frames_only: hold the whole geometry and fit only the base (instrument) frame and
    the tool frame / target points: re-registering a calibrated robot in a new cell.

    Nothing is written when an output file exists and ``overwrite`` is false (``FileExistsError``
    naming the file, checked before any work); the files are written into a temporary folder and
    moved into place together (:mod:`robocal.workflows.outputs`). The sanity gates
    (:mod:`robocal.calib.sanity`) give ``status`` and ``reasons`` in result.json; a failed result
    writes no calibrated robot files unless ``force``. A fit that did not converge (the baseline or
    the calibration; :mod:`robocal.workflows.convergence`) marks result.json (``convergence``) and
    writes no calibrated robot files unless ``allow_unconverged``. Returns a dict with ``result``
    (the JSON dict), ``files``, ``notes``, ``verdict``, ``convergence`` (a
    :class:`~robocal.workflows.convergence.Convergence`), ``convergence_warnings`` and the solver objects.
    """
    step = progress or (lambda i, n, text: None)
    total = 6 if report else 5
    out = Path(out_dir)
    names = [n for k, n in OUTPUT_FILES.items() if report or k != "report"]
    _check_options(out, names, overwrite, loss, sigma_mm, method)
    nominal = load_robot(robot)
    if measurements is None:
        size_mb = Path(data).stat().st_size / 1e6 if Path(data).is_file() else 0.0
        if size_mb > 10.0:  # a large file takes seconds to read: say so (small files stay silent on errors)
            step(1, total, f"reading {data} ({size_mb:.0f} MB)")
        measurements = read_measurements(data, robot=nominal, check_limits=True, drop_duplicates=drop_duplicates)
    ensure_writable_dir(out)
    computed = compute_calibration(
        nominal, measurements, robot_label=robot, data_label=data, free=free, free_all=free_all, fix=fix,
        holdout=holdout, seed=seed, loss=loss, sigma_mm=sigma_mm, tool=tool, method=method,
        rotation_weight=rotation_weight, prior=prior, train_ids=train_ids, holdout_ids=holdout_ids,
        use_orientation=use_orientation, max_iterations=max_iterations, particles=particles,
        generations=generations, swarm_progress=swarm_progress, elastic=elastic, payload=payload,
        progress=step, total=total, frames_only=frames_only)
    return write_calibration(computed, out, overwrite=overwrite, report=report, force=force, progress=step,
                             allow_unconverged=allow_unconverged)


def compute_calibration(nominal, meas, *, robot_label, data_label, free=None, free_all: bool = False, fix=(),
                        holdout: float = 0.2, seed: int = 0, loss: str = "linear", sigma_mm: float | None = None,
                        tool=None, method: str = "lm", rotation_weight: float | None = None, prior=None,
                        train_ids=(), holdout_ids=(), use_orientation: bool = True, max_iterations: int = 1000,
                        particles: int = 20, generations: int = 2000, swarm_progress=None,
                        elastic: str | None = None, payload=None, progress=None, total: int = 6,
                        frames_only: bool = False) -> dict:
    """The in-memory part of :func:`run_calibration`: split, solve, validate, sanity gates.

    ``nominal`` is a loaded :class:`~robocal.kinematics.RobotModel` and ``meas`` read
    :class:`~robocal.io.Measurements`; ``robot_label`` and ``data_label`` name them in the result's
    metadata. The other arguments are those of :func:`run_calibration`. Nothing is written; the
    returned dict goes to :func:`write_calibration` (``result`` is the JSON dict of result.json).
    """
    step = progress or (lambda i, n, text: None)
    robot, data = robot_label, data_label
    _check_solver_options(loss, sigma_mm, method)
    from .calibrate_elastic import elastic_option, parse_payload

    if isinstance(payload, str):
        payload = parse_payload(payload)
    elastic_model = elastic_option(nominal, elastic, payload)
    free_names = select_free(nominal, free, free_all, fix, frames_only=frames_only)
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
    coverage = _coverage(nominal, meas, train, hold, setup["problem"], result, free_names)
    verdict = verdict + coverage["verdict"]
    verdict = _non_convergence_first(verdict, convergence_warnings, max_iterations)
    elastic_json = None
    if elastic_model is not None:  # the plausibility gate of the compliances and mass parameters
        from .calibrate_elastic import elastic_summary

        elastic_json = elastic_summary(setup["problem"], result)
        verdict = Verdict(tuple(verdict.reasons) + tuple(elastic_json["gate_reasons"]), verdict.checks)
    convergence = Convergence.of([("baseline fit (nominal geometry)", res0), ("calibration", result)])
    notes = list(split_notes) + list(setup["notes"])
    if "dropped_duplicates" in meas.metadata:
        notes.insert(0, f"dropped duplicate poses: {meas.metadata['dropped_duplicates']}")
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    metadata = {
        "robot": str(robot), "measurements": str(data), "n_poses_file": meas.n_poses,
        "n_poses_calibration": int(len(train)), "n_poses_holdout": int(len(hold)), "holdout_fraction": holdout,
        "seed": seed, "loss": loss, "sigma_mm": sigma_mm, "method": method, "free": free_names,
        "frames_only": bool(frames_only),
        "fixed_by_option": list(fix), "initial_target_mm": [0.0, 0.0, 0.0] if tool is None else [float(v) for v in tool],
        "targets": list(meas.targets), "instrument": meas.metadata.get("instrument"),
        "frame": meas.metadata.get("frame"), "written": stamp, "measurement_kind": setup["description"],
        "rotation_weight_mm_per_rad": setup["rotation_weight"],
        "prior_sigma_mm_deg": None if prior is None else [float(v) for v in prior],
        "split": protocol, "max_iterations": max_iterations, "elastic": elastic,
    }
    rdict = _result_dict(setup, nominal, res0, result, meas, train, validation, accuracy, metadata, convergence_warnings)
    from .orientation_errors import orientation_summary

    rdict["orientation"] = json_ready(orientation_summary(setup, res0, result, meas, train, hold))
    if setup["six_d"]:
        rdict["baseline"]["T_flange_tool"] = json_ready(res0.state.tool[0])
    rdict["status"], rdict["reasons"], rdict["sanity_checks"] = verdict.status, list(verdict.reasons), verdict.checks
    rdict["joint_coverage"] = coverage["table"]
    rdict["convergence"] = convergence.as_dict()
    if elastic_model is not None:
        rdict["elastic"] = json_ready(elastic_json)
    computed = {"result": rdict, "notes": notes, "calibration_result": result, "baseline_result": res0,
                "problem": setup["problem"], "verdict": verdict, "six_d": bool(setup["six_d"]),
                "description": setup["description"], "convergence_warnings": convergence_warnings,
                "nominal": nominal, "measurements": meas, "data": data, "train": train, "validation": validation,
                "accuracy": accuracy, "stamp": stamp, "elastic": elastic_model is not None,
                "convergence": convergence}
    computed["robot"] = calibrated_model(computed)
    return computed


def calibrated_model(computed: dict):
    """The calibrated :class:`~robocal.kinematics.RobotModel` of a :func:`compute_calibration`
    (title and source say where it came from; an ``[elastic]`` section when identified)."""
    nominal, result = computed["nominal"], computed["calibration_result"]
    calibrated = result.model.replace(
        title=f"{nominal.title or nominal.name} (calibrated)",
        source=f"robocal calibrate of {Path(str(computed['data'])).name} ({len(computed['train'])} poses, "
               f"{computed['stamp']}) from nominal: {nominal.source}")
    if computed["elastic"]:
        from .calibrate_elastic import with_elastic

        calibrated = with_elastic(calibrated, computed["problem"], result)
    return _with_identified_tool(calibrated, result, computed["result"])


def write_calibration(computed: dict, out_dir, *, overwrite: bool = False, report: bool = True,
                      force: bool = False, progress=None, allow_unconverged: bool = False) -> dict:
    """Write a :func:`compute_calibration` into ``out_dir`` (result.json, calibrated_robot.toml/.urdf
    unless the sanity gates failed and not ``force``, or a fit did not converge and not
    ``allow_unconverged``; report.html with ``report``), as
    :func:`run_calibration` does; returns its dict (``files`` added)."""
    step = progress or (lambda i, n, text: None)
    total = 6 if report else 5
    out = Path(out_dir)
    names = check_calibration_outputs(out, overwrite=overwrite, report=report)
    ensure_writable_dir(out)
    verdict, rdict, result = computed["verdict"], computed["result"], computed["calibration_result"]
    convergence = computed["convergence"]
    write_robot = (verdict.ok or force) and convergence.may_write_model(allow_unconverged)
    step(5, total, "writing result.json" + (", calibrated robot (TOML, URDF)" if write_robot else
                                            " (no calibrated robot file: FAILED the sanity gates or did not converge)"))
    notes = list(computed["notes"])
    if not convergence.may_write_model(allow_unconverged):
        notes.append(convergence.skipped_note("calibrated_robot.toml/.urdf"))
    elastic_out = None
    if computed["elastic"]:
        from .calibrate_elastic import torque_plot

        problem, res0 = computed["problem"], computed["baseline_result"]
        elastic_out = (lambda: torque_plot(problem, res0, result)) if report else None
    if report:
        step(6, total, "writing report.html; moving the outputs into place together")
    with staged_outputs(out, names, overwrite) as stage:
        files = _write_outputs(output_paths(stage), rdict, computed["robot"], computed["nominal"],
                               computed["measurements"], computed["data"], computed["train"], computed["validation"],
                               list(computed["problem"].targets), computed["accuracy"], write_robot, notes, report,
                               result=result, torque_plots=elastic_out, failed_gates=not (verdict.ok or force))
    files = {k: out / p.name for k, p in files.items()}
    return {**{k: computed[k] for k in ("result", "calibration_result", "problem", "verdict", "six_d", "description",
                                        "convergence_warnings", "convergence")},
            "files": files, "notes": notes}


def check_calibration_outputs(out_dir, *, overwrite: bool = False, report: bool = True, inputs=None) -> list:
    """Refuse an output folder that is a file, an output that is one of ``inputs`` (a path, a list
    or ``{what: path}``: the robot file, the measurements; even with ``overwrite``), or outputs of
    an earlier run without ``overwrite`` (``OutputExistsError``); the names of the files a
    calibration writes there."""
    out = Path(out_dir)
    names = [n for k, n in OUTPUT_FILES.items() if report or k != "report"]
    if out.exists() and not out.is_dir():
        raise CalibrationInputError(f"{out}: exists and is not a folder")
    check_output_folder(out, names, inputs, overwrite)
    return names


def _check_solver_options(loss, sigma_mm, method) -> None:
    if loss not in ("linear", "huber", "cauchy"):
        raise CalibrationInputError(f"--loss must be linear, huber or cauchy, got {loss!r}")
    check_method(method, loss)
    if sigma_mm is not None and not (math.isfinite(sigma_mm) and sigma_mm > 0):
        raise CalibrationInputError(f"--noise must be a positive number of mm, got {sigma_mm}")


def _non_convergence_first(verdict, convergence_warnings, max_iterations):
    """A failed verdict after an unconverged solve names the non-convergence first: the gates then
    judge an unfinished solve, and their likely causes (swapped columns, units) may not apply."""
    if verdict.ok or not convergence_warnings:
        return verdict
    from ...calib.sanity import Verdict

    first = (f"the solver did not converge within {max_iterations} iterations: the figures the gates judged come "
             "from an unfinished solve (try --max-iterations, better starting values or fewer free parameters) "
             "before suspecting the causes below")
    return Verdict((first,) + tuple(verdict.reasons), dict(verdict.checks))


def _coverage(nominal, meas, train, hold, problem, result, free_names) -> dict:
    """The coverage gates (:mod:`robocal.calib.coverage`) of the calibration poses: ``{verdict, table}``.
    The full reference campaign (identified-parameter gate): seeded poses a floor-mounted robot can
    take, spread over the joint limits (serial robots; others skip that gate)."""
    from ...calib.cell import default_cell, sample_feasible
    from ...calib.coverage import REFERENCE_POSES, coverage_verdict, joint_coverage

    q_hold = meas.joints[hold] if len(hold) else None
    if not free_names:  # frames only (geometry held): the joints' coverage does not bear on the frames
        from ...calib.sanity import Verdict

        return {"verdict": Verdict((), {}), "table": joint_coverage(nominal, meas.joints[train], q_hold)}
    targets = np.asarray(result.state.targets, dtype=float)
    ref = None
    if nominal.is_serial and len(train):
        try:
            ref, _ = sample_feasible(default_cell(tuple(targets[0])), nominal, REFERENCE_POSES,
                                     np.random.default_rng(0))
        except ValueError:
            ref = None
    identified = [n for n in result.identifiability.identifiable if n in set(nominal.params.names)]
    q_hold = meas.joints[hold] if len(hold) else None
    verdict = coverage_verdict(nominal, meas.joints[train], q_hold, targets_mm=targets,
                               ee_of_target=tuple(int(e) for e in problem.ee_of_target), identified=identified,
                               free=free_names, reference_q=ref)
    return {"verdict": verdict, "table": joint_coverage(nominal, meas.joints[train], q_hold)}


def _check_options(out: Path, names, overwrite, loss, sigma_mm, method) -> None:
    if out.exists() and not out.is_dir():
        raise CalibrationInputError(f"{out}: exists and is not a folder")
    check_outputs_free(out, names, overwrite)
    _check_solver_options(loss, sigma_mm, method)


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
    # no warnings.catch_warnings on the default path: it changes the filters of every thread at once,
    # and calibrations run side by side in the threads of a fleet worker or a user's program
    res0 = solve(setup["problem0"], loss=loss, method="svd" if method == "svd" else "lm",
                 max_iterations=max_iterations, progress=solver_progress(step, 2, total),
                 warn=False)  # the baseline only starts the real solve
    step(3, total, f"identifying {n_free} parameter(s) + base + {K} target point(s) ({loss} loss)")
    start = res0.state
    if getattr(setup["problem"], "deflection", None) is not None:  # the baseline has no elastic blocks
        start = start._replace(**{b.name: b.initial for b in setup["problem"].deflection.blocks})
    if method in ("lm", "svd"):
        result = solve(setup["problem"], loss=loss, method=method, state0=start,
                       max_iterations=max_iterations, progress=solver_progress(step, 3, total), warn=False)
        messages = [] if result.converged else [not_converged_message(result)]
    else:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", NotConvergedWarning)
            result = identify(setup["problem"], start, method=method, loss=loss, max_iterations=max_iterations,
                              **swarm)
        messages = [str(w.message) for w in caught if issubclass(w.category, NotConvergedWarning)]
    if start is not res0.state:
        _before_is_the_baseline(result, res0)
    return res0, result, messages


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


#: The accuracy map's per-pose entries (written to accuracy_map.csv, not to result.json).
_PER_POSE_MAP = ("pose_ids", "flange_position_base_mm", "predicted_std_mm")


def _accuracy_map(problem, result, meas) -> dict:
    """Predicted uncertainty over every pose of the file (the report's accuracy map)."""
    std_pts = predicted_point_std(problem, result, meas.joints)  # (N, K)
    # the flange origin in the base frame by the solver's kernel (no second kinematics kernel to compile)
    model = result.model
    positions = model.target_points(meas.joints, model.params.values, np.zeros((1, 3)), np.zeros(1, dtype=np.int64),
                                    np.zeros(0, dtype=np.int64), want_jacobian=False)[0][:, 0]
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
    # the per-pose arrays stay arrays: they go to accuracy_map.csv, not into result.json (as lists they
    # cost ~30 MiB at 100 000 poses, the big campaign's peak)
    rdict["accuracy_map"] = {k: v if k in _PER_POSE_MAP else json_ready(v) for k, v in accuracy.items()}
    rdict["six_d"] = bool(setup["six_d"])
    _name_parallel_axes(rdict, nominal)
    rdict["tool_frame"] = json_ready(tool_frame_summary(result, problem))
    swarm_record(rdict, result, metadata["method"])
    if convergence_warnings:
        rdict["solver"]["warning"] = convergence_warnings[-1]
    return rdict


def _with_identified_tool(calibrated, result, rdict):
    """The calibrated model with the identified 6-DoF tool frame (a 6-D fit with one measured frame)
    as its tool: the robot file's ``[tool]`` (docs/robot-files.md), so ``robocal fk`` and
    ``robocal correct`` work at the measured frame. Other fits: unchanged."""
    from ...kinematics.model import EndEffector

    tf = rdict.get("tool_frame")
    if tf is None or getattr(result.state, "tool", None) is None or "targets" in result.state._fields:
        return calibrated
    ees = calibrated.end_effectors
    if len(ees) != 1 or ees[0].link != len(calibrated.links) - 1:
        return calibrated  # a tree robot: the tool stays in result.json
    T = ees[0].T_link_ee @ np.asarray(result.state.tool[0], dtype=float)
    return calibrated.replace(end_effectors=[EndEffector("tool", ees[0].link, T)])


def _name_parallel_axes(rdict: dict, nominal) -> None:
    """``identifiability.parallel_axes``: the robot's (nearly) parallel consecutive joint axes with
    the beta that carries their tilt; a dropped parameter of such a pair says so in its ``why``."""
    from ...kinematics.parallel_axes import parallel_axis_pairs

    ident = rdict.setdefault("identifiability", {})
    free = set(rdict.get("metadata", {}).get("free") or ())
    rows = []
    for pair in parallel_axis_pairs(nominal.links):
        a, b = nominal.links[pair.first].name, nominal.links[pair.second].name
        beta = f"beta{pair.beta_link + 1}"
        rows.append({"joints": [a, b], "beta": beta, "beta_free": beta in free})
        mine = {beta} | {f"d{k + 1}" for k in (pair.first, pair.second)}
        for d in ident.get("dropped") or ():
            if d["name"] in mine:
                d["why"] = (d.get("why") or "") + f" (axes {a} and {b} are parallel; {beta} carries their tilt)"
    ident["parallel_axes"] = rows


def _csv_number(v) -> str:
    """A number for the side CSV files: 6 significant digits (um on mm errors); empty for NaN / null."""
    return "" if v is None or not math.isfinite(v) else f"{v:.6g}"


def _move_per_pose_to_csv(paths, rdict, files) -> dict:
    """Write the per-point errors (calibration and held-out poses) to ``residuals.csv`` and the accuracy
    map (one row per pose of the file) to ``accuracy_map.csv``, and replace those arrays in ``rdict`` by
    the file names, so that result.json's size does not grow with the pose count. Returns a shallow copy
    of ``rdict`` with the arrays (for the report). Adds the files to ``files``."""
    full = dict(rdict)
    res = rdict.get("residuals") or {}
    val = rdict.get("validation") or {}
    sets = [(name, d["per_point"]) for name, d in (("calibration", res), ("holdout", val)) if d.get("per_point")]
    if sets:
        with open(paths["residuals"], "w", encoding="utf-8", newline="\n") as fh:
            fh.write("set,pose_id,target,error_before_mm,error_after_mm\n")
            for name, per in sets:
                fh.writelines(f"{name},{p},{t},{_csv_number(b)},{_csv_number(a)}\n"
                              for p, t, b, a in zip(per["pose"], per["target"], per["before"], per["after"]))
        files["residuals"] = paths["residuals"]
        ref = {"file": OUTPUT_FILES["residuals"], "n": None,
               "columns": ["set", "pose_id", "target", "error_before_mm", "error_after_mm"], "unit": "mm"}
        for name, d, key in (("calibration", res, "residuals"), ("holdout", val, "validation")):
            if d.get("per_point"):
                full[key] = dict(d)
                # the held-out pose ids are the file's "holdout" rows
                rdict[key] = {k: v for k, v in d.items() if k not in ("per_point", "pose_ids")}
                rdict[key]["per_point_file"] = dict(ref, set=name, n=len(d["per_point"]["pose"]))
    amap = rdict.get("accuracy_map")
    if amap and amap.get("pose_ids") is not None:
        with open(paths["accuracy"], "w", encoding="utf-8", newline="\n") as fh:
            fh.write("pose_id,flange_x_mm,flange_y_mm,flange_z_mm,predicted_std_mm\n")
            fh.writelines(f"{p},{_csv_number(x)},{_csv_number(y)},{_csv_number(z)},{_csv_number(v)}\n"
                          for p, (x, y, z), v in zip(amap["pose_ids"], amap["flange_position_base_mm"],
                                                     amap["predicted_std_mm"]))
        files["accuracy"] = paths["accuracy"]
        rdict["accuracy_map"] = {k: v for k, v in amap.items()
                                 if k not in ("pose_ids", "flange_position_base_mm", "predicted_std_mm")}
        rdict["accuracy_map"]["file"] = OUTPUT_FILES["accuracy"]
        rdict["accuracy_map"]["n_poses"] = len(amap["pose_ids"])
    return full


def _write_outputs(paths, rdict, calibrated, nominal, meas, data, train, validation, targets, accuracy,
                   write_robot, notes, report, *, result, torque_plots=None, failed_gates: bool = True) -> dict:
    """Write result.json, the calibrated robot ``calibrated`` (TOML, URDF; only with
    ``write_robot``) and the report (with ``report``) into ``paths`` (a staging folder); returns
    {kind: path}. torque_plots: None or a function giving the report's elastic torque plots."""
    if not write_robot and failed_gates:
        notes.append("calibrated_robot.toml/.urdf not written: the result FAILED the sanity gates "
                     "(pass --force to write them anyway)")
    N = meas.n_poses
    comment = (f"Calibrated by robocal from {data} ({len(train)} of {N} poses; held-out RMS "
               + (f"{validation['before']['rms']:.4f} -> {validation['after']['rms']:.4f} mm" if validation else "n/a")
               + ").\n[base] is the robot base in the measurement instrument's frame "
               f"({meas.metadata.get('frame') or 'instrument'}). Identified target points (flange frame, mm): "
               + "; ".join(f"{t.name} = [{', '.join(f'{v:.4f}' for v in result.state.targets[k])}]"
                           for k, t in enumerate(targets))
               + ".\nAll numbers with uncertainties: result.json.")
    implausible = (rdict.get("elastic") or {}).get("not_identified") or []
    if implausible:
        comment += ("\n[elastic]: NOT identified by these data (negative, or sigma >= |value|; kept at their fitted "
                    "values, do not read them as known): " + ", ".join(r["name"] for r in implausible) + ".")
    files = {}
    from ...io.urdf import UrdfError, write_urdf

    if write_robot:
        files["robot"] = save_robot(calibrated, paths["robot"], comment=comment)
        try:
            files["urdf"] = write_urdf(calibrated, paths["urdf"])
        except UrdfError as exc:  # a stale URDF of an earlier run is removed by staged_outputs
            notes.append(f"calibrated_robot.urdf not written: {exc}")
    rdict["notes"] = notes
    full = _move_per_pose_to_csv(paths, rdict, files)  # result.json keeps summaries and the file names
    text = json.dumps(rdict, indent=2, allow_nan=False) + "\n"
    files["result"] = atomic_write_text(paths["result"], text)
    if not report:
        return files
    rdict = full  # the report's per-pose figures read the per-point errors
    from ...report.html import write_report

    amap = {"positions_mm": accuracy["flange_position_base_mm"], "values_mm": accuracy["predicted_std_mm"],
            "label": "predicted position std [mm]",
            "title": f"{nominal.name}: predicted uncertainty of the calibrated model at the measured poses",
            "note": "Flange positions in the robot base frame, coloured by the predicted 1-std position uncertainty "
                    "(J Cov J^T over the identified variables, base frame included)."}
    cov_rows = [[c["joint"], c["unit"], f"{c['min']:.4g}", f"{c['max']:.4g}", f"{c['span']:.4g}",
                 "unlimited" if c["range"] is None else f"{c['range']:.4g}",
                 "" if c["fraction"] is None else f"{100 * c['fraction']:.0f} %"] for c in rdict.get("joint_coverage", [])]
    files["report"] = write_report(paths["report"], rdict, accuracy_map=amap,
                                   extra_tables={"Joint-range coverage of the calibration poses": (
                                       ["joint", "unit", "min", "max", "span", "range", "covered"], cov_rows)},
                                   title=f"Calibration of {nominal.name} from {Path(str(data)).name}",
                                   extra_plots={**convergence_plots(result),
                                                **(torque_plots() if torque_plots is not None else {})})
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


def _controller_tool(nominal, calibrated):
    """The nominal model as the controller runs it: with the calibrated file's tool (``[tool]``,
    e.g. the 6-DoF tool frame ``robocal calibrate`` identified) when the nominal robot has a bare
    flange, so targets and the filtered Cartesian targets are poses of the same tool frame."""
    from ...kinematics.model import EndEffector

    c_ees, n_ees = calibrated.end_effectors, nominal.end_effectors
    if (len(c_ees) == 1 and c_ees[0].name == "tool" and len(n_ees) == 1 and n_ees[0].name == "flange"
            and np.array_equal(np.asarray(n_ees[0].T_link_ee, dtype=float), np.eye(4))
            and len(nominal.links) == len(calibrated.links)):
        return nominal.replace(end_effectors=[EndEffector("tool", n_ees[0].link, np.asarray(c_ees[0].T_link_ee))])
    return nominal


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
    A calibrated file with a ``[tool]`` (a 6-D calibration's identified tool frame): targets are
    poses of that tool, and a nominal robot with a bare flange gets the same tool (the controller's
    TCP). A robot file with an ``[elastic]`` section: the joint deflection under gravity and ``payload``
    (``KG@x,y,z`` or a :class:`~robocal.calib.elastic.Payload`) is compensated (docs/elastic.md).
    """
    from ...io.output_paths import check_outputs

    out_file = Path(out_file)
    check_outputs(out_file, {"the robot file": robot_file, "the targets": targets_file, "--nominal": nominal},
                  overwrite=overwrite)
    calibrated = load_robot(robot_file)
    nominal_model = _controller_tool(load_robot(nominal if nominal is not None else calibrated.name), calibrated)
    if tuple(nominal_model.controller_joints) != tuple(calibrated.controller_joints):
        raise CalibrationInputError(f"nominal robot {nominal_model.name} has joints "
                                    f"{list(nominal_model.controller_joints)}, the calibrated robot "
                                    f"{list(calibrated.controller_joints)}")
    tg = read_targets(targets_file, calibrated)
    fr = frame or tg["frame"]
    if fr is None:
        raise CalibrationInputError(
            f"{targets_file}: the targets' frame is not stated; add '# frame: world' (the calibrated robot file's "
            "world frame: the measurement instrument's, e.g. the tracker) or '# frame: base' (the robot base frame) "
            "to the header, or pass --frame world|base")
    targets = tg["positions"]
    _check_orientations(tg, nominal_model, calibrated, fr, targets_file)
    corr = corrected_joint_targets(calibrated, nominal_model, targets, tg["rotations"], q_seed=tg["q_seed"], frame=fr,
                                   reach=deflection_of(calibrated, payload))
    write_corrected_targets(out_file, corr, calibrated, tg["names"], robot=str(robot_file), nominal=nominal_model.name,
                            targets=f"{targets_file} (frame {fr})", length_unit=tg["length_unit"],
                            angle_unit=tg["angle_unit"], orientation=tg["orientation"], overwrite=overwrite)
    return {"corrected": corr, "file": out_file, "names": tg["names"], "frame": fr, "nominal": nominal_model.name}


#: A target's orientation farther than this from the orientation of its own taught (seed) joints
#: is refused [deg]: a calibration moves orientations by hundredths of a degree, not by this.
ORIENTATION_SEED_TOLERANCE_DEG = 5.0


def _check_orientations(tg, nominal_model, calibrated, frame, targets_file) -> None:
    """Refuse targets whose orientation does not fit their taught seed joints: the orientation unit
    or convention of the file is then wrong (the message names the ones that fit)."""
    if tg["rotations"] is None or tg["q_seed"] is None:
        return
    from ...transforms import POSE_CONVENTIONS, so3_log, transform_from_pose

    base = calibrated.T_world_base if frame == "world" else np.eye(4)
    R_taught = nominal_model.replace(T_world_base=base).fk(tg["q_seed"])[:, :3, :3]

    def worst(R):
        return float(np.degrees(np.max(np.linalg.norm(so3_log(np.swapaxes(R_taught, 1, 2) @ R), axis=1))))

    off = worst(tg["rotations"])
    if off <= ORIENTATION_SEED_TOLERANCE_DEG:
        return
    raw, fits = tg["orientation_values"], []
    for conv in POSE_CONVENTIONS:
        for au in ("deg", "rad"):
            if (conv == "quaternion") != (raw.shape[1] == 4) or (conv == "quaternion" and au == "rad"):
                continue
            try:
                T = transform_from_pose(np.concatenate([np.zeros((len(raw), 3)), raw], axis=1), conv, angle_unit=au)
            except ValueError:
                continue
            if worst(T[:, :3, :3]) <= ORIENTATION_SEED_TOLERANCE_DEG:
                fits.append(f"'# orientation: {conv}'" + ("" if conv == "quaternion" else f" with '# angle_unit: {au}'"))
    hint = ("; the taught joints fit " + " or ".join(fits)) if fits else "; check '# orientation:' and '# angle_unit:'"
    raise CalibrationInputError(
        f"{targets_file}: target orientations are up to {off:.1f} deg from the orientations of their taught joints "
        f"(the seed columns; at most {ORIENTATION_SEED_TOLERANCE_DEG:g} deg expected) as read with orientation "
        f"{tg['orientation']} in {tg['angle_unit']}{hint}")
