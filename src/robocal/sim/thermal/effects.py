"""Effects of the thermal simulator that the compensation model does not contain (issue 11).

The compensation identifies a few of the 24 free DH + beta parameters from sphere differences
(thesis 3.1); everything here is *outside* that model, or bends its assumptions. Each effect is
a frozen dataclass; :class:`ThermalEffects` holds one of each, ``None`` meaning off, so every
effect is switchable (``ThermalEffects.realistic().without("hall")``). Presets:

* ``ideal`` -- every effect off: the simulator of before (first-order heat with one time
  constant per motor, drift exactly in the span of the parameter directions, constant-variance
  noise, no outliers); bit-identical to it.
* ``realistic`` -- every effect on, each number justified in its class docstring from the thesis
  text (``thesis:``) or, where the thesis is silent, from a named engineering source or
  assumption (``assumed:``). docs/thermal.md ("Realism") tabulates them.

Units: mm, rad (``_deg`` / ``_urad`` names say otherwise), s, K.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

__all__ = [
    "HeatResponse", "HallTemperature", "LinkDeformation", "JointErrors", "SensorNoise", "Outliers",
    "ThermalEffects", "PRESETS", "thermal_effects",
]


@dataclass(frozen=True)
class HeatResponse:
    """Nonlinear heating and cooling with two time constants and a cycle-dependent duty.

    Each motor's temperature rise is the sum of a fast mode (motor winding and gearbox oil,
    share ``fast_share``, time constant ``fast_tau_s``) and a slow mode (the arm casting, the
    motor's own ~1 h constant times ``slow_tau_scale``). Heat input grows as ``load **
    load_exponent`` (copper losses ~ torque squared, friction ~ speed: between 1 and 2); the loss
    grows faster than linearly with the rise (``loss_nonlinearity``: convection and radiation),
    normalised so a motor at full load still settles at its gain. Every cycle runs one of
    ``n_programs`` programs whose per-joint duty is drawn in ``1 +- duty_spread``: the joints do
    not heat in fixed proportions, so the drift direction wanders.

    thesis: "heat concentrates in joints 2, 3, 4" (fig. 3-1a) and the robot lives in a
    "heating - steady - cooling" cycle (ch. 3 intro); the line builds several car models (1.2).
    assumed: 10-min winding/oil constant and ~30 % share (motor data sheets: thermal time
    constants of servo windings 5-20 min); exponent 1.5; 30 % stronger loss at the steady state;
    3 programs, +-30 % duty.
    """

    fast_share: float = 0.3
    fast_tau_s: float = 600.0
    slow_tau_scale: float = 1.3
    load_exponent: float = 1.5
    loss_nonlinearity: float = 0.3
    n_programs: int = 3
    duty_spread: float = 0.3


@dataclass(frozen=True)
class HallTemperature:
    """The hall temperature and what follows it: the robot base, the sensor stand, the arm and
    the car body.

    Hall temperature change since the cold start: a daily sine of ``amplitude_K`` (start phase
    drawn per run) plus an Ornstein-Uhlenbeck wander (``wander_K`` rms, ``wander_tau_s``). It
    expands every length of the arm uniformly (``arm_expansion_per_K``, cast aluminium) -- a
    drift in the model's span but not tied to the motors --, tilts the robot base about a seeded
    horizontal axis (``base_tilt_urad_per_K``) and lifts it (``base_lift_mm_per_K``), moves the
    fixed sensor's stand (``sensor_shift_mm_per_K`` up, ``sensor_tilt_urad_per_K``), and expands
    the steel car body about its centre (``body_expansion_per_K``). Base and sensor motion are
    outside the model (``T_sensor_base`` is calibrated once).

    thesis: silent on the hall; the sphere is tungsten carbide "with a very low expansion" (5.1.1)
    so it is not drifted. assumed: a non-air-conditioned body shop swings 3 K per day (+-1.5 K);
    aluminium 23e-6/K, steel 11.5e-6/K; a 1 m steel sensor stand; slab tilt 2 urad/K.
    """

    amplitude_K: float = 1.5
    period_s: float = 86400.0
    wander_K: float = 0.2
    wander_tau_s: float = 3600.0
    arm_expansion_per_K: float = 23e-6
    base_tilt_urad_per_K: float = 2.0
    base_lift_mm_per_K: float = 0.006
    sensor_shift_mm_per_K: float = 0.012
    sensor_tilt_urad_per_K: float = 3.0
    body_expansion_per_K: float = 11.5e-6


@dataclass(frozen=True)
class LinkDeformation:
    """Heat-driven deformation of the arm: a bending field over the links, and a gravity sag
    that changes with temperature (:mod:`robocal.sim.thermal.deformation`).

    Along link i the temperature rise runs linearly from its proximal motor (joint i) to its
    distal one (joint i+1); across the section the motor side is warmer by ``gradient_share``
    of the local rise. The non-uniform expansion (coefficient ``expansion_per_K``) of a section
    ``section_depth_mm`` deep curves the link, ``kappa(s) = expansion g T(s) / depth``, about a
    link-fixed axis drawn per cell; integrated along the link it rotates and deflects the distal
    joint. Being body-fixed, this bending moves the joint axes against each other, which the
    kinematic parameters describe: measured, almost all of it is in the span of the 24 free DH +
    beta parameters. The part that is not a parameter change is the sag: joint j deflects under
    the gravity torque of the arm beyond it; calibrated cold, that sag is in the model, but the
    warm gearbox is softer -- its compliance grows by ``sag_change_per_K`` per kelvin of the
    motor's rise --, so the pose-dependent deflection ``sag_rad[j] tau_j(q) / tau_ref_j`` grows
    with the heat, differently in every pose.

    thesis: links "expand and deform" (3 intro, 2.2.4: a small tilt of Z_i moves the common
    normal far); fig. 3-1b shows the three coordinates drifting differently. assumed: motor side
    5 % warmer than the local rise, 250 mm sections (KR150 arm castings), aluminium; cold sag
    0.5 / 0.3 mrad at joints 2 / 3 at full lever (1.5 mm at 3 m, a heavy robot's static
    deflection) and 0.2 %/K softer gearboxes (lubricant and bearing preload).
    """

    gradient_share: float = 0.05
    section_depth_mm: float = 250.0
    expansion_per_K: float = 23e-6
    sag_rad: tuple = (0.0, 5e-4, 3e-4, 0.0, 0.0, 0.0)
    sag_change_per_K: float = 0.002


@dataclass(frozen=True)
class JointErrors:
    """Backlash: joint j stands ``backlash_deg[j]`` on the side it was approached from. Each pose
    of a measurement program has a fixed approach side per joint; in a cycle each side flips with
    ``flip_probability`` (the production move before the measurement differs between programs).
    Joint-angle noise stays the cell's ``joint_noise_deg``.

    thesis: silent on the KR150's repeatability. assumed: KUKA's data sheet gives +-0.06 mm
    (ISO 9283) for the KR 150 R3100; lost motion of the gravity-loaded joints 2-3 is small
    (preloaded), 0.0006 deg (0.03 mm at 3 m) on the others.
    """

    backlash_deg: tuple = (0.0006, 0.0002, 0.0002, 0.0006, 0.0006, 0.0006)
    flip_probability: float = 0.15


@dataclass(frozen=True)
class SensorNoise:
    """Noise that grows with the distance from the sensor: lateral ``~ z``, depth ``~ z**2``
    (stereo triangulation), ``*_lateral_mm`` / ``*_depth_mm`` standard deviations at the
    reference distance ``*_ref_mm`` along the sensor's optical (z) axis.

    thesis: the stereo fringe sensor works at 700 mm (570 x 430 mm field) and measures a ball
    bar with -0.02 mm radius and -0.018 mm distance error (5.1.1): 0.012 / 0.03 mm at 700 mm give
    0.02 mm rms per coordinate. assumed: feature holes on sheet metal measured by the robot-held
    sensor at 250 mm: 0.02 / 0.04 mm.
    """

    sphere_lateral_mm: float = 0.012
    sphere_depth_mm: float = 0.03
    sphere_ref_mm: float = 700.0
    monitor_lateral_mm: float = 0.02
    monitor_depth_mm: float = 0.04
    monitor_ref_mm: float = 250.0


@dataclass(frozen=True)
class Outliers:
    """Occasional gross errors: a bad sphere fit (dust, a reflection, partial occlusion) with
    ``sphere_probability`` per measurement, a bad feature-hole fit with ``monitor_probability``;
    the error has a random direction and a magnitude uniform in the ``*_range_mm``.

    thesis: table 5-2's percentages are of 88, 85 and 77 directions out of 34 x 3 = 102: real
    monitored measurements fail and were dropped. assumed: 1 % / 0.5 %, 0.1-0.4 / 0.1-0.3 mm.
    """

    sphere_probability: float = 0.003
    sphere_range_mm: tuple = (0.05, 0.2)
    monitor_probability: float = 0.005
    monitor_range_mm: tuple = (0.1, 0.3)


_EFFECTS = ("heat", "hall", "deformation", "joints", "noise", "outliers")


@dataclass(frozen=True)
class ThermalEffects:
    """One optional instance of each effect (``None``: off). ``name``: the preset's name."""

    heat: HeatResponse | None = None
    hall: HallTemperature | None = None
    deformation: LinkDeformation | None = None
    joints: JointErrors | None = None
    noise: SensorNoise | None = None
    outliers: Outliers | None = None
    name: str = "custom"

    @classmethod
    def ideal(cls) -> "ThermalEffects":
        return cls(name="ideal")

    @classmethod
    def realistic(cls) -> "ThermalEffects":
        return cls(HeatResponse(), HallTemperature(), LinkDeformation(), JointErrors(), SensorNoise(), Outliers(),
                   name="realistic")

    @property
    def is_ideal(self) -> bool:
        return not self.enabled

    @property
    def enabled(self) -> tuple:
        """Names of the effects that are on."""
        return tuple(k for k in _EFFECTS if getattr(self, k) is not None)

    def without(self, *names) -> "ThermalEffects":
        """A copy with the named effects off (e.g. ``"hall", "outliers"``)."""
        bad = [n for n in names if n not in _EFFECTS]
        if bad:
            raise ValueError(f"unknown effect(s) {bad}; effects: {', '.join(_EFFECTS)}")
        return replace(self, name=f"{self.name} without {'+'.join(names)}", **{n: None for n in names})

    def only(self, *names) -> "ThermalEffects":
        """A copy with only the named effects on."""
        return self.without(*[n for n in _EFFECTS if n not in names])

    def as_dict(self) -> dict:
        """Plain data (for ``truth.json``): ``{effect: {field: value} | None}``."""
        out = {"name": self.name}
        for k in _EFFECTS:
            v = getattr(self, k)
            out[k] = None if v is None else {f.name: getattr(v, f.name) for f in fields(v)}
        return out


PRESETS = ("ideal", "realistic")


def thermal_effects(preset) -> ThermalEffects:
    """A :class:`ThermalEffects` from a preset name (``"ideal"``, ``"realistic"``) or itself."""
    if isinstance(preset, ThermalEffects):
        return preset
    if preset == "ideal":
        return ThermalEffects.ideal()
    if preset == "realistic":
        return ThermalEffects.realistic()
    raise ValueError(f"unknown thermal preset {preset!r}; choose from {', '.join(PRESETS)}")
