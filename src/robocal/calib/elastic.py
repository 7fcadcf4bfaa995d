"""What an elastic calibration identifies: which joints are compliant, where the gravity torques
come from (a mass model or lumped parameters identified from the data), the payload, gravity.

:class:`ElasticModel` is the option of :class:`~robocal.calib.problem.CalibrationProblem`
(``elastic=``); :func:`build_deflection` turns it into the two parameter blocks and the
:class:`~robocal.calib.residuals.deflection.Deflection` of the shared chain. docs/elastic.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .blocks.elastic import COMPLIANCE_UNITS, GravityParameters, JointCompliance, LateralCompliance
from .errors import ProblemError
from .gravity import STANDARD_GRAVITY, GravityTorques
from .residuals.deflection import Deflection

__all__ = ["ElasticModel", "Payload", "build_deflection", "target_joints", "bodies_from_masses", "joint_torques",
           "model_joint_deflection", "elastic_description", "ElasticDescription"]


@dataclass(frozen=True)
class Payload:
    """A load on an end effector: ``mass`` [kg] (scalar or per pose (N,)) with its centre of mass
    ``com`` [mm] ((3,) or (N, 3)) in the end effector's frame."""

    mass: object
    com: tuple = (0.0, 0.0, 0.0)
    end_effector: object = None

    def checked(self) -> "Payload":
        m = np.asarray(self.mass, dtype=float)
        if m.size == 0 or not np.all(np.isfinite(m)):
            raise ProblemError(f"payload: mass must be a finite number [kg], got {self.mass!r}")
        if np.any(m <= 0):
            raise ProblemError("payload: a payload needs a mass > 0 kg (a payload without mass has no "
                               "gravity torque; leave the payload out instead)")
        c = np.asarray(self.com, dtype=float)
        if c.shape[-1:] != (3,) or not np.all(np.isfinite(c)):
            raise ProblemError(f"payload: centre of mass must be x, y, z [mm], got {self.com!r}")
        if np.any(np.abs(c) > 5000):
            raise ProblemError(f"payload: centre of mass {c.tolist()} is more than 5 m from the flange: "
                               "metres and millimetres mixed up? (it is in mm)")
        return self


@dataclass(frozen=True)
class ElasticModel:
    """The deflection model of a calibration.

    joints: names of the compliant model joints (default: every moving joint carrying a target);
    masses: the mass model, ``{link name: (mass [kg], com (3,) [mm] in the link frame)}``; None:
    lumped gravity parameters of every moving link carrying a target are identified from the data
    (then only ``c_j tau_j`` is identifiable, see :mod:`robocal.calib.blocks.elastic`);
    payload: a :class:`Payload` or None; g: gravity in the robot base frame [m/s^2];
    compliance_initial: start value [mrad/kNm | mm/kN] (lumped parameters need a non-zero start);
    mass_initial: start mass of each lumped body [kg]; compliance_prior: optional sigma of a weak
    prior around the start (same unit); lateral: also two lateral (bending) compliances per
    compliant joint (the ``full`` model, :class:`~robocal.calib.blocks.elastic.LateralCompliance`).
    """

    joints: tuple | None = None
    masses: dict | None = None
    payload: Payload | None = None
    g: tuple = tuple(STANDARD_GRAVITY)
    compliance_initial: float = 10.0
    mass_initial: float = 10.0
    compliance_prior: float | None = None
    lateral: bool = False
    lateral_joints: tuple | None = None

    @property
    def lumped(self) -> bool:
        return self.masses is None


def target_joints(model, end_effectors) -> list:
    """Indices (into ``model.moving``) of the moving joints that move any of ``end_effectors``."""
    anc = np.zeros(len(model.links), dtype=bool)
    for e in end_effectors:
        anc |= model._ee_ancestors[model.end_effector_index(e)]
    return [j for j, k in enumerate(model.moving) if anc[k]]


def _joint_indices(model, names, default):
    if names is None:
        return np.array(default, dtype=int)
    moving = [model.links[int(k)].name for k in model.moving]
    out = []
    for n in names:
        if n not in moving:
            raise ProblemError(f"elastic: {n!r} is not a moving joint of {model.name}; joints: {', '.join(moving)}")
        out.append(moving.index(n))
    return np.array(out, dtype=int)


