"""Small seeded set-ups for the residual blocks' ``example`` factories (finite-difference tests).

A 4-joint robot with random DH + beta geometry and two end effectors, random poses, and the
parameter blocks of a chain, all built from the numpy ``Generator`` passed in.
"""

from __future__ import annotations

import numpy as np

from ...kinematics.links import Link
from ...kinematics.model import EndEffector, RobotModel
from ...transforms import so3_exp
from ..blocks import RobotGeometry, StationFrames, TargetPoints
from ..blocks.elastic import GravityParameters, JointCompliance, LateralCompliance
from .chain import TargetChain
from .deflection import Deflection

__all__ = ["example_robot", "example_frames", "example_chain", "example_elastic_chain",
           "example_full_elastic_chain"]


def example_robot(rng, n_joints: int = 4) -> RobotModel:
    """A random ``dh_beta`` arm (lengths ~100-500 mm) with end effectors ``flange`` and ``side``."""
    links = []
    for i in range(n_joints):
        params = {"theta": rng.uniform(-0.3, 0.3), "d": rng.uniform(0, 300), "a": rng.uniform(100, 500),
                  "alpha": rng.choice([-1.0, 1.0]) * np.pi / 2 + rng.normal(0, 0.01), "beta": rng.normal(0, 0.01)}
        links.append(Link(f"l{i + 1}", "revolute", "dh_beta", params, i - 1))
    T_side = np.eye(4)
    T_side[:3, :3] = so3_exp(rng.normal(0, 0.5, 3))
    T_side[:3, 3] = rng.normal(0, 50, 3)
    return RobotModel(name="example", kind="dh_beta", links=links,
                      controller_joints=tuple(f"j{i + 1}" for i in range(n_joints)),
                      coupling=np.eye(n_joints), limits=np.tile([-np.pi, np.pi], (n_joints, 1)),
                      T_world_base=np.eye(4), end_effectors=[EndEffector("flange", n_joints - 1, np.eye(4)),
                                                             EndEffector("side", n_joints - 2, T_side)])


def example_frames(rng, n: int) -> np.ndarray:
    """(n, 4, 4) random frames, rotations of ~1 rad, origins ~1000 mm."""
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = so3_exp(rng.normal(0, 0.6, (n, 3)))
    T[:, :3, 3] = rng.normal(0, 1000, (n, 3))
    return T


def example_chain(rng, n_poses: int = 6, n_stations: int = 2, n_targets: int = 2) -> TargetChain:
    """A :class:`TargetChain` on :func:`example_robot`: every parameter, frame and point free."""
    model = example_robot(rng)
    q = rng.uniform(-2.0, 2.0, (n_poses, model.n_joints))
    geometry = RobotGeometry(model, model.params.names)
    frames = StationFrames(example_frames(rng, n_stations))
    ees = ["flange", "side"] * n_targets
    targets = TargetPoints([f"t{k}" for k in range(n_targets)], rng.normal(0, 80, (n_targets, 3)),
                           end_effectors=ees[:n_targets])
    stations = np.arange(n_poses) % n_stations
    return TargetChain(model, q, geometry, frames, targets, stations=stations)


def example_elastic_chain(rng, n_poses: int = 6, n_stations: int = 2, n_targets: int = 2,
                          lateral: bool = False) -> TargetChain:
    """:func:`example_chain` with a gravity-induced joint deflection: every joint compliant
    (~50-500 mrad/kNm: deflections of a few mrad), lumped gravity parameters of every link free
    (~5-30 kg, first moments ~1-5 kg m) and a payload on the flange, all free; with ``lateral``
    also two lateral compliances per joint (~20-200 mrad/kNm)."""
    chain = example_chain(rng, n_poses, n_stations, n_targets)
    model = chain.model
    n = len(model.moving)
    compliance = JointCompliance(model, np.arange(n), rng.uniform(50.0, 500.0, n))
    theta = np.column_stack([rng.uniform(5.0, 30.0, n), rng.normal(0.0, 3.0, (n, 3))])
    gravity = GravityParameters(model, model.moving, theta)
    payload = ("flange", rng.uniform(1.0, 10.0, n_poses), rng.normal(0.0, 100.0, (n_poses, 3)))
    g = rng.normal(0.0, 0.3, 3) + np.array([0.0, 0.0, -9.81])
    lat = LateralCompliance(model, np.arange(n), rng.uniform(20.0, 200.0, 2 * n)) if lateral else None
    deflection = Deflection(model, chain.q, compliance, gravity, payload=payload, g=g, lateral=lat)
    return TargetChain(model, chain.q, chain.geometry, chain.frames, chain.targets, stations=chain.stations,
                       deflection=deflection)


def example_full_elastic_chain(rng, n_poses: int = 6, n_stations: int = 2, n_targets: int = 2) -> TargetChain:
    """:func:`example_elastic_chain` with lateral compliances too (the ``full`` elastic model)."""
    return example_elastic_chain(rng, n_poses, n_stations, n_targets, lateral=True)
