"""`robocal closed-chain simulate|calibrate`: the virtual closed kinematic chain, file to file.

``simulate_closed_chain`` writes a held-spot file (``robocal-spots/1``, :mod:`robocal.io.spots`)
of a simulated cell (:mod:`robocal.sim.closed_chain`) and the hidden truth next to it.

``run_closed_chain_calibration`` reads a robot and a held-spot file and writes the same outputs as
``robocal calibrate`` (:data:`robocal.workflows.calibration.calibrate.OUTPUT_FILES`: ``result.json``,
``calibrated_robot.toml``/``.urdf``, ``report.html``), all or nothing
(:mod:`robocal.workflows.outputs`), after the same sanity gates. Steps:

1. split the held spots (seeded): per spot, a share is held out, at least two stay to close it;
2. the "before" fit: nominal geometry, best-fit laser mount and spots;
3. the calibration (:class:`~robocal.calib.closed_chain.ClosedChainProblem`): geometry, mount,
   spots (+ the known target spacing); parameters the data barely see are held and reported;
4. held-out spots: their in-plate error with the calibrated model and the spots of step 3.

``result.json`` adds ``closed_chain``: E_OP before/after (eq. 6), the mount, the spots, and the
identifiability findings in plain words (base frame, length scale, along the beam).
"""

from __future__ import annotations

import json
import math
import warnings
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ...calib import solve
from ...calib.closed_chain import (
    ClosedChainProblem,
    classify_unidentified,
    e_op,
    length_scale_check,
    practically_unidentifiable,
)
from ...calib.outputs import json_ready, problem_result_dict
from ...calib.sanity import calibration_verdict
from ...calib.solve import NotConvergedWarning
from ...io.atomic import atomic_write_text
from ...io.spots import canonical_order, read_spots, write_spots
from ...metrics import error_statistics
from ...robots import load_robot, save_robot
from ...sim import VirtualRobot, write_truth
from ...sim.closed_chain import ClosedChainCell, JointReadout, LaserPointer, default_plates
from ...sim.closed_chain_effects import CellEffects
from .calibrate import OUTPUT_FILES, CalibrationInputError, output_paths, select_free
from ..convergence import Convergence, record_fit
from ..outputs import check_output_folder, ensure_writable_dir, staged_outputs
from .simulate import check_simulation_outputs

__all__ = ["simulate_closed_chain", "run_closed_chain_calibration", "split_spots", "make_cell", "calibrate_held_spots", "DEFAULT_JOINT_RESOLUTION_DEG"]

#: joint resolution / reading noise of the simulated controller [deg]: ABB's 0.03 mm position
#: repeatability of the IRB 140 over its ~0.8 m reach is ~0.002 deg; half of it per joint
DEFAULT_JOINT_RESOLUTION_DEG = 0.001
#: rounds of "hold what the data barely see, solve again"
_HOLD_ROUNDS = 3


