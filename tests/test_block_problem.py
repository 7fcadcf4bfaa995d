"""A calibration problem built directly from parameter blocks and residual blocks: the same numbers
as the CalibrationProblem builder, per-variable free masks, Gaussian priors, unit vectors,
identifiability per block, clear errors."""

import numpy as np
import pytest

from robocal.calib import CalibrationProblem, Problem, ProblemError, Target, solve
from robocal.calib.blocks import (
    GaussianPrior,
    Planes,
    RobotGeometry,
    StationFrames,
    TargetPoints,
    UnitVectorsBlock,
    VectorBlock,
)
from robocal.calib.residuals import DistanceResidual, PointOnPlaneResidual, PointResidual, TargetChain
from robocal.robots import load_robot
from robocal.sim import LaserTracker, VirtualRobot
from robocal.transforms import so3_exp


def _campaign(seed=3, n=60, sigma=0.02):
    nominal = load_robot("kuka_kr150_r3100")
    robot = VirtualRobot.perturbed(nominal, seed, joint_noise_deg=0.0)
    tracker = LaserTracker.placed(seed + 1, reflectors=np.array([[30.0, 40.0, 100.0]]), sigma_mm=sigma)
    rng = np.random.default_rng(seed + 2)
    q = robot.random_configurations(n, rng, margin=0.1)
    return nominal, robot, tracker, q, tracker.measure(robot, q, rng).points


def test_blocks_built_by_hand_give_the_builders_numbers():
    nominal, robot, tracker, q, pts = _campaign()
    stations = np.arange(len(q)) % 2
    base = np.tile(tracker.T_tracker_world @ nominal.T_world_base, (2, 1, 1))
    dist = [(0, 1, 0, 700.0), (2, 9, 0, 900.0)]
    contacts = [(3, 0, 0), (8, 0, 0)]
    built = CalibrationProblem(nominal, q, [Target("r1", None, (0.0, 0.0, 50.0))], pts, stations=stations,
                               base_initial=base, point_sigma_mm=0.02, distances=dist, on_plane=contacts,
                               planes_initial=[[0.1, 1.3, 500.0]])
    geometry = RobotGeometry(nominal)
    frames = StationFrames(base)
    targets = TargetPoints(["r1"], [[0.0, 0.0, 50.0]])
    planes = Planes([[0.1, 1.3, 500.0]])
    chain = TargetChain(nominal, q, geometry, frames, targets, stations=stations)
    by_hand = Problem([geometry, frames, targets, planes],
                      [PointResidual(chain, pts, 0.02), DistanceResidual(chain, dist, 0.02),
                       PointOnPlaneResidual(chain, planes, contacts, 0.02)])
    assert by_hand.names == built.names and by_hand.units == built.units
    assert list(by_hand.blocks) == list(built.blocks)
    step = np.random.default_rng(4).normal(0, 1e-3, built.n_variables)
    r1, J1, lab1 = built.evaluate(built.retract(built.initial_state(), step))
    r2, J2, lab2 = by_hand.evaluate(by_hand.retract(by_hand.initial_state(), step))
    np.testing.assert_allclose(r1, r2, rtol=1e-12, atol=1e-12)  # the same blocks, built two ways
    np.testing.assert_allclose(J1, J2, rtol=1e-12, atol=1e-12)
    assert np.array_equal(lab1[:, 0], lab2[:, 0])
    assert [built.kinds[c] for c in lab1[:, 1]] == [by_hand.kinds[c] for c in lab2[:, 1]]
    assert by_hand.row_label(len(r2) - 1)[:2] == (8, "plane")
    res = solve(by_hand, max_iterations=3)  # made-up distances and plane: only the plumbing is checked
    assert np.array_equal(res.model.T_world_base, res.value("base")[0])
    assert np.array_equal(res.model.params.values, res.value(geometry))


