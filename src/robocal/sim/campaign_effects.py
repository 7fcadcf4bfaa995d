"""Effects of a tracker calibration campaign that the geometric model lacks (issue 25, item 4).

A simulator identical to the model makes "the identified parameters are within 3 reported
sigma" true by construction. :class:`CampaignEffects` adds what a real campaign meets and a
DH (+ beta) model with joint offsets cannot follow, with a preset each (the pattern of
:class:`~robocal.sim.tool.barrier_effects.BarrierEffects` and the thermal presets):

* ``ideal`` -- none: the simulator is the model (plus the tracker's noise).
* ``realistic`` -- every field justified in :meth:`CampaignEffects.realistic`.

The effects, all deterministic given the seed:

* **transmission error**: the joint really turns to ``q + a1 sin(q + phi1) + a2 sin(2 q + phi2)``
  (reducer and encoder eccentricity: once and twice per output revolution; a constant offset
  is in the model, a periodic error is not);
* **warm-up of the arm**: the arm and tool grow uniformly by ``growth_ppm`` over the campaign,
  linearly in the order the poses are measured; a uniform growth scales every point about the
  robot base origin (the arm stays geometrically similar), so the position seen in the base
  frame is ``(1 + eps(t)) p``. A static growth is a length change the model absorbs; the growth
  during the campaign is not;
* **tracker scale error**: the tracker reports distances from its origin scaled by
  ``tracker_scale_ppm`` (a wrong air temperature: about 1 ppm per kelvin). It is in the
  measurements, not in where the robot really is.

:func:`measure_with_effects` returns the noisy measured points, the points the robot really
reached (the hidden truth a hold-out check compares with) and the effect-free points. Lengths mm,
angles rad unless a name says deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..transforms import invert_transforms, transform_points
from .robot import VirtualRobot, as_rng
from .tracker import LaserTracker

__all__ = ["CampaignEffects", "CAMPAIGN_PRESETS", "measure_with_effects", "grown"]

CAMPAIGN_PRESETS = ("ideal", "realistic")


@dataclass(frozen=True)
class CampaignEffects:
    """Effects of a tracker campaign outside the geometric model (zero: off).

    transmission_deg: (a1, a2) amplitudes of the joint error once and twice per output revolution
        [deg], the same for every revolute joint, phases drawn per joint from the seed;
    growth_ppm: uniform growth of arm and tool from the first to the last measured pose [ppm];
    tracker_scale_ppm: scale error of the tracker's distances from its origin [ppm].
    """

    transmission_deg: tuple = (0.0, 0.0)
    growth_ppm: float = 0.0
    tracker_scale_ppm: float = 0.0
    name: str = "custom"

    @classmethod
    def ideal(cls) -> "CampaignEffects":
        return cls(name="ideal")

    @classmethod
    def realistic(cls) -> "CampaignEffects":
        """A calibration campaign in an ordinary hall, assumed where no source is given:

        * transmission error 0.005 deg once and 0.003 deg twice per revolution: within the
          <= 1 arcmin (0.0167 deg) angular transmission error cycloidal reducer makers specify for
          robot joints (Nabtesco RV catalogue); after gravity, the largest joint-dependent error
          of a stiff arm;
        * growth 20 ppm over the campaign: an aluminium arm (23 ppm/K) warming by about 1 K while
          it moves through the poses, or a steel/cast arm (11.5 ppm/K) by 2 K (assumed: a campaign
          started after a short warm-up);
        * tracker scale 5 ppm: the air temperature at the tracker off by ~5 K (refractive index of
          air: ~0.93 ppm/K, Edlen), inside the 6 um/m distance-dependent MPE of a class AT960
          tracker (Leica datasheet).
        """
        return cls(transmission_deg=(0.005, 0.003), growth_ppm=20.0, tracker_scale_ppm=5.0, name="realistic")

    @classmethod
    def preset(cls, name) -> "CampaignEffects":
        if isinstance(name, CampaignEffects):
            return name
        if name in CAMPAIGN_PRESETS:
            return getattr(cls, name)()
        raise ValueError(f"unknown campaign preset {name!r}; choose from {', '.join(CAMPAIGN_PRESETS)}")

    def is_ideal(self) -> bool:
        """True when every effect is zero (the simulator is the model)."""
        return not any(self.transmission_deg) and not self.growth_ppm and not self.tracker_scale_ppm

    @staticmethod
    def transmission_phases(n_joints: int, rng_seed) -> np.ndarray:
        """Phases (2, n_joints) [rad] of the once / twice per revolution errors, uniform in [0, 2 pi)."""
        return as_rng(rng_seed).uniform(0.0, 2.0 * math.pi, size=(2, int(n_joints)))

    def transmission_error(self, q, phases, prismatic) -> np.ndarray:
        """Joint error (N, n_ctrl) [rad] at ``q`` (N, n_ctrl) with ``phases`` (2, n_ctrl) [rad];
        0 on the ``prismatic`` (n_ctrl,) joints."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        phases = np.asarray(phases, dtype=float)
        a1, a2 = (math.radians(float(a)) for a in self.transmission_deg)
        err = a1 * np.sin(q + phases[0]) + a2 * np.sin(2.0 * q + phases[1])
        return np.where(np.asarray(prismatic, dtype=bool), 0.0, err)

    def joint_positions(self, robot: VirtualRobot, q, rng_seed=None, *, phases=None) -> np.ndarray:
        """Joints (N, n_ctrl) the arm really reaches at commanded ``q`` (N, n_ctrl) [rad | mm]:
        the transmission error on every revolute joint, phases (2, n_ctrl) [rad] as given or
        drawn from ``rng_seed``."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        if phases is None:
            phases = self.transmission_phases(q.shape[1], rng_seed)
        return q + self.transmission_error(q, phases, robot.prismatic)

    def as_truth(self, phases) -> dict:
        """The effects and their drawn phases as written to a truth file (``campaign_effects``)."""
        return {"preset": self.name, "transmission_deg": [float(a) for a in self.transmission_deg],
                "transmission_phases_rad": np.asarray(phases, dtype=float).tolist(),
                "growth_ppm": float(self.growth_ppm), "tracker_scale_ppm": float(self.tracker_scale_ppm),
                "growth": "linear in measuring order, 0 at the first pose, growth_ppm at the last; about the "
                          "true base origin",
                "after_campaign": "robocal simulate execute: transmission error with these phases, growth "
                                  "growth_ppm (the arm as warm as at the last pose); the tracker scale is in "
                                  "the measurements only"}

    @classmethod
    def from_truth(cls, entry: dict) -> tuple:
        """``(effects, phases (2, n_ctrl) [rad])`` from a truth file's ``campaign_effects`` entry."""
        eff = cls(transmission_deg=tuple(float(a) for a in entry["transmission_deg"]),
                  growth_ppm=float(entry["growth_ppm"]), tracker_scale_ppm=float(entry["tracker_scale_ppm"]),
                  name=str(entry.get("preset", "custom")))
        return eff, np.asarray(entry["transmission_phases_rad"], dtype=float)

    def growth(self, n: int) -> np.ndarray:
        """Relative growth (n,) of the arm at each of ``n`` poses in measuring order (0 at the first)."""
        return self.growth_ppm * 1e-6 * np.linspace(0.0, 1.0, int(n)) if n > 1 else np.zeros(int(n))