def _mass_bodies(model, masses):
    names = [L.name for L in model.links]
    links, theta = [], []
    for ln, entry in masses.items():
        if ln not in names:
            raise ProblemError(f"mass model: {ln!r} is not a link of {model.name}")
        try:
            m, com = float(entry[0]), np.asarray(entry[1], dtype=float).reshape(3)
        except (TypeError, ValueError, IndexError):
            raise ProblemError(f"mass model: {ln}: expected (mass kg, (x, y, z) mm), got {entry!r}") from None
        if not np.isfinite(m) or m < 0 or not np.all(np.isfinite(com)):
            raise ProblemError(f"mass model: {ln}: mass must be >= 0 kg and the centre of mass finite, got {entry!r}")
        links.append(names.index(ln))
        theta.append([m, *(m * com / 1000.0)])
    return np.array(links, dtype=int), np.array(theta, dtype=float).reshape(-1, 4)


def build_deflection(model, q, elastic: ElasticModel, end_effectors) -> Deflection:
    """The :class:`Deflection` (with its compliance and gravity blocks) of ``elastic`` for
    ``model`` at joints ``q``; ``end_effectors`` are those carrying targets."""
    carrying = target_joints(model, end_effectors)
    joints = _joint_indices(model, elastic.joints, carrying)
    if not len(joints):
        raise ProblemError("elastic: no compliant joint (no moving joint carries a target)")
    prior = None
    if elastic.compliance_prior is not None:
        from .blocks import GaussianPrior

        prior = GaussianPrior(float(elastic.compliance_prior))
    c0 = np.full(len(joints), float(elastic.compliance_initial))
    compliance = JointCompliance(model, joints, c0, prior=prior)
    if elastic.lumped:
        body_links = model.moving[carrying]
        theta0 = np.zeros((len(body_links), 4))
        theta0[:, 0] = elastic.mass_initial
        gravity = GravityParameters(model, body_links, theta0)
    else:
        body_links, theta = _mass_bodies(model, elastic.masses)
        gravity = GravityParameters(model, body_links, theta, free=False)
    payload = None
    if elastic.payload is not None:
        p = elastic.payload.checked()
        payload = (p.end_effector, p.mass, p.com)
    lateral = None
    if elastic.lateral:
        lj = joints if elastic.lateral_joints is None else _joint_indices(model, elastic.lateral_joints, ())
        lateral = LateralCompliance(model, lj, np.full(2 * len(lj), float(elastic.compliance_initial)))
    return Deflection(model, q, compliance, gravity, payload=payload, g=np.asarray(elastic.g, dtype=float),
                      lateral=lateral)


def bodies_from_masses(masses: dict) -> dict:
    """``{link: (m [kg], hx, hy, hz [kg m])}`` from a mass model ``{link: (m [kg], com (3,) [mm])}``."""
    out = {}
    for ln, (m, com) in masses.items():
        out[ln] = (float(m), *(float(m) * np.asarray(com, dtype=float).reshape(3) / 1000.0))
    return out


def _joints_model(model):
    names = tuple(model.links[int(k)].name for k in model.moving)
    n = len(names)
    return model.replace(controller_joints=names, coupling=np.eye(n), limits=np.tile([-np.inf, np.inf], (n, 1)))


def joint_torques(model, q_model, bodies: dict, *, payload=None, g=None) -> np.ndarray:
    """Gravity torques (N, n_model) [N m | N] at model joints ``q_model`` (N, n_model) of the bodies
    ``{link name: (m, hx, hy, hz)}`` and a payload ``(end_effector, mass, com)``."""
    names = [L.name for L in model.links]
    for ln in bodies:
        if ln not in names:
            raise ProblemError(f"mass model: {ln!r} is not a link of {model.name}")
    links = np.array([names.index(ln) for ln in bodies], dtype=int)
    theta = np.array([bodies[ln] for ln in bodies], dtype=float).reshape(-1, 4)
    gt = GravityTorques(_joints_model(model), q_model, links, payload=payload, g=g)
    return gt.torques(theta)


