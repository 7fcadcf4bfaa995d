"""Producers of the documented figures of the data-set, elastic and self-calibration pages (docs/datasets.md,
docs/elastic.md, docs/self-calibration.md, docs/self-calibration-simulator.md; :mod:`robocal.docs.figures`):
the protocols' plain-text report
(``python -m robocal.workflows.datasets``), figures derived from the dataset protocols' records
(ranges over seeds and sets, differences between models), the ROS-Industrial hand-eye sets beside
the default solve (OpenCV's linear solutions, the former default, the two-step calibration), the
positioner's prose, and the set-ups of the elastic and self-calibration tests and commands the
pages quote. Each returns a flat ``{field: value}`` dict and is cached."""

from __future__ import annotations

import functools
import re

__all__ = ["DATASETS_NEEDED", "DATASET_PRODUCERS", "SLOW_DATASET_PRODUCERS", "report_text"]


@functools.lru_cache(maxsize=None)
def report_text() -> str:
    """``python -m robocal.workflows.datasets``'s text (every geometric protocol once)."""
    from ..workflows.datasets.report import report

    return report()


@functools.lru_cache(maxsize=None)
def report_tables() -> dict:
    """The report's numbers that the protocols' JSON records do not carry.

    Fields: ``justin.{nominal,offsets,all}.train`` (training RMS per level [mm]),
    ``hilti.train_before`` / ``hilti.train_after`` (training RMS on ``flat``, nominal and calibrated
    [mm]), ``hilti.{set}.nominal.{rms,p95_xy,p95_z}`` and ``hilti.{set}.calibrated.{rms,p95_xy,p95_z,
    mean,max}`` [mm]."""
    text = report_text()
    out = {}
    for level, label in (("nominal", r"base \+ 2 markers"), ("offsets", r"\+ 18 joint offsets"), ("all", r"\+ all DH")):
        m = re.search(label + r".*?\(train ([0-9.]+)\)", text)
        if m:
            out[f"justin.{level}.train"] = float(m.group(1))
    m = re.search(r"train RMS ([0-9.]+) -> ([0-9.]+) mm", text)
    if m:
        out["hilti.train_before"], out["hilti.train_after"] = float(m.group(1)), float(m.group(2))
    for line in text.splitlines():
        f = line.split()
        if len(f) == 10 and re.fullmatch(r"[a-z_]+", f[0]) and f[1].isdigit():
            v = list(map(float, f[2:]))
            for k, x in zip(("nominal.rms", "nominal.p95_xy", "nominal.p95_z", "calibrated.rms", "calibrated.p95_xy",
                             "calibrated.p95_z", "calibrated.mean", "calibrated.max"), v):
                out[f"hilti.{f[0]}.{k}"] = x
    return out


def _producer(name: str) -> dict:
    from .figure_producers import PRODUCERS

    return PRODUCERS[name]()


@functools.lru_cache(maxsize=None)
def boby_seeds(model: str) -> dict:
    """boby_fanuc's per-seed holdout RMS with ``model``: ``holdout.min`` / ``holdout.max`` [mm],
    and ``seed3.holdout`` [mm]."""
    r = _producer(f"boby_fanuc/{model}")
    per = [v for k, v in r.items() if re.fullmatch(r"per_seed_holdout_rms_mm\.\d+", k)]
    return {"holdout.min": min(per), "holdout.max": max(per), "seed3.holdout": r["per_seed_holdout_rms_mm.3"]}


@functools.lru_cache(maxsize=None)
def hilti_gain(model: str) -> dict:
    """How much lower Hilti's holdout RMS is with ``model`` than with the geometric model over the
    seven sets: ``gain.min`` / ``gain.max`` [mm]."""
    geo, ela = _producer("hilti_trailblazer/geometric"), _producer(f"hilti_trailblazer/{model}")
    sets = [k.split(".")[0] for k in geo if k.endswith(".holdout_rms_mm") and k.count(".") == 1]
    gain = [geo[f"{s}.holdout_rms_mm"] - ela[f"{s}.holdout_rms_mm"] for s in sets]
    return {"gain.min": min(gain), "gain.max": max(gain)}


#: the Hilti repository README's calibrated 95 % xy figures of the tilted sets [mm] (docs/datasets.md's
#: "README calibrated" column)
HILTI_README_P95_XY = {"wood_left_track": 11.1, "seesaw": 12.4, "diagonal_wood": 7.4}


@functools.lru_cache(maxsize=None)
def hilti_vs_readme() -> dict:
    """robocal's calibrated 95 % xy error minus the README's on the tilted sets: ``above.min`` /
    ``above.max`` [mm]."""
    geo = _producer("hilti_trailblazer/geometric")
    d = [geo[f"sets.{s}.p95_xy_mm"] - v for s, v in HILTI_README_P95_XY.items()]
    return {"above.min": min(d), "above.max": max(d)}


@functools.lru_cache(maxsize=None)
def justin_joint_seeds() -> dict:
    """docs/elastic.md: ``calibrate_justin(seed, model="elastic-joint")`` over seeds 0-4: holdout mean
    ``min`` / ``max`` [mm] and ``n_not_converged`` (every fit of every seed)."""
    from ..workflows.convergence import recording_fits
    from ..workflows.datasets.dlr_justin import calibrate_justin

    with recording_fits() as fits:
        means = [calibrate_justin(seed, model="elastic-joint")["calibrated"]["mean"] for seed in range(5)]
    return {"min": min(means), "max": max(means), "n_not_converged": float(sum(not f.converged for f in fits))}


