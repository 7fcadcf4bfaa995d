"""A virtual robot: a nominal model plus hidden true parameters and encoder noise.

The simulator stands in for a real robot in tests and demos. :meth:`VirtualRobot.perturbed`
draws "true" kinematic parameters around the nominal ones (only the model's *free* parameters;
fixed ones stay exactly nominal), and :meth:`VirtualRobot.reach` returns where the flange really
goes when the controller is commanded to ``q``: the true model evaluated at ``q`` plus encoder
noise. Every random draw takes a seed or a ``numpy.random.Generator``. Lengths mm, angles rad.
"""

from __future__ import annotations

import math

import numpy as np

from ..kinematics.model import RobotModel
from ..transforms import check_transforms

__all__ = ["VirtualRobot", "as_rng", "controller_joint_prismatic", "parameter_kinds"]


def as_rng(rng) -> np.random.Generator:
    """A ``numpy.random.Generator`` from a Generator or an integer seed (``None`` is refused)."""
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None or isinstance(rng, bool) or not isinstance(rng, (int, np.integer)):
        raise TypeError(f"expected a numpy.random.Generator or an integer seed, got {rng!r} "
                        "(robocal never draws unseeded random numbers)")
    return np.random.default_rng(int(rng))


def controller_joint_prismatic(model: RobotModel) -> np.ndarray:
    """(n_ctrl,) bool: the controller joint drives a prismatic model joint (its unit is mm)."""
    return model.prismatic_joints


def parameter_kinds(model: RobotModel) -> np.ndarray:
    """(P,) array of ``"length"``, ``"angle"`` or ``"offset"`` for every model parameter.

    ``offset`` marks joint zero offsets: ``theta`` of a moving revolute link (an angle) and ``d``
    of a moving prismatic link of the DH kinds (a length).
    """
    kinds = []
    for name, unit, k in zip(model.params.names, model.params.units, model.params.link_of):
        link = model.links[int(k)]
        base = name[: len(name) - len(str(k + 1))]
        if link.joint_type == "revolute" and base == "theta":
            kinds.append("offset")
        elif link.joint_type == "prismatic" and base == "d":
            kinds.append("offset")
        else:
            kinds.append("angle" if unit == "rad" else "length")
    return np.array(kinds)


