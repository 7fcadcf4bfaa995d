"""``robocal correct MODEL PROGRAM --out NEW_PROGRAM``: a robot program with corrected targets.

Cartesian targets: the joints that put the calibrated robot on the target (inverse kinematics of
the calibrated model), then the nominal model's pose at those joints is the corrected target (what
a controller running the nominal model must be told so that it commands those joints). Joint
targets: the pose the nominal model reaches at the taught joints is the intended one; the
corrected joints put the calibrated robot there.

Targets are taken in the robot base frame with the flange as TCP (tool 0, base 0); a target with
another tool or user frame is corrected all the same and flagged in the report's ``note``. A
target that cannot be reached, or only outside the joint limits, keeps its value and is reported.
The program is written by :func:`robocal.io.programs.write_program` (only changed numbers differ;
never over the input); the report goes next to it (``<NEW_PROGRAM>.report.csv``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..calib.outputs import corrected_joint_targets
from ..io.correction_report import write_correction_report
from ..io.programs import read_program, write_program
from ..robots import load_robot

__all__ = ["report_path_for", "run_correct_program"]

_DEFAULT_FRAMES = {None, "", "0", "tool0", "wobj0", "$nullframe", "#base"}


def report_path_for(out_file) -> Path:
    p = Path(out_file)
    return p.with_name(p.name + ".report.csv")


def _note(t) -> str:
    odd = [f"{what} {v}" for what, v in (("tool", t.tool), ("base", t.base))
           if v is not None and str(v).strip().lower() not in _DEFAULT_FRAMES]
    return f"{', '.join(odd)}: taken as robot base / flange" if odd else ""


def _rows(targets, corr, kind):
    rows, updates = [], {}
    for i, t in enumerate(targets):
        rep = corr.report[i]
        ok = bool(corr.converged[i]) and rep["within_limits"]
        status = "corrected" if ok else ("outside limits" if corr.converged[i] else "not reached")
        if ok:
            updates[t.name] = corr.T_filtered[i] if kind == "cartesian" else corr.q[i]
        rows.append({"target": t.name, "kind": kind, "line": t.line, "status": status,
                     "cartesian_correction_mm": rep["cartesian_correction_mm"],
                     "orientation_correction_deg": math.degrees(rep["orientation_correction_rad"]),
                     "max_joint_change_deg": math.degrees(rep["max_joint_change"]),
                     "remaining_error_mm": rep["position_error_mm"], "within_limits": rep["within_limits"],
                     "note": _note(t)})
    return rows, updates


def run_correct_program(model_file, program_file, out_file, *, nominal=None, overwrite: bool = False,
                        payload=None) -> dict:
    """Correct every target of ``program_file`` with the calibrated robot ``model_file``.

    nominal: the robot the controller runs (default the one named in the model file). payload:
    ``KG@x,y,z`` for a model file with an ``[elastic]`` section (deflection compensated).
    Returns ``{rows, changes, file, report, n_corrected, n_targets}``; ``rows`` one dict per
    target (:data:`robocal.io.correction_report.REPORT_COLUMNS`).
    """
    from ..io.output_paths import check_outputs

    out_file = Path(out_file)
    report = report_path_for(out_file)
    check_outputs([out_file, report], {"the robot file": model_file, "the program": program_file,
                                       "--nominal": nominal}, overwrite=overwrite)
    calibrated = load_robot(model_file)
    nominal_model = load_robot(nominal if nominal is not None else calibrated.name)
    from .calibrate import deflection_of

    deflection = deflection_of(calibrated, payload)
    prog = read_program(program_file)
    if not prog.targets:
        raise ValueError(f"{program_file}: no targets found ({len(prog.skipped)} declaration(s) skipped)")
    rows, updates = [], {}
    cart = [t for t in prog.targets if t.kind == "cartesian"]
    if cart:
        T = np.stack([t.T_frame_tcp for t in cart])
        corr = corrected_joint_targets(calibrated, nominal_model, T, frame="base", reach=deflection)
        r, u = _rows(cart, corr, "cartesian")
        rows, updates = rows + r, {**updates, **u}
    joint = [t for t in prog.targets if t.kind == "joint"]
    if joint:
        q = np.stack([t.joints for t in joint])
        if q.shape[1] != nominal_model.n_joints:
            raise ValueError(f"{program_file}: joint targets have {q.shape[1]} axes, {nominal_model.name} has "
                             f"{nominal_model.n_joints}")
        T = nominal_model.replace(T_world_base=np.eye(4)).fk(q)
        corr = corrected_joint_targets(calibrated, nominal_model, T, q_seed=q, frame="base", reach=deflection)
        r, u = _rows(joint, corr, "joint")
        rows, updates = rows + r, {**updates, **u}
    changes = write_program(prog, updates, out_file, overwrite=overwrite)
    write_correction_report(report, rows, program=str(program_file), model=str(model_file), overwrite=overwrite)
    return {"rows": rows, "changes": changes, "file": out_file, "report": report,
            "n_corrected": len(updates), "n_targets": len(rows), "skipped": list(prog.skipped)}