def simulate_closed_chain(robot, out_path, *, plates: int = 2, targets: int = 5, configurations: int = 8,
                          spacing_mm: float = 50.0, tolerance_mm: float = 0.1,
                          joint_resolution_deg: float = DEFAULT_JOINT_RESOLUTION_DEG, joint_noise_deg=None,
                          cyclic_error_deg: float = 0.0005, seed: int = 0, length_sigma_mm: float = 0.5,
                          angle_sigma_deg: float = 0.05, offset_sigma_deg: float = 0.05, overwrite: bool = False,
                          return_cell: bool = False, effects="ideal") -> dict:
    """Simulate the spot-holding procedure and write ``out_path`` (held spots) and
    ``<name>.truth.json``. joint_noise_deg: reading noise (default: the resolution); effects: a
    :data:`~robocal.sim.closed_chain_effects.CELL_PRESETS` name (``realistic``: transmission
    error, gravity sag of J2/J3, warm-up; written to the truth file as ``cell_effects``). Seeds:
    ``SeedSequence(seed).spawn(4)`` -> robot, laser mount, holding, effects' phases. Returns the
    paths, the row count and (``return_cell``) the simulated cell."""
    out_path = Path(out_path)
    truth_path = check_simulation_outputs(out_path, overwrite)
    for name, v, lo in (("--plates", plates, 1), ("--targets", targets, 2), ("--configurations", configurations, 2)):
        if v < lo:
            raise ValueError(f"{name} must be at least {lo}, got {v}")
    if not (0.0 < tolerance_mm < 50.0) or not (0.0 < spacing_mm < 2000.0):
        raise ValueError("--distance-tolerance must be in (0, 50) mm and --spacing in (0, 2000) mm")
    nominal = load_robot(robot)
    cell, s_hold = make_cell(nominal, seed, plates=plates, targets=targets, spacing_mm=spacing_mm,
                             joint_resolution_deg=joint_resolution_deg, joint_noise_deg=joint_noise_deg,
                             cyclic_error_deg=cyclic_error_deg, length_sigma_mm=length_sigma_mm,
                             angle_sigma_deg=angle_sigma_deg, offset_sigma_deg=offset_sigma_deg, effects=effects)
    spots, _ = cell.hold_spots(configurations, s_hold, tolerance_mm=tolerance_mm)
    notes = [f"simulated: {plates} plate position(s), {targets} targets {spacing_mm:g} mm apart, {configurations} "
             f"configurations each; seed {seed}; effects {CellEffects.preset(effects).name}", f"robocal closed-chain calibrate ... --target-spacing {spacing_mm:g}"]
    write_spots(out_path, spots, robot=nominal.name, notes=notes, overwrite=overwrite)
    truth = cell.truth()
    truth.update(seed=int(seed), spacing_mm=spacing_mm, tolerance_mm=tolerance_mm,
                 simulation={"seed_streams": "SeedSequence(seed).spawn(4): robot, laser mount, holding, effects' phases",
                             "joint_resolution_deg": joint_resolution_deg, "cyclic_error_deg": cyclic_error_deg,
                             "effects": CellEffects.preset(effects).name, "spots_file": out_path.name})
    write_truth(truth_path, truth, overwrite=overwrite)
    out = {"spots": out_path, "truth": truth_path, "n_rows": spots.n_rows, "robot": nominal.name}
    if return_cell:
        out["cell"] = cell
    return out


def make_cell(nominal, seed: int, *, plates: int = 2, targets: int = 5, spacing_mm: float = 50.0,
              joint_resolution_deg: float = DEFAULT_JOINT_RESOLUTION_DEG, joint_noise_deg=None,
              cyclic_error_deg: float = 0.0005, length_sigma_mm: float = 0.5, angle_sigma_deg: float = 0.05,
              offset_sigma_deg: float = 0.05, effects="ideal"):
    """A simulated cell (:class:`~robocal.sim.closed_chain.ClosedChainCell`) of ``nominal`` and the
    random generator for the holding; seeds ``SeedSequence(seed).spawn(4)``: robot (and the
    readout's cyclic-error phases), laser mount, holding, the phases of the ``effects``' transmission
    error (a :data:`~robocal.sim.closed_chain_effects.CELL_PRESETS` name; ``ideal``: the cell as
    before, the first three streams unchanged). The plates are placed for the robot's reach (its
    flange distance at zero joints)."""
    s_robot, s_laser, s_hold, s_effects = (np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(4))
    virtual = VirtualRobot.perturbed(nominal, s_robot, length_sigma_mm=length_sigma_mm, angle_sigma_deg=angle_sigma_deg,
                                     offset_sigma_deg=offset_sigma_deg, joint_noise_deg=0.0, joint_noise_mm=0.0)
    res = math.radians(joint_resolution_deg)
    noise = res if joint_noise_deg is None else math.radians(joint_noise_deg)
    readout = JointReadout(noise, res, math.radians(cyclic_error_deg), s_robot.uniform(-np.pi, np.pi, nominal.n_joints))
    reach = float(np.linalg.norm(nominal.fk(np.zeros(nominal.n_joints))[:3, 3]))
    cell = ClosedChainCell(virtual, LaserPointer.drawn(s_laser), default_plates(plates, reach_mm=reach,
                           n_targets=targets, spacing_mm=spacing_mm), readout, effects=CellEffects.preset(effects),
                           phases=CellEffects.transmission_phases(nominal.n_joints, s_effects))
    return cell, s_hold


