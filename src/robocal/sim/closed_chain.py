"""Simulated virtual closed kinematic chain: a laser pointer on the flange held on plate targets.

What a user does in the cell (METHODS.md section 3, the IRB140 paper): a laser pointer is clamped
to the flange (its mount is off by two small rotations and two offsets, eq. 3), a plate with a
row of marked targets stands in the workspace, and for each target the operator jogs the robot
into several configurations, each time until the spot sits on the mark within what a camera or
the eye can tell; then the controller's joints are logged. The plate is moved and it starts again.

The simulation does exactly that on a hidden true robot:

* **mount** -- :class:`LaserPointer`: eq. 3 errors (theta_x, theta_y, px, py) on a nominal mount;
* **plate** -- :class:`Plate`: any pose ``T_base_plate`` (its +z faces the robot), targets on its
  x axis at a fixed pitch; :func:`default_plates` gives plate positions around a robot;
* **holding** -- for each target and configuration a beam direction (within ``max_tilt_deg`` of
  the plate normal), a stand-off along the beam and a roll about it are drawn (the ray's own
  DOF, free to the operator), the spot aim point is drawn within ``tolerance_mm`` of the mark (the
  detection tolerance: uniform in a disc on the plate), and the joints come from IK on the *true*
  model (closed-form branch on the nominal model, refined numerically on the true one);
* **effects the identification model lacks** -- every joint has a small cyclic (gear) error
  ``a sin(2 q + phi)`` between the encoder and the link, and the controller reads the encoders
  with Gaussian noise and quantises them to its resolution; with ``effects``
  (:class:`~robocal.sim.closed_chain_effects.CellEffects`, preset ``realistic``) also a
  transmission error of realistic size, the gravity sag of J2 and J3 and the arm's warm-up during
  the session.

Output: :class:`~robocal.io.spots.HeldSpots` (written as a ``robocal-spots/1`` file) and the
truth. Lengths mm, angles rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..calib.blocks import LaserMount
from ..io.spots import HeldSpots
from ..kinematics.ik import ik_numeric
from ..kinematics.ik_analytic import ik_analytic
from ..transforms import so3_exp
from .campaign_effects import grown
from .closed_chain_effects import CellEffects
from .robot import VirtualRobot, as_rng

__all__ = ["LaserPointer", "Plate", "default_plates", "JointReadout", "ClosedChainCell"]


@dataclass(frozen=True)
class LaserPointer:
    """The true laser mount: ``errors`` (theta_x, theta_y [rad], px, py [mm]) of eq. 3 on the
    nominal mount ``T0`` (4, 4) (default: the beam along the flange's z axis from its centre)."""

    errors: tuple = (0.0, 0.0, 0.0, 0.0)
    T0: np.ndarray | None = None

    @classmethod
    def drawn(cls, rng, *, angle_sigma_deg: float = 0.3, offset_sigma_mm: float = 0.5, T0=None) -> "LaserPointer":
        """A mount with Gaussian errors: a pointer clamped by hand is off by tenths of a degree and mm."""
        rng = as_rng(rng)
        a, o = math.radians(angle_sigma_deg), offset_sigma_mm
        return cls(tuple(float(v) for v in rng.normal(0.0, [a, a, o, o])), T0)

    @property
    def T_flange_laser(self) -> np.ndarray:
        return LaserMount(self.errors, T0=self.T0).transform(self.errors)


@dataclass(frozen=True)
class Plate:
    """A plate at ``T_base_plate`` (4, 4) [mm] (+z towards the robot) with ``n_targets`` marks on
    its x axis, ``spacing_mm`` apart, centred on its origin; ``name`` labels it in the files."""

    name: str
    T_base_plate: np.ndarray
    n_targets: int = 5
    spacing_mm: float = 50.0

    def targets_plate(self) -> np.ndarray:
        """(K, 3) [mm] the marks in the plate frame."""
        x = (np.arange(self.n_targets) - (self.n_targets - 1) / 2.0) * self.spacing_mm
        return np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=1)

    def targets_base(self) -> np.ndarray:
        """(K, 3) [mm] the marks in the robot base frame."""
        T = self.T_base_plate
        return self.targets_plate() @ T[:3, :3].T + T[:3, 3]

    @property
    def target_names(self) -> list:
        return [f"t{k + 1}" for k in range(self.n_targets)]