def measure_with_effects(robot: VirtualRobot, tracker: LaserTracker, q, effects, rng_seed, *, phases=None) -> dict:
    """Measure a campaign of poses ``q`` (N, n_ctrl), in this order, with ``effects``.

    The robot's encoder noise is not added (the transmission error is the joint error here);
    tracker noise ``tracker.sigma_at`` per coordinate. ``rng_seed`` seeds the phases and the noise.

    phases: (2, n_ctrl) [rad] of the transmission error; default: drawn first from ``rng_seed``.

    Returns ``{"points": measured (N, k, 3), "reached": where the reflectors really were
    (N, k, 3), "model": the effect-free points of the true geometric robot (N, k, 3), "phases":
    (2, n_ctrl) [rad]}``, points in the tracker frame [mm].
    """
    effects = CampaignEffects.preset(effects)
    rng = as_rng(rng_seed)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    model = tracker.true_points(robot, q)
    if phases is None:
        phases = effects.transmission_phases(q.shape[1], rng)
    q_real = effects.joint_positions(robot, q, phases=phases)
    # the base frame in the tracker frame: the growth scales points about the base origin
    T_tracker_base = tracker.T_tracker_world @ robot.true_model.T_world_base
    p_base = transform_points(invert_transforms(T_tracker_base)[None, None], tracker.true_points(robot, q_real))
    p_base = p_base * (1.0 + effects.growth(len(q)))[:, None, None]
    reached = transform_points(T_tracker_base[None, None], p_base)
    seen = reached * (1.0 + effects.tracker_scale_ppm * 1e-6)
    points = seen + rng.standard_normal(seen.shape) * tracker.sigma_at(seen)[..., None]
    return {"points": points, "reached": reached, "model": model, "phases": np.asarray(phases)}


def grown(T_world_x, T_world_base, growth) -> np.ndarray:
    """Poses ``T_world_x`` (..., 4, 4) [mm] of an arm grown uniformly by the relative ``growth``
    (scalar or (...,)): positions scaled about the base origin, orientations unchanged."""
    T = np.array(T_world_x, dtype=float)
    T_wb = np.asarray(T_world_base, dtype=float)
    p_base = np.einsum("ij,...j->...i", np.linalg.inv(T_wb)[:3, :3], T[..., :3, 3]) + np.linalg.inv(T_wb)[:3, 3]
    p_base = p_base * (1.0 + np.asarray(growth, dtype=float))[..., None]
    T[..., :3, 3] = np.einsum("ij,...j->...i", T_wb[:3, :3], p_base) + T_wb[:3, 3]
    return T