def split_spots(spots, holdout: float, seed: int):
    """(train rows, held-out rows): per spot ``round(holdout * n)`` rows held out (seeded), never
    leaving fewer than two to close the chain."""
    if not 0.0 <= holdout < 1.0:
        raise CalibrationInputError(f"--holdout must be a fraction in [0, 1), got {holdout}")
    rng = np.random.default_rng(seed)
    keys = list(zip(spots.plate, spots.target))
    hold = []
    for k in dict.fromkeys(keys):
        rows = [i for i, kk in enumerate(keys) if kk == k]
        n = min(int(round(holdout * len(rows))), max(len(rows) - 2, 0))
        hold += list(rng.permutation(rows)[:n])
    hold = np.sort(np.array(hold, dtype=int))
    return np.setdiff1d(np.arange(spots.n_rows), hold), hold


def _problem(nominal, spots, rows, **kw):
    s = spots.subset(rows)
    return ClosedChainProblem(nominal, s.joints, s.plate, s.target, **kw)


def _solve_quiet(problem, state0=None, max_iterations=50):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", NotConvergedWarning)
        res = record_fit(solve(problem, state0=state0, max_iterations=max_iterations))
    return res, [str(w.message) for w in caught if issubclass(w.category, NotConvergedWarning)]


def _state_from(problem, laser, spots_by_label, params=None):
    """A state of ``problem`` with the given mount, spots (by label) and geometry parameters."""
    P = np.array([spots_by_label[lab] for lab in problem.spot_labels])
    geom = problem.geometry.initial if params is None else np.asarray(params, dtype=float)
    return (geom, problem.frames.initial, np.asarray(laser, dtype=float), P)


def _spots_by_label(problem, state):
    return {lab: p for lab, p in zip(problem.spot_labels, np.asarray(state[3]).reshape(-1, 3))}


def calibrate_held_spots(nominal, spots, train, free_names, kw, max_iterations: int = 50) -> tuple:
    """The "before" fit and the calibration of the rows ``train`` of ``spots`` (HeldSpots).

    kw: ``sigma_mm``, ``spacing_mm``, ``spacing_sigma_mm`` of
    :class:`~robocal.calib.closed_chain.ClosedChainProblem`. Returns ``(problem0, result0, problem,
    result, convergence warnings, practically unidentifiable entries)``."""
    problem0 = _problem(nominal, spots, train, free=[], **kw)
    res0, _ = _solve_quiet(problem0, max_iterations=max_iterations)
    problem, result, warns, weak = _calibrate(nominal, spots, train, free_names, kw,
                                              (problem0, res0.state, res0.value("laser")), max_iterations)
    return problem0, res0, problem, result, warns, weak


def _calibrate(nominal, spots, train, free_names, kw, state0, max_iterations):
    """The calibration with practically unidentifiable parameters held (re-checked at the solution)."""
    hold, weak = [], []
    for _ in range(_HOLD_ROUNDS):
        problem = _problem(nominal, spots, train, free=free_names, hold=hold, **kw)
        start = _state_from(problem, state0[2], _spots_by_label(state0[0], state0[1]))
        new = [w for w in practically_unidentifiable(problem, start) if w["name"] not in hold]
        if new:
            weak += new
            hold += [w["name"] for w in new]
            continue
        result, warns = _solve_quiet(problem, start, max_iterations)
        new = [w for w in practically_unidentifiable(problem, result.state) if w["name"] not in hold]
        if not new:
            return problem, result, warns, weak
        weak += new
        hold += [w["name"] for w in new]
    return problem, result, warns, weak


