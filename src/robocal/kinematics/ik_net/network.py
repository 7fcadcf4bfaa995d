"""The learned IK seed: training on one configuration branch, prediction with a domain check, and
batched damped least squares started from it.

Training (:func:`train_ik_network`): joints sampled uniformly on a branch (:mod:`.branch`), poses by
one batched FK call, encoded (:mod:`.encoding`), split into training and validation sets; the GA
(:mod:`.tuning`) picks the RBF structure on the validation split; the final network is fitted on the
training split, and the validation split gives the error statistics and the *envelope* a query is
checked against.

Prediction (:meth:`IKSeedNetwork.seed`) never answers silently: every pose gets a flag. A pose is
``in_domain`` only if (1) its position is no farther from the nearest training position than 1.5 times
the largest such distance of the validation poses, and its encoding no farther from the nearest RBF
centre than 1.1 times the largest such distance of the samples (else ``outside_workspace``: the
network would extrapolate), (2) the predicted joints lie in
the branch's joint box (else ``outside_branch``) and (3) FK of the predicted joints is within the
validation envelope (95th percentile of position and rotation error) of the target (else ``poor_seed``: typically a pose
whose solution on this branch needs joints outside the trained box, or a pose near a singularity).
"""

from __future__ import annotations
from ...errors import InputError

import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..fingerprint import model_fingerprint
from ..ik import IKResult, ik_numeric, pose_errors
from ..model import RobotModel
from ..ik_analytic import NotAnalyticError
from .branch import ConfigurationBranch, default_branch, on_branch, reference_model, sample_branch
from .encoding import ENCODING, encode_poses
from .rbf import RBFNetwork, fit_rbf
from .tuning import DEFAULT_STRUCTURE, Structure, tune_structure

__all__ = ["IKSeedNetwork", "SeedPrediction", "train_ik_network", "ik_with_seed_network", "NetworkMismatchError",
           "ENVELOPE_FACTOR", "ENVELOPE_PERCENTILE"]

ENVELOPE_FACTOR = 1.5
"""Workspace check: a position farther than this times the validation poses' largest distance from the
nearest training position is ``outside_workspace``."""
ENVELOPE_PERCENTILE = 95.0
"""A seed whose FK misses the target by more than the validation seeds' 95th percentile (position or
rotation) is ``poor_seed``: about 5 % of poses inside the branch get that flag (a false alarm rate
stated in docs/kinematics.md), poses outside it far more often."""


class NetworkMismatchError(InputError):
    """The network was trained for another robot (or other kinematic parameters)."""


@dataclass(frozen=True)
class SeedPrediction:
    """Per pose: ``q`` (N, n) seed joints [rad | mm]; ``in_domain`` (N,) bool; ``status`` (N,) one of
    ``ok``, ``outside_workspace``, ``outside_branch``, ``poor_seed``; ``centre_distance`` (N,) to the
    nearest RBF centre [sigma]; ``position_error_mm``, ``rotation_error_rad`` (N,): FK of the seed
    against the target."""

    q: np.ndarray
    in_domain: np.ndarray
    status: np.ndarray
    centre_distance: np.ndarray
    position_error_mm: np.ndarray
    rotation_error_rad: np.ndarray


