"""Realism of the light-barrier cell (issue 11): what the tool-frame methods meet on a real robot.

:class:`BarrierEffects` gathers the cell's error sources with a preset each:

* ``ideal`` -- the cell of the tool-recalibration study before: 1 kHz I/O, 2 ms constant
  latency, 0.1 mm repeatability, a robot that goes exactly where the controller believes, clean
  beams, a perfectly round tool whose cylinder is coaxial with its tip; the check is the truth.
* ``realistic`` -- every field justified in :meth:`BarrierEffects.realistic`.

:class:`RobotAccuracy` is the robot's absolute error: the controller converts a Cartesian pose
to joints with its model (the nominal UR10 after a calibration) and the arm follows its true
geometry; the error is evaluated at a few poses of every motion (numerical IK) and interpolated
in time. :class:`MeasuringArm` checks a tool's tip as an articulated measuring arm registered to
the robot base does. :func:`cell_realism` draws one cell's realism. Lengths mm, times s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...transforms import invert_transforms, so3_exp, so3_log
from .barrier_geometry import BeamDirt
from ..robot import VirtualRobot, as_rng

__all__ = ["BarrierEffects", "RobotAccuracy", "MeasuringArm", "cell_realism", "BARRIER_PRESETS"]

BARRIER_PRESETS = ("ideal", "realistic")


@dataclass(frozen=True)
class BarrierEffects:
    """Error sources of a light-barrier cell (zero: off). io_rate_hz, latency_s: the controller's
    I/O clock and its constant delay; latency_jitter_s: a further delay uniform in 0..jitter per
    event; repeatability_mm: ISO 9283 pose repeatability; robot_length_sigma_mm /
    robot_angle_sigma_deg: the true geometry's deviation from the controller's calibrated model
    (absolute error); dirt_fraction_max / beam_width_mm: each beam's optics dirty by a share
    uniform in 0..max on the lower side; runout_mm / runout_deg: the tool cylinder's eccentricity
    and tilt against its tip; arm_noise_mm (per coordinate) and arm_registration_mm /
    arm_registration_deg: the measuring arm of the check and its registration to the robot base."""

    io_rate_hz: float = 1000.0
    latency_s: float = 0.002
    latency_jitter_s: float = 0.0
    repeatability_mm: float = 0.1
    robot_length_sigma_mm: float = 0.0
    robot_angle_sigma_deg: float = 0.0
    dirt_fraction_max: float = 0.0
    beam_width_mm: float = 2.0
    runout_mm: float = 0.0
    runout_deg: float = 0.0
    arm_noise_mm: float = 0.0
    arm_registration_mm: float = 0.0
    arm_registration_deg: float = 0.0
    name: str = "custom"

    @classmethod
    def ideal(cls) -> "BarrierEffects":
        return cls(name="ideal")

    @classmethod
    def realistic(cls) -> "BarrierEffects":
        """The thesis's cell (5.2.1) as far as it is described, the rest assumed:

        * UR10 (thesis), repeatability 0.1 mm (thesis); its CB3 controller runs at 125 Hz (8 ms;
          Universal Robots), the I/O seen one cycle late plus up to one more cycle of jitter
          (assumed: the barrier signal is not synchronised with the controller cycle);
        * absolute error after a calibration: 0.1 mm / 0.01 deg per parameter (assumed; gives
          0.2-0.4 mm absolute position error over the workspace, typical of a calibrated UR10);
        * laser tubes of 12 mm diameter (thesis): a 2 mm beam, dust covering up to 30 % of it on
          the lower side (assumed);
        * a precision-machined nozzle (thesis): 0.02 mm eccentricity, 0.02 deg tilt (assumed);
        * ROMER absolute arm (thesis): 0.025 mm per coordinate at a probed cone (the maker's
          single-point figure, ~0.04 mm 3-D), registered to the base to 0.05 mm / 0.003 deg
          (assumed: through robot poses, so it inherits part of the robot's absolute error).
        """
        return cls(io_rate_hz=125.0, latency_s=0.008, latency_jitter_s=0.008, repeatability_mm=0.1,
                   robot_length_sigma_mm=0.1, robot_angle_sigma_deg=0.01, dirt_fraction_max=0.3, beam_width_mm=2.0,
                   runout_mm=0.02, runout_deg=0.02, arm_noise_mm=0.025, arm_registration_mm=0.05,
                   arm_registration_deg=0.003, name="realistic")

    @classmethod
    def preset(cls, name) -> "BarrierEffects":
        if isinstance(name, BarrierEffects):
            return name
        if name in BARRIER_PRESETS:
            return getattr(cls, name)()
        raise ValueError(f"unknown cell preset {name!r}; choose from {', '.join(BARRIER_PRESETS)}")

    def cell_kwargs(self) -> dict:
        """The clock and noise keywords of :class:`~robocal.sim.tool.light_barrier.LightBarrierCell`."""
        return {"io_rate_hz": self.io_rate_hz, "latency_s": self.latency_s, "repeatability_mm": self.repeatability_mm,
                "latency_jitter_s": self.latency_jitter_s}


class RobotAccuracy:
    """The robot's absolute error: ``nominal`` is the controller's model, ``true_model`` the arm.

    :meth:`apply` moves actual flange poses (base frame) by the error the commanded poses of the
    motion have at ``n_samples`` instants (numerical IK of the nominal model from the last
    solution, or from ``q_seed`` if that fails; FK of the true model), interpolated in time.
    ``reach_errors_mm``: the worst IK position error per motion (inf: not reached)."""

    def __init__(self, nominal, true_model, q_seed, n_samples: int = 5):
        self.nominal, self.true_model = nominal, true_model
        self._q = self._home = np.asarray(q_seed, float)
        self.n_samples = int(n_samples)
        self._Tbw = invert_transforms(nominal.T_world_base)
        self.reach_errors_mm: list = []

    def errors(self, T_cmd):
        """(rotation vectors (K, 3) [rad], shifts (K, 3) [mm]) taking commanded flange poses
        (K, 4, 4) to the true ones: ``R_true = exp(w) R_cmd``, ``p_true = p_cmd + d``."""
        from ...kinematics import ik_numeric

        T_cmd = np.asarray(T_cmd, float)
        target = self.nominal.T_world_base @ T_cmd
        res = ik_numeric(self.nominal, target, self._q)
        if not res.all_converged:                                  # lost the branch: start from home
            res = ik_numeric(self.nominal, target, self._home)
        if res.all_converged:
            self._q = res.q[-1]
        self.reach_errors_mm.append(float(np.max(res.position_error_mm)) if res.all_converged else math.inf)
        T_true = self._Tbw @ self.true_model.fk(res.q)
        w = so3_log(T_true[:, :3, :3] @ np.transpose(T_cmd[:, :3, :3], (0, 2, 1)))
        return w, T_true[:, :3, 3] - T_cmd[:, :3, 3]

    def apply(self, motion, t, T):
        """Actual poses ``T`` (N, 4, 4) at motion times ``t`` (N,) [s] moved by the absolute error."""
        ts = np.linspace(0.0, float(motion.duration_s), self.n_samples)
        w, d = self.errors(motion.poses(ts))
        wt = np.stack([np.interp(t, ts, w[:, i]) for i in range(3)], axis=1)
        dt = np.stack([np.interp(t, ts, d[:, i]) for i in range(3)], axis=1)
        out = np.array(T, float, copy=True)
        out[:, :3, 3] += dt
        out[:, :3, :3] = so3_exp(wt) @ out[:, :3, :3]
        return out


class MeasuringArm:
    """A measuring arm registered to the robot base: reports a base-frame point with a fixed
    registration error (``T_error``, drawn once) and fresh noise per probe."""

    def __init__(self, noise_mm: float, registration_mm: float, registration_deg: float, rng):
        rng = as_rng(rng)
        self.rng = rng
        self.noise_mm = float(noise_mm)
        self.T_error = np.eye(4)
        self.T_error[:3, :3] = so3_exp(rng.normal(0.0, math.radians(registration_deg) / math.sqrt(3.0), 3))
        self.T_error[:3, 3] = rng.normal(0.0, registration_mm / math.sqrt(3.0), 3)

    def probe(self, p_base) -> np.ndarray:
        """The arm's reading (3,) [mm, base frame as registered] of the true point ``p_base`` (3,)."""
        p = self.T_error[:3, :3] @ np.asarray(p_base, float) + self.T_error[:3, 3]
        return p + self.rng.normal(0.0, self.noise_mm, 3) if self.noise_mm > 0 else p


def cell_realism(effects: BarrierEffects, beams: dict, rng, *, robot=None, q_seed=None) -> dict:
    """One cell's drawn realism as keywords of :class:`~robocal.sim.tool.light_barrier.LightBarrierCell`
    (besides :meth:`BarrierEffects.cell_kwargs`): ``accuracy`` (a :class:`RobotAccuracy` if the
    effects have an absolute error and ``robot``, the nominal model, is given) and ``dirt``
    (``{beam: BeamDirt}``, share uniform in 0..max, on the lower side of the beam)."""
    rng = as_rng(rng)
    out = {}
    if robot is not None and (effects.robot_length_sigma_mm > 0 or effects.robot_angle_sigma_deg > 0):
        true = VirtualRobot.perturbed(robot, rng, length_sigma_mm=effects.robot_length_sigma_mm,
                                      angle_sigma_deg=effects.robot_angle_sigma_deg,
                                      offset_sigma_deg=effects.robot_angle_sigma_deg).true_model
        out["accuracy"] = RobotAccuracy(robot, true, q_seed)
    if effects.dirt_fraction_max > 0:
        dirt = {}
        for name, beam in beams.items():
            down = np.array([0.0, 0.0, -1.0]) - beam.direction * -beam.direction[2]
            side = down if np.linalg.norm(down) > 1e-6 else np.cross(beam.direction, [1.0, 0.0, 0.0])
            dirt[name] = BeamDirt(float(rng.uniform(0.0, effects.dirt_fraction_max)), effects.beam_width_mm, side)
        out["dirt"] = dirt
    return out