@functools.lru_cache(maxsize=None)
def justin_full_seeds() -> dict:
    """docs/elastic.md "How the full model converges": ``calibrate_justin(seed, model="elastic-full")``
    over seeds 0-4: holdout mean ``min`` / ``max`` / ``mean`` [mm], the full level's iterations
    (``iterations.min`` / ``iterations.max``, solve and re-solve) and ``n_not_converged`` (every fit
    of every seed)."""
    from ..workflows.convergence import recording_fits
    from ..workflows.datasets.dlr_justin import calibrate_justin

    means, its = [], []
    with recording_fits() as fits:
        for seed in range(5):
            out = calibrate_justin(seed, model="elastic-full")
            means.append(out["calibrated"]["mean"])
            its.append(out["results"]["full"].iterations)
    return {"min": min(means), "max": max(means), "mean": sum(means) / len(means),
            "iterations.min": float(min(its)), "iterations.max": float(max(its)),
            "n_not_converged": float(sum(not f.converged for f in fits))}


@functools.lru_cache(maxsize=None)
def justin_joint_gravity() -> dict:
    """docs/elastic.md "Without a mass model": ``calibrate_justin(0, model="elastic-joint")``'s
    identifiability analysis of the elastic level: ``gravity.held`` (lumped gravity parameters held
    at their start, each naming what it trades off against) and ``gravity.total``."""
    from ..workflows.datasets.dlr_justin import calibrate_justin

    rep = calibrate_justin(0, model="elastic-joint")["results"]["elastic"].identifiability
    held = [n for n in rep.dropped_names if n.startswith("gravity.")]
    kept = [n for n in rep.identifiable if n.startswith("gravity.")]
    return {"gravity.held": float(len(held)), "gravity.total": float(len(held) + len(kept))}


#: docs/datasets.md "Elastic models": the protocols behind each model's convergence counts
CONVERGENCE_DATASETS = ("boby_fanuc", "dlr_justin", "hilti_trailblazer")


def datasets_convergence(model: str) -> dict:
    """docs/datasets.md "Elastic models": ``robocal datasets run NAME --model MODEL --json``'s
    ``convergence`` for boby / Justin / Hilti (the producers ``NAME/MODEL``): ``{name}.n_fits``,
    ``{name}.n_not_converged``, ``all.n_not_converged`` (the three) and ``justin_hilti.n_not_converged``."""
    from .figure_producers import PRODUCERS

    out = {}
    for name in CONVERGENCE_DATASETS:
        r = PRODUCERS[f"{name}/{model}"]()
        out[f"{name}.n_fits"] = float(r["convergence.n_fits"])
        out[f"{name}.n_not_converged"] = float(r["convergence.n_not_converged"])
    out["all.n_not_converged"] = sum(out[f"{n}.n_not_converged"] for n in CONVERGENCE_DATASETS)
    out["justin_hilti.n_not_converged"] = out["dlr_justin.n_not_converged"] + out["hilti_trailblazer.n_not_converged"]
    return out


@functools.lru_cache(maxsize=None)
def justin_full_vs_source() -> dict:
    """docs/datasets.md: Justin's elastic-full holdout mean above the source's published 3.12 mm [mm]."""
    return {"above_source_mm": _producer("dlr_justin/elastic-full")["holdout_mean_mm"] - 3.12}


@functools.lru_cache(maxsize=None)
def nao_sigma_gain() -> dict:
    """docs/self-calibration.md: how much smaller the shared head joint's (``theta1``) sigma is with
    both arms than with one arm alone (NAO acceptance, ``nao/acceptance``): ``left_percent``,
    ``right_percent`` [%]."""
    r = _producer("nao/acceptance")
    both = r["both.theta1.sigma_deg"]
    return {f"{h.split('_')[0]}_percent": 100.0 * (1.0 - both / r[f"{h}.theta1.sigma_deg"])
            for h in ("left_hand", "right_hand")}


@functools.lru_cache(maxsize=None)
def positioner() -> dict:
    """docs/datasets.md's positioner prose: ``calibrate_positioner_seeds(range(5))`` (the table's run).

    Fields: ``angle_deg.min`` / ``.max`` and ``common_normal_mm.min`` / ``.max`` over the seeds,
    ``a1_sigma_mm.mean``; the means over seeds ``{nominal,calibrated}.{train,test}.{pos_mean,rot_mean,
    pos_max}`` [mm, deg]; ``gain_percent.{pos_mean,pos_max,rot_mean}`` (hold-out, calibrated against
    nominal) [%]; seed 0's hold-out ``seed0.{nominal,calibrated}.{pos_mean,rot_mean}`` and its axes
    ``seed0.angle_deg``, ``seed0.common_normal_mm``, ``seed0.alpha1_sigma_deg``, ``seed0.a1_sigma_mm``."""
    import numpy as np

    from ..workflows.datasets.ros_industrial_positioner import calibrate_positioner_seeds

    res = calibrate_positioner_seeds(range(5))
    axes = [r["axes"] for r in res["runs"]]
    out = {}
    for k in ("angle_deg", "common_normal_mm"):
        out[f"{k}.min"], out[f"{k}.max"] = min(a[k] for a in axes), max(a[k] for a in axes)
    out["a1_sigma_mm.mean"] = float(np.mean([next(p["std"] for p in r["result"].parameter_table() if p["name"] == "a1")
                                             for r in res["runs"]]))
    table0 = {p["name"]: p for p in res["runs"][0]["result"].parameter_table()}
    out.update({"seed0.angle_deg": axes[0]["angle_deg"], "seed0.common_normal_mm": axes[0]["common_normal_mm"],
                "seed0.alpha1_sigma_deg": float(np.degrees(table0["alpha1"]["std"])),
                "seed0.a1_sigma_mm": float(table0["a1"]["std"])})
    for key in ("nominal", "calibrated"):
        for part in ("train", "test"):
            out.update({f"{key}.{part}.{s}": float(v) for s, v in res[key][part].items()})
        out.update({f"seed0.{key}.{s}": float(res["runs"][0][key]["test"][s]) for s in ("pos_mean", "rot_mean")})
    for s in ("pos_mean", "pos_max", "rot_mean"):
        out[f"gain_percent.{s}"] = 100.0 * (1.0 - out[f"calibrated.test.{s}"] / out[f"nominal.test.{s}"])
    return out


