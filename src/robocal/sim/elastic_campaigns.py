"""The simulated elastic KR150 campaigns of tests/test_elastic.py and of docs/elastic.md's round
trips: a KR 150 R3100 carrying 120 kg whose hidden compliances, mass model and (optionally) lateral
bending deflect it, measured by a placed laser tracker (0.02 mm). Written once, so that the tests and
the documented figures use the same draws. Lengths mm, masses kg, compliances mrad/kNm."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..robots import load_robot
from .elastic import ElasticTruth
from .robot import VirtualRobot
from .tracker import LaserTracker

__all__ = ["KR150_COMPLIANCE", "KR150_LATERAL", "KR150_MASSES", "KR150_PAYLOAD", "KR150_TOOL", "SIGMA_MM",
           "ElasticCampaign", "kr150_correction_cell", "kr150_elastic_campaign", "kr150_elastic_truth",
           "kr150_mass_model_file", "reached_error_mm", "write_flange_targets"]

#: a KR150-class mass model (simulation numbers: kg, centre of mass in each DH link frame [mm])
KR150_MASSES = {"A1": (450.0, (0.0, 150.0, 0.0)), "A2": (280.0, (-600.0, 0.0, 150.0)),
                "A3": (220.0, (-60.0, -40.0, 0.0)), "A4": (70.0, (0.0, 0.0, -300.0)),
                "A5": (30.0, (0.0, 20.0, 0.0)), "A6": (8.0, (0.0, 0.0, -20.0))}
#: the payload: (end effector, mass [kg], centre of mass on the flange [mm])
KR150_PAYLOAD = ("flange", 120.0, (0.0, 50.0, 200.0))
#: the hidden joint compliances [mrad/kNm]
KR150_COMPLIANCE = {"A1": 0.15, "A2": 0.25, "A3": 0.4, "A4": 1.5, "A5": 2.0, "A6": 3.0}
#: the hidden lateral (bending) compliances about each bearing's two axes [mrad/kNm]
KR150_LATERAL = {"A2": (0.05, 0.08), "A3": (0.1, 0.06), "A4": (0.4, 0.3)}
#: the reflector on the flange [mm]
KR150_TOOL = np.array([30.0, 40.0, 250.0])
#: the tracker's noise per coordinate [mm]
SIGMA_MM = 0.02


def kr150_elastic_truth(hardening: float = 0.0002, lateral: dict | None = None,
                        unmodelled: bool = True) -> ElasticTruth:
    """The hidden elastic truth: :data:`KR150_COMPLIANCE`, :data:`KR150_MASSES`, :data:`KR150_PAYLOAD`.

    Parameters
    ----------
    hardening : float
        Relative stiffening at 1 kNm (0.0002: 0.2 % at 10 kNm).
    lateral : dict, optional
        Lateral compliances (e.g. :data:`KR150_LATERAL`).
    unmodelled : bool
        False: none of the effects the identified model lacks (no hardening, torques taken at the
        commanded pose instead of the deflected one).
    """
    if not unmodelled:
        return ElasticTruth(KR150_COMPLIANCE, KR150_MASSES, payload=KR150_PAYLOAD, hardening=0.0,
                            equilibrium_iterations=0, lateral=lateral)
    return ElasticTruth(KR150_COMPLIANCE, KR150_MASSES, payload=KR150_PAYLOAD, hardening=hardening, lateral=lateral)


@dataclass(frozen=True)
class ElasticCampaign:
    """One simulated campaign: ``nominal`` (the library KR150), ``robot`` (the deflecting
    :class:`VirtualRobot`), ``q`` (N, 6) [rad], ``points`` (N, R, 3) measured and ``true_points``
    (N, R, 3) noise-free [mm], ``n_train`` (the first poses train, the rest are the holdout),
    ``measurements`` (the tracker's record) and ``tracker``."""

    nominal: object
    robot: VirtualRobot
    q: np.ndarray
    points: np.ndarray
    true_points: np.ndarray
    n_train: int
    measurements: object
    tracker: LaserTracker


def kr150_elastic_campaign(seed: int, n_train: int = 100, n_hold: int = 100, reflectors=None,
                           truth: ElasticTruth | None = None) -> ElasticCampaign:
    """The campaign of ``tests/test_elastic.py``: the KR150 perturbed with ``seed`` (no joint noise),
    deflecting as ``truth`` (default :func:`kr150_elastic_truth`), the tracker placed with
    ``seed + 100``, ``n_train + n_hold`` random configurations 0.1 rad inside the limits and the
    noise drawn from ``seed + 200``.

    Parameters
    ----------
    seed : int
    n_train, n_hold : int
        Training and holdout poses.
    reflectors : ndarray, shape (R, 3), optional
        Reflectors on the flange [mm] (default one, :data:`KR150_TOOL`).
    truth : ElasticTruth, optional

    Returns
    -------
    ElasticCampaign
    """
    nominal = load_robot("kuka_kr150_r3100")
    truth = kr150_elastic_truth() if truth is None else truth
    robot = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0).with_elastic(truth)
    tracker = LaserTracker.placed(seed + 100, reflectors=KR150_TOOL[None] if reflectors is None else reflectors,
                                  sigma_mm=SIGMA_MM)
    rng = np.random.default_rng(seed + 200)
    q = robot.random_configurations(n_train + n_hold, rng, margin=0.1)
    meas = tracker.measure(robot, q, rng)
    return ElasticCampaign(nominal, robot, q, meas.points, tracker.true_points(robot, q), n_train, meas, tracker)