def run_closed_chain_calibration(robot, spots_file, out_dir, *, target_spacing_mm=None,
                                 spacing_sigma_mm: float = 0.02, sigma_mm=None, holdout: float = 0.2,
                                 seed: int = 0, free=None, free_all: bool = False, fix=(), overwrite: bool = False,
                                 report: bool = True, force: bool = False, max_iterations: int = 1000,
                                 progress=None, allow_unconverged: bool = False) -> dict:
    """Calibrate ``robot`` from the held-spot file ``spots_file``; write the outputs into ``out_dir``.

    target_spacing_mm: the known distance between consecutive targets of a plate [mm] (fixes the
    length scale; without it the scale is reported unidentifiable and one length is held).
    sigma_mm: in-plate spread of a held spot per axis [mm] (default: half the file's
    ``spot_tolerance_mm``, else 0.05). holdout: share of each spot's rows held out (seeded).
    free / free_all / fix: as ``robocal calibrate``. Returns ``result`` (the JSON dict), ``files``,
    ``notes``, ``verdict``, ``calibration_result``, ``problem``, ``convergence`` and
    ``convergence_warnings``. A fit that did not converge writes no robot files unless
    ``allow_unconverged`` (:mod:`robocal.workflows.convergence`).
    """
    step = progress or (lambda i, n, text: None)
    out = Path(out_dir)
    names = [n for k, n in OUTPUT_FILES.items() if report or k != "report"]
    check_output_folder(out, names, {"ROBOT": robot, "SPOTS": spots_file}, overwrite)
    nominal = load_robot(robot)
    spots = read_spots(spots_file, robot=nominal)
    spots = spots.subset(canonical_order(spots))  # the same data in any row order gives the same result
    if target_spacing_mm is not None and not (1.0 <= target_spacing_mm <= 5000.0):
        raise CalibrationInputError(f"--target-spacing {target_spacing_mm:g}: expected the distance between two "
                                    "targets in mm (1 to 5000); metres given as millimetres?")
    if sigma_mm is None:
        sigma_mm = spots.tolerance_mm / 2.0 if spots.tolerance_mm else 0.05
    if not sigma_mm > 0:
        raise CalibrationInputError(f"--noise must be a positive number of mm, got {sigma_mm}")
    ensure_writable_dir(out)
    free_names = select_free(nominal, free, free_all, fix)
    train, hold = split_spots(spots, holdout, seed)
    kw = dict(sigma_mm=sigma_mm, spacing_mm=target_spacing_mm, spacing_sigma_mm=spacing_sigma_mm)
    step(1, 5, f"read {spots.n_rows} held spots of {nominal.name} from {spots_file}: {len(train)} to calibrate, "
               f"{len(hold)} held out (seed {seed})")
    step(2, 5, "'before': nominal geometry, best-fit laser mount and spots; then identifying "
               f"{len(free_names)} parameter(s), the laser mount and the spots")
    problem0, res0, problem, result, warns, weak = calibrate_held_spots(nominal, spots, train, free_names, kw,
                                                                        max_iterations)
    step(4, 5, f"validating on {len(hold)} held-out spot(s)")
    e_before, e_after = problem0.spot_errors(res0.state), problem.spot_errors(result.state)
    validation = _validate(nominal, spots, hold, problem0, res0, problem, result, kw)
    verdict = calibration_verdict(
        robot=nominal.name, rms_before_mm=_rms(e_before), rms_after_mm=_rms(e_after), sigma_mm=sigma_mm,
        holdout_before_mm=validation["before"]["rms"] if validation else None,
        holdout_after_mm=validation["after"]["rms"] if validation else None,
        parameters=(nominal.params.names, nominal.params.units, nominal.params.values, result.value("geometry")))
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    metadata = {"robot": str(robot), "spots": str(spots_file), "n_held_spots_file": spots.n_rows,
                "n_held_spots_calibration": int(len(train)), "n_held_spots_holdout": int(len(hold)),
                "holdout_fraction": holdout, "seed": seed, "sigma_mm": sigma_mm,
                "target_spacing_mm": target_spacing_mm, "spacing_sigma_mm": spacing_sigma_mm, "free": free_names,
                "fixed_by_option": list(fix), "measurement_kind": "virtual closed chain: laser ray through held spots",
                "method": "lm", "written": stamp}
    rdict = problem_result_dict(result, problem, nominal=nominal, calibrated_params=result.value("geometry"),
                                metadata=metadata)
    rdict["residuals"] = json_ready(_residuals(problem, spots, train, e_before, e_after))
    if validation:
        rdict["validation"] = json_ready(validation)
    rdict["closed_chain"] = json_ready(_closed_chain_section(problem, result, res0, e_before, e_after, weak))
    rdict["status"], rdict["reasons"], rdict["sanity_checks"] = verdict.status, list(verdict.reasons), verdict.checks
    notes = [f"held (barely observable): {w['name']}: {w['why']}" for w in weak]
    if problem.scale_held:
        notes.append(f"length scale not identifiable (no known distance): {problem.scale_held} held at its nominal "
                     "value; give --target-spacing MM")
    if warns:
        rdict["solver"]["warning"] = warns[-1]
    convergence = Convergence.of([("baseline fit (nominal geometry)", res0), ("calibration", result)])
    rdict["convergence"] = convergence.as_dict()
    write_robot = (verdict.ok or force) and convergence.may_write_model(allow_unconverged)
    if not (verdict.ok or force):
        notes.append("calibrated_robot.toml/.urdf not written: the result FAILED the sanity gates "
                     "(pass --force to write them anyway)")
    elif not write_robot:
        notes.append(convergence.skipped_note("calibrated_robot.toml/.urdf"))
    rdict["notes"] = notes
    step(5, 5, "writing result.json, calibrated robot, report")
    with staged_outputs(out, names, overwrite) as stage:
        files = _write(output_paths(stage), rdict, result, nominal, spots_file, len(train), stamp, write_robot,
                       notes, report)
    return {"result": rdict, "files": {k: out / p.name for k, p in files.items()}, "notes": notes,
            "verdict": verdict, "calibration_result": result, "problem": problem, "baseline": res0,
            "convergence_warnings": warns, "convergence": convergence}


