"""``robocal verify``: a quick check of a calibrated robot from a handful of measured poses.

The calibration's folder (or its ``calibrated_robot.toml`` with ``result.json`` beside it) gives
the model, the identified target point (reflector) and the parameter covariance. The covariance is
propagated to each measured pose (finite differences of the predicted point over the named
parameters), the instrument noise is added, and :func:`robocal.performance.verify.verify_positions`
decides: ok, recalibrate, or mechanical fault suspected (one joint's offset named).
"""

from __future__ import annotations

import datetime as _dt
import json
from pathlib import Path

import numpy as np

from ...io.measurements import read_measurements
from ...performance.verify import verify_positions
from ...robots import load_robot
from ...transforms import so3_exp

__all__ = ["calibration_files", "predicted_points", "run_verify", "split_approach_columns"]

#: the approach-direction column of a joint: ``approach_J1`` ... (+1 / -1; 0 or empty: unknown)
APPROACH_PREFIX = "approach_"


def split_approach_columns(path, joint_names) -> tuple[str, np.ndarray | None]:
    """The measurement file's text without its ``approach_<joint>`` columns, and the signs (N,
    n_joints) they held (+1: the joint arrived moving in its positive direction, -1: negative,
    0: unknown or not given); (the text unchanged, None) when the file has no such column."""
    from ...errors import InputFileError

    text = Path(path).read_text(encoding="utf-8")
    lines = text.splitlines()
    head = next((i for i, s in enumerate(lines) if s.strip() and not s.lstrip().startswith("#")), None)
    if head is None:
        return text, None
    cols = [c.strip() for c in lines[head].split(",")]
    idx = [j for j, c in enumerate(cols) if c.startswith(APPROACH_PREFIX)]
    if not idx:
        return text, None
    unknown = [cols[j] for j in idx if cols[j][len(APPROACH_PREFIX):] not in joint_names]
    if unknown:
        raise InputFileError(f"{path}: line {head + 1}: column {unknown[0]!r} names no joint of the robot "
                             f"(approach columns: {', '.join(APPROACH_PREFIX + j for j in joint_names)})")
    keep = [j for j in range(len(cols)) if j not in idx]
    out, signs = lines[:head] + [",".join(cols[j] for j in keep)], []
    for ln, row in enumerate(lines[head + 1:], start=head + 2):
        if not row.strip() or row.lstrip().startswith("#"):
            out.append(row)
            continue
        cells = row.split(",")
        if len(cells) != len(cols):
            out.append(row)          # the reader reports the wrong field count
            continue
        s_row = np.zeros(len(joint_names))
        for j in idx:
            v = cells[j].strip()
            if v in ("", "0"):
                continue
            if v not in ("+1", "1", "-1", "+", "-"):
                raise InputFileError(f"{path}: line {ln}: column {cols[j]!r}: approach direction must be +1 or -1 "
                                     f"(or 0 / empty: unknown), got {v!r}")
            s_row[joint_names.index(cols[j][len(APPROACH_PREFIX):])] = -1.0 if v.startswith("-") else 1.0
        signs.append(s_row)
        out.append(",".join(cells[j] for j in keep))
    return "\n".join(out) + "\n", np.array(signs)



def calibration_files(model_path) -> tuple[Path, Path | None]:
    """(robot file, result.json or None) from a calibration folder or a robot file."""
    p = Path(model_path)
    if p.is_dir():
        toml = p / "calibrated_robot.toml"
        if not toml.is_file():
            from ...errors import InputFileError

            raise InputFileError(f"{p}: no calibrated_robot.toml in this folder (give a robot file or the folder "
                                 "`robocal calibrate --out` wrote)")
        p = toml
    res = p.with_name("result.json")
    return p, (res if res.is_file() else None)


def _point_of(model, T_world_flange_fn, q, point):
    T = T_world_flange_fn(model, q)
    return T[:, :3, :3] @ point + T[:, :3, 3]


def _fk(model, q):
    return model.fk(q).reshape(-1, 4, 4)


def _perturbed(model, point, name, h):
    """(model, point) with the named parameter moved by ``h`` (base.* in the instrument frame)."""
    if name.startswith("base."):
        T = model.T_world_base.copy()
        k = name[5:]
        if k in ("x", "y", "z"):
            T[:3, 3] += h * np.eye(3)["xyz".index(k)]
        else:
            T[:3, :3] = so3_exp(h * np.eye(3)["rx ry rz".split().index(k)]) @ T[:3, :3]
        return model.replace(T_world_base=T), point
    if "." in name:                                        # a target point: <target>.x
        k = name.rsplit(".", 1)[1]
        pt = point.copy()
        pt["xyz".index(k)] += h
        return model, pt
    return model.with_params(**{name: float(model.params.values[model.params.index(name)] + h)}), point