#: the boards of the ROS-Industrial hand-eye sets (as their cal_data.yaml)
ROS_BOARDS = {"test_set_charuco": "charuco:5x7:36.195mm:18.256mm:DICT_6X6_250",
              "test_set_10x10": "circles:10x10:25.4mm:modified"}


@functools.lru_cache(maxsize=None)
def ros_handeye_variants(test_set: str) -> dict:
    """docs/datasets.md "ros_industrial_handeye", the columns and prose beside the default solve, each
    through the command line on ``<datasets>/ros_industrial_handeye/raw/TEST_SET``:

    * ``prior.rms_px``: ``handeye solve cal_data.yaml --robot-pose-sigma 0.05,0.01`` (the former default);
    * ``refined.rms_px``: ``handeye solve cal_data.yaml --refine-intrinsics --exact-poses``;
    * ``camera.{rms_px,fx,sigma_fx}``: ``camera calibrate images --board B --distortion 5``, and
      ``two_step.rms_px``: ``handeye solve cal_data.yaml --camera cam/camera.json --exact-poses`` with it;
    * ``auto.rms_px``: ``camera calibrate images --board B`` (the default ``--distortion auto``)."""
    import json
    import tempfile
    from pathlib import Path

    from ..io.datasets import datasets_root
    from .figure_producers_cli import run_cli

    src = datasets_root() / "ros_industrial_handeye" / "raw" / test_set
    cal, images, board = src / "cal_data.yaml", src / "images", ROS_BOARDS[test_set]

    def doc(text: str) -> dict:
        return json.loads(text[text.index("{"):])

    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        prior = doc(run_cli("handeye", "solve", cal, "--robot-pose-sigma", "0.05,0.01", "--out", t / "p", "--json"))
        refined = doc(run_cli("handeye", "solve", cal, "--refine-intrinsics", "--exact-poses", "--out", t / "r", "--json"))
        cam = doc(run_cli("camera", "calibrate", images, "--board", board, "--distortion", "5", "--out", t / "c", "--json"))
        two = doc(run_cli("handeye", "solve", cal, "--camera", t / "c" / "camera.json", "--exact-poses", "--out", t / "h",
                          "--json"))
        auto = doc(run_cli("camera", "calibrate", images, "--board", board, "--out", t / "a", "--json"))
    return {"prior.rms_px": prior["reprojection_rms_px"], "refined.rms_px": refined["reprojection_rms_px"],
            "camera.rms_px": cam["reprojection_rms_px"], "camera.fx": cam["camera"]["parameters"]["fx"],
            "camera.sigma_fx": cam["camera"]["sigma"]["fx"], "camera.n_images_used": float(cam["n_images_used"]),
            "camera.n_corners": float(cam["n_corners"]), "two_step.rms_px": two["reprojection_rms_px"],
            "auto.rms_px": auto["reprojection_rms_px"]}