def _rms(e) -> float:
    return float(np.sqrt(np.mean(np.square(e)))) if np.size(e) else float("nan")


def _residuals(problem, spots, train, e_before, e_after) -> dict:
    s = spots.subset(train)
    return {"unit": "mm", "quantity": "in-plate spot error |E_i| (eq. 5) per held spot",
            "before": error_statistics(e_before), "after": error_statistics(e_after),
            "rms_before": _rms(e_before), "rms_after": _rms(e_after),
            "per_point": {"pose": list(s.ids), "target": [f"{p}.{t}" for p, t in zip(s.plate, s.target)],
                          "before": e_before, "after": e_after}}


def _validate(nominal, spots, hold, problem0, res0, problem, result, kw):
    """In-plate errors of the held-out spots: the model and spots of the training fit at their joints."""
    if not len(hold):
        return None
    h = spots.subset(hold)
    out = {}
    for label, pb, res in (("before", problem0, res0), ("after", problem, result)):
        model = nominal.with_params(res.value("geometry"))
        P = _spots_by_label(pb, res.state)
        chk = ClosedChainProblem(model, h.joints, h.plate, h.target, free=[], laser_initial=res.value("laser"), check_closure=False,
                                 spots_initial=np.array([P[k] for k in
                                                         dict.fromkeys(zip(h.plate, h.target))]), **kw)
        chk.ray.set_normals(pb.ray.normals[[pb.spot_labels.index(k) for k in chk.spot_labels]])
        out[label] = chk.spot_errors(chk.initial_state())
    return {"n_poses": int(len(hold)), "pose_ids": list(h.ids), "before": error_statistics(out["before"]),
            "after": error_statistics(out["after"]),
            "per_point": {"pose": list(h.ids), "target": [f"{p}.{t}" for p, t in zip(h.plate, h.target)],
                          "before": out["before"], "after": out["after"]}}


