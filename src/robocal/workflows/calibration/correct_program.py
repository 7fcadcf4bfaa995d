"""``robocal correct MODEL PROGRAM --out NEW_PROGRAM``: a robot program with corrected targets.

Cartesian targets, as the controller will run them (docs/robot-programs.md, "Correcting a
program"):

1. the joints the controller commands today: the nominal model with the program's tool and frame,
   on the target's configuration (KUKA ``S``/``T``, ABB ``confdata``, FANUC ``CONFIG``; UR: the
   solution nearest the current joints in program order) —
   :class:`robocal.sim.virtual_controller.VirtualController` on the nominal robot;
2. the joints that put the calibrated robot's TCP on the target: numeric IK on the calibrated
   model started there; a solution that leaves the branch (another shoulder/elbow/wrist, another
   turn) is refused;
3. the corrected target: the nominal model's TCP pose at those joints, in the target's frame. The
   configuration data stays true (it is checked, not changed).

Joint targets are taught positions and are kept unless ``joint_targets="correct"`` (offline
programs): then the joints that put the calibrated robot where the nominal model meant, never
changing the configuration nor any joint by more than ``max_joint_change``.

Each row of the report gives the joints the correction assumes and the predicted accuracy
(1 sigma [mm]) of the corrected TCP from the calibration's covariance (``result.json`` next to the
robot file), with the parameters the calibration could not determine counted at a stated
tolerance when the TCP depends on them (``warnings``).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ...io.correction_report import write_correction_report
from ...io.programs import read_program, write_program
from ...io.programs.configuration import configuration_of, configuration_text
from ...io.programs.controller import controller_joints, with_tool
from ...io.programs.frames import resolve_frames
from ...kinematics.arm_configuration import arm_signature
from ...kinematics.ik import ik_numeric
from ...kinematics.ik_analytic import is_analytic
from ...robots import load_robot
from ...sim.virtual_controller import VirtualController

__all__ = ["report_path_for", "run_correct_program", "UNKNOWN_TOLERANCE"]

#: Tolerance assumed for a parameter the calibration could not determine: 0.5 mm, 0.05 deg (the
#: size of machining and assembly errors of a link; what ``robocal simulate`` draws).
UNKNOWN_TOLERANCE = {"mm": 0.5, "rad": math.radians(0.05)}
#: A target's joints may move this much from the nominal controller joints before the correction is
#: refused as leaving the branch [rad].
MAX_BRANCH_STEP = math.radians(15.0)


def report_path_for(out_file) -> Path:
    p = Path(out_file)
    return p.with_name(p.name + ".report.csv")


def _result_of(model_file):
    p = Path(model_file).with_name("result.json")
    if not p.is_file():
        return None
    try:
        return json.loads(p.read_text())
    except (OSError, ValueError):
        return None


class _Accuracy:
    """Predicted 1-sigma TCP position [mm] from the calibration's covariance."""

    def __init__(self, calibrated, result):
        self.cal = calibrated
        self.ok = result is not None and "covariance" in result
        if not self.ok:
            return
        cov = result["covariance"]
        names = list(cov["names"])
        C = np.asarray(cov["matrix"], dtype=float)
        pnames = set(calibrated.params.names)
        self.model_idx = [i for i, n in enumerate(names) if n in pnames]
        self.names = names
        self.C = C
        self.points = {t["name"]: np.asarray(t["point_mm"], dtype=float) for t in result.get("targets", [])}
        dropped = [d for d in result.get("identifiability", {}).get("dropped", []) if d["name"] in pnames]
        # held parameters that only trade off against the base placement (A1 zero, base height) are
        # part of the calibrated base frame: targets are taken in that frame
        self.in_base = [d["name"] for d in dropped
                        if d.get("trades_off_with") and all(w["name"].startswith("base.") for w in d["trades_off_with"])]
        # held parameters that trade off against the target points (the last link against the
        # reflectors) are determined only for those points: unknown for any other TCP; the others
        # trade off within the arm, which compensates them for every TCP alike
        points = {t["name"] for t in result.get("targets", [])} | {"tool"}
        self.unknown = [d["name"] for d in dropped
                        if any(w["name"].split(".")[0] in points for w in d.get("trades_off_with", []))]

    def _jac(self, names, q, T_tool):
        base = with_tool(self.cal, T_tool)
        p0 = base.fk(q)[:3, 3]
        J = np.zeros((3, len(names)))
        for k, n in enumerate(names):
            h = 1e-6
            m = with_tool(self.cal.with_params(**{n: self.cal.params.values[self.cal.params.index(n)] + h}), T_tool)
            J[:, k] = (m.fk(q)[:3, 3] - p0) / h
        return J

    def sigma(self, q, T_tool):
        """``(sigma [mm], unknown [mm], point name or None)``: the identified part, the part from
        parameters held as unidentifiable (at :data:`UNKNOWN_TOLERANCE`; 0 when the TCP is an
        identified target point)."""
        if not self.ok:
            return None, 0.0, None
        idx = list(self.model_idx)
        names = [self.names[i] for i in idx]
        J = self._jac(names, q, T_tool)
        point = next((n for n, p in self.points.items()
                      if np.linalg.norm(p - T_tool[:3, 3]) < 0.01 and all(f"{n}.{a}" in self.names for a in "xyz")),
                     None)
        if point is not None:  # the TCP is an identified point: its own uncertainty counts too
            R = with_tool(self.cal, np.eye(4)).fk(q)[:3, :3]
            idx += [self.names.index(f"{point}.{a}") for a in "xyz"]
            J = np.hstack([J, R])
        C = self.C[np.ix_(idx, idx)]
        s = float(np.sqrt(max(np.trace(J @ C @ J.T), 0.0)))
        unknown = 0.0
        if self.unknown and point is None:
            Ju = self._jac(self.unknown, q, T_tool)
            tol = np.array([UNKNOWN_TOLERANCE["mm"] if self.cal.params.units[self.cal.params.index(n)] == "mm"
                            else UNKNOWN_TOLERANCE["rad"] for n in self.unknown])
            unknown = float(np.sqrt(np.sum((Ju * tol) ** 2)))
        return s, unknown, point