def kr150_mass_model_file(folder) -> tuple:
    """Write the KR150 robot file whose ``[elastic]`` section holds the mass model
    :data:`KR150_MASSES` (no compliances): ``folder/kr150_masses.toml``.

    Returns
    -------
    path : Path
        The file written.
    description : ElasticDescription
        Its elastic section.
    """
    from pathlib import Path

    from ..calib.elastic import ElasticDescription, bodies_from_masses
    from ..robots import save_robot

    nominal = load_robot("kuka_kr150_r3100")
    desc = ElasticDescription({}, bodies_from_masses(KR150_MASSES), mass_model=True)
    return save_robot(nominal.replace(extra={**nominal.extra, "elastic": desc}), Path(folder) / "kr150_masses.toml"), desc


def kr150_correction_cell(robot_file, n_poses: int = 120) -> tuple:
    """The closed-loop cell of ``tests/test_elastic.py``'s calibrate-then-correct test: the robot of
    ``robot_file`` (:func:`kr150_mass_model_file`) perturbed with seed 3 except its last link's
    geometry (which trades off against the single reflector and is held at nominal by the
    identifiability analysis), deflecting as :func:`kr150_elastic_truth` (unmodelled effects on),
    the tracker placed with seed 103, ``n_poses`` configurations drawn from seed 7.

    Returns
    -------
    robot : VirtualRobot
        The model is the file's (its mass model); the truth deflects.
    tracker : LaserTracker
    measurements : Measurements
        The tracker's record of the ``n_poses`` poses (noise 0.02 mm).
    """
    nominal = load_robot(robot_file)
    truth = kr150_elastic_truth()
    last = [n.endswith("6") for n in nominal.params.names]
    keep = nominal.with_free(np.asarray(nominal.params.free) & ~np.asarray(last))
    robot = VirtualRobot.perturbed(keep, 3, joint_noise_deg=0.0).with_elastic(truth)
    robot = VirtualRobot(nominal, robot.true_model, elastic=truth)
    tracker = LaserTracker.placed(103, reflectors=KR150_TOOL[None], sigma_mm=SIGMA_MM)
    rng = np.random.default_rng(7)
    q = robot.random_configurations(n_poses, rng, margin=0.1)
    return robot, tracker, tracker.measure(robot, q, rng)


def write_flange_targets(robot: VirtualRobot, tracker: LaserTracker, path, n: int = 5, seed: int = 8) -> np.ndarray:
    """Write ``n`` flange targets the true robot reaches (configurations 0.2 rad inside the limits,
    drawn from ``seed``) in the tracker frame as a ``robocal-targets/1`` file (mm, KUKA ABC deg).

    Returns
    -------
    ndarray, shape (n, 4, 4)
        The targets T_tracker_flange [mm].
    """
    from pathlib import Path

    from ..transforms import pose_from_transform

    T_goal = tracker.T_tracker_world @ robot.true_poses(robot.random_configurations(n, np.random.default_rng(seed), 0.2))
    rows = [f"P{i}," + ",".join(f"{v:.9f}" for v in pose_from_transform(T, "kuka_abc")) for i, T in enumerate(T_goal)]
    head = ["# format: robocal-targets/1", "# length_unit: mm", "# angle_unit: deg", "# orientation: kuka_abc",
            "# frame: world", "name,x,y,z,rx,ry,rz"]
    Path(path).write_text("\n".join(head + rows) + "\n")
    return T_goal


def reached_error_mm(robot: VirtualRobot, tracker: LaserTracker, corrected_csv, T_goal) -> np.ndarray:
    """Distance [mm] between each target and where the true (deflecting) robot's flange lands at
    the joints of ``corrected_csv`` (``robocal correct``'s output, degrees), shape (n,)."""
    import csv

    with open(corrected_csv, newline="") as fh:
        recs = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    q_cmd = np.radians([[float(rec[j]) for j in robot.nominal.controller_joints] for rec in recs])
    reached = tracker.T_tracker_world @ robot.true_poses(q_cmd)
    return np.linalg.norm(reached[:, :3, 3] - np.asarray(T_goal)[:, :3, 3], axis=1)