def test_fixing_named_variables_of_a_block():
    nominal, robot, tracker, q, pts = _campaign()
    T_true = tracker.T_tracker_world @ robot.true_model.T_world_base
    base = T_true.copy()
    base[:3, 3] += [2.0, -1.0, 0.5]
    geometry = RobotGeometry(nominal, ["a2", "a3", "d4", "theta2", "theta3"])
    frames = StationFrames(base, free=["base.x", "base.y", "base.z"])  # orientation known
    targets = TargetPoints(["r1"], [[30.0, 40.0, 100.0]], free=False)
    chain = TargetChain(nominal, q, geometry, frames, targets)
    prob = Problem([geometry, frames, targets], [PointResidual(chain, pts, 0.02)])
    assert prob.names == ("a2", "a3", "d4", "theta2", "theta3", "base.x", "base.y", "base.z")
    res = solve(prob)
    R_end = prob.value(res.state, "base")[0, :3, :3]
    assert np.array_equal(R_end, base[:3, :3])  # fixed rotation untouched
    assert np.array_equal(prob.value(res.state, targets), targets.initial)
    assert res.converged


def test_a_gaussian_prior_adds_rows_and_pulls_towards_its_mean():
    nominal, robot, tracker, q, pts = _campaign(n=40)
    base = tracker.T_tracker_world @ nominal.T_world_base
    a2 = nominal.params.index("a2")

    def fit(prior):
        geometry = RobotGeometry(nominal, ["a2", "a3", "theta2"], prior=prior)
        frames = StationFrames(base)
        targets = TargetPoints(["r1"], [[30.0, 40.0, 100.0]])
        chain = TargetChain(nominal, q, geometry, frames, targets)
        prob = Problem([geometry, frames, targets], [PointResidual(chain, pts, 0.02)])
        return prob, solve(prob, loss="huber")

    mean = nominal.params.values.copy()
    mean[a2] += 1.0  # a prior 1 mm off the nominal a2, very tight
    free_prob, free_res = fit(None)
    tight_prob, tight_res = fit(GaussianPrior(sigma=[1e-4, 10.0, 10.0], mean=mean))
    assert tight_prob.n_residuals == free_prob.n_residuals + 3
    assert np.all(tight_prob.labels[-3:, 0] == -1) and tight_prob.kinds[tight_prob.labels[-1, 1]] == "prior"
    assert abs(free_res.state[0][a2] - mean[a2]) > 0.5
    assert abs(tight_res.state[0][a2] - mean[a2]) < 1e-3
    assert tight_res.std[0] < 1e-4  # the prior dominates a2's uncertainty
    assert free_res.converged and tight_res.converged


def test_unit_vector_block_fits_a_direction():
    """A toy problem on the unit-vector manifold: points along a line through a known origin."""
    from robocal.calib.residuals import ResidualBlock

    class AlongLine(ResidualBlock, register=False):
        kind = "line"

        def __init__(self, block, t, measured):
            super().__init__((block,), np.repeat(np.arange(len(t)), 3), 0.01)
            self.block, self.t, self.measured = block, t, measured

        def evaluate(self, ev, jacobian):
            u = ev[self.block][0]
            r = ((self.measured - self.t[:, None] * u) * self.weight).ravel()
            if not jacobian:
                return r, None
            du = self.block.derivative(ev[self.block])[0]  # (3, 2)
            return r, {self.block: (self.t[:, None, None] * du).reshape(-1, 2) * self.weight}

    rng = np.random.default_rng(7)
    truth = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    t = rng.uniform(100, 1000, 30)
    meas = t[:, None] * truth + rng.normal(0, 0.01, (30, 3))
    block = UnitVectorsBlock("axis", [1.0, 0.0, 0.0])
    prob = Problem([block], [AlongLine(block, t, meas)])
    assert prob.names == ("axis.azimuth", "axis.elevation")
    res = solve(prob)
    u = prob.value(res.state, block)[0]
    assert abs(np.linalg.norm(u) - 1.0) < 1e-12
    assert np.degrees(np.arccos(min(1.0, u @ truth))) < 0.01
    assert res.values[0] == pytest.approx(np.arctan2(truth[1], truth[0]), abs=1e-4)
    assert np.all(res.std < 1e-4)