@functools.lru_cache(maxsize=None)
def ros_handeye_opencv(test_set: str) -> dict:
    """docs/datasets.md's table of linear solutions, OpenCV's columns: on robocal's detections of
    ``<datasets>/ros_industrial_handeye/raw/TEST_SET`` (the cal_data.yaml's board, blob settings,
    homography check and intrinsics), ``cv2.solvePnP`` per used image, then ``cv2.calibrateHandEye``
    (TSAI, PARK, HORAUD, ANDREFF, DANIILIDIS; the flange poses inverted for the static camera) and
    ``cv2.calibrateRobotWorldHandEye`` (RW_SHAH, RW_LI). Fields ``{METHOD}.distance_mm``: the camera
    position's distance from robocal's refined one (``robocal handeye solve --exact-poses``) [mm];
    ``guess.distance_mm``: the refined position's distance from the layout's ``camera_guess`` [mm];
    the detections: ``pnp_rms_px.min`` / ``.max`` (per image, OpenCV's PnP with the given intrinsics),
    ``homography_px.max`` (the largest mean homography error, :func:`robocal.io.detection.homography_error_px`),
    ``subpix_move_px.mean`` (ChArUco: how far ``cornerSubPix`` moves the corners, mean) and
    ``subpix_move_px.image_mean_max`` (the largest of the per-image means) [px]."""
    import cv2
    import numpy as np

    from ..io.datasets import datasets_root
    from ..io.detection import homography_error_px
    from ..io.ros_calibration import read_cal_data
    from ..transforms import invert_transforms
    from ..workflows.cameras.camera_common import detect_set

    d = read_cal_data(datasets_root() / "ros_industrial_handeye" / "raw" / test_set / "cal_data.yaml")
    det = detect_set(d.image_paths, d.board, blob_settings=d.blob_settings, homography_threshold=d.homography_threshold)
    used = det.used
    X = d.board.object_points().astype(np.float64)
    K, dist = d.camera.matrix, np.asarray(d.camera.distortion, float)
    T_ct, pnp_rms, homography = [], [], []  # target in the camera frame per used image, its PnP RMS [px]
    for uv in det.image_points[used]:
        ok = np.all(np.isfinite(uv), axis=1)
        _, rvec, tvec = cv2.solvePnP(X[ok], uv[ok].astype(np.float64), K, dist)
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
        T_ct.append(T)
        proj = cv2.projectPoints(X[ok], rvec, tvec, K, dist)[0].reshape(-1, 2)
        pnp_rms.append(float(np.sqrt(np.mean(np.sum((proj - uv[ok]) ** 2, axis=1)))))
        homography.append(homography_error_px(uv, X))
    out = {"pnp_rms_px.min": min(pnp_rms), "pnp_rms_px.max": max(pnp_rms), "homography_px.max": max(homography)}
    if det.refined_points is not None:  # cornerSubPix's move of the corners, mean over the used images' corners
        move = np.linalg.norm(det.refined_points[used] - det.image_points[used], axis=2)
        out["subpix_move_px.mean"] = float(np.nanmean(move))
        out["subpix_move_px.image_mean_max"] = float(np.nanmax(np.nanmean(move, axis=1)))
    T_ct, F = np.array(T_ct), d.T_base_flange[used]
    static = d.setup == "eye_to_hand"
    G = invert_transforms(F) if static else F  # "gripper to base" as calibrateHandEye reads it
    refined = np.array([_producer(f"ros_handeye/{test_set}")[f"position_mm.{k}"] for k in range(3)])
    for name in ("TSAI", "PARK", "HORAUD", "ANDREFF", "DANIILIDIS"):
        R, t = cv2.calibrateHandEye(G[:, :3, :3], G[:, :3, 3], T_ct[:, :3, :3], T_ct[:, :3, 3],
                                    method=getattr(cv2, f"CALIB_HAND_EYE_{name}"))
        out[f"{name}.distance_mm"] = float(np.linalg.norm(t.ravel() - refined))
    # calibrateRobotWorldHandEye: X_cam = T_cam_world X_world observed, the camera rigid with the "gripper"
    # and the world with the "base"; for a static camera the robot is read backwards: the "gripper" is
    # the base, the "base" the flange (base2gripper = T_base_flange) and the "world" the target
    B = F if static else invert_transforms(F)
    for name in ("SHAH", "LI"):
        _, _, R_gc, t_gc = cv2.calibrateRobotWorldHandEye(
            T_ct[:, :3, :3], T_ct[:, :3, 3], B[:, :3, :3], B[:, :3, 3],
            method=getattr(cv2, f"CALIB_ROBOT_WORLD_HAND_EYE_{name}"))
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R_gc, t_gc.ravel()  # the "gripper" in the camera frame
        out[f"RW_{name}.distance_mm"] = float(np.linalg.norm(invert_transforms(T)[:3, 3] - refined))
    if d.camera_guess is not None:
        out["guess.distance_mm"] = float(np.linalg.norm(d.camera_guess[:3, 3] - refined))
    return out


@functools.lru_cache(maxsize=None)
def elastic_rigid_robot() -> dict:
    """docs/elastic.md, the gate on a rigid robot, through the command line as the page states:
    ``robocal simulate tracker kuka_kr150_r3100 --seed 1 --out m.csv``, then ``robocal calibrate
    kuka_kr150_r3100 m.csv --out cal --elastic joint`` (exit 3). Fields from ``result.json``'s
    ``elastic``: ``compliance.{min,max}.{value,std}`` (the smallest and largest estimated compliance
    with its sigma) [mrad/kNm], ``moment.{value,std}`` (the first mass moment of largest magnitude)
    [kg m], ``n_identified`` (compliances identified), ``exit_code``."""
    import json
    import tempfile
    from pathlib import Path

    from .figure_producers_cli import run_cli

    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        run_cli("simulate", "tracker", "kuka_kr150_r3100", "--seed", "1", "--out", t / "m.csv")
        run_cli("calibrate", "kuka_kr150_r3100", t / "m.csv", "--out", t / "cal", "--elastic", "joint", "--no-report",
                ok=(3,))
        e = json.loads((t / "cal" / "result.json").read_text())["elastic"]
    comp = [c for c in e["compliance"] if c["std"] is not None]
    lo, hi = min(comp, key=lambda c: c["value"]), max(comp, key=lambda c: c["value"])
    mom = max((m for m in e["mass_parameters"] if m["std"] is not None), key=lambda m: abs(m["value"]))
    return {"compliance.min.value": lo["value"], "compliance.min.std": lo["std"], "compliance.max.value": hi["value"],
            "compliance.max.std": hi["std"], "moment.value": mom["value"], "moment.std": mom["std"],
            "n_identified": float(sum(bool(c["identifiable"]) for c in e["compliance"])), "exit_code": 3.0}


#: the hidden elastic truth of ``tests/test_elastic.py``: link masses [kg] with centres of mass [mm],
#: the payload (frame, kg, centre [mm]) and the joint compliances [mrad/kNm]
ELASTIC_MASSES = {"A1": (450.0, (0.0, 150.0, 0.0)), "A2": (280.0, (-600.0, 0.0, 150.0)),
                  "A3": (220.0, (-60.0, -40.0, 0.0)), "A4": (70.0, (0.0, 0.0, -300.0)),
                  "A5": (30.0, (0.0, 20.0, 0.0)), "A6": (8.0, (0.0, 0.0, -20.0))}
ELASTIC_PAYLOAD = ("flange", 120.0, (0.0, 50.0, 200.0))
ELASTIC_COMPLIANCE = {"A1": 0.15, "A2": 0.25, "A3": 0.4, "A4": 1.5, "A5": 2.0, "A6": 3.0}