@dataclass(frozen=True)
class IKSeedNetwork:
    """A trained GA-RBF seed network for one robot model and one configuration branch.

    ``envelope``: ``centre_distance`` [sigma], ``workspace_mm`` (distance to the nearest training
    position), ``position_mm``, ``rotation_rad`` limits of the domain check; ``workspace_points`` (N, 3)
    the training positions [mm]; ``stats``: validation errors (``joint_deg``, ``position_mm``, ``rotation_deg``: median, p95,
    max) and training facts (samples, seed, seconds, GA history)."""

    robot_name: str
    robot_fingerprint: str
    branch: ConfigurationBranch
    length_scale_mm: float
    rbf: RBFNetwork
    structure: Structure
    envelope: dict
    workspace_points: np.ndarray
    stats: dict = field(default_factory=dict)
    encoding: str = ENCODING

    def check_model(self, model: RobotModel) -> None:
        """Raise :class:`NetworkMismatchError` unless ``model`` is the robot this network was trained on."""
        fp = model_fingerprint(model)
        if fp == self.robot_fingerprint:
            return
        if model.name != self.robot_name:
            raise NetworkMismatchError(f"the IK network was trained for robot {self.robot_name!r} "
                                       f"(model {self.robot_fingerprint}), not for {model.name!r} (model {fp})")
        raise NetworkMismatchError(f"the IK network was trained for other kinematic parameters of {model.name!r} "
                                   f"(model {self.robot_fingerprint}, this one is {fp}: recalibrated or edited?); "
                                   "train a new network for this model")

    def predict_joints(self, T) -> np.ndarray:
        """Raw network output (N, n) [rad | mm] for poses ``T`` (N, 4, 4) [mm], no checks."""
        return self.rbf.predict(encode_poses(T, self.length_scale_mm))

    def seed(self, model: RobotModel, T) -> SeedPrediction:
        """Seed joints for poses ``T`` (N, 4, 4) or (4, 4) [mm] of ``model``'s first end effector, with
        the domain check of the module docstring (one batched FK)."""
        self.check_model(model)
        T = np.asarray(T, dtype=float).reshape(-1, 4, 4)
        X = encode_poses(T, self.length_scale_mm)
        q = self.rbf.predict(X)
        dist = self.rbf.nearest_centre_distance(X)
        ws, _ = cKDTree(self.workspace_points).query(T[:, :3, 3])
        dp, dr = pose_errors(model.fk(q), T)
        pos, rot = np.linalg.norm(dp, axis=1), np.linalg.norm(dr, axis=1)
        env = self.envelope
        outside = (dist > env["centre_distance"]) | (ws > env["workspace_mm"])
        off_box = ~self.branch.contains(q, tol=self.branch.margin_rad)
        poor = (pos > env["position_mm"]) | (rot > env["rotation_rad"])
        status = np.where(outside, "outside_workspace", np.where(off_box, "outside_branch",
                                                                 np.where(poor, "poor_seed", "ok")))
        return SeedPrediction(q, status == "ok", status, dist, pos, rot)


def _percentiles(x) -> dict:
    return {"median": float(np.median(x)), "p95": float(np.percentile(x, 95)), "max": float(np.max(x))}


def pose_error_stats(model, q_pred, q_true, T) -> dict:
    """Error statistics (median, p95, max) of predicted joints against true joints and poses."""
    dp, dr = pose_errors(model.fk(q_pred), T)
    return {"joint_deg": _percentiles(np.degrees(np.abs(q_pred - q_true)).max(axis=1)),
            "position_mm": _percentiles(np.linalg.norm(dp, axis=1)),
            "rotation_deg": _percentiles(np.degrees(np.linalg.norm(dr, axis=1)))}