def test_identifiability_is_reported_per_block():
    nominal, robot, tracker, q, pts = _campaign()
    prob = CalibrationProblem(nominal, q, [Target("r1", None, (0.0, 0.0, 50.0))], pts, point_sigma_mm=0.02,
                              base_initial="fit")
    res = solve(prob)
    per = res.identifiability.by_block()
    assert list(per) == ["geometry", "base", "targets"]
    assert {d["name"] for d in per["geometry"]["dropped"]} >= {"theta1", "d1"}
    assert all(d["block"] == "geometry" for d in per["geometry"]["dropped"])
    assert len(per["base"]["identifiable"]) == 6 and len(per["targets"]["identifiable"]) == 3


def test_bad_block_set_ups_name_the_problem():
    blk = VectorBlock("p", ["p.x"], ["mm"], [0.0])
    other = VectorBlock("q", ["p.x"], ["mm"], [0.0])
    with pytest.raises(ProblemError, match="used twice: p.x"):
        Problem([blk, other], [])
    with pytest.raises(ProblemError, match="duplicate block names"):
        Problem([blk, VectorBlock("p", ["z"], ["mm"], [0.0])], [])
    nominal = load_robot("ur10")
    geometry = RobotGeometry(nominal, ["a2"])
    frames = StationFrames(np.eye(4))
    targets = TargetPoints(["r1"], [[0.0, 0.0, 10.0]])
    chain = TargetChain(nominal, np.zeros((3, 6)), geometry, frames, targets)
    with pytest.raises(ProblemError, match="reads the parameter block 'targets'"):
        Problem([geometry, frames], [PointResidual(chain, np.zeros((3, 1, 3)))])
    with pytest.raises(ProblemError, match="did you mean 'base.rx'"):
        StationFrames(np.eye(4), free=["base.rz", "base.rxx"])
    with pytest.raises(ProblemError, match="no measurements"):
        Problem([geometry], []).evaluate((nominal.params.values,))
    with pytest.raises(ProblemError, match="no parameter block named 'tool'"):
        Problem([geometry], []).value((nominal.params.values,), "tool")


def test_frames_and_unit_vectors_retract_on_their_manifolds():
    rng = np.random.default_rng(11)
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, :3, :3] = so3_exp(rng.normal(0, 1, (3, 3)))
    frames = StationFrames(T)
    T2 = frames.retract(T, rng.normal(0, 0.3, 18))
    R = T2[:, :3, :3]
    assert np.allclose(R @ np.swapaxes(R, 1, 2), np.eye(3), atol=1e-12) and np.allclose(np.linalg.det(R), 1.0)
    assert np.array_equal(frames.retract(T, np.zeros(18)), T)
    u = UnitVectorsBlock("u", rng.normal(0, 1, (4, 3)))
    u2 = u.retract(u.initial, rng.normal(0, 0.5, 8))
    assert np.allclose(np.linalg.norm(u2, axis=1), 1.0, atol=1e-14)
    # pole: the tangent basis stays defined
    pole = UnitVectorsBlock("n", [0.0, 0.0, 1.0])
    assert np.allclose(np.linalg.norm(pole.retract(pole.initial, [0.1, -0.2]), axis=1), 1.0)


def test_the_robot_chain_runs_once_per_evaluation_for_all_kinds_that_share_it(monkeypatch):
    nominal, robot, tracker, q, pts = _campaign(n=12)
    prob = CalibrationProblem(nominal, q, [Target("r1", None, (0.0, 0.0, 50.0))], pts, point_sigma_mm=0.02,
                              base_initial="fit", distances=[(0, 1, 0, 700.0)], on_plane=[(3, 0, 0)],
                              planes_initial=[[0.1, 1.3, 500.0]])
    calls = []
    original = type(nominal).target_points

    def counted(self, *a, **k):
        calls.append(1)
        return original(self, *a, **k)

    monkeypatch.setattr(type(nominal), "target_points", counted)
    state = prob.initial_state()
    prob.evaluate(state)
    assert len(calls) == 1  # points, distances and the plane contact read one chain evaluation
    prob.evaluate(state, jacobian=False)
    assert len(calls) == 2
