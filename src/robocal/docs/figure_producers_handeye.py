"""Producers of the documented figures of docs/handeye.md and docs/controller.md that run the
page's own commands (:mod:`robocal.docs.figures`): the walk-through and the probe of
docs/controller.md and ``handeye solve``'s default on the ROS-Industrial sets. Each returns a flat
``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools
import json
import tempfile
from pathlib import Path

__all__ = ["HANDEYE_PRODUCERS", "camera_board_shape", "camera_calibrate_real", "camera_sag", "detection_rendered", "handeye_agreement", "handeye_auto_simulated", "handeye_fair_counts", "handeye_gate_shifted", "handeye_joint_offsets", "handeye_noise_estimate", "handeye_plain_fit",
           "handeye_refine_cases", "handeye_study_summary", "handeye_variants_real", "controller_probe", "controller_walkthrough", "handeye_default_real",
           "principal_point_rotation", "ur_angle_convention",
           "ur_controller_table"]


def _controller_data(name: str) -> Path:
    """``tests/data/controller/NAME`` of the repository."""
    from .figure_producers import repository_root

    return repository_root() / "tests" / "data" / "controller" / name


@functools.lru_cache(maxsize=None)
def controller_walkthrough() -> dict:
    """docs/controller.md "Walk-through": the page's six commands on
    ``tests/data/controller/ur10_driver_test.conf`` in a temporary folder.

    Fields: ``import.fk_mm`` (the robot file's FK against the controller's, 1000 joint sets [mm]),
    ``factory.{rms|max}_mm``, ``factory.rot_max_deg`` (``diff ur10 ur10_controller.toml``, 2000
    joint sets), ``holdout.{before|after}_mm`` (RMS of ``calibrate``'s held-out poses [mm]),
    ``added.{rms|max}_mm``, ``added.aligned_rms_mm`` (``diff`` of the calibrated model, and after a
    best-fit base), ``export.fk_mm`` (the YAML's chain against the calibrated model [mm]),
    ``urdf.fk_mm`` (``controller export urdf``'s file read back against the model [mm])."""
    from .figure_producers_cli import run_cli

    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        ctl, cal = t / "ur10_controller.toml", t / "calib"
        imp = json.loads(run_cli("controller", "import", "ur", "ur10", _controller_data("ur10_driver_test.conf"),
                                 "--out", ctl, "--json"))
        d1 = json.loads(run_cli("controller", "diff", "ur10", ctl, "--json"))
        run_cli("simulate", "tracker", ctl, "--poses", 100, "--seed", 3, "--out", t / "tracker.csv")
        c = json.loads(run_cli("calibrate", ctl, t / "tracker.csv", "--out", cal, "--json"))
        d2 = json.loads(run_cli("controller", "diff", ctl, cal / "calibrated_robot.toml", "--json"))
        ex = json.loads(run_cli("controller", "export", "ur", cal / "calibrated_robot.toml", "--out",
                                t / "my_robot_calibration.yaml", "--json"))
        urdf = json.loads(run_cli("controller", "export", "urdf", cal / "calibrated_robot.toml", "--out",
                                  t / "robot.urdf", "--json"))
    return {"import.fk_mm": float(imp["fk_check"]["max_mm"]),
            "factory.rms_mm": d1["position_mm"]["rms"], "factory.max_mm": d1["position_mm"]["max"],
            "factory.rot_max_deg": d1["rotation_deg"]["max"],
            "holdout.before_mm": c["validation"]["before"]["rms"], "holdout.after_mm": c["validation"]["after"]["rms"],
            "added.rms_mm": d2["position_mm"]["rms"], "added.max_mm": d2["position_mm"]["max"],
            "added.aligned_rms_mm": d2["base_aligned"]["position_mm"]["rms"],
            "export.fk_mm": float(ex["fk_check"]["max_mm"]), "urdf.fk_mm": float(urdf["fk_check"]["max_mm"])}


@functools.lru_cache(maxsize=None)
def controller_probe() -> dict:
    """docs/controller.md "Measured with a virtual controller": the walk-through's
    ``ur10_controller.toml``, then per format (``ur``, ``abb``, ``kuka``, ``doosan``)
    ``controller probe-simulate ... --count 200 --seed 1``, ``controller probe ur10 pairs.txt``,
    ``controller diff ur10_controller.toml probed.toml --poses 1000``.

    Fields (the ``ur`` format): ``fit.max_mm``, ``fit.max_deg`` (the fit's largest residual at the
    pairs), ``tolerance_mm`` (what the rounding allows); over the four formats:
    ``diff.{min|max}_mm``, ``diff.rot_max_deg`` (largest difference at 1000 joint sets)."""
    from .figure_producers_cli import run_cli

    out, diffs, rots = {}, [], []
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        ctl = t / "ur10_controller.toml"
        run_cli("controller", "import", "ur", "ur10", _controller_data("ur10_driver_test.conf"), "--out", ctl)
        for fmt in ("ur", "abb", "kuka", "doosan"):
            pairs, probed = t / f"pairs_{fmt}.txt", t / f"probed_{fmt}.toml"
            run_cli("controller", "probe-simulate", ctl, fmt, "--count", 200, "--seed", 1, "--out", pairs)
            p = json.loads(run_cli("controller", "probe", "ur10", pairs, "--out", probed, "--json"))
            d = json.loads(run_cli("controller", "diff", ctl, probed, "--poses", 1000, "--json"))
            if fmt == "ur":
                out.update({"fit.max_mm": p["fit_residual"]["position_mm"]["max"],
                            "fit.max_deg": p["fit_residual"]["rotation_deg"]["max"],
                            "tolerance_mm": p["tolerance"]["mm"]})
            diffs.append(d["position_mm"]["max"])
            rots.append(d["rotation_deg"]["max"])
    out.update({"diff.min_mm": min(diffs), "diff.max_mm": max(diffs), "diff.rot_max_deg": max(rots)})
    return out


@functools.lru_cache(maxsize=None)
def ur_controller_table(conf: str, robot: str) -> dict:
    """docs/controller.md: the controller's own DH table (nominal + deltas, metres) of
    ``robocal controller import ur ROBOT tests/data/controller/CONF``: ``d.{0..5}`` [m]."""
    from ..workflows.controller.models import import_ur

    r = import_ur(_controller_data(conf), robot, n_check=10, seed=0)
    return {f"d.{k}": float(v) for k, v in enumerate(r["dh"]["d"])}


@functools.lru_cache(maxsize=None)
def ur_angle_convention() -> dict:
    """docs/controller.md "Angle convention, an open point": robocal's joint origins of the three UR
    driver test arms (``ur_joint_origins``), their intrinsic X-Y'-Z'' angles read as URDF ``rpy``,
    over 1000 random joint sets (seed 0): ``{arm}.mm``, ``{arm}.deg`` (largest flange move), ``arm``
    in ``ur10``, ``ur10e_a``, ``ur10e_b``."""
    import numpy as np

    from ..kinematics.links import frame_from_xyz_rpy
    from ..transforms import euler_from_matrix
    from ..workflows.controller.models import _pose_errors, import_ur, origins_fk, random_joints, ur_joint_origins

    out = {}
    for arm, conf, robot in (("ur10", "ur10_driver_test.conf", "ur10"), ("ur10e_a", "ur10e_driver_test_a.conf", "ur10e"),
                             ("ur10e_b", "ur10e_driver_test_b.conf", "ur10e")):
        m = import_ur(_controller_data(conf), robot, n_check=2)["model"]
        O = ur_joint_origins(m)
        mixed = [frame_from_xyz_rpy(T[:3, 3], euler_from_matrix(T[:3, :3], "xyz_intrinsic")) for T in O]
        dp, ang = _pose_errors(origins_fk(O, random_joints(m, 1000, seed=0)),
                               origins_fk(mixed, random_joints(m, 1000, seed=0)))
        out[f"{arm}.mm"], out[f"{arm}.deg"] = float(dp.max()), float(np.degrees(ang.max()))
    return out


@functools.lru_cache(maxsize=None)
def handeye_default_real(test_set: str) -> dict:
    """docs/handeye.md "The default": ``robocal handeye solve
    <datasets>/ros_industrial_handeye/raw/TEST_SET/cal_data.yaml --out DIR --json`` (``--robot-pose-sigma
    auto``): ``cv.{exact|estimated}`` (held-out RMS [px]), ``kept_exact`` (1 when the exact model was
    kept), ``rms_px``, ``rms_mm`` (on the target plane), ``noise.{mm|deg|px}`` (the estimated noise), ``difference.{mm|deg|sigma}`` (the
    two fits' cameras apart), ``default_vs_exact.{mm|deg}`` (the kept camera against the
    ``--exact-poses`` fit's), the sanity gate's ``gate.angle_mismatch_deg`` (median motion-angle
    mismatch), ``gate.backprojection_px``, ``gate.backprojection_limit_px`` and ``gate.pnp_rms_px`` (the
    per-image PnP RMS, the corner noise)."""
    import numpy as np

    from ..io.datasets import datasets_root
    from .figure_producers_cli import ros_handeye, run_cli

    src = datasets_root() / "ros_industrial_handeye" / "raw" / test_set / "cal_data.yaml"
    with tempfile.TemporaryDirectory() as tmp:
        d = json.loads(run_cli("handeye", "solve", src, "--out", Path(tmp) / "out", "--json"))
    s = d["robot_pose_sigma"]
    exact = ros_handeye(test_set)
    pose = d["camera_pose"]
    d_mm = float(np.linalg.norm(np.subtract(pose["position_mm"], [exact[f"position_mm.{k}"] for k in range(3)])))
    d_deg = float(np.linalg.norm(np.subtract(pose["rotation_vector_deg"],
                                             [exact[f"rotation_vector_deg.{k}"] for k in range(3)])))
    return {"cv.exact": s["cv_rms_px"]["exact"], "cv.estimated": s["cv_rms_px"]["estimated"],
            "kept_exact": float(s["choice"] == "exact"), "rms_px": float(d["reprojection_rms_px"]),
            "rms_mm": float(d["reprojection_rms_mm"]),
            "noise.mm": s["estimated"]["robot_pose_sigma"][0], "noise.deg": s["estimated"]["robot_pose_sigma"][1],
            "noise.px": s["estimated"]["pixel_sigma_px"], "difference.mm": s["difference"]["position_mm"],
            "difference.deg": s["difference"]["rotation_deg"], "difference.sigma": s["difference"]["sigma"],
            "default_vs_exact.mm": d_mm, "default_vs_exact.deg": d_deg,
            "gate.angle_mismatch_deg": d["sanity_checks"]["motion_angle_consistency"]["value"],
            "gate.backprojection_px": d["sanity_checks"]["reprojection_vs_corner_noise"]["value"],
            "gate.backprojection_limit_px": d["sanity_checks"]["reprojection_vs_corner_noise"]["limit"],
            "gate.pnp_rms_px": d["sanity_checks"]["corner_noise_pnp_rms_px"]["value"]}


@functools.lru_cache(maxsize=None)
def handeye_gate_shifted() -> dict:
    """docs/handeye.md "Sanity gate" (``tests/test_handeye_gate.py``): the ROS-Industrial 10x10 set with
    image i paired to pose i+1 (14 images) through ``robocal handeye solve CAL_DATA --json`` (exit 3).

    Fields: ``angle_mismatch_deg``, ``backprojection_px`` (the failed checks' values), and from the
    named likely cause ``repaired.angle_mismatch_deg``, ``repaired.linear_rms_px`` (the data re-paired)."""
    import re

    from ..io.datasets import datasets_root
    from .figure_producers_cli import run_cli

    src = datasets_root() / "ros_industrial_handeye" / "raw" / "test_set_10x10"
    lines = ["data:"]
    for i in range(14):
        lines += [f"  - pose: {src / 'poses' / f'{i + 1}.yaml'}", f"    image: {src / 'images' / f'{i}.png'}"]
    text = (src / "cal_data.yaml").read_text(encoding="utf-8")
    with tempfile.TemporaryDirectory() as tmp:
        cal = Path(tmp) / "cal_data.yaml"
        cal.write_text("\n".join(lines) + "\n" + text[text.index("target_finder"):], encoding="utf-8")
        run_cli("handeye", "solve", cal, "--out", Path(tmp) / "he", "--json", ok=(3,))
        d = json.loads((Path(tmp) / "he" / "handeye.json").read_text(encoding="utf-8"))
    cause = next(r for r in d["reasons"] if r.startswith("likely cause"))
    m = re.search(r"motion angle mismatch ([0-9.]+) deg, linear solution's back-projection RMS ([0-9.]+) px", cause)
    return {"angle_mismatch_deg": d["sanity_checks"]["motion_angle_consistency"]["value"],
            "backprojection_px": d["sanity_checks"]["reprojection_vs_corner_noise"]["value"],
            "repaired.angle_mismatch_deg": float(m.group(1)), "repaired.linear_rms_px": float(m.group(2))}


@functools.lru_cache(maxsize=None)
def handeye_noise_estimate() -> dict:
    """docs/handeye.md "Or let the data say" (``robot_pose_sigma="estimate"``): ``simulate_hand_eye``
    (eye-in-hand, 0.3 px corner noise), seeds 0-2, robot pose noise 0.05 mm / 0.01 deg ("l1"),
    0.3 mm / 0.05 deg ("l2"), 1 mm / 0.1 deg ("l3"), 20 images (and 12 for the last count).

    Fields ``{l1|l2|l3}.{px|mm|deg}.{min|max}`` (the estimated noise), over the six runs of l2 and l3
    ``err.{estimate|default|exact}.{min|max}`` [mm] (camera position error with the estimate, the
    default fixed 0.05 mm / 0.01 deg prior and the poses taken as exact), ``z.{estimate|default}.{min|max}``
    (largest |error| / reported sigma over the three axes), and ``n12.worse`` (runs of the six at
    12 images where the estimate's camera is farther from the truth than the default's)."""
    import numpy as np

    from ..handeye import refine_hand_eye
    from ..sim.cameras.handeye_points import simulate_hand_eye

    def err(res, sim):
        d = np.abs(res.camera_pose[:3, 3] - sim.camera_pose[:3, 3])
        return float(np.linalg.norm(d)), float(np.max(d / res.sigma_translation_mm))

    out, runs, worse = {}, {"estimate": [], "default": [], "exact": []}, 0
    for level, (mm, deg) in (("l1", (0.05, 0.01)), ("l2", (0.3, 0.05)), ("l3", (1.0, 0.1))):
        est = {"px": [], "mm": [], "deg": []}
        for seed in range(3):
            sim = simulate_hand_eye(seed, n_images=20, pixel_noise=0.3, pose_noise_mm=mm, pose_noise_deg=deg)
            data = (sim.T_base_flange, sim.image_points, sim.target_points, sim.camera)
            r = refine_hand_eye(*data, robot_pose_sigma="estimate")
            n = r.noise_estimate
            est["px"].append(n["pixel_sigma_px"])
            est["mm"].append(n["robot_pose_sigma"][0])
            est["deg"].append(n["robot_pose_sigma"][1])
            if level != "l1":
                runs["estimate"].append(err(r, sim))
                runs["default"].append(err(refine_hand_eye(*data), sim))
                runs["exact"].append(err(refine_hand_eye(*data, robot_pose_sigma=None), sim))
                sim12 = simulate_hand_eye(seed, n_images=12, pixel_noise=0.3, pose_noise_mm=mm, pose_noise_deg=deg)
                d12 = (sim12.T_base_flange, sim12.image_points, sim12.target_points, sim12.camera)
                worse += err(refine_hand_eye(*d12, robot_pose_sigma="estimate"), sim12)[0] > err(refine_hand_eye(*d12),
                                                                                                   sim12)[0]
        for k, v in est.items():
            out[f"{level}.{k}.min"], out[f"{level}.{k}.max"] = float(min(v)), float(max(v))
    for k, v in runs.items():
        e = [x[0] for x in v]
        out[f"err.{k}.min"], out[f"err.{k}.max"] = min(e), max(e)
        if k != "exact":
            z = [x[1] for x in v]
            out[f"z.{k}.min"], out[f"z.{k}.max"] = min(z), max(z)
    out["n12.worse"] = float(worse)
    return out


@functools.lru_cache(maxsize=None)
def handeye_variants_real(test_set: str) -> dict:
    """docs/handeye.md: ``robocal handeye solve <datasets>/ros_industrial_handeye/raw/TEST_SET/cal_data.yaml
    --json`` with the former fixed prior (``--robot-pose-sigma 0.05,0.01``) and with ``--exact-poses
    --refine-intrinsics``: ``prior.backprojection_px`` (through the reported flange poses),
    ``prior.from_exact_mm``, ``prior.from_exact_deg`` (its camera against the ``--exact-poses``
    fit's), ``exact.rms_px`` and ``refined_intrinsics.rms_px``; on ChArUco ``source.from_default_{mm|deg}``
    (the exact-pose refinement on the 14 images the source library uses, standing in for its camera as in
    ``tests/test_handeye_real.py``, against the default's camera, which is the exact-pose fit),
    ``pnp_rms_px.{min|max}`` (one PnP pose per image with the given intrinsics) and ``n_corners``."""
    import numpy as np

    from ..io.datasets import datasets_root
    from ..transforms import so3_exp
    from .figure_producers_cli import ros_handeye, run_cli

    src = datasets_root() / "ros_industrial_handeye" / "raw" / test_set / "cal_data.yaml"
    with tempfile.TemporaryDirectory() as tmp:
        prior = json.loads(run_cli("handeye", "solve", src, "--robot-pose-sigma", "0.05,0.01", "--out",
                                   Path(tmp) / "prior", "--json"))
        refined = json.loads(run_cli("handeye", "solve", src, "--exact-poses", "--refine-intrinsics", "--out",
                                     Path(tmp) / "refined", "--json"))
    exact = ros_handeye(test_set)
    p = prior["camera_pose"]
    R_prior = so3_exp(np.radians(p["rotation_vector_deg"]))
    R_exact = so3_exp(np.radians([exact[f"rotation_vector_deg.{k}"] for k in range(3)]))
    def angle_deg(R_a, R_b):
        return float(np.degrees(np.arccos(np.clip((np.trace(R_a.T @ R_b) - 1.0) / 2.0, -1.0, 1.0))))

    out = {}
    if test_set == "test_set_charuco":  # the default keeps the exact-pose fit: its camera against the source's
        from ..handeye import refine_hand_eye
        from ..io.ros_calibration import read_cal_data
        from ..workflows.cameras.camera_common import detect_set

        data = read_cal_data(src)
        det = detect_set(data.image_paths, data.board, blob_settings=data.blob_settings,
                         homography_threshold=data.homography_threshold)
        keep = np.isin(det.names, [f"{i}.png" for i in range(16) if i not in (2, 15)]) & det.used
        source_like = refine_hand_eye(data.T_base_flange[keep], det.image_points[keep], det.board.object_points(),
                                      data.camera, setup=data.setup, robot_pose_sigma=None).camera_pose
        out["source.from_default_mm"] = float(np.linalg.norm(source_like[:3, 3] - [exact[f"position_mm.{k}"]
                                                                                  for k in range(3)]))
        out["source.from_default_deg"] = angle_deg(source_like[:3, :3], R_exact)
        from ..handeye import solve_pnp

        _, rms, _ = solve_pnp(data.camera, det.board.object_points(), det.image_points[det.used])
        out["pnp_rms_px.min"], out["pnp_rms_px.max"] = float(np.nanmin(rms)), float(np.nanmax(rms))
        out["n_corners"] = float(np.sum(np.isfinite(det.image_points[det.used][..., 0])))
    return {**out, "prior.backprojection_px": float(prior["backprojection_rms_px"]),
            "prior.from_exact_mm": float(np.linalg.norm(np.subtract(p["position_mm"],
                                                                    [exact[f"position_mm.{k}"] for k in range(3)]))),
            "prior.from_exact_deg": angle_deg(R_prior, R_exact), "exact.rms_px": exact["rms_px"],
            "refined_intrinsics.rms_px": float(refined["reprojection_rms_px"])}


@functools.lru_cache(maxsize=None)
def handeye_auto_simulated() -> dict:
    """docs/handeye.md "The default" (``tests/test_handeye_refine.py::
    test_auto_keeps_the_estimated_noise_when_the_robot_is_randomly_noisy``): ``simulate_hand_eye(0,
    n_images=16, pixel_noise=0.2, pose_noise_mm=1, pose_noise_deg=0.1)``; ``kept_estimated`` (1 when
    ``auto`` kept the estimated noise), ``auto.error_mm``, ``exact.error_mm`` (camera position error)."""
    import numpy as np

    from ..handeye import refine_hand_eye
    from ..sim.cameras.handeye_points import simulate_hand_eye

    sim = simulate_hand_eye(0, n_images=16, pixel_noise=0.2, pose_noise_mm=1.0, pose_noise_deg=0.1)
    data = (sim.T_base_flange, sim.image_points, sim.target_points, sim.camera)
    auto = refine_hand_eye(*data, robot_pose_sigma="auto")
    exact = refine_hand_eye(*data, robot_pose_sigma=None)
    return {"kept_estimated": float(auto.noise_estimate["choice"] == "estimated"),
            "auto.error_mm": float(np.linalg.norm(auto.camera_pose[:3, 3] - sim.camera_pose[:3, 3])),
            "exact.error_mm": float(np.linalg.norm(exact.camera_pose[:3, 3] - sim.camera_pose[:3, 3]))}


@functools.lru_cache(maxsize=None)
def handeye_study_summary() -> dict:
    """docs/handeye.md "Do the paper's conclusions hold?": summaries of ``python
    benchmarks/handeye_study.py --seeds 16``'s refined table (the producer ``handeye/study``).

    Fields: ``brown.ratio_3_6_to_8.{min|max}`` (refined translation error at 3-6 images over that at 8),
    ``brown.rot_10_30.median`` [deg] (the rotation floor), ``none.trans_4_30.{min|max}`` [mm] and
    ``none.rot.{min|max}`` [deg] (no distortion model), ``radial_division.rot_8_30.median`` [deg],
    ``{none|brown}.rot_refined_better.count`` (image counts, of 9, where the refined rotation error is below
    Tsai–Lenz's)."""
    import numpy as np

    from .figure_producers import PRODUCERS

    t = PRODUCERS["handeye/study"]()

    def v(model, n, what):
        return t[f"{model}.{n}.refined.{what}"]

    ratios = [v("brown", n, "trans_mm") / v("brown", 8, "trans_mm") for n in (3, 4, 5, 6)]
    none_t = [v("none", n, "trans_mm") for n in (4, 5, 6, 8, 10, 15, 20, 30)]
    none_r = [v("none", n, "rot_deg") for n in (3, 4, 5, 6, 8, 10, 15, 20, 30)]
    floor = [v(m, n, "rot_deg") for m in ("radial", "division") for n in (8, 10, 15, 20, 30)]
    images = (3, 4, 5, 6, 8, 10, 15, 20, 30)
    better = {m: float(sum(v(m, n, "rot_deg") < t[f"{m}.{n}.linear.rot_deg"] for n in images))
              for m in ("none", "brown")}
    return {"brown.ratio_3_6_to_8.min": min(ratios), "brown.ratio_3_6_to_8.max": max(ratios),
            "brown.rot_10_30.median": float(np.median([v("brown", n, "rot_deg") for n in (10, 15, 20, 30)])),
            "none.trans_4_30.min": min(none_t), "none.trans_4_30.max": max(none_t),
            "none.rot.min": min(none_r), "none.rot.max": max(none_r),
            "radial_division.rot_8_30.median": float(np.median(floor)),
            **{f"{m}.rot_refined_better.count": c for m, c in better.items()}}


#: docs/handeye.md "A fair comparison": the robot pose noise levels (the table's first cell)
FAIR_LEVELS = ("none (0 / 0)", "0.02 mm / 0.004 deg", "0.2 mm / 0.03 deg", "1 mm / 0.1 deg",
               "systematic 0.5 mm/m + 0.02 mm / 0.004 deg")
_OPENCV_LINEAR = ("TSAI", "PARK", "HORAUD", "ANDREFF", "DANIILIDIS", "RW_SHAH", "RW_LI")


@functools.lru_cache(maxsize=None)
def handeye_fair_counts() -> dict:
    """docs/handeye.md "Where robocal's default wins and where not": counts of seeds out of 20 from
    ``python benchmarks/handeye_fair_comparison.py --seeds 20`` (the run of the producer
    ``handeye/fair_comparison``).

    Fields: ``auto_kept.{level}`` (seeds where ``--robot-pose-sigma auto`` kept the estimated noise),
    ``auto_kept.{min|max}`` over the levels, ``linear_closer.{level}.{min|max}`` (seeds where the
    default is closer in position than an OpenCV linear method, over the seven methods) and
    ``closer_1mm_best_linear.{min|max}`` (the same at 1 mm / 0.1 deg against DANIILIDIS, TSAI,
    HORAUD and PARK, the four with lower medians)."""
    import re

    from .figure_producers import PRODUCERS, _benchmark_text

    t = PRODUCERS["handeye/fair_comparison"]()
    text = _benchmark_text("handeye_fair_comparison.py", tuple(range(20)))
    out = {}
    for level in FAIR_LEVELS:
        m = re.search(r"\| " + re.escape(level) + r" \| \(auto kept the estimated noise in ([0-9]+) of", text)
        out[f"auto_kept.{level}"] = float(m.group(1))
        wins = [t[f"{level} | OpenCV {k}|2|0"] for k in _OPENCV_LINEAR]
        out[f"linear_closer.{level}.min"], out[f"linear_closer.{level}.max"] = min(wins), max(wins)
    kept = [out[f"auto_kept.{level}"] for level in FAIR_LEVELS]
    out["auto_kept.min"], out["auto_kept.max"] = min(kept), max(kept)
    best = [t[f"1 mm / 0.1 deg | OpenCV {k}|2|0"] for k in ("DANIILIDIS", "TSAI", "HORAUD", "PARK")]
    out["closer_1mm_best_linear.min"], out["closer_1mm_best_linear.max"] = min(best), max(best)
    return out


@functools.lru_cache(maxsize=None)
def handeye_refine_cases() -> dict:
    """docs/handeye.md "Accuracy against OpenCV", the other tests of ``tests/test_handeye_refine.py`` on
    their set-ups (``simulate_hand_eye``):

    * ``sigma.{eye_in_hand|eye_to_hand}.max``: the largest |translation error| / reported sigma over
      the axes and seeds 0-4 (15 images, 0.3 px, 0.05 mm / 0.01 deg);
    * ``corner.px``: seed 5, 8 noise-free images, one corner moved by (3, -2) px, its residual [px];
    * ``wrong.{held|free}.{px|mm}``: seed 2, 20 images, fx 1390 / fy 1410 and distortion (-0.2, 0.1):
      back-projection RMS and camera position error, intrinsics held and refined;
    * ``swapped.{plain|huber}.{mm|deg}``: seed 20, 15 images, poses 4 and 9 swapped: camera error;
    * ``one_off.{plain|huber}.{mm|outliers}``: the same set, pose 4 moved by 3.7 mm along (1, 1, 1):
      camera error and the images rejected."""
    import dataclasses

    import numpy as np

    from ..handeye import refine_hand_eye
    from ..handeye.refine import rotation_error_deg
    from ..sim.cameras.handeye_points import simulate_hand_eye

    def pos_err(T, sim):
        return float(np.linalg.norm(T[:3, 3] - sim.camera_pose[:3, 3]))

    out = {}
    for setup in ("eye_in_hand", "eye_to_hand"):
        z = []
        for seed in range(5):
            sim = simulate_hand_eye(seed, setup=setup, n_images=15, pixel_noise=0.3, pose_noise_mm=0.05,
                                    pose_noise_deg=0.01)
            res = refine_hand_eye(sim.T_base_flange, sim.image_points, sim.target_points, sim.camera, setup=setup)
            z.append(np.max(np.abs(res.camera_pose[:3, 3] - sim.camera_pose[:3, 3]) / res.sigma_translation_mm))
        out[f"sigma.{setup}.max"] = float(max(z))
    sim = simulate_hand_eye(5, n_images=8, pixel_noise=0.0, pose_noise_mm=0.0, pose_noise_deg=0.0)
    uv = sim.image_points.copy()
    uv[2, 40] += [3.0, -2.0]
    res = refine_hand_eye(sim.T_base_flange, uv, sim.target_points, sim.camera, robot_pose_sigma=None)
    out["corner.px"] = float(np.linalg.norm(res.residuals_px[2, 40]))
    sim = simulate_hand_eye(2, n_images=20)
    wrong = dataclasses.replace(sim.camera, fx=1390.0, fy=1410.0, distortion=(-0.2, 0.1, 0.0, 0.0, 0.0))
    for k, free in (("held", False), ("free", True)):
        r = refine_hand_eye(sim.T_base_flange, sim.image_points, sim.target_points, wrong, refine_intrinsics=free)
        out[f"wrong.{k}.px"], out[f"wrong.{k}.mm"] = float(r.rms_px), pos_err(r.camera_pose, sim)
    sim = simulate_hand_eye(20, n_images=15)
    F = sim.T_base_flange.copy()
    F[[4, 9]] = F[[9, 4]]
    for k, loss in (("plain", "linear"), ("huber", "huber")):
        r = refine_hand_eye(F, sim.image_points, sim.target_points, sim.camera, loss=loss)
        out[f"swapped.{k}.mm"] = pos_err(r.camera_pose, sim)
        out[f"swapped.{k}.deg"] = float(rotation_error_deg(r.camera_pose, sim.camera_pose))
    F = sim.T_base_flange.copy()
    F[4, :3, 3] += 3.7 / np.sqrt(3.0)  # one reading 3.7 mm off
    for k, loss in (("plain", "linear"), ("huber", "huber")):
        r = refine_hand_eye(F, sim.image_points, sim.target_points, sim.camera, loss=loss)
        out[f"one_off.{k}.mm"] = pos_err(r.camera_pose, sim)
        out[f"one_off.{k}.outliers"] = float(len(r.outliers))
    return out


@functools.lru_cache(maxsize=None)
def camera_board_shape() -> dict:
    """docs/handeye.md "Board shape" (the set-up of ``tests/test_camera_board_shape.py``): 10 rendered
    views (seed 3) of ``checkerboard:9x6:25mm`` bent into a cylinder with its middle 1 mm out of the
    plane of the printed pattern's ends, through ``robocal camera calibrate --distortion 5 --fix k3``
    without and with ``--board-shape``.

    Fields: ``true_sag_mm`` (the bend over the corners, analytic), ``sag.{x|y|sigma_x}`` [mm],
    ``fx_error.{flat|shaped}`` [px] (|fx - truth|), ``rms.{flat|shaped}`` [px]."""
    import cv2
    import numpy as np

    from ..io.boards import board_image, parse_board
    from ..sim.cameras.camera_cell import simulate_hand_eye_poses
    from ..sim.cameras.camera_render import BoardRenderer
    from ..sim.cameras.self_calibration import board_surface
    from ..workflows.cameras.camera_simulate import _texel_mm
    from .figure_producers_cli import run_cli

    spec = "checkerboard:9x6:25mm"
    b = parse_board(spec)
    X = b.object_points()
    cell = simulate_hand_eye_poses(X, setup="eye_in_hand", n_images=10, front_z=b.front_z, seed=3)
    texture, affine = board_image(b, _texel_mm(b))
    surface = board_surface(b, 1.0)
    renderer = BoardRenderer(cell.camera, texture, affine, surface=surface)
    rng = np.random.default_rng(3)
    z = surface(X[:, 0], X[:, 1])
    out = {"true_sag_mm": float(z.max() - z[np.argmin(X[:, 0])])}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "images"
        folder.mkdir()
        for k, T in enumerate(cell.T_camera_target):
            cv2.imwrite(str(folder / f"{k:02d}.png"), renderer.render(T, rng))
        for key, extra in (("flat", ()), ("shaped", ("--board-shape",))):
            text = run_cli("camera", "calibrate", folder, "--board", spec, "--distortion", "5", "--fix", "k3", "--json",
                           "--out", Path(tmp) / key, *extra)
            d = json.loads(text[text.index("{"):])
            out[f"fx_error.{key}"] = abs(d["camera"]["parameters"]["fx"] - cell.camera.fx)
            out[f"rms.{key}"] = float(d["reprojection_rms_px"])
            if key == "shaped":
                sag = d["board_sag_mm"]
                out.update({"sag.x": sag["x"], "sag.y": sag["y"], "sag.sigma_x": sag["sigma_x"]})
    return out


def _T(R, t):
    """A 4 x 4 transform from a rotation and a translation [mm]."""
    import numpy as np

    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


@functools.lru_cache(maxsize=None)
def handeye_joint_offsets() -> dict:
    """docs/handeye.md "Accuracy against OpenCV", the joint-offset tests of
    ``tests/test_handeye_refine.py`` on their set-ups: an ABB IRB 140 with offsets (0, 0.03, -0.04,
    0.05, -0.03, 0) deg, 20 images, 0.1 px corner noise, 0.02 mm / 0.002 deg flange-pose noise,
    eye-to-hand (seed 7) and eye-in-hand (seed 8).

    Fields ``{e2h|e2i}.err_max`` (largest |error| of theta2..theta5 [deg]), ``{e2h|e2i}.sigma.{min|max}``
    [deg], ``{e2h|e2i}.rms_px`` (back-projection with the offsets) and ``{e2h|e2i}.without_px`` (without)."""
    import numpy as np

    from ..handeye import refine_hand_eye
    from ..sim.cameras.handeye_joint_offsets import (OFFSET_NAMES, TRUE_OFFSETS_RAD, eye_in_hand_campaign,
                                                     eye_to_hand_campaign)

    names, true_offsets = list(OFFSET_NAMES), TRUE_OFFSETS_RAD

    def summary(key, res, without):
        err = np.degrees(res.joint_offsets_rad[1:5] - true_offsets[1:5])
        sigma = np.degrees([np.sqrt(res.covariance[i, i]) for i in map(res.variable_names.index, names[1:5])])
        return {f"{key}.err_max": float(np.max(np.abs(err))), f"{key}.sigma.min": float(sigma.min()),
                f"{key}.sigma.max": float(sigma.max()), f"{key}.rms_px": float(res.rms_px),
                f"{key}.without_px": float(without.rms_px)}

    out = {}
    for key, c in (("e2h", eye_to_hand_campaign()), ("e2i", eye_in_hand_campaign())):  # the tests' campaigns
        args = (c.T_base_flange, c.image_points, c.target_points, c.camera)
        res = refine_hand_eye(*args, setup=c.setup, joints=c.joints, robot=c.robot, joint_offsets=True,
                              robot_pose_sigma=(0.02, 0.002))
        out.update(summary(key, res, refine_hand_eye(*args, setup=c.setup, robot_pose_sigma=(0.02, 0.002))))
    return out


@functools.lru_cache(maxsize=None)
def camera_sag() -> dict:
    """docs/handeye.md "Camera calibration" (the set-up of ``tests/test_camera_calibration.py``): 12
    simulated views (seed 11, 0.3 px, no robot noise) of a board whose middle sags by 0.15 mm and by
    1 mm, calibrated with the planar model, Brown and division: ``{model}.z_max_0.15`` (largest
    |error| / sigma over the parameters) and ``{model}.fx_z_1`` (|fx error| / sigma at 1 mm)."""
    from ..handeye import calibrate_camera
    from ..sim.cameras.handeye_points import CAMERA_MODELS, simulate_hand_eye

    def values(camera):
        names = ("fx", "fy", "cx", "cy") + (("k1", "k2", "p1", "p2", "k3") if camera.model == "brown" else ("kappa",))
        return dict(zip(names, (*camera.intrinsics, *camera.distortion)))

    out = {}
    for model in ("brown", "division"):
        for bend in (0.15, 1.0):
            sim = simulate_hand_eye(11, n_images=12, camera=CAMERA_MODELS[model], bend_mm=bend, pose_noise_mm=0.0,
                                    pose_noise_deg=0.0)
            res = calibrate_camera(sim.image_points, sim.target_points, (1280, 1024), model=model)
            ours, truth = values(res.camera), values(sim.camera)
            if bend < 0.5:
                out[f"{model}.z_max_0.15"] = float(max(abs(ours[k] - truth[k]) / res.sigma[k] for k in truth))
            else:
                out[f"{model}.fx_z_1"] = float(abs(ours["fx"] - truth["fx"]) / res.sigma["fx"])
    return out


@functools.lru_cache(maxsize=None)
def handeye_plain_fit() -> dict:
    """docs/handeye.md "Errors in variables": ``simulate_hand_eye`` seeds 0-2, 15 images, 0.05 mm /
    0.01 deg robot noise, no corner noise; the plain reprojection fit (``robot_pose_sigma=None``)
    against the linear solvers and the default errors-in-variables fit.

    Fields ``plain.{rot_deg|mm}.{min|max}``, ``plain.z.{min|max}`` (largest |error| / sigma over the
    axes), ``linear_best.{rot_deg|mm}.median`` (the median over the seeds of the best linear solver's
    error), ``default.z.max``."""
    import numpy as np

    from ..handeye import refine_hand_eye
    from ..handeye.refine import rotation_error_deg
    from ..sim.cameras.handeye_points import simulate_hand_eye

    rows = {"plain.rot_deg": [], "plain.mm": [], "plain.z": [], "lin.rot": [], "lin.mm": [], "default.z": []}
    for seed in range(3):
        sim = simulate_hand_eye(seed, n_images=15, pixel_noise=0.0, pose_noise_mm=0.05, pose_noise_deg=0.01)
        data = (sim.T_base_flange, sim.image_points, sim.target_points, sim.camera)
        for key, res in (("plain", refine_hand_eye(*data, robot_pose_sigma=None)), ("default", refine_hand_eye(*data))):
            d = res.camera_pose[:3, 3] - sim.camera_pose[:3, 3]
            rows[f"{key}.z"].append(float(np.max(np.abs(d) / res.sigma_translation_mm)))
            if key == "plain":
                rows["plain.rot_deg"].append(float(rotation_error_deg(res.camera_pose, sim.camera_pose)))
                rows["plain.mm"].append(float(np.linalg.norm(d)))
                lin = [v[0] for v in res.linear.values()]
                rows["lin.rot"].append(min(float(rotation_error_deg(T, sim.camera_pose)) for T in lin))
                rows["lin.mm"].append(min(float(np.linalg.norm(T[:3, 3] - sim.camera_pose[:3, 3])) for T in lin))
    out = {}
    for k in ("plain.rot_deg", "plain.mm", "plain.z"):
        out[f"{k}.min"], out[f"{k}.max"] = min(rows[k]), max(rows[k])
    out["linear_best.rot_deg.median"] = float(np.median(rows["lin.rot"]))
    out["linear_best.mm.median"] = float(np.median(rows["lin.mm"]))
    out["default.z.max"] = max(rows["default.z"])
    return out


@functools.lru_cache(maxsize=None)
def handeye_agreement() -> dict:
    """docs/handeye.md "Agreement with OpenCV" (the set-ups of ``tests/test_camera_projection.py``,
    ``tests/test_camera_reprojection.py`` and ``tests/test_handeye_linear.py``, seeded, noise-free where
    the test is): floating-point agreement, checked to its order of magnitude.

    Fields: ``projection_px`` (largest |robocal - cv2.projectPoints| over seeds 0-2 and 4, 5, 8
    coefficients, 200 points), ``reprojection.{intrinsics_px|distortion}`` (the core's camera
    calibration against ``cv2.calibrateCamera``, 12 views of a 9 x 6 board, 0.1 px), ``ax_xb.truth.{rad|mm}``,
    ``ax_xb.opencv.{rad|mm}`` (TSAI, PARK, DANIILIDIS, both set-ups), ``ax_zb.truth.{rad|mm}``."""
    import cv2
    import numpy as np

    from ..calib import Problem, solve
    from ..calib.blocks import CameraIntrinsics, FramesBlock
    from ..calib.residuals import ReprojectionResidual
    from ..camera import Camera, project_points
    from ..handeye import solve_hand_eye, solve_robot_world_hand_eye
    from ..transforms import invert_transforms, so3_exp, so3_log

    out = {"projection_px": 0.0}
    for seed in range(3):
        for n_dist in (4, 5, 8):
            rng = np.random.default_rng(seed)
            P = np.column_stack([rng.uniform(-300, 300, (200, 2)), rng.uniform(400, 1500, 200)])
            intr = np.array([rng.uniform(800, 2500), rng.uniform(800, 2500), rng.uniform(500, 700), rng.uniform(400, 600)])
            dist = rng.normal(0, [0.1, 0.05, 0.002, 0.002, 0.02, 0.01, 0.005, 0.002][:n_dist])
            ref, _ = cv2.projectPoints(P, np.zeros(3), np.zeros(3), Camera(*intr, distortion=tuple(dist)).matrix, dist)
            out["projection_px"] = max(out["projection_px"],
                                       float(np.max(np.abs(project_points(P, intr, dist).pixels - ref[:, 0]))))
    # the core's camera calibration against cv2.calibrateCamera
    true_intr, true_dist = np.array([1400.0, 1380.0, 645.0, 508.0]), np.array([-0.12, 0.08, 0.0008, -0.0005, -0.02])
    rng = np.random.default_rng(0)
    g = np.stack(np.meshgrid(np.arange(9.0), np.arange(6.0)), -1).reshape(-1, 2) * 25.0
    X = np.column_stack([g - g.mean(0), np.zeros(len(g))])
    T = np.tile(np.eye(4), (12, 1, 1))
    T[:, :3, :3] = so3_exp(rng.normal(0, 0.35, (12, 3)))
    T[:, :3, 3] = np.column_stack([rng.normal(0, 60, (12, 2)), rng.uniform(450, 800, 12)])
    P = (T[:, None, :3, :3] @ X[None, :, :, None])[..., 0] + T[:, None, :3, 3]
    uv = project_points(P.reshape(-1, 3), true_intr, true_dist).pixels.reshape(12, len(X), 2)
    uv = uv + rng.normal(0, 0.1, uv.shape)
    cam = CameraIntrinsics(np.array([1300.0, 1300.0, 640.0, 512.0]), np.zeros(5))
    start = T.copy()
    start[:, :3, 3] += 5.0
    res = ReprojectionResidual(cam, FramesBlock("camera", np.eye(4), free=False), FramesBlock("board", start), uv, X,
                               sigma=0.1)
    ours = solve(Problem([cam, res.camera_poses, res.target_poses], [res])).value("cam")
    _, K, dist, _, _ = cv2.calibrateCamera([X.astype(np.float32)] * len(uv), [u.astype(np.float32) for u in uv],
                                           (1280, 1024), None, None, flags=0,
                                           criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12))
    theirs = np.concatenate([[K[0, 0], K[1, 1], K[0, 2], K[1, 2]], dist.ravel()[:5]])
    out["reprojection.intrinsics_px"] = float(np.max(np.abs(ours[:4] - theirs[:4])))
    out["reprojection.distortion"] = float(np.max(np.abs(ours[4:] - theirs[4:])))

    # the linear solvers on noise-free pose sets
    def frame(rng, rot_sigma, t_sigma, t_mean=(0.0, 0.0, 0.0)):
        F = np.eye(4)
        F[:3, :3] = so3_exp(rng.normal(0, rot_sigma, 3))
        F[:3, 3] = np.asarray(t_mean) + rng.normal(0, t_sigma, 3)
        return F

    def data(seed, setup):
        rng = np.random.default_rng(seed)
        F = np.stack([frame(rng, 0.5, 200, (800, 0, 600)) for _ in range(10)])
        if setup == "eye_in_hand":
            Xh, Z = frame(rng, 1.0, 80), frame(rng, 0.3, 100, (900, 0, 0))
            return F, invert_transforms(F @ Xh) @ Z, Xh, Z
        Xh, Z = frame(rng, 1.0, 300, (500, 1200, 1500)), frame(rng, 0.5, 60)
        return F, invert_transforms(Xh) @ F @ Z, Xh, Z

    def err(A, B):
        return (float(np.linalg.norm(so3_log((A[:3, :3] @ B[:3, :3].T)[None])[0])),
                float(np.linalg.norm(A[:3, 3] - B[:3, 3])))

    methods = {"tsai": cv2.CALIB_HAND_EYE_TSAI, "park": cv2.CALIB_HAND_EYE_PARK,
               "daniilidis": cv2.CALIB_HAND_EYE_DANIILIDIS}
    truth, opencv, zb = [], [], []
    for setup in ("eye_in_hand", "eye_to_hand"):
        F, C, Xh, _ = data(1, setup)
        F_cv = F if setup == "eye_in_hand" else invert_transforms(F)
        for method, flag in methods.items():
            ours = solve_hand_eye(F, C, setup=setup, method=method)
            truth.append(err(ours, Xh))
            R, t = cv2.calibrateHandEye(list(F_cv[:, :3, :3]), list(F_cv[:, :3, 3]), list(C[:, :3, :3]),
                                        list(C[:, :3, 3]), method=flag)
            Tcv = np.eye(4)
            Tcv[:3, :3], Tcv[:3, 3] = R, t.ravel()
            opencv.append(err(ours, Tcv))
        F, C, Xh, Z = data(2, setup)
        for T_found, T_ref in zip(solve_robot_world_hand_eye(F, C, setup=setup), (Xh, Z)):
            zb.append(err(T_found, T_ref))
    for key, rows in (("ax_xb.truth", truth), ("ax_xb.opencv", opencv), ("ax_zb.truth", zb)):
        out[f"{key}.rad"], out[f"{key}.mm"] = max(r[0] for r in rows), max(r[1] for r in rows)
    return out


@functools.lru_cache(maxsize=None)
def detection_rendered() -> dict:
    """docs/handeye.md "Detection" (the set-up of ``tests/test_camera_detection.py``): 3 rendered views
    (seed 3, noise seed 11) of each of ``checkerboard:9x6:30mm``, ``charuco:9x7:30mm:22mm:DICT_5X5_100``
    and ``circles:10x10:25.4mm:modified``, detected; ``rms_px.{min|max}`` of the detections against the
    exact projections over the nine images."""
    import numpy as np

    from ..io.boards import board_image, parse_board
    from ..io.detection import detect_board
    from ..sim.cameras.camera_cell import default_camera, simulate_hand_eye_poses
    from ..sim.cameras.camera_render import BoardRenderer
    from ..workflows.cameras.camera_simulate import _texel_mm

    rms = []
    for spec in ("checkerboard:9x6:30mm", "charuco:9x7:30mm:22mm:DICT_5X5_100", "circles:10x10:25.4mm:modified"):
        board = parse_board(spec)
        obj = board.object_points()
        cam = default_camera()
        truth = simulate_hand_eye_poses(obj, n_images=3, camera=cam, front_z=board.front_z, seed=3)
        texture, affine = board_image(board, _texel_mm(board))
        renderer = BoardRenderer(cam, texture, affine)
        rng = np.random.default_rng(11)
        for i, T in enumerate(truth.T_camera_target):
            det = detect_board(renderer.render(T, rng), board, name=f"v{i}")
            err = det.image_points - cam.project((T[:3, :3] @ obj.T).T + T[:3, 3]).pixels
            ok = np.isfinite(err[:, 0])
            rms.append(float(np.sqrt(np.mean(np.sum(err[ok] ** 2, axis=1)))))
    return {"rms_px.min": min(rms), "rms_px.max": max(rms)}


#: the ROS-Industrial sets' boards (as ``tests/test_camera_calibrate_real.py``)
ROS_BOARDS = {"test_set_charuco": "charuco:5x7:36.195mm:18.256mm:DICT_6X6_250",
              "test_set_10x10": "circles:10x10:25.4mm:modified"}


@functools.lru_cache(maxsize=None)
def camera_calibrate_real(test_set: str) -> dict:
    """docs/handeye.md "`camera calibrate`: the distortion model by held-out reprojection":
    ``robocal camera calibrate <datasets>/ros_industrial_handeye/raw/TEST_SET/images --board SPEC
    --json`` (``--distortion auto``) and, on ChArUco, ``--distortion 8``.

    Fields: ``held_out.{k1-k2|k1-k2-p1-p2|k1-k3|k1-k3-p1-p2|rational}`` [px], ``rms_px`` (the chosen
    model's training RMS), ``richer_lower_percent`` (how much lower the best richer model's held-out
    RMS is than the chosen one's [%]); with ``--distortion 8``: ``rational.rms_px``,
    ``rational.{k3|k6}``, ``rational.{k3|k6}_sigma``, ``rational.n_not_determined``."""
    from ..io.datasets import datasets_root
    from .figure_producers_cli import run_cli

    images = datasets_root() / "ros_industrial_handeye" / "raw" / test_set / "images"

    def run(*extra):
        with tempfile.TemporaryDirectory() as tmp:
            text = run_cli("camera", "calibrate", images, "--board", ROS_BOARDS[test_set], *extra, "--json",
                           "--out", Path(tmp) / "out")
        return json.loads(text[text.index("{"):])

    d = run()
    held = d["distortion_selection"]["held_out_rms_px"]
    chosen = d["distortion_selection"]["chosen"]
    out = {f"held_out.{k}": float(v) for k, v in held.items()}
    out["rms_px"] = float(d["reprojection_rms_px"])
    out["richer_lower_percent"] = 100.0 * (1.0 - min(held.values()) / held[chosen])
    if test_set == "test_set_charuco":
        r = run("--distortion", "8")
        nd = r["not_determined"]
        out.update({"rational.rms_px": float(r["reprojection_rms_px"]), "rational.n_not_determined": float(len(nd))})
        for k in ("k3", "k6"):
            out[f"rational.{k}"], out[f"rational.{k}_sigma"] = float(nd[k]["value"]), float(nd[k]["sigma"])
    return out


def principal_point_rotation() -> dict:
    """docs/handeye.md "Uncertainty caveat": the camera rotation [deg] that a 3 px principal-point error
    is at the study's focal length (1400 px): ``deg = atan(3 / 1400)``."""
    import math

    return {"deg": math.degrees(math.atan(3.0 / 1400.0))}


HANDEYE_PRODUCERS = {
    "handeye/principal_point_rotation": principal_point_rotation,
    "handeye/gate_shifted": handeye_gate_shifted,
    "handeye/noise_estimate": handeye_noise_estimate,
    "handeye/auto_simulated": handeye_auto_simulated,
    "handeye/study_summary": handeye_study_summary,
    "handeye/fair_counts": handeye_fair_counts,
    "handeye/refine_cases": handeye_refine_cases,
    "handeye/board_shape": camera_board_shape,
    "handeye/joint_offsets": handeye_joint_offsets,
    "handeye/camera_sag": camera_sag,
    "handeye/plain_fit": handeye_plain_fit,
    "handeye/agreement": handeye_agreement,
    "handeye/detection_rendered": detection_rendered,
    **{f"handeye/variants_real/{t}": functools.partial(handeye_variants_real, t) for t in ROS_BOARDS},
    **{f"handeye/camera_real/{t}": functools.partial(camera_calibrate_real, t) for t in ROS_BOARDS},
    "controller/walkthrough": controller_walkthrough,
    "controller/probe": controller_probe,
    "controller/angle_convention": ur_angle_convention,
    "controller/ur10e_b_table": lambda: ur_controller_table("ur10e_driver_test_b.conf", "ur10e"),
    **{f"handeye/default_real/{t}": functools.partial(handeye_default_real, t)
       for t in ("test_set_10x10", "test_set_charuco")},
}
