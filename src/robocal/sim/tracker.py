"""A virtual laser tracker: measures reflectors on the robot flange in its own frame.

The tracker stands somewhere in the cell at an unknown pose: ``T_tracker_world`` is the world
(robot cell) frame written in the tracker frame, so a world point ``p_w`` is measured at
``T_tracker_world @ p_w``. One or more reflectors (SMRs) sit on the flange at ``reflectors``
(k, 3) [mm] in the flange frame: one reflector gives a 3-D point per pose, three or more give
the full 6-D flange pose. Each coordinate gets independent Gaussian noise with standard
deviation ``sigma_mm + ppm * 1e-6 * distance`` (distance from the tracker in mm), the usual
"a + b/m" form of tracker specifications. Lengths mm, angles rad.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ..io.measurements import DEFAULT_TARGET, Measurements, write_measurements
from ..transforms import (
    check_transforms,
    invert_transforms,
    matrix_from_quaternion,
    transform_points,
    transforms_from,
)
from .robot import VirtualRobot, as_rng

__all__ = ["LaserTracker", "reflector_triangle", "fit_rotations", "write_truth"]


def reflector_triangle(radius_mm: float = 100.0, height_mm: float = 40.0) -> np.ndarray:
    """Three reflectors (3, 3) [mm] on a circle of ``radius_mm`` at 120 deg, ``height_mm`` above the flange."""
    ang = np.deg2rad([0.0, 120.0, 240.0])
    return np.stack([radius_mm * np.cos(ang), radius_mm * np.sin(ang), np.full(3, height_mm)], axis=1)


def fit_rotations(local, measured) -> np.ndarray:
    """Best-fit rotations (N, 3, 3) taking points ``local`` (k, 3) onto ``measured`` (N, k, 3).

    Kabsch / Umeyama without scale on centred point sets (least squares); needs k >= 3
    non-collinear points.
    """
    local = np.asarray(local, dtype=float)
    measured = np.asarray(measured, dtype=float)
    a = local - local.mean(axis=0)
    b = measured - measured.mean(axis=1, keepdims=True)
    H = np.einsum("ki,nkj->nij", a, b)  # sum_k a_k b_k^T
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(np.swapaxes(Vt, -1, -2) @ np.swapaxes(U, -1, -2)))
    D = np.zeros_like(H)
    D[:, 0, 0] = 1.0
    D[:, 1, 1] = 1.0
    D[:, 2, 2] = d
    return np.swapaxes(Vt, -1, -2) @ D @ np.swapaxes(U, -1, -2)


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    raise TypeError(f"cannot write {type(obj).__name__} to JSON")


def write_truth(path, truth: dict, overwrite: bool = False):
    """Write a campaign's truth dictionary as JSON (atomically; see ``atomic_write_text``)."""
    text = json.dumps(truth, indent=2, default=_json_default, allow_nan=False) + "\n"
    return atomic_write_text(path, text, overwrite=overwrite)


