"""The ros_industrial positioner protocol: a 2-axis part positioner calibrated from the target poses
a fixed camera measured (issue 14; the ROS-Industrial ``kinematic_calibration`` example data).

Model: the positioner as two revolute DH links in the source's nominal geometry (link 1: theta 0,
d 0, a 0, alpha -90 deg; link 2: d -475 mm, theta -90 deg, a 0, alpha 0), its base anywhere in the
camera frame. Each measured pose ``T_camera_target`` becomes three points of the target (its
origin and 100 mm along its x and y axes) seen in the camera frame, so the calibration core's
point calibration (:class:`~robocal.calib.CalibrationProblem`) estimates, together,

* the positioner's base in the camera frame (the camera mount; 6),
* the three target points on the last link (the target mount),
* the DH parameters of the two axes the data determine (the identifiability analysis holds and
  names the rest: link 1's theta and d move the whole positioner like the base frame does, link 2's
  four parameters move the target like its mount does).

``nominal``: base and target mount only, nominal DH; ``calibrated``: plus every DH parameter (the
identifiable ones). Seeded random split, ``n_train`` records for the fit, the rest held out; hold-out
errors of the measured pose: position of the target origin [mm] and orientation [deg].
"""

from __future__ import annotations

import numpy as np

from ...calib import Target
from ...io.datasets import read_ros_industrial_positioner
from ...kinematics.links import Link
from ...kinematics.model import EndEffector, RobotModel
from ...transforms import so3_log
from ._fitting import fit, random_split, with_state_targets

__all__ = ["positioner_model", "target_points_mm", "calibrate_positioner", "axes_on_training_records",
           "calibrate_positioner_seeds",
           "pose_errors"]

#: the target points used as measurements, in the target frame [mm]
target_points_mm = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]])


def positioner_model() -> RobotModel:
    """The source's nominal 2-axis positioner (DH, mm / rad), base at (2200, 0, 1600) mm turned
    90 deg about x (the source's arbitrary base offset; the calibration re-estimates it)."""
    links = [Link("j1", "revolute", "dh", {"theta": 0.0, "d": 0.0, "a": 0.0, "alpha": -np.pi / 2}, -1),
             Link("j2", "revolute", "dh", {"theta": -np.pi / 2, "d": -475.0, "a": 0.0, "alpha": 0.0}, 0)]
    base = np.eye(4)
    base[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]
    base[:3, 3] = [2200.0, 0.0, 1600.0]
    return RobotModel(name="positioner_2axis", kind="dh", links=links, controller_joints=("j1", "j2"),
                      coupling=np.eye(2), limits=np.array([[-np.pi, np.pi], [-2 * np.pi, 2 * np.pi]]),
                      T_world_base=base, end_effectors=[EndEffector("flange", 1, np.eye(4))])


def _frames_from_points(p) -> np.ndarray:
    """(N, 4, 4) target frames from its three points (N, 3, 3): origin, +x, +y (Gram-Schmidt)."""
    x = p[:, 1] - p[:, 0]
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = p[:, 2] - p[:, 0]
    y -= np.sum(y * x, axis=1, keepdims=True) * x
    y /= np.linalg.norm(y, axis=1, keepdims=True)
    T = np.tile(np.eye(4), (len(p), 1, 1))
    T[:, :3, :3] = np.stack([x, y, np.cross(x, y)], axis=2)
    T[:, :3, 3] = p[:, 0]
    return T


def pose_errors(T_pred, T_meas) -> dict:
    """Position [mm] and orientation [deg] differences between predicted and measured target poses
    (N, 4, 4): mean, rms, max of each."""
    dp = np.linalg.norm(T_pred[:, :3, 3] - T_meas[:, :3, 3], axis=1)
    dr = np.degrees(np.linalg.norm(so3_log(np.swapaxes(T_pred[:, :3, :3], 1, 2) @ T_meas[:, :3, :3]), axis=1))
    return {"pos_mean": float(dp.mean()), "pos_rms": float(np.sqrt(np.mean(dp**2))), "pos_max": float(dp.max()),
            "rot_mean": float(dr.mean()), "rot_rms": float(np.sqrt(np.mean(dr**2))), "rot_max": float(dr.max()),
            "n": int(len(dp))}


def _points(T_camera_target) -> np.ndarray:
    return np.einsum("nij,kj->nki", T_camera_target[:, :3, :3], target_points_mm) + T_camera_target[:, None, :3, 3]


def _predicted_poses(problem, result, q) -> np.ndarray:
    return _frames_from_points(problem.predict_points(result.state, q=q, stations=np.zeros(len(q), int)))


def calibrate_positioner(seed: int = 0, n_train: int = 150, data=None, root=None) -> dict:
    """The protocol for one seeded split (module docstring). Returns ``{"seed", "train", "test",
    "nominal": {"train": errors, "test": errors}, "calibrated": {...}, "result", "nominal_result",
    "problem", "axes"}`` with :func:`pose_errors` figures and the calibrated axes
    (:func:`axes_in_camera`)."""
    ds = read_ros_industrial_positioner(root) if data is None else data
    T_meas = ds.per_pose["T_camera_target"]
    tr, te = random_split(ds.n_poses, n_train, seed)
    model = positioner_model()
    T_mt = ds.metadata["T_mount_target_guess"]
    start = (T_mt[:3, :3] @ target_points_mm.T).T + T_mt[:3, 3]
    targets = [Target(n, "flange", tuple(p)) for n, p in zip(("origin", "x100", "y100"), start)]
    pts = _points(T_meas)
    p0, r0 = fit(model, ds.joints[tr], targets, pts[tr], free=[])
    targets = with_state_targets(targets, r0.state)
    free = list(model.params.names)
    p1, r1 = fit(model, ds.joints[tr], targets, pts[tr], free=free, base_initial=r0.state.bases)
    out = {"seed": seed, "train": tr, "test": te, "result": r1, "nominal_result": r0, "problem": p1}
    for key, p, r in (("nominal", p0, r0), ("calibrated", p1, r1)):
        out[key] = {"train": pose_errors(_predicted_poses(p, r, ds.joints[tr]), T_meas[tr]),
                    "test": pose_errors(_predicted_poses(p, r, ds.joints[te]), T_meas[te])}
    out["axes"] = axes_in_camera(p1, r1)
    return out