def train_ik_network(model: RobotModel, n_samples: int = 20000, seed: int = 0, *, tune: bool = True,
                     population: int = 10, generations: int = 5, k_max: int = 1200,
                     validation_fraction: float = 0.2, branch: ConfigurationBranch | None = None,
                     reference: RobotModel | None = None, structure: Structure | None = None,
                     progress=None) -> IKSeedNetwork:
    """Train a seed network for ``model`` (a 6R arm) on one configuration branch.

    n_samples: FK samples (training + validation); seed: seeds sampling, centres and the GA.
    tune: run the GA (DEAP needed); else ``structure`` (default :data:`DEFAULT_STRUCTURE`).
    branch / reference: see :mod:`.branch` (default: branch 0 ``front/up/noflip`` labelled by the
    closed form of ``model`` or of its beta-free nominal shape; a joint-box branch needs no reference). progress(stage, detail) gets
    one-line reports: ``("sample", text)``, ``("ga", text)`` per generation, ``("fit", text)``.
    """
    if n_samples < 100:
        raise ValueError(f"n_samples must be at least 100, got {n_samples}")
    if not 0.05 <= validation_fraction <= 0.5:
        raise ValueError(f"validation_fraction must be in [0.05, 0.5], got {validation_fraction}")
    report = progress or (lambda stage, text: None)
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    if branch is None or branch.index >= 0:
        reference = reference if reference is not None else reference_model(model)
    branch = branch if branch is not None else default_branch(model)
    q = sample_branch(reference, branch, n_samples, rng)
    T = model.fk(q)
    length_scale = float(np.linalg.norm(T[:, :3, 3], axis=1).max())
    X = encode_poses(T, length_scale)
    n_val = int(round(validation_fraction * n_samples))
    tr, va = slice(n_val, None), slice(0, n_val)
    report("sample", f"{n_samples} FK samples on branch {branch.name} ({time.perf_counter() - t0:.1f} s)")
    history = []
    if tune:
        def ga_progress(gen, ngen, best, s):
            report("ga", f"generation {gen}/{ngen}: validation RMS joint error {np.degrees(best):.2f} deg "
                         f"(K={s.n_centres}, width {s.width_factor:.2f}, lam {s.reg:.1e}, "
                         f"position weight {s.position_weight:.2f})")

        structure, history = tune_structure(X[tr], q[tr], X[va], q[va], seed=seed, population=population,
                                            generations=generations, k_max=k_max, progress=ga_progress)
    structure = structure or DEFAULT_STRUCTURE
    rbf = fit_rbf(X[tr], q[tr], structure.n_centres, structure.width_factor, structure.reg,
                  np.random.default_rng(seed), input_weights=structure.input_weights(X.shape[1]))
    q_val = rbf.predict(X[va])
    stats = pose_error_stats(model, q_val, q[va], T[va])
    dp, dr = pose_errors(model.fk(q_val), T[va])
    ws, _ = cKDTree(T[tr, :3, 3]).query(T[va, :3, 3])
    envelope = {"centre_distance": float(1.1 * rbf.nearest_centre_distance(X).max()),
                "workspace_mm": float(ENVELOPE_FACTOR * ws.max()),
                "position_mm": float(np.percentile(np.linalg.norm(dp, axis=1), ENVELOPE_PERCENTILE)),
                "rotation_rad": float(np.percentile(np.linalg.norm(dr, axis=1), ENVELOPE_PERCENTILE))}
    seconds = time.perf_counter() - t0
    stats.update({"n_samples": int(n_samples), "n_validation": n_val, "seed": int(seed), "tuned": bool(tune),
                  "train_seconds": float(seconds), "ga_history": history})
    report("fit", f"K={structure.n_centres} centres; validation median joint error "
                  f"{stats['joint_deg']['median']:.2f} deg, position {stats['position_mm']['median']:.1f} mm "
                  f"({seconds:.1f} s)")
    return IKSeedNetwork(model.name, model_fingerprint(model), branch, length_scale, rbf, structure, envelope,
                         np.ascontiguousarray(T[tr, :3, 3]), stats)


def ik_with_seed_network(model: RobotModel, T_target, network: IKSeedNetwork, **ik_options):
    """Batched damped least squares (:func:`~robocal.kinematics.ik.ik_numeric`) started from the
    network's seeds. Returns ``(IKResult, SeedPrediction, on_branch)``: ``on_branch`` (N,) bool says
    whether the converged solution lies on the network's branch (closed-form labels of the reference
    model, see :mod:`.branch`; the box alone for a joint-box branch). Poses whose seed is not
    ``in_domain`` are still solved; damped least squares converges to the solution nearest its start,
    which for a poor seed can be another branch, so check the flags."""
    pred = network.seed(model, T_target)
    res: IKResult = ik_numeric(model, np.asarray(T_target, dtype=float).reshape(-1, 4, 4), pred.q, **ik_options)
    q = np.atleast_2d(res.q)
    try:
        ref = None if network.branch.index < 0 else reference_model(model)
        branch_ok = on_branch(ref, q, network.branch) & np.atleast_1d(res.converged)
    except NotAnalyticError:
        branch_ok = np.zeros(len(q), dtype=bool)
    return res, pred, branch_ok