class LaserTracker:
    """A simulated laser tracker.

    T_tracker_world: (4, 4) the world frame in the tracker frame [mm] (unknown to calibration).
    reflectors: (k, 3) reflector centres in the flange (end-effector) frame [mm].
    sigma_mm: noise standard deviation per coordinate [mm] (default 0.02).
    ppm: distance-dependent term [mm per km = um per m]; sigma = sigma_mm + ppm * 1e-6 * distance.
    reflector_names: k target names (default ``point`` for one reflector, else ``r1 .. rk``).
    """

    def __init__(self, T_tracker_world, reflectors, *, sigma_mm: float = 0.02, ppm: float = 0.0,
                 reflector_names=None, name: str = "laser tracker (simulated)"):
        self.T_tracker_world = check_transforms(T_tracker_world, "T_tracker_world").reshape(4, 4).copy()
        self.T_tracker_world.setflags(write=False)
        refl = np.array(reflectors, dtype=float).reshape(-1, 3)
        if not np.all(np.isfinite(refl)) or len(refl) == 0:
            raise ValueError(f"reflectors: expected finite (k, 3) [mm], got {np.shape(reflectors)}")
        refl.setflags(write=False)
        self.reflectors = refl
        if reflector_names is None:
            reflector_names = (DEFAULT_TARGET,) if len(refl) == 1 else tuple(f"r{i + 1}" for i in range(len(refl)))
        self.reflector_names = tuple(reflector_names)
        if len(self.reflector_names) != len(refl):
            raise ValueError(f"{len(self.reflector_names)} reflector names for {len(refl)} reflectors")
        if sigma_mm < 0 or ppm < 0:
            raise ValueError("sigma_mm and ppm must be >= 0")
        self.sigma_mm = float(sigma_mm)
        self.ppm = float(ppm)
        self.name = name

    @classmethod
    def placed(cls, rng_seed, reflectors=1, *, distance_mm=(2500.0, 4000.0), height_mm=(500.0, 1800.0),
               sigma_mm: float = 0.02, ppm: float = 0.0, position=None, **kwargs) -> "LaserTracker":
        """A tracker at a random (seeded) place and orientation in the cell.

        The tracker origin is at a horizontal distance uniform in ``distance_mm`` from the world
        origin (the robot base), at a height uniform in ``height_mm`` (a tripod on the floor the
        robot stands on), with a uniformly random orientation; ``position`` (3,) [mm, world frame]
        puts it at a given place instead (the orientation stays random). ``reflectors`` is a (k, 3) array [mm], or 1 (one reflector 60 mm above the
        flange, off its axis) or 3 (:func:`reflector_triangle`).
        """
        rng = as_rng(rng_seed)
        if isinstance(reflectors, (int, np.integer)):
            if reflectors == 1:
                reflectors = np.array([[15.0, -10.0, 60.0]])
            elif reflectors == 3:
                reflectors = reflector_triangle()
            else:
                raise ValueError("reflectors: give 1, 3 or a (k, 3) array [mm]")
        r = rng.uniform(*distance_mm)
        phi = rng.uniform(-np.pi, np.pi)
        p_world_tracker = np.array([r * np.cos(phi), r * np.sin(phi), rng.uniform(*height_mm)])
        if position is not None:
            p_world_tracker = np.asarray(position, dtype=float).reshape(3)
        quat = rng.standard_normal(4)
        R_world_tracker = matrix_from_quaternion(quat / np.linalg.norm(quat))
        T_tracker_world = invert_transforms(transforms_from(R_world_tracker, p_world_tracker))
        return cls(T_tracker_world, reflectors, sigma_mm=sigma_mm, ppm=ppm, **kwargs)

    # ------------------------------------------------------------------ measuring
    def true_points(self, robot: VirtualRobot, q, end_effector=None) -> np.ndarray:
        """Noise-free reflector positions (N, k, 3) [mm] in the tracker frame, no encoder noise."""
        T = self.T_tracker_world @ np.atleast_3d(robot.true_poses(np.atleast_2d(q), end_effector))
        return transform_points(T[:, None], self.reflectors[None])

    def sigma_at(self, points) -> np.ndarray:
        """Noise standard deviation [mm] at tracker-frame points (..., 3)."""
        return self.sigma_mm + self.ppm * 1e-6 * np.linalg.norm(points, axis=-1)

    def measure(self, robot: VirtualRobot, q, rng, *, end_effector=None, orientation: bool | None = None,
                pose_ids=None, effects=None, phases=None) -> Measurements:
        """Measure the reflectors with the robot commanded to ``q`` (N, n_ctrl) [rad | mm].

        The robot moves with encoder noise (:meth:`VirtualRobot.reach`, limits checked), the
        reflectors are seen from the tracker, and tracker noise is added. With three or more
        reflectors and ``orientation`` (default: True when k >= 3) the result also carries the
        measured flange orientation in the tracker frame (``rotations``), fitted to the noisy
        reflector points as tracker software does.
        effects / phases: a :class:`~robocal.sim.campaign_effects.CampaignEffects` and its
        transmission phases (2, n_ctrl) [rad] (:func:`~robocal.sim.campaign_effects.measure_with_effects`:
        encoder noise, then the effects, then tracker noise; the poses are grown in the order of
        ``q``); None or an ideal one: the robot moves as its true model says.
        Returns :class:`~robocal.io.Measurements` in the tracker frame, ``joints`` = commanded.
        """
        rng = as_rng(rng)
        q = np.atleast_2d(np.asarray(q, dtype=float))
        k = len(self.reflectors)
        if orientation is None:
            orientation = k >= 3
        if orientation and k < 3:
            raise ValueError(f"orientation needs at least 3 reflectors, this tracker has {k}")
        if effects is None or effects.is_ideal():
            T = self.T_tracker_world @ robot.reach(q, rng, end_effector)
            pts = transform_points(T[:, None], self.reflectors[None])
            pts = pts + rng.standard_normal(pts.shape) * self.sigma_at(pts)[..., None]
        else:
            from .campaign_effects import measure_with_effects

            if end_effector is not None:
                raise ValueError("campaign effects: only the default end effector is simulated")
            robot.check_limits(q)
            pts = measure_with_effects(robot, self, robot.encoder_noise(q, rng), effects, rng, phases=phases)["points"]
        rotations = fit_rotations(self.reflectors, pts) if orientation else None
        nominal = robot.nominal
        metadata = {
            "robot": nominal.name,
            "instrument": f"{self.name}, sigma {self.sigma_mm:g} mm + {self.ppm:g} ppm",
            "frame": "tracker",
            "length_unit": "mm",
            "angle_unit": "deg",
        }
        if orientation:
            metadata["orientation"] = "quaternion"
            metadata["note"] = "orientation: flange frame fitted to the reflectors, in the tracker frame"
        return Measurements(joints=q, points=pts, targets=self.reflector_names, joint_names=nominal.controller_joints,
                            pose_ids=() if pose_ids is None else pose_ids, rotations=rotations, prismatic=robot.prismatic,
                            metadata=metadata)

    def truth(self, robot: VirtualRobot) -> dict:
        """What the calibration should find: true parameters, frames and reflector offsets."""
        true, nom = robot.true_model, robot.nominal
        return {
            "robot": nom.name,
            "parameter_units": dict(zip(nom.params.names, nom.params.units)),
            "true_parameters": true.params.as_dict(),
            "nominal_parameters": nom.params.as_dict(),
            "free": dict(zip(nom.params.names, nom.params.free.tolist())),
            "T_tracker_world": self.T_tracker_world,
            "T_world_base": true.T_world_base,
            "T_tracker_base": self.T_tracker_world @ true.T_world_base,
            "reflectors_mm": self.reflectors,
            "reflector_names": list(self.reflector_names),
            "tracker_sigma_mm": self.sigma_mm,
            "tracker_ppm": self.ppm,
            "joint_noise": dict(zip(nom.controller_joints, robot.joint_noise.tolist())),
            "units": "lengths mm, angles rad; T_a_b is frame b written in frame a",
        }

    def cell_for(self, robot: VirtualRobot, cell=None):
        """The cell ``cell`` (default :func:`~robocal.calib.cell.default_cell`) with this tracker as its
        instrument (position from ``T_tracker_world`` and the nominal base, unless the cell names
        one) and the reflectors' centroid as the tool's last point (the cell's tool polyline kept)."""
        from dataclasses import replace

        from ..calib.cell import Instrument, default_cell

        cell = default_cell() if cell is None else cell
        if cell.instrument is None:
            T_base_tracker = invert_transforms(self.T_tracker_world @ robot.nominal.T_world_base)
            pos = cell.T_cell_base[:3, :3] @ T_base_tracker[:3, 3] + cell.T_cell_base[:3, 3]
            cell = cell.with_instrument(Instrument(tuple(pos)))
        return replace(cell, tool_mm=tuple(cell.tool_mm[:-1]) + (tuple(self.reflectors.mean(axis=0)),))

    def feasible_poses(self, robot: VirtualRobot, n_poses: int, rng, cell, *, margin: float = 0.05) -> np.ndarray:
        """``n_poses`` poses (n, n_ctrl) of the nominal robot that ``cell`` allows (every reflector
        in range, within its acceptance angle and in sight, no collision), in a driving order whose
        every move is feasible (:func:`~robocal.calib.cell.order_poses`)."""
        from dataclasses import replace

        from ..calib.cell import feasible, order_poses, sample_feasible

        model = robot.nominal
        cells = [replace(cell, tool_mm=tuple(cell.tool_mm[:-1]) + (tuple(r),)) for r in self.reflectors]
        q = np.zeros((0, model.n_joints))
        for _ in range(20):
            want = n_poses - len(q)
            draw, _ = sample_feasible(cells[0], model, 2 * want + 4, rng, margin=margin)
            for c in cells[1:]:
                draw = draw[feasible(c, model, draw)]
            q = np.vstack([q, draw[:want]])
            q, _, _ = order_poses(cells[0], model, q)
            if len(q) >= n_poses:
                return q[:n_poses]
        raise ValueError(f"{model.name}: could not connect {n_poses} feasible poses in the cell ({cell.source})")

    def campaign(self, robot: VirtualRobot, n_poses: int, seed, *, margin: float = 0.05, end_effector=None,
                 orientation: bool | None = None, measurements_path=None, truth_path=None,
                 overwrite: bool = False, length_unit: str = "mm", angle_unit: str = "deg", cell="default",
                 effects=None):
        """Simulate a measurement campaign: poses the robot can take in its cell, measured by this tracker.

        seed: integer seed (or Generator) for the poses, encoder noise and tracker noise.
        cell: a :class:`~robocal.calib.cell.Cell`, ``"default"`` (a floor-mounted robot, this
            tracker as the instrument: :meth:`cell_for`) or None (uniform poses within the joint
            limits, no cell: poses a real robot may not take).
        measurements_path / truth_path: when given, the measurements are written as a
            ``robocal-measurements/1`` CSV file and the truth as JSON (atomic writes; an existing
            file raises ``FileExistsError`` unless ``overwrite``).
        effects: a :class:`~robocal.sim.campaign_effects.CampaignEffects` (None / ideal: none); its
            drawn transmission phases go to the truth as ``campaign_effects``
            (:meth:`~robocal.sim.campaign_effects.CampaignEffects.as_truth`).
        Returns ``(measurements, truth)``; ``truth`` is :meth:`truth` plus ``seed`` and ``n_poses``.
        """
        if not overwrite:  # refuse before writing anything, so no half campaign is left behind
            for p in (measurements_path, truth_path):
                if p is not None and Path(p).exists():
                    raise FileExistsError(f"{p}: file exists; pass overwrite=True to replace it")
        rng = as_rng(seed)
        if cell is None:
            q = robot.random_configurations(n_poses, rng, margin=margin)
        else:
            q = self.feasible_poses(robot, n_poses, rng,
                                    self.cell_for(robot, None if isinstance(cell, str) else cell), margin=margin)
        phases = None
        if effects is not None and not effects.is_ideal():
            phases = effects.transmission_phases(np.atleast_2d(q).shape[1], rng)
        meas = self.measure(robot, q, rng, end_effector=end_effector, orientation=orientation, effects=effects,
                            phases=phases)
        truth = self.truth(robot)
        if phases is not None:
            truth["campaign_effects"] = effects.as_truth(phases)
        truth["seed"] = seed if isinstance(seed, (int, np.integer)) else None
        truth["n_poses"] = int(n_poses)
        if measurements_path is not None:
            write_measurements(measurements_path, meas, length_unit=length_unit, angle_unit=angle_unit,
                               overwrite=overwrite)
        if truth_path is not None:
            write_truth(truth_path, truth, overwrite=overwrite)
        return meas, truth

    def __repr__(self) -> str:
        return f"LaserTracker({len(self.reflectors)} reflector(s), sigma {self.sigma_mm:g} mm + {self.ppm:g} ppm)"