def predicted_points(model, q, point, cov_names=None, cov=None):
    """Predicted positions (N, 3) [mm], their full covariance (3N, 3N) [mm²] (or None) and the
    joint Jacobian (N, 3, n) [mm/rad]."""
    p0 = _point_of(model, _fk, q, point)
    C = None
    if cov_names is not None:
        cols = []
        for name, unit in cov_names:
            h = 1e-6 if unit == "rad" else 1e-4
            try:
                mp, pp = _perturbed(model, point, name, h)
                mm, pm = _perturbed(model, point, name, -h)
            except (KeyError, ValueError, IndexError):
                cols.append(np.zeros(p0.size))
                continue
            cols.append(((_point_of(mp, _fk, q, pp) - _point_of(mm, _fk, q, pm)) / (2 * h)).reshape(-1))
        J = np.array(cols).T
        C = J @ cov @ J.T
    n = q.shape[1]
    Jq = np.empty((len(q), 3, n))
    for j in range(n):
        h = 1e-6
        dq = np.zeros(n)
        dq[j] = h
        Jq[:, :, j] = (_point_of(model, _fk, q + dq, point) - _point_of(model, _fk, q - dq, point)) / (2 * h)
    return p0, C, Jq


def run_verify(model_path, measurements_path, *, noise_mm: float, false_alarm_rate: float = 0.01,
               register_frame: bool = False, tool_point_mm=None, temperature_c: float | None = None,
               instrument: str | None = None) -> dict:
    """Verify a calibrated robot; returns the JSON-ready result (decision, statistic, reasons...)."""
    toml, result_path = calibration_files(model_path)
    model = load_robot(toml)
    text, signs = split_approach_columns(measurements_path, list(model.controller_joints))
    if signs is None:
        meas = read_measurements(measurements_path, model)
    else:                           # the reader takes a file: the same name, without the approach columns
        import tempfile

        with tempfile.TemporaryDirectory(prefix="robocal-verify-") as tmp:
            stripped = Path(tmp) / Path(measurements_path).name
            stripped.write_text(text, encoding="utf-8")
            meas = read_measurements(stripped, model)
        if len(signs) != len(meas.joints):
            from ...errors import InputFileError

            raise InputFileError(f"{measurements_path}: {len(signs)} rows with approach directions, "
                                 f"{len(meas.joints)} poses read")
    point = np.zeros(3)
    cov_names = cov = None
    if result_path is not None:
        res = json.loads(result_path.read_text(encoding="utf-8"))
        targets = res.get("targets") or []
        if targets and tool_point_mm is None:
            point = np.asarray(targets[0]["point_mm"], float)
        c = res.get("covariance")
        if c and c.get("matrix"):
            cov_names = list(zip(c["names"], c["units"]))
            cov = np.asarray(c["matrix"], float)
    if tool_point_mm is not None:
        point = np.asarray(tool_point_mm, float)
    q = np.asarray(meas.joints, float)
    measured = np.asarray(meas.points, float)[:, 0, :]
    pred, C, Jq = predicted_points(model, q, point, cov_names, cov)
    v = verify_positions(measured, pred, instrument_sigma_mm=noise_mm, prediction_covariance_mm2=C,
                         joint_jacobian=Jq, joint_names=model.controller_joints, false_alarm_rate=false_alarm_rate,
                         register_frame=register_frame, approach_signs=signs)
    out = {"format": "robocal-verification/1", "robot": model.name, "model": str(toml),
           "measurements": str(measurements_path), "n_poses": int(len(q)),
           "time": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
           "temperature_c": temperature_c, "instrument": instrument or meas.metadata.get("instrument"),
           "instrument_noise_mm": noise_mm, "covariance_used": C is not None, "register_frame": register_frame,
           "decision": v.decision, "statistic": v.statistic, "dof": v.dof, "threshold": v.threshold,
           "false_alarm_rate": v.false_alarm_rate, "p_value": v.p_value, "rms_mm": v.rms_mm, "max_mm": v.max_mm,
           "suspect_joint": v.suspect_joint, "suspect_cause": v.suspect_cause,
           "approach_directions": signs is not None, "reasons": v.reasons}
    if v.suspect_joint is not None:
        k = model.controller_joints.index(v.suspect_joint)
        deg = not model.prismatic_joints[k]
        f = np.degrees if deg else (lambda x: x)
        out["suspect_offset"] = {"value": float(f(v.suspect_offset)), "std": float(f(v.suspect_offset_sigma)),
                                 "unit": "deg" if deg else "mm", "cause": v.suspect_cause}
    return out