def model_joint_deflection(model, q, compliance: dict, bodies: dict, *, payload=None, g=None) -> np.ndarray:
    """``dtheta`` (N, n_model) [rad | mm] of the model joints at controller joints ``q`` (N, n_ctrl):
    ``s_j c_j tau_j(q)`` with ``compliance`` ``{joint name: c [mrad/kNm | mm/kN]}``."""
    q_model = np.atleast_2d(np.asarray(q, dtype=float)) @ model.coupling.T
    tau = joint_torques(model, q_model, bodies, payload=payload, g=g)
    moving = [model.links[int(k)].name for k in model.moving]
    c = np.zeros(len(moving))
    for n, v in compliance.items():
        if n not in moving:
            raise ProblemError(f"compliance: {n!r} is not a moving joint of {model.name}")
        c[moving.index(n)] = float(v)
    s = np.array([COMPLIANCE_UNITS[model.links[int(k)].joint_type == "revolute"][1] for k in model.moving])
    return tau * c * s


@dataclass(frozen=True)
class ElasticDescription:
    """The elastic part of a calibrated robot (the robot file's ``[elastic]`` section):
    compliance ``{joint: c}`` [mrad/kNm | mm/kN]; bodies ``{link: (m, hx, hy, hz)}`` [kg, kg m];
    ``mass_model``: the bodies are a given mass model (True) or identified lumped parameters;
    g (3,) [m/s^2] in the base frame; lateral ``{joint: (c1, c2)}`` [mrad/kNm] (the full model)."""

    compliance: dict
    bodies: dict
    mass_model: bool
    g: tuple = tuple(STANDARD_GRAVITY)
    lateral: dict | None = None

    def deflection(self, model, q, payload=None) -> np.ndarray:
        """Model-joint deflections (N, n_model) at controller joints ``q`` with ``payload``."""
        return model_joint_deflection(model, q, self.compliance, self.bodies, payload=payload, g=self.g)

    def reached_poses(self, model, q, payload=None, end_effector=None) -> np.ndarray:
        """Poses (N, 4, 4) [mm] of ``end_effector`` the deflecting robot reaches at controller joints
        ``q``: forward kinematics at the deflected joints, then the lateral rotations (as in the
        calibration's chain: torques and bending moments at the commanded joints)."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        jm = _joints_model(model).replace(T_world_base=np.eye(4))
        T = jm.fk(q @ model.coupling.T + self.deflection(model, q, payload), end_effector)
        if self.lateral:
            T = self._lateral(model, q, payload, end_effector, T)
        return model.T_world_base @ T

    def _lateral(self, model, q, payload, end_effector, T):
        from ..transforms import so3_exp

        names = [L.name for L in model.links]
        moving = [model.links[int(k)].name for k in model.moving]
        links = np.array([names.index(n) for n in self.bodies], dtype=int)
        theta = np.array(list(self.bodies.values()), dtype=float).reshape(-1, 4)
        gt = GravityTorques(_joints_model(model), q @ model.coupling.T, links, payload=payload, g=self.g, lateral=True)
        c = np.zeros((len(moving), 2))
        for n, v in self.lateral.items():
            c[moving.index(n)] = v
        ee = model.end_effector_index(end_effector)
        carried = model._ee_ancestors[ee][model.moving].astype(float)  # (n_model,)
        phi = np.einsum("nja,njai->nji", 1e-6 * c[None] * gt.lateral_moments(theta), gt.lateral_axes)
        phi = phi * carried[None, :, None]
        p = T[:, :3, 3]
        out = T.copy()
        out[:, :3, 3] = p + np.cross(phi, p[:, None, :] - gt.joint_origin).sum(axis=1)
        out[:, :3, :3] = so3_exp(phi.sum(axis=1)) @ T[:, :3, :3]
        return out


def elastic_description(problem, state) -> ElasticDescription:
    """The :class:`ElasticDescription` of an elastic :class:`~robocal.calib.CalibrationProblem` at ``state``."""
    d = problem.deflection
    if d is None:
        raise ProblemError("the problem has no elastic model")
    model = problem.model
    comp = {model.links[int(model.moving[j])].name: float(c) for j, c in zip(d.compliance.joints, state.compliance)}
    theta = d.gravity.theta(state.gravity)
    bodies = {n: tuple(float(x) for x in t) for n, t in zip(d.gravity.body_names, theta)}
    g = STANDARD_GRAVITY if d.g is None else d.g
    lateral = None
    if d.lateral is not None:
        vals = np.asarray(state.lateral, dtype=float).reshape(-1, 2)
        lateral = {model.links[int(model.moving[j])].name: (float(a), float(b)) for j, (a, b) in zip(d.lateral.joints, vals)}
    return ElasticDescription(comp, bodies, mass_model=not problem.elastic.lumped, g=tuple(float(x) for x in g),
                              lateral=lateral)