def _branch_ok(nominal, q_nom, q, analytic) -> tuple[bool, str]:
    step = float(np.max(np.abs(q - q_nom)))
    if step > MAX_BRANCH_STEP:
        return False, f"the correction would move a joint by {math.degrees(step):.1f} deg (another branch)"
    if analytic:
        s0, s1 = arm_signature(nominal, np.stack([q_nom, q]))
        if not np.array_equal(s0, s1):
            return False, "the correction would change the arm configuration"
    return True, ""


def run_correct_program(model_file, program_file, out_file, *, nominal=None, overwrite: bool = False,
                        payload=None, tool=None, base=None, config_dat=None, joint_targets: str = "keep",
                        max_joint_change: float = 0.017453292519943295) -> dict:
    """Correct the targets of ``program_file`` with the calibrated robot ``model_file``.

    nominal: the robot the controller runs (default the one named in the model file). tool, base:
    ``(x, y, z[, a, b, c])`` [mm, deg] values of the program's tool / base
    (:func:`robocal.io.programs.frames.resolve_frames`); config_dat: text of a KUKA
    ``$config.dat``. joint_targets: ``keep`` (taught positions, default) or ``correct``;
    max_joint_change [rad]: the bound for corrected joint targets. payload: ``KG@x,y,z`` for a
    robot file with an ``[elastic]`` section (the deflection is compensated for Cartesian targets).
    Returns ``{rows, changes, file, report, n_corrected, n_targets, n_failed, warnings, skipped}``.
    """
    from ...io.output_paths import check_outputs

    out_file = Path(out_file)
    report = report_path_for(out_file)
    if joint_targets not in ("keep", "correct"):
        raise ValueError(f"joint_targets: expected 'keep' or 'correct', got {joint_targets!r}")
    check_outputs([out_file, report], {"the robot file": model_file, "the program": program_file,
                                       "--nominal": nominal}, overwrite=overwrite)
    calibrated = load_robot(model_file)
    nominal_model = load_robot(nominal if nominal is not None else calibrated.name)
    if tuple(calibrated.controller_joints) != tuple(nominal_model.controller_joints):
        raise ValueError(f"{model_file}: controller joints {calibrated.controller_joints} differ from the nominal "
                         f"{nominal_model.name}'s {nominal_model.controller_joints}")
    from .calibrate import deflection_of

    reach = deflection_of(calibrated.replace(T_world_base=np.eye(4)), payload)
    prog = read_program(program_file)
    if not prog.targets:
        raise ValueError(f"{program_file}: no targets found ({len(prog.skipped)} declaration(s) skipped)")
    from ...io.programs.checks import check_program

    check_program(prog, nominal_model)
    frames = resolve_frames(prog, tool=tool, base=base, config_dat=config_dat)
    vc = VirtualController(nominal_model, nominal_model)
    executed = {e.name: e for e in vc.execute(prog, tool=tool, base=base, config_dat=config_dat)}
    cal = calibrated.replace(T_world_base=np.eye(4))
    accuracy = _Accuracy(cal, _result_of(model_file))
    analytic = is_analytic(nominal_model)
    rows, updates, warnings, config_updates = [], {}, [], {}
    for t in prog.targets:
        e = executed[t.name]
        row = {"target": t.name, "kind": t.kind, "line": t.line, "cartesian_correction_mm": 0.0,
               "orientation_correction_deg": 0.0, "max_joint_change_deg": 0.0, "remaining_error_mm": float("nan"),
               "within_limits": True, "note": "", "joints_deg": "", "sigma_mm": float("nan"),
               "unknown_mm": 0.0, "frames": ""}
        if t.kind == "joint":
            row.update(_joint_row(t, cal, nominal_model, joint_targets, max_joint_change, analytic, updates))
            rows.append(row)
            continue
        T_tool, T_frame, what = frames[t.name]
        row["frames"] = what
        if e.q is None:
            row.update(status="not reached", note=e.reason)
            rows.append(row)
            continue
        if t.other_frames:
            row.update(status="two configurations",
                       note="used with several tools / frames (" + ", ".join(f"{a}/{b}" for a, b in
                                                                          ((t.tool, t.base), *t.other_frames))
                            + "); one corrected value cannot serve both (split the target)")
            rows.append(row)
            continue
        if e.other_joints:
            row.update(status="two configurations",
                       note=f"used in {1 + len(e.other_joints)} arm configurations; one value cannot serve both "
                            "(split the target)")
            rows.append(row)
            continue
        T_goal = T_frame @ t.T_frame_tcp
        cal_tool, nom_tool = with_tool(cal, T_tool), with_tool(nominal_model, T_tool)
        r = ik_numeric(cal_tool, T_goal, e.q, tol_mm=1e-7, tol_rad=1e-10, max_iterations=200)
        q = np.asarray(r.q, dtype=float)
        if reach is not None and bool(r.converged):  # aim so that the deflecting robot lands on the target
            r, q = _aim_deflected(reach, cal, cal_tool, T_tool, T_goal, q)
        ok, why = (False, f"calibrated IK: {r.status}") if not bool(r.converged) else _branch_ok(
            nominal_model, e.q, q, analytic)
        row["joints_deg"] = " ".join(f"{v:.3f}" for v in np.degrees(q if ok else e.q))
        new_config = {}
        if ok and analytic and not configuration_of(t, prog.format).nearest:
            new_config, ok, why = _configuration_update(t, prog.format, nominal_model, nom_tool, T_frame, q, e.q)
        if not ok:
            row.update(status="not reached", note=why)
            rows.append(row)
            continue
        T_new = np.linalg.inv(T_frame) @ nom_tool.fk(q)
        updates[t.name] = T_new
        if new_config:
            config_updates[t.name] = new_config
        dR = T_new[:3, :3].T @ t.T_frame_tcp[:3, :3]
        sig, unknown, point = accuracy.sigma(q, T_tool)
        row.update(status="corrected", cartesian_correction_mm=float(np.linalg.norm(T_new[:3, 3] - t.T_frame_tcp[:3, 3])),
                   orientation_correction_deg=math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(dR) - 1) / 2)))),
                   max_joint_change_deg=float(np.degrees(np.max(np.abs(q - e.q)))),
                   remaining_error_mm=float(r.position_error_mm),
                   sigma_mm=float("nan") if sig is None else float(np.hypot(sig, unknown)), unknown_mm=unknown,
                   note="; ".join(x for x in (f"TCP = identified point {point}" if point else "",
                                              "no joint target before it: the arm configuration is assumed"
                                              if e.assumed_start else "",
                                              "configuration data re-derived: " + ", ".join(
                                                  f"{k} {t.config[k]} -> {v}" for k, v in new_config.items())
                                              if new_config else "") if x))
        if unknown > 0:
            warnings.append((t.name, unknown))
        rows.append(row)
    changes = write_program(prog, updates, out_file, overwrite=overwrite, config_updates=config_updates)
    write_correction_report(report, rows, program=str(program_file), model=str(model_file), overwrite=overwrite)
    failed = [r for r in rows if r["status"] not in ("corrected", "kept")]
    return {"rows": rows, "changes": changes, "file": out_file, "report": report,
            "n_corrected": sum(r["status"] == "corrected" for r in rows), "n_targets": len(rows),
            "n_failed": len(failed), "warnings": warnings, "unknown_parameters": accuracy.unknown if accuracy.ok else [],
            "base_parameters": accuracy.in_base if accuracy.ok else [],
            "skipped": list(prog.skipped),
            "identified_points": accuracy.points if accuracy.ok else {}}