def _closed_chain_section(problem, result, res0, e_before, e_after, weak) -> dict:
    """E_OP, the mount, the spots and the identifiability findings in plain words."""
    ident = result.identifiability
    geom_names = set(problem.geometry.names)
    dropped = [d for d in ident.dropped if d["name"] in geom_names] + list(weak)
    cls = classify_unidentified(dropped, problem.spots.names, problem.laser.names)
    scale = length_scale_check(problem, result.state)
    laser = result.value("laser")
    i = {n: k for k, n in enumerate(result.names)}
    std = [float(result.std[i[n]]) if n in i else None for n in problem.laser.names]
    findings = [
        {"what": "base frame", "identifiable": False,
         "why": "nothing outside the robot is measured: the robot base is the reference frame and the spots are "
                "found in it; turning the arm about its first axis or shifting it along that axis moves every spot "
                "the same way",
         "parameters_held": cls["base_frame"],
         "to_recover": "measure the base in the cell separately (e.g. three known points), if the cell frame matters"},
        {"what": "length scale", "identifiable": bool(scale["identifiable"]),
         "why": ("a known distance fixes it (--target-spacing)" if scale["identifiable"] else
                 "every length of the robot, the mount and the spots can grow by one factor and every ray still "
                 "meets its spot"),
         "parameters_held": [problem.scale_held] if problem.scale_held else [],
         "to_recover": "give the known distance between consecutive targets: --target-spacing MM"},
        {"what": "along the beam", "identifiable": False,
         "why": "a shift along the beam or a turn about it moves no spot (eq. 3 has no such mount parameters); the "
                "last link's length along the beam and its turn about it are seen only through the mount's small "
                "errors, and the mount's four parameters absorb every other change of the last link",
         "parameters_held": cls["along_beam"] + cls["laser_mount"],
         "to_recover": "a tool (TCP) calibration for the last link and the tool length; the robot's other links do "
                       "not need it"},
    ]
    if cls["other"]:
        findings.append({"what": "trade-offs", "identifiable": False,
                         "why": "these parameters act exactly or nearly like combinations of identified robot "
                                "parameters (e.g. offsets along parallel axes, whose sum alone is seen); the "
                                "identifiability table names the partners",
                         "parameters_held": cls["other"],
                         "to_recover": "nothing for exact redundancies (any measurement sees only the combination); "
                                       "for near ones, more plate positions and more varied configurations"})
    return {
        "E_OP_before_mm": e_op(e_before), "E_OP_after_mm": e_op(e_after),
        "E_OP_definition": "mean in-plate distance |E_i| between each ray's intersection with the plate and its spot "
                           "(the paper's eq. 5-6)",
        "laser_mount": {"names": list(problem.laser.names), "value": laser, "std": std,
                        "baseline_value": res0.value("laser")},
        "spots": [{"plate": p, "target": t, "position_mm": x}
                  for (p, t), x in zip(problem.spot_labels, np.asarray(result.value("spots")).reshape(-1, 3))],
        "n_spots": len(problem.spot_labels),
        "length_scale": dict(scale, held=problem.scale_held),
        "practically_unidentifiable": weak,
        "findings": findings,
    }


def _write(paths, rdict, result, nominal, spots_file, n_train, stamp, write_robot, notes, report) -> dict:
    files = {}
    if write_robot:
        calibrated = result.model.replace(
            title=f"{nominal.title or nominal.name} (calibrated, closed chain)",
            source=f"robocal closed-chain calibrate of {Path(str(spots_file)).name} ({n_train} held spots, {stamp}) "
                   f"from nominal: {nominal.source}")
        cc = rdict["closed_chain"]
        comment = (f"Calibrated by robocal from held laser spots in {spots_file} ({n_train} held spots; E_OP "
                   f"{cc['E_OP_before_mm']:.4f} -> {cc['E_OP_after_mm']:.4f} mm).\n[base] is the robot base itself "
                   "(the closed chain has no external frame). All numbers with uncertainties: result.json.")
        files["robot"] = save_robot(calibrated, paths["robot"], comment=comment)
        from ...io.urdf import UrdfError, write_urdf

        try:
            files["urdf"] = write_urdf(calibrated, paths["urdf"])
        except UrdfError as exc:
            notes.append(f"calibrated_robot.urdf not written: {exc}")
    files["result"] = atomic_write_text(paths["result"], json.dumps(rdict, indent=2, allow_nan=False) + "\n")
    if report:
        from ...report.html import write_report

        cc = rdict["closed_chain"]
        table = (["quantity", "before", "after"],
                 [["E_OP (eq. 6) [mm]", f"{cc['E_OP_before_mm']:.4f}", f"{cc['E_OP_after_mm']:.4f}"]]
                 + [[f["what"], "identifiable" if f["identifiable"] else "NOT identifiable",
                     ", ".join(f["parameters_held"]) or "-"] for f in cc["findings"]])
        files["report"] = write_report(paths["report"], rdict, title=f"Closed-chain calibration of {nominal.name} "
                                       f"from {Path(str(spots_file)).name}",
                                       extra_tables={"Virtual closed chain: E_OP and identifiability": table})
    return files