def _frame(origin, normal, x_hint) -> np.ndarray:
    z = np.asarray(normal, float) / np.linalg.norm(normal)
    x = np.asarray(x_hint, float) - (np.asarray(x_hint, float) @ z) * z
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, np.cross(z, x), z], axis=1)
    T[:3, 3] = origin
    return T


def default_plates(n: int = 2, *, reach_mm: float = 810.0, n_targets: int = 5, spacing_mm: float = 50.0) -> list:
    """``n`` (1-4) plate positions around a robot of reach ``reach_mm``: the first parallel to the
    base XZ plane in front of +y (the paper's), then moved and tilted as a user would place it."""
    r = reach_mm
    specs = [((0.0, 0.8 * r, 0.55 * r), (0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),
             ((0.85 * r, -0.15 * r, 0.3 * r), (-1.0, 0.1, 0.35), (0.0, 1.0, 0.3)),
             ((0.5 * r, -0.65 * r, 0.75 * r), (-0.5, 0.8, -0.35), (0.85, 0.5, 0.2)),
             ((-0.1 * r, -0.8 * r, 0.2 * r), (0.1, 1.0, 0.4), (1.0, 0.0, 0.2))]
    if not 1 <= n <= len(specs):
        raise ValueError(f"plates: 1 to {len(specs)} plate positions, got {n}")
    return [Plate(f"p{i + 1}", _frame(*specs[i]), n_targets, spacing_mm) for i in range(n)]


@dataclass(frozen=True)
class JointReadout:
    """The controller's view of its joints: each joint's link angle differs from its encoder by a
    cyclic error ``cyclic_rad * sin(2 q + phase)`` (not in any kinematic model), and the reading is
    the encoder plus Gaussian ``noise_rad``, quantised to ``resolution_rad`` (all (n,) or scalars)."""

    noise_rad: float | np.ndarray = 0.0
    resolution_rad: float | np.ndarray = 0.0
    cyclic_rad: float | np.ndarray = 0.0
    phase: float | np.ndarray = 0.0

    def link_angles(self, q_encoder) -> np.ndarray:
        return q_encoder + self.cyclic_rad * np.sin(2.0 * q_encoder + self.phase)

    def encoder_angles(self, q_link) -> np.ndarray:
        """The encoder angles whose link angles are ``q_link`` (fixed point; the error is tiny)."""
        q = np.array(q_link, dtype=float)
        for _ in range(4):
            q = q_link - self.cyclic_rad * np.sin(2.0 * q + self.phase)
        return q

    def read(self, q_encoder, rng) -> np.ndarray:
        q = q_encoder + as_rng(rng).standard_normal(np.shape(q_encoder)) * self.noise_rad
        res = np.broadcast_to(np.asarray(self.resolution_rad, dtype=float), np.shape(q)[-1:])
        return np.where(res > 0, np.round(q / np.where(res > 0, res, 1.0)) * res, q)


class ClosedChainCell:
    """A hidden true robot (:class:`~robocal.sim.VirtualRobot`), a laser pointer, plates and the
    controller's joint readout; :meth:`hold_spots` simulates the spot-holding procedure.

    effects: :class:`~robocal.sim.closed_chain_effects.CellEffects` (or a preset name) the
    geometric model lacks, with ``phases`` (2, n) [rad] of its transmission error; ``None``: the
    cell without them (the same random streams either way)."""

    def __init__(self, robot: VirtualRobot, laser: LaserPointer, plates, readout: JointReadout, effects=None,
                 phases=None):
        self.robot, self.laser, self.plates, self.readout = robot, laser, list(plates), readout
        self.effects = None if effects is None else CellEffects.preset(effects)
        if self.effects is not None and self.effects.is_ideal():
            self.effects = None
        n = robot.nominal.n_joints
        self.phases = np.zeros((2, n)) if phases is None else np.asarray(phases, dtype=float).reshape(2, n)

    def encoder_angles(self, q_link) -> np.ndarray:
        """Encoder angles (N, n) [rad] whose link angles are ``q_link`` (N, n) [rad]: the readout's
        cyclic error and the effects inverted by fixed-point iteration (NaN rows stay NaN)."""
        q_link = np.atleast_2d(np.asarray(q_link, dtype=float))
        if self.effects is None:
            return self.readout.encoder_angles(q_link)
        q = self.readout.encoder_angles(q_link)
        ok = np.all(np.isfinite(q_link), axis=1)
        for _ in range(6):
            err = np.zeros_like(q)
            if ok.any():
                err[ok] = self.effects.joint_error(self.robot.true_model, q[ok], self.phases)
            q = self.readout.encoder_angles(q_link - err)
        return q

    def _candidate_poses(self, aim, normal, rng, max_tilt_deg, standoff_mm):
        """Flange poses (C, 4, 4) putting the *true* beam through ``aim`` (C, 3) [mm], from beam
        directions within ``max_tilt_deg`` of the plate ``normal``, stand-offs and rolls drawn."""
        C = len(aim)
        tilt = np.radians(max_tilt_deg) * np.sqrt(rng.uniform(0, 1, C))
        az = rng.uniform(-np.pi, np.pi, C)
        n = normal / np.linalg.norm(normal)
        e1 = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        # beam direction: into the plate (against its normal), tilted
        u = -(np.cos(tilt)[:, None] * n + np.sin(tilt)[:, None] * (np.cos(az)[:, None] * e1 + np.sin(az)[:, None] * e2))
        dist = rng.uniform(*standoff_mm, C)
        roll = rng.uniform(-np.pi, np.pi, C)
        x0 = np.cross(u, e2 + 0.3 * e1)
        x0 /= np.linalg.norm(x0, axis=1, keepdims=True)
        x = np.einsum("cij,cj->ci", so3_exp(u * roll[:, None]), x0)
        T_base_laser = np.tile(np.eye(4), (C, 1, 1))
        T_base_laser[:, :3, :3] = np.stack([x, np.cross(u, x), u], axis=2)
        T_base_laser[:, :3, 3] = aim - dist[:, None] * u
        return T_base_laser @ np.linalg.inv(self.laser.T_flange_laser)

    def _solve_joints(self, T_flange, rng):
        """Link angles (C, n) putting the true flange at ``T_flange`` (NaN rows: unreachable)."""
        nominal, true = self.robot.nominal, self.robot.true_model
        q8, valid = ik_analytic(nominal, T_flange, within_limits=True)
        C = len(T_flange)
        pick = np.full(C, -1)
        for c in range(C):  # choose a random valid branch per candidate (small loop, set-up only)
            ok = np.flatnonzero(valid[c])
            if ok.size:
                pick[c] = rng.choice(ok)
        has = pick >= 0
        q = np.full((C, nominal.n_joints), np.nan)
        if not has.any():
            return q
        res = ik_numeric(true, T_flange[has], q8[np.flatnonzero(has), pick[has]], tol_mm=1e-7, tol_rad=1e-10)
        good = res.converged & (np.abs(res.q[:, 4]) > math.radians(8.0))  # away from the wrist singularity
        rows = np.flatnonzero(has)[good]
        q[rows] = res.q[good]
        return q

    def hold_spots(self, n_configs: int, rng, *, tolerance_mm: float = 0.1, max_tilt_deg: float = 35.0,
                   standoff_mm=(120.0, 450.0), max_rounds: int = 12) -> tuple:
        """Hold every target of every plate in ``n_configs`` configurations.

        Returns ``(spots, truth_rows)``: :class:`~robocal.io.spots.HeldSpots` (joints as the
        controller reads them) and a dict of per-row truth (``aim_mm`` (H, 3) where the spot really
        was, ``q_link`` (H, n) the true link angles, ``q_encoder`` (H, n) the encoders before the
        reading's noise, ``growth`` (H,) the arm's relative growth, 0 without effects)."""
        rng = as_rng(rng)
        if n_configs < 1:
            raise ValueError(f"n_configs must be at least 1, got {n_configs}")
        rows_q, rows_aim, plate_l, target_l, rows_g = [], [], [], [], []
        lo, hi = self.robot.nominal.limits[:, 0], self.robot.nominal.limits[:, 1]
        n_targets = sum(p.n_targets for p in self.plates)
        growth = self.effects.target_growth(n_targets) if self.effects is not None else np.zeros(n_targets)
        T_wb = self.robot.true_model.T_world_base
        k_target = -1
        for plate in self.plates:
            normal = plate.T_base_plate[:3, 2]
            ex, ey = plate.T_base_plate[:3, 0], plate.T_base_plate[:3, 1]
            for name, P in zip(plate.target_names, plate.targets_base()):
                k_target += 1
                eps = float(growth[k_target])
                got_q, got_aim = [], []
                for _ in range(max_rounds):
                    C = 6 * n_configs
                    rad = tolerance_mm * np.sqrt(rng.uniform(0, 1, C))
                    ang = rng.uniform(-np.pi, np.pi, C)
                    aim = P + (rad * np.cos(ang))[:, None] * ex + (rad * np.sin(ang))[:, None] * ey
                    T = self._candidate_poses(aim, normal, rng, max_tilt_deg, standoff_mm)
                    if eps:  # the grown arm reaches (1 + eps) times where the geometric one does
                        T = grown(T, T_wb, 1.0 / (1.0 + eps) - 1.0)
                    q_link = self._solve_joints(T, rng)
                    q_enc = self.encoder_angles(q_link)
                    ok = np.all(np.isfinite(q_enc), axis=1) & np.all((q_enc >= lo) & (q_enc <= hi), axis=1)
                    got_q += list(q_link[ok])
                    got_aim += list(aim[ok])
                    if len(got_q) >= n_configs:
                        break
                if len(got_q) < n_configs:
                    raise RuntimeError(f"plate {plate.name}, target {name}: only {len(got_q)} of {n_configs} "
                                       "configurations reachable; move the plate closer")
                rows_q += got_q[:n_configs]
                rows_aim += got_aim[:n_configs]
                rows_g += [eps] * n_configs
                plate_l += [plate.name] * n_configs
                target_l += [name] * n_configs
        q_link = np.array(rows_q)
        q_enc = self.encoder_angles(q_link)
        q_read = self.readout.read(q_enc, rng)
        H = len(q_link)
        spots = HeldSpots(tuple(str(i + 1) for i in range(H)), tuple(plate_l), tuple(target_l), q_read,
                          tuple(self.robot.nominal.controller_joints), tolerance_mm)
        return spots, {"aim_mm": np.array(rows_aim), "q_link": q_link, "q_encoder": q_enc, "growth": np.array(rows_g)}

    def truth(self) -> dict:
        """What a calibration should find (JSON-ready with numpy arrays)."""
        nom, true = self.robot.nominal, self.robot.true_model
        return {
            "robot": nom.name,
            "parameter_units": dict(zip(nom.params.names, nom.params.units)),
            "true_parameters": true.params.as_dict(), "nominal_parameters": nom.params.as_dict(),
            "laser_mount_errors": dict(zip(["theta_x_rad", "theta_y_rad", "px_mm", "py_mm"], self.laser.errors)),
            "plates": [{"name": p.name, "T_base_plate": p.T_base_plate, "spacing_mm": p.spacing_mm,
                        "targets_base_mm": p.targets_base(), "target_names": p.target_names} for p in self.plates],
            "joint_readout": {"noise_rad": self.readout.noise_rad, "resolution_rad": self.readout.resolution_rad,
                              "cyclic_error_rad": self.readout.cyclic_rad},
            **({"cell_effects": self.effects.as_truth(self.phases)} if self.effects is not None else {}),
            "units": "lengths mm, angles rad; T_a_b is frame b written in frame a",
        }