def _aim_deflected(reach, cal, cal_tool, T_tool, T_goal, q):
    """Joints that put the deflecting calibrated robot's TCP on ``T_goal`` (a few fixed-point passes
    on the rigid target); returns (the last IK result with its error at the deflected pose, q)."""
    T_aim = T_goal.copy()
    for _ in range(5):
        T_reached = reach(cal, q[None])[0] @ T_tool
        T_aim[:3, 3] += T_goal[:3, 3] - T_reached[:3, 3]
        T_aim[:3, :3] = T_goal[:3, :3] @ T_reached[:3, :3].T @ T_aim[:3, :3]
        r = ik_numeric(cal_tool, T_aim, q, tol_mm=1e-7, tol_rad=1e-10, max_iterations=200)
        q = np.asarray(r.q, dtype=float)
    err = float(np.linalg.norm((reach(cal, q[None])[0] @ T_tool)[:3, 3] - T_goal[:3, 3]))
    return r.__class__(q, r.converged, r.iterations, err, r.rotation_error_rad, r.status), q


def _configuration_update(t, fmt, nominal_model, nom_tool, T_frame, q, q_nom):
    """``(new config items, ok, why)``: the configuration data that states the corrected joints
    ``q`` (rewritten only where it no longer does: a turn bit or quadrant crossed), checked by
    running the corrected target through the controller's choice."""
    cfg = configuration_of(t, fmt)
    sig = arm_signature(nominal_model, q)[0]
    new = {}
    if not cfg.matches(sig[None], q[None])[0]:
        derived = configuration_text(t, fmt, q, sig)
        new = {k: v for k, v in derived.items() if k in t.config_spans and v != t.config.get(k)}
        if not new:
            return {}, False, f"the corrected joints leave configuration {cfg.text}"
        t = replace(t, config={**t.config, **new})
        cfg = configuration_of(t, fmt)
    T_new = nom_tool.fk(q)
    q_ctrl, why = controller_joints(nom_tool, T_new, cfg, q_nom)
    if q_ctrl is None or np.max(np.abs(q_ctrl - q)) > 1e-6:
        return {}, False, f"the controller would not run the corrected target on its joints ({why or 'other branch'})"
    return new, True, ""