def elastic_six_d_campaign(seed: int, n: int):
    """``tests/test_elastic_six_d.py``'s campaign: (nominal, q (n, 6) [rad], T (n, 4, 4) the true probe
    poses in the instrument frame [mm], measured points (n, 3) [mm] with 0.02 mm noise and rotations
    (n, 3, 3) with 2e-4 rad): a 6-D probe on a 38 deg / 185 mm tool of a KR150 carrying 120 kg that
    deflects with :data:`ELASTIC_COMPLIANCE` (torques at the deflected pose, ``hardening=0.0002``)."""
    import numpy as np

    from ..robots import load_robot
    from ..sim import VirtualRobot
    from ..sim.elastic import ElasticTruth
    from ..transforms import so3_exp

    sigma = 0.02
    nominal = load_robot("kuka_kr150_r3100")
    truth = ElasticTruth(ELASTIC_COMPLIANCE, ELASTIC_MASSES, payload=ELASTIC_PAYLOAD, hardening=0.0002)
    true = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0).with_elastic(truth)
    rng = np.random.default_rng(seed + 300)
    q = true.random_configurations(n, rng, margin=0.1)
    T_inst, tool = np.eye(4), np.eye(4)
    T_inst[:3, :3], T_inst[:3, 3] = so3_exp([0.05, -0.1, 2.0]), [3200.0, -400.0, -600.0]
    tool[:3, :3], tool[:3, 3] = so3_exp([0.25, -0.15, 0.6]), [35.0, -20.0, 180.0]
    T = T_inst @ true.true_poses(q) @ tool
    p = T[:, :3, 3] + rng.normal(0, sigma, (n, 3))
    R = so3_exp(rng.normal(0, sigma / 100.0, (n, 3))) @ T[:, :3, :3]
    return nominal, q, T, p, R


@functools.lru_cache(maxsize=None)
def elastic_six_d_round_trip() -> dict:
    """docs/elastic.md's 6-D round-trip table (``tests/test_elastic_six_d.py``'s library round trip):
    mass model and payload known, geometry + base + 6-DoF tool frame (+ compliances) fitted to 60
    poses of :func:`elastic_six_d_campaign` (seeds 0, 1), 40 held out. Fields per seed ``s`` and
    ``{elastic,rigid}``: ``{model}.{s}.rotation_rms`` (rotation residual RMS in noise sigmas),
    ``{model}.{s}.holdout_rms_mm``; ``elastic.{s}.z.{A2..A6}`` (compliance error / sigma) and
    ``elastic.z_max`` (largest |z| over both seeds)."""
    import numpy as np

    from ..calib import solve
    from ..calib.elastic import ElasticModel, Payload
    from ..calib.pose_problem import PoseCalibrationProblem

    elastic = ElasticModel(masses=ELASTIC_MASSES, payload=Payload(ELASTIC_PAYLOAD[1], ELASTIC_PAYLOAD[2], "flange"),
                           compliance_initial=0.0)
    n, out, z_all = 60, {}, []
    for seed in (0, 1):
        nominal, q, T, p, R = elastic_six_d_campaign(seed, n + 40)
        for label, el in (("elastic", elastic), ("rigid", None)):
            prob = PoseCalibrationProblem(nominal, q[:n], p[:n], R[:n], point_sigma_mm=0.02, rotation_weight=100.0,
                                          elastic=el)
            res = solve(prob)
            rows = np.array([prob.row_label(i)[1] == "rotation" for i in range(prob.n_residuals)])
            out[f"{label}.{seed}.rotation_rms"] = float(np.sqrt(np.mean(res.residuals_after[rows] ** 2)))
            pred = prob.predict_points(res.state, q=q[n:])[:, 0]
            out[f"{label}.{seed}.holdout_rms_mm"] = float(np.sqrt(np.mean(np.sum((pred - T[n:, :3, 3]) ** 2, axis=-1))))
            out[f"{label}.{seed}.converged"] = float(res.converged)
            if el is not None:
                for j in ("A2", "A3", "A4", "A5", "A6"):
                    i = res.names.index(f"compliance.{j}")
                    z = float((res.values[i] - ELASTIC_COMPLIANCE[j]) / res.std[i])
                    out[f"elastic.{seed}.z.{j}"] = z
                    z_all.append(abs(z))
    out["elastic.z_max"] = max(z_all)
    return out


@functools.lru_cache(maxsize=None)
def elastic_six_d_cli() -> dict:
    """docs/elastic.md "Through the command": the campaign of ``tests/test_elastic_six_d.py``
    (``elastic_six_d_campaign(4, 80)``: a 6-D probe, 0.02 mm / 2e-4 rad, on a 38 deg / 185 mm tool of
    a KR150 carrying 120 kg, the hidden compliances, torques at the deflected pose, ``hardening=0.0002``), then ``robocal calibrate kuka_kr150_r3100 six_d.csv --noise 0.02 --seed 0`` with
    ``--elastic joint``, ``--elastic full`` and without (exit 3: the sanity gates). Fields
    ``{joint,full,geometric}.holdout_rms_mm`` (result.json ``validation.after.rms``)."""
    import json
    import tempfile
    from pathlib import Path

    from ..io.measurements import Measurements, write_measurements
    from .figure_producers_cli import run_cli

    robot, sigma = "kuka_kr150_r3100", 0.02
    nominal, q, _, p, R = elastic_six_d_campaign(4, 80)
    meas = Measurements(q, p, joint_names=nominal.controller_joints, rotations=R,
                        metadata={"robot": robot, "instrument": "6-D probe", "frame": "tracker"})
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = write_measurements(Path(tmp) / "six_d.csv", meas, length_unit="mm", angle_unit="deg",
                                  orientation="kuka_abc")
        for label, extra, ok in (("joint", ["--elastic", "joint"], (0,)), ("full", ["--elastic", "full"], (0, 3)),
                                 ("geometric", [], (3,))):
            run_cli("calibrate", robot, path, "--out", Path(tmp) / label, "--noise", sigma, "--seed", 0, "--no-report",
                    *extra, ok=ok)
            res = json.loads((Path(tmp) / label / "result.json").read_text())
            out[f"{label}.holdout_rms_mm"] = float(res["validation"]["after"]["rms"])
    return out