def axes_in_camera(problem, result) -> dict:
    """The calibrated axes in the camera frame at joints 0: ``axis1_point``, ``axis1_direction``,
    ``axis2_point``, ``axis2_direction`` (mm, unit), the angle between them [deg] and their common
    normal's length [mm]; ``dropped``: the DH parameters the data cannot determine, with why."""
    model = problem.model.with_params(result.state.params)
    base = result.state.bases[0]
    frames = model.replace(T_world_base=base).link_frames(np.zeros((1, 2)))[0]  # (2, 3, 4) frames of links 1, 2
    z0, o0 = base[:3, 2], base[:3, 3]
    z1, o1 = frames[0][:3, 2], frames[0][:3, 3]
    n = np.cross(z0, z1)
    dist = abs(np.dot(o1 - o0, n)) / np.linalg.norm(n) if np.linalg.norm(n) > 1e-12 else float("nan")
    return {"axis1_point": o0, "axis1_direction": z0, "axis2_point": o1, "axis2_direction": z1,
            "angle_deg": float(np.degrees(np.arccos(np.clip(abs(z0 @ z1), -1.0, 1.0)))),
            "common_normal_mm": float(dist),
            "dropped": [(d["name"], d["why"]) for d in result.identifiability.dropped]}


def axes_on_training_records(seed: int = 0, n_train: int = 150, data=None, root=None) -> dict:
    """robocal's axis estimates on one split's training records, with those records, for a comparison
    with another estimator on the same data (tests/test_positioner_real_data.py, docs/testing.md).

    Returns ``T_camera_target`` (n_train, 4, 4) [mm] and ``joints`` (n_train, 2) [rad] of the training
    records, ``axes`` (2,) = (angle between the axes [deg], common normal [mm]) and ``sigma`` (2,)
    their formal standard deviations (alpha1 in deg, a1 in mm), and ``run`` (:func:`calibrate_positioner`).
    """
    from ...io.datasets import read_ros_industrial_positioner

    ds = read_ros_industrial_positioner(root) if data is None else data
    run = calibrate_positioner(seed=seed, n_train=n_train, data=ds)
    train = np.asarray(run["train"])
    table = {p["name"]: p for p in run["result"].parameter_table()}
    return {"T_camera_target": ds.per_pose["T_camera_target"][train], "joints": ds.joints[train],
            "axes": np.array([run["axes"]["angle_deg"], run["axes"]["common_normal_mm"]]),
            "sigma": np.array([np.degrees(table["alpha1"]["std"]), table["a1"]["std"]]), "run": run}


def calibrate_positioner_seeds(seeds=range(5), root=None, **kw) -> dict:
    """:func:`calibrate_positioner` per seed; means over seeds of the hold-out figures."""
    ds = read_ros_industrial_positioner(root)
    runs = [calibrate_positioner(s, data=ds, **kw) for s in seeds]
    out = {"runs": runs}
    for key in ("nominal", "calibrated"):
        out[key] = {part: {s: float(np.mean([r[key][part][s] for r in runs])) for s in runs[0][key][part]}
                    for part in ("train", "test")}
    return out


def positioner_table(seeds=range(5), root=None) -> str:
    """The Markdown table of docs/datasets.md (means over ``seeds`` of the hold-out figures)."""
    res = calibrate_positioner_seeds(seeds, root)
    lines = ["| model | train pos mean / rms / max [mm] | train rot mean [deg] | hold-out pos mean / rms / max [mm] "
             "| hold-out rot mean / max [deg] |", "|---|---:|---:|---:|---:|"]
    for key, label in (("nominal", "nominal DH (base + target mount fitted)"),
                       ("calibrated", "calibrated (+ the identifiable DH parameters)")):
        tr, te = res[key]["train"], res[key]["test"]
        lines.append(f"| {label} | {tr['pos_mean']:.3f} / {tr['pos_rms']:.3f} / {tr['pos_max']:.3f} | "
                     f"{tr['rot_mean']:.4f} | {te['pos_mean']:.3f} / {te['pos_rms']:.3f} / {te['pos_max']:.3f} | "
                     f"{te['rot_mean']:.4f} / {te['rot_max']:.4f} |")
    axes = [r["axes"] for r in res["runs"]]
    sig = [r["result"].parameter_table() for r in res["runs"]]
    a1 = [next(p for p in t if p["name"] == "a1") for t in sig]
    lines.append("")
    angles = ", ".join(f"{a['angle_deg']:.4f}" for a in axes)
    normals = ", ".join(f"{a['common_normal_mm']:.3f}" for a in axes)
    sigmas = ", ".join(f"{p['std']:.3f}" for p in a1)
    lines.append(f"Axes (per seed): angle between them {angles} deg; common normal {normals} mm "
                 f"(a1 1-sigma {sigmas} mm).")
    lines.append("Not identifiable (held at nominal): " + "; ".join(f"{n}: {why}" for n, why in axes[0]["dropped"]))
    return "\n".join(lines)


if __name__ == "__main__":
    print(positioner_table())