def _joint_row(t, cal, nominal_model, mode, max_change, analytic, updates) -> dict:
    q0 = np.asarray(t.joints, dtype=float)
    row = {"joints_deg": " ".join(f"{v:.3f}" for v in np.degrees(q0))}
    if mode == "keep":
        return {**row, "status": "kept", "note": "taught joint target (kept; --joint-targets correct to change)"}
    T_meant = with_tool(nominal_model, np.eye(4)).fk(q0)
    r = ik_numeric(with_tool(cal, np.eye(4)), T_meant, q0, tol_mm=1e-7, tol_rad=1e-10, max_iterations=200)
    note = ""
    if not bool(r.converged):  # e.g. at a wrist singularity (A5 = 0): the position alone, least joint motion
        r = ik_numeric(with_tool(cal, np.eye(4)), T_meant, q0, tol_mm=1e-7, max_iterations=200, position_only=True)
        note = "position only (the orientation is not reachable near this pose: wrist singularity)"
    q = np.asarray(r.q, dtype=float)
    change = float(np.max(np.abs(q - q0)))
    if not bool(r.converged):
        return {**row, "status": "not reached", "note": f"calibrated IK: {r.status}"}
    if change > max_change:
        return {**row, "status": "not reached", "max_joint_change_deg": math.degrees(change),
                "note": f"a joint would move {math.degrees(change):.3f} deg > bound {math.degrees(max_change):.3f} deg"}
    if analytic and not np.array_equal(*arm_signature(nominal_model, np.stack([q0, q]))):
        return {**row, "status": "not reached", "note": "the correction would change the arm configuration"}
    updates[t.name] = q
    return {"joints_deg": " ".join(f"{v:.3f}" for v in np.degrees(q)), "status": "corrected", "note": note,
            "max_joint_change_deg": math.degrees(change), "remaining_error_mm": float(r.position_error_mm),
            "cartesian_correction_mm": float(np.linalg.norm(with_tool(nominal_model, np.eye(4)).fk(q)[:3, 3]
                                                            - T_meant[:3, 3]))}