@functools.lru_cache(maxsize=None)
def nao_joint_noise() -> dict:
    """docs/self-calibration.md "Joint-reading noise": the setup of ``tests/test_self_calibration_nao.py``'s
    ``test_joint_reading_noise_needs_the_per_image_joint_corrections`` (nao-model's simulator, seed 3,
    40 views per hand, no partial views, 0.3 px, 0.05 deg reading noise per log row), solved with the
    readings as exact (``exact``) and with ``joint_noise_deg=0.05`` (``eiv``). Fields per fit:
    ``max_abs_z``, ``max_error_deg`` (identifiable offsets), ``variance_factor``,
    ``rms_px_per_coordinate`` [px]."""
    import numpy as np

    from ..handeye.self_calibration import solve_self_calibration
    from ..io.capture_times import match_capture_times
    from ..sim.cameras.self_calibration import simulate_self_calibration

    run = simulate_self_calibration("nao_h25", n_images_per_chain=40, pixel_noise=0.3, joint_noise_deg=0.05,
                                    partial_fraction=0.0, seed=3)
    q, _, _ = match_capture_times(run.frame_times, run.log_times, run.log_joints, tolerance=0.06)
    X = run.board.object_points()
    out = {}
    for label, noise in (("exact", None), ("eiv", 0.05)):
        res = solve_self_calibration(run.robot, q, run.image_points, X, run.camera, run.chain_of_image,
                                     camera_end_effector="camera_top", pixel_sigma=0.3, joint_noise_deg=noise)
        err = [(v - run.joint_offsets_rad[r["joint"]], s)
               for r, v, s in zip(res.joint_report, res.joint_offsets, res.joint_offset_sigma) if r["identifiable"]]
        out[f"{label}.max_abs_z"] = float(max(abs(e) / s for e, s in err))
        out[f"{label}.max_error_deg"] = float(np.degrees(max(abs(e) for e, _ in err)))
        out[f"{label}.variance_factor"] = float(res.variance_factor)
        out[f"{label}.rms_px_per_coordinate"] = float(res.rms_px / np.sqrt(2))
    return out


def _true_corners(run, q, chain: str):
    """The corners [px] (P, 2) of a self-calibration run's board on ``chain`` seen by its camera, through
    the true robot at joints ``q`` (n_joints,) [rad]."""
    import numpy as np

    from ..transforms import compose, invert_transforms

    m = run.true_robot
    T_cam = compose(m.fk(q[None], run.camera_end_effector), run.T_ee_camera)
    T_board = run.T_ee_board[chain][None] if chain == "world" else compose(m.fk(q[None], chain), run.T_ee_board[chain])
    T = compose(invert_transforms(T_cam), T_board)
    pts = np.einsum("nij,pj->npi", T[:, :3, :3], run.board.object_points()) + T[:, None, :3, 3]
    return run.camera.project(pts.reshape(-1, 3)).pixels


@functools.lru_cache(maxsize=None)
def self_calibration_noise_budget() -> dict:
    """docs/self-calibration-simulator.md "Noise budget": ``simulate_self_calibration(robot, seed=1,
    n_images_per_chain=40, joint_noise_deg=J)`` (the other settings default; NAO both hands, the KR 150
    with the world board); each full view's corners projected through the true robot at the joints
    read from the log (the row :func:`~robocal.io.capture_times.match_capture_times` pairs with the
    frame) against those at the true joints. Fields ``{robot}.{J}.rms_px`` (RMS per pixel coordinate)."""
    import numpy as np

    from ..io.capture_times import match_capture_times
    from ..sim.cameras.self_calibration import simulate_self_calibration

    out = {}
    for robot, chains in (("nao_h25", ("left_hand", "right_hand")), ("kuka_kr150_r3100", ("world",))):
        for jn in (0.01, 0.05):
            r = simulate_self_calibration(robot, chains=chains, n_images_per_chain=40, joint_noise_deg=jn, seed=1)
            q, _, _ = match_capture_times(r.frame_times, r.log_times, r.log_joints, tolerance=0.06)
            d = np.concatenate([_true_corners(r, q[i], r.chain_of_image[i]) - _true_corners(r, r.q_true[i], r.chain_of_image[i])
                                for i in np.flatnonzero(r.fully_visible)])
            out[f"{robot}.{jn}.rms_px"] = float(np.sqrt(np.mean(d ** 2)))
    return out


