"""Orientation errors of a 6-D calibration: how far the models' predicted tool orientations are
from the measured ones, on the calibration and on the held-out poses (issue 31, item 3).

Three states are compared, each a full prediction of the measured frame
``R_inst_tool = R_inst_base R_base_flange(q) R_flange_tool``:

* ``nominal``: nominal geometry, the start estimates of the base frame and the tool rotation;
* ``baseline``: nominal geometry with the best-fit base and tool frames (the "before" state);
* ``calibrated``: the identified geometry, base and tool frames.

The error of a pose is the angle of ``R_measured R_predicted^T`` [deg] (rigid geometry; an elastic
model's deflection is not in these figures).
"""

from __future__ import annotations

import numpy as np

from ...metrics import error_statistics
from ...transforms import so3_log

__all__ = ["rotation_errors_deg", "orientation_summary"]


def rotation_errors_deg(model, params, T_inst_base, T_flange_tool, q, R_measured, end_effector=0) -> np.ndarray:
    """(N,) angles [deg] between measured orientations ``R_measured`` (N, 3, 3) and the ones
    predicted at joints ``q`` (N, n_ctrl) [rad | mm] by ``model`` with parameter vector ``params``
    (P,), base ``T_inst_base`` (4, 4) and tool ``T_flange_tool`` (4, 4)."""
    m = model.with_params(np.asarray(params, dtype=float)).replace(T_world_base=np.asarray(T_inst_base, float))
    R_pred = m.fk(np.asarray(q, dtype=float), end_effector)[..., :3, :3] @ np.asarray(T_flange_tool)[:3, :3]
    d = so3_log(np.asarray(R_measured) @ np.swapaxes(R_pred, -1, -2))
    return np.degrees(np.linalg.norm(d, axis=-1))


def _stats(errors):
    s = error_statistics(errors)
    return {"rms": s["rms"], "mean": s["mean"], "p95": s["p95"], "max": s["max"], "n": s["n"]}


def orientation_summary(setup, res0, result, meas, train, hold) -> dict | None:
    """``{unit, train: {nominal, baseline, calibrated}, holdout: {...} | None, note}`` with error
    statistics (rms, mean, p95, max [deg], n) of each state; ``None`` without measured (and used)
    orientations."""
    if not setup.get("six_d") or meas.rotations is None:
        return None
    problem0, problem = setup["problem0"], setup["problem"]
    model = problem.model
    ee = int(problem.ee_of_target[0])
    start = problem0.initial_state()
    states = {"nominal": start, "baseline": res0.state, "calibrated": result.state}
    out = {"unit": "deg", "quantity": "angle of R_measured R_predicted^T per pose (rigid geometry)",
           "train": {}, "holdout": None}
    for split, idx in (("train", train), ("holdout", hold)):
        if not len(idx):
            continue
        q, R = meas.joints[idx], meas.rotations[idx]
        out[split] = {name: _stats(rotation_errors_deg(model, st.params, st.bases[0], st.tool[0], q, R, ee))
                      for name, st in states.items()}
    return out