class VirtualRobot:
    """A simulated robot with hidden true kinematics.

    Attributes
    ----------
    nominal: the nominal :class:`RobotModel` (what the user believes).
    true_model: the model the simulated robot really follows.
    joint_noise: (n_ctrl,) encoder noise standard deviation per controller joint [rad | mm].
    elastic: optional :class:`~robocal.sim.elastic.ElasticTruth`: the robot deflects under gravity
    and payload (hidden compliances; :meth:`reach` and :meth:`true_poses` include it).
    """

    def __init__(self, nominal: RobotModel, true_model: RobotModel, joint_noise=0.0, elastic=None):
        self.elastic = elastic
        if true_model.params.names != nominal.params.names or true_model.controller_joints != nominal.controller_joints:
            raise ValueError("true_model must have the same parameters and controller joints as nominal")
        self.nominal = nominal
        self.true_model = true_model
        jn = np.broadcast_to(np.asarray(joint_noise, dtype=float), (nominal.n_joints,)).copy()
        if np.any(jn < 0) or not np.all(np.isfinite(jn)):
            raise ValueError(f"joint_noise must be finite and >= 0, got {jn}")
        jn.setflags(write=False)
        self.joint_noise = jn
        self.prismatic = controller_joint_prismatic(nominal)

    # ------------------------------------------------------------------ construction
    @classmethod
    def perturbed(cls, nominal: RobotModel, rng_seed, *, length_sigma_mm: float = 0.5,
                  angle_sigma_deg: float = 0.05, offset_sigma_deg: float = 0.05,
                  base=None, joint_noise_deg: float = 0.002, joint_noise_mm: float = 0.001) -> "VirtualRobot":
        """A virtual robot whose true free parameters are Gaussian draws around the nominal ones.

        rng_seed: integer seed or ``numpy.random.Generator``.
        length_sigma_mm: standard deviation of length parameters (a, d, x, y, z, prismatic offsets) [mm].
        angle_sigma_deg: standard deviation of angle parameters (alpha, beta, roll, pitch, yaw,
            theta of fixed links) [deg].
        offset_sigma_deg: standard deviation of revolute joint zero offsets (theta of moving links) [deg].
        base: optional (4, 4) true ``T_world_base`` [mm] (where the robot really stands); default
            the nominal one.
        joint_noise_deg / joint_noise_mm: encoder noise of revolute / prismatic controller joints,
            added to the commanded joints before forward kinematics in :meth:`reach`.

        Fixed parameters (``nominal.params.free == False``) are copied exactly.
        """
        rng = as_rng(rng_seed)
        kinds = parameter_kinds(nominal)
        sigma = np.where(kinds == "length", length_sigma_mm,
                         np.where(kinds == "angle", math.radians(angle_sigma_deg), np.nan))
        offset_sigma = np.where(np.array(nominal.params.units) == "rad", math.radians(offset_sigma_deg), length_sigma_mm)
        sigma = np.where(kinds == "offset", offset_sigma, sigma)
        sigma = np.where(nominal.params.free, sigma, 0.0)
        if np.any(sigma < 0):
            raise ValueError("perturbation standard deviations must be >= 0")
        delta = rng.standard_normal(len(nominal.params)) * sigma
        true = nominal.with_params(nominal.params.values + delta)
        if base is not None:
            true = true.replace(T_world_base=check_transforms(base, "base").reshape(4, 4))
        prism = controller_joint_prismatic(nominal)
        noise = np.where(prism, joint_noise_mm, math.radians(joint_noise_deg))
        return cls(nominal, true, noise)

    # ------------------------------------------------------------------ truth
    def true_parameters(self) -> dict:
        """True parameter values by name [mm | rad]."""
        return self.true_model.params.as_dict()

    def parameter_errors(self) -> dict:
        """True minus nominal parameter values by name [mm | rad]."""
        d = self.true_model.params.values - self.nominal.params.values
        return dict(zip(self.nominal.params.names, d.tolist()))

    # ------------------------------------------------------------------ joints
    def _joints(self, q) -> tuple[np.ndarray, bool]:
        q = np.asarray(q, dtype=float)
        single = q.ndim == 1
        q2 = np.atleast_2d(q)
        n = self.nominal.n_joints
        if q2.ndim != 2 or q2.shape[1] != n:
            raise ValueError(f"{self.nominal.name}: joints must have shape (N, {n}) or ({n},), got {q.shape}")
        if not np.all(np.isfinite(q2)):
            r, j = np.argwhere(~np.isfinite(q2))[0]
            raise ValueError(f"pose {r}: joint {self.nominal.controller_joints[j]} is {q2[r, j]} (not finite)")
        return q2, single

    def check_limits(self, q) -> None:
        """Raise ``ValueError`` naming the first pose index and joint outside the joint limits."""
        q2, _ = self._joints(q)
        lim = self.nominal.limits
        bad = (q2 < lim[:, 0] - 1e-9) | (q2 > lim[:, 1] + 1e-9)
        if bad.any():
            r, j = np.argwhere(bad)[0]
            name = self.nominal.controller_joints[j]
            scale, unit = (1.0, "mm") if self.prismatic[j] else (180.0 / math.pi, "deg")
            val, lo, hi = q2[r, j] * scale, lim[j, 0] * scale, lim[j, 1] * scale
            raise ValueError(f"{self.nominal.name}: pose {r}: joint {name} = {val:.4f} {unit} outside its limits "
                             f"[{lo:.4f}, {hi:.4f}] {unit} ({int(bad.any(axis=1).sum())} pose(s) out of limits)")

    def random_configurations(self, n: int, rng, margin: float = 0.05) -> np.ndarray:
        """``n`` joint configurations (n, n_ctrl) [rad | mm], uniform within the joint limits.

        margin: fraction of each joint's range kept free at both ends (0 <= margin < 0.5).
        """
        if not 0.0 <= margin < 0.5:
            raise ValueError(f"margin must be a fraction in [0, 0.5), got {margin}")
        rng = as_rng(rng)
        lo, hi = self.nominal.limits[:, 0], self.nominal.limits[:, 1]
        span = hi - lo
        return rng.uniform(lo + margin * span, hi - margin * span, size=(int(n), self.nominal.n_joints))

    def feasible_configurations(self, n: int, rng, margin: float = 0.05, cell=None) -> np.ndarray:
        """``n`` configurations (n, n_ctrl) [rad | mm] uniform within the joint limits that the robot
        can take in ``cell`` (default: on the floor, the floor an obstacle, no link in another;
        docs/cells.md). A robot that is not a serial chain gets :meth:`random_configurations`."""
        if not self.nominal.is_serial:
            return self.random_configurations(n, rng, margin)
        from ..calib.cell import default_cell, sample_feasible

        q, _ = sample_feasible(default_cell() if cell is None else cell, self.nominal, int(n), as_rng(rng),
                               margin=margin, batch=max(200, 4 * int(n)))
        return q

    # ------------------------------------------------------------------ motion
    def encoder_noise(self, q, rng) -> np.ndarray:
        """Joint positions really reached for commanded ``q``: ``q`` plus Gaussian encoder noise."""
        q2, single = self._joints(q)
        if np.any(self.joint_noise > 0):
            q2 = q2 + as_rng(rng).standard_normal(q2.shape) * self.joint_noise
        return q2[0] if single else q2

    def reach(self, q_commanded, rng, end_effector=None) -> np.ndarray:
        """True end-effector poses ``T_world_ee`` (N, 4, 4) [mm] for commanded joints (N, n_ctrl).

        The commanded joints are checked against the limits (``ValueError`` naming pose index and
        joint), encoder noise is added, and the true model's forward kinematics is evaluated.
        ``rng``: seed or Generator for the encoder noise.
        """
        self.check_limits(q_commanded)
        q_true = self.encoder_noise(q_commanded, rng)
        return self._fk(q_true, end_effector)

    def with_elastic(self, elastic) -> "VirtualRobot":
        """The same robot deflecting under gravity as ``elastic`` (an :class:`~robocal.sim.elastic.ElasticTruth`)."""
        return VirtualRobot(self.nominal, self.true_model, self.joint_noise, elastic=elastic)

    def _fk(self, q2, end_effector):
        if self.elastic is None:
            return self.true_model.fk(q2, end_effector)
        from .elastic import deflected_model_joints, lateral_bending

        qm = deflected_model_joints(self.true_model, q2, self.elastic)
        n_m = qm.shape[1]
        names = tuple(self.true_model.links[int(k)].name for k in self.true_model.moving)
        m = self.true_model.replace(controller_joints=names, coupling=np.eye(n_m),
                                    limits=np.tile([-np.inf, np.inf], (n_m, 1)), T_world_base=np.eye(4))
        T = lateral_bending(self.true_model, qm, self.elastic, end_effector, m.fk(qm, end_effector))
        return self.true_model.T_world_base @ T

    def true_poses(self, q, end_effector=None) -> np.ndarray:
        """Noise-free true poses ``T_world_ee`` for joints ``q`` (no limit check)."""
        q2, single = self._joints(q)
        T = self._fk(q2, end_effector)
        return T[0] if single else T

    def __repr__(self) -> str:
        return f"VirtualRobot({self.nominal.name!r}, {len(self.nominal.params)} parameters)"