@functools.lru_cache(maxsize=None)
def nao_null_directions() -> dict:
    """docs/self-calibration-simulator.md "Identifiability": ``simulate_self_calibration("nao_h25",
    n_images_per_chain=40, seed=1)``; the finite-difference Jacobian (step 1e-6) of the ideal corners of
    the full views with respect to the 12 joint offsets, the camera mount and both board mounts (small
    rotation vector + translation each), columns scaled to unit norm, as
    ``tests/test_self_calibration_sim.py``. Fields: ``next_singular_value`` (the fourth smallest),
    ``next_relative`` (over the largest), ``null_relative_max`` (the three smallest over the largest)."""
    import numpy as np

    from ..sim.cameras.self_calibration import simulate_self_calibration
    from ..transforms import compose, invert_transforms, so3_exp, transforms_from

    r = simulate_self_calibration("nao_h25", n_images_per_chain=40, seed=1)
    m, X, full = r.true_robot, r.board.object_points(), np.flatnonzero(r.fully_visible)
    theta = [m.params.index(f"theta{k + 1}") for k, link in enumerate(m.links) if link.moves]
    chains = np.array(r.chain_of_image)[full]

    def pixels(p):
        values = m.params.values.copy()
        values[theta] += p[:12]
        mm, out = m.with_params(values), []
        for c, off in (("left_hand", 18), ("right_hand", 24)):
            q = r.q_true[full[chains == c]]
            T_cam = compose(mm.fk(q, "camera_top"), r.T_ee_camera, transforms_from(so3_exp(p[15:18]), p[12:15]))
            T = compose(invert_transforms(T_cam), mm.fk(q, c), r.T_ee_board[c],
                        transforms_from(so3_exp(p[off + 3:off + 6]), p[off:off + 3]))
            out.append(r.camera.project((np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]).reshape(-1, 3))
                       .pixels.ravel())
        return np.concatenate(out)

    f0 = pixels(np.zeros(30))
    J = np.stack([(pixels(np.eye(30)[j] * 1e-6) - f0) / 1e-6 for j in range(30)], axis=1)
    s = np.linalg.svd(J / np.linalg.norm(J, axis=0), compute_uv=False)
    return {"next_singular_value": float(s[-4]), "next_relative": float(s[-4] / s[0]),
            "null_relative_max": float(s[-3:].max() / s[0])}


@functools.lru_cache(maxsize=None)
def nao_self_calibrate_cli() -> dict:
    """docs/self-calibration.md "Sanity gate and the joint-reading noise by default", through the command
    line as the page states: ``robocal simulate self-calibration nao_h25 --out nao --images-per-chain 15
    --seed 3``, then ``robocal self-calibrate nao_h25 --images nao/images --joints nao/joint_log.csv
    --frames nao/frames.csv --board checkerboard:7x4:12mm --camera-on camera_top --board-on
    left_hand,right_hand --camera nao/camera.json --out nao-cal --json`` by default (``default``) and with
    ``--joint-noise 0.0001`` (``exact``, exit 3). Fields per run: ``joint_noise_deg``, ``variance_factor``,
    ``max_abs_z`` and ``max_error_deg`` of the identifiable offsets against ``truth.json``, ``ok`` (status)."""
    import json
    import math
    import tempfile
    from pathlib import Path

    from .figure_producers_cli import run_cli

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        sim = Path(tmp) / "nao"
        run_cli("simulate", "self-calibration", "nao_h25", "--out", sim, "--images-per-chain", 15, "--seed", 3)
        truth = json.loads((sim / "truth.json").read_text())["joint_offsets_deg"]
        args = ["self-calibrate", "nao_h25", "--images", sim / "images", "--joints", sim / "joint_log.csv", "--frames",
                sim / "frames.csv", "--board", "checkerboard:7x4:12mm", "--camera-on", "camera_top", "--board-on",
                "left_hand,right_hand", "--camera", sim / "camera.json", "--json"]
        for label, extra, ok in (("default", [], (0,)), ("exact", ["--joint-noise", "0.0001"], (3,))):
            text = run_cli(*args, "--out", Path(tmp) / label, *extra, ok=ok)
            s = json.loads(text[text.index("{"):])
            joint = {r["name"]: r["joint"] for r in s["joint_report"] if r["identifiable"]}
            err = [(math.degrees(j["value"]) - truth[joint[j["name"]]], math.degrees(j["sigma"]))
                   for j in s["joint_offsets"] if j["name"] in joint]
            out.update({f"{label}.joint_noise_deg": float(s["joint_noise_deg"]),
                        f"{label}.variance_factor": float(s["variance_factor"]),
                        f"{label}.max_abs_z": max(abs(e) / sg for e, sg in err),
                        f"{label}.max_error_deg": max(abs(e) for e, _ in err), f"{label}.ok": float(s["status"] == "ok"),
                        f"{label}.n_identifiable": float(len(err))})
    return out


def _expected_holdout_rms(prob, res, q_hold, sigma: float) -> float:
    """The noise-limited optimum of the holdout RMS [mm]: sqrt(sigma^2 trace(J_h (J^T J)^-1 J_h^T) / N_h)
    over the identifiable set (as ``tests/test_calibration.py``)."""
    import numpy as np

    active = np.isfinite(np.diag(res.covariance))
    _, J, _ = prob.evaluate(res.state)
    _, Jh = prob.predict_points(res.state, q=q_hold, jacobian=True)
    Jh = Jh.reshape(-1, prob.n_variables)[:, active] / sigma
    cov = np.linalg.inv(J[:, active].T @ J[:, active])
    return float(np.sqrt(np.einsum("ij,jk,ik->", Jh, cov, Jh) * sigma**2 / len(q_hold)))


@functools.lru_cache(maxsize=None)
def elastic_round_trips() -> dict:
    """docs/elastic.md's full round trip, the set-up of ``tests/test_elastic.py``'s
    ``test_simulated_full_elastic_round_trip`` (:func:`robocal.sim.elastic_campaigns.kr150_elastic_campaign`,
    seed 4, 150 + 100 poses, lateral compliances of A2-A4 hidden, no stiffening): ``full.holdout_rms_mm`` /
    ``full.optimum_mm`` and ``joint_only.holdout_rms_mm`` / ``joint_only.optimum_mm``, the full and the
    joint-only model; ``n_not_converged``. Holdout: RMS of the predicted against the true reflector
    positions [mm]. (The joint round trip of seeds 0 and 1: ``elastic/joint_round_trip``.)"""
    import numpy as np

    from ..calib import CalibrationProblem, Target, solve
    from ..calib.elastic import ElasticModel, Payload
    from ..sim.elastic_campaigns import (KR150_LATERAL, KR150_MASSES, KR150_PAYLOAD, SIGMA_MM, kr150_elastic_campaign,
                                         kr150_elastic_truth)

    c = kr150_elastic_campaign(4, 150, 100, truth=kr150_elastic_truth(hardening=0.0, lateral=KR150_LATERAL))
    n, out, conv = c.n_train, {}, []
    for label, with_lateral in (("full", True), ("joint_only", False)):
        el = ElasticModel(masses=KR150_MASSES, payload=Payload(KR150_PAYLOAD[1], KR150_PAYLOAD[2], "flange"),
                          compliance_initial=0.0, joints=("A2", "A3", "A4", "A5", "A6"), lateral=with_lateral,
                          lateral_joints=tuple(KR150_LATERAL))
        prob = CalibrationProblem(c.nominal, c.q[:n], [Target("r1", None, (0.0, 0.0, 50.0))], c.points[:n],
                                  point_sigma_mm=SIGMA_MM, base_initial="fit", elastic=el)
        res = solve(prob, max_iterations=200)
        pred = prob.predict_points(res.state, q=c.q[n:])
        out[f"{label}.holdout_rms_mm"] = float(np.sqrt(np.mean(np.sum((pred - c.true_points[n:]) ** 2, axis=-1))))
        out[f"{label}.optimum_mm"] = _expected_holdout_rms(prob, res, c.q[n:], SIGMA_MM)
        conv.append(res.converged)
    out["n_not_converged"] = float(sum(not x for x in conv))
    return out


DATASET_PRODUCERS = {
    "elastic/round_trips": elastic_round_trips,
    "self_calibration/nao_cli": nao_self_calibrate_cli,
    "self_calibration/nao_null_directions": nao_null_directions,
    "self_calibration/noise_budget": self_calibration_noise_budget,
    "self_calibration/nao_joint_noise": nao_joint_noise,
    "elastic/six_d_round_trip": elastic_six_d_round_trip,
    "elastic/six_d_cli": elastic_six_d_cli,
    "elastic/rigid_robot": elastic_rigid_robot,
    **{f"datasets/ros_handeye_opencv/{t}": functools.partial(ros_handeye_opencv, t) for t in ROS_BOARDS},
    **{f"datasets/ros_handeye_variants/{t}": functools.partial(ros_handeye_variants, t) for t in ROS_BOARDS},
    "datasets/positioner": positioner,
    "self_calibration/nao_sigma_gain": nao_sigma_gain,
    "datasets/report_tables": report_tables,
    "datasets/boby_joint_seeds": lambda: boby_seeds("elastic-joint"),
    "datasets/boby_geometric_seeds": lambda: boby_seeds("geometric"),
    "elastic/hilti_gain_joint": lambda: hilti_gain("elastic-joint"),
    "elastic/hilti_gain_full": lambda: hilti_gain("elastic-full"),
    "elastic/justin_joint_seeds": justin_joint_seeds,
    "elastic/justin_full_seeds": justin_full_seeds,
    "elastic/justin_joint_gravity": justin_joint_gravity,
    **{f"datasets/convergence/{m}": functools.partial(datasets_convergence, m)
       for m in ("geometric", "elastic-joint", "elastic-full")},
    "datasets/hilti_vs_readme": hilti_vs_readme,
    "datasets/justin_full_vs_source": justin_full_vs_source,
}

#: the data sets these producers read where the producer's first name part does not tell
#: (``figure_producers.datasets_needed``)
DATASETS_NEEDED = {"datasets/positioner": ("ros_industrial_handeye",),
                   **{f"datasets/ros_handeye_{v}/{t}": ("ros_industrial_handeye",) for t in ROS_BOARDS
                      for v in ("variants", "opencv")},
                   "datasets/boby_joint_seeds": ("boby_fanuc",), "datasets/boby_geometric_seeds": ("boby_fanuc",),
                   "datasets/hilti_vs_readme": ("hilti_trailblazer",), "datasets/justin_full_vs_source": ("dlr_justin",),
                   "elastic/hilti_gain_joint": ("hilti_trailblazer",), "elastic/hilti_gain_full": ("hilti_trailblazer",),
                   "elastic/justin_joint_seeds": ("dlr_justin",), "elastic/justin_full_seeds": ("dlr_justin",), "elastic/justin_joint_gravity": ("dlr_justin",),
                   **{f"datasets/convergence/{m}": CONVERGENCE_DATASETS for m in ("geometric", "elastic-joint", "elastic-full")}}

#: slow: more than ~10 s of CPU (the Justin / Hilti elastic-full fits, five Justin elastic fits, five hand-eye /
#: camera runs per ROS-Industrial set, the NAO joint-noise fits ~22 s) or, to keep the suite's added CPU under
#: ~8 s, 1-6 s (the 6-D calibrations through the command line, the NAO null directions)
SLOW_DATASET_PRODUCERS = {"elastic/round_trips", "self_calibration/nao_cli", "self_calibration/nao_null_directions", "self_calibration/nao_joint_noise", "elastic/six_d_cli",
                          *(f"datasets/ros_handeye_variants/{t}" for t in ROS_BOARDS), "elastic/hilti_gain_full",
                          "elastic/justin_joint_seeds", "elastic/justin_full_seeds", "datasets/justin_full_vs_source",
                          # Justin's elastic-joint fit (~40 s); the convergence counts of the elastic models (their
                          # Justin / Hilti runs are slow; geometric: the three fast protocols)
                          "elastic/justin_joint_gravity", "datasets/convergence/elastic-joint",
                          "datasets/convergence/elastic-full"}
