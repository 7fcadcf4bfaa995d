"""`robocal simulate tracker`: a simulated laser-tracker campaign written as real files.

A virtual robot whose true kinematic parameters differ from the nominal ones by realistic
tolerances is measured by a virtual laser tracker placed at a random (seeded) spot in the cell.
Writes the measurement file (``robocal-measurements/1``, docs/measurement-files.md) and, next to
it, ``<name>.truth.json`` with the hidden truth (true and nominal parameters, ``T_tracker_base``,
reflector offsets, noise levels, seeds).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...calib.cell import Cell
from ...io.cell_file import read_cell
from ...robots import load_robot
from ...sim import LaserTracker, VirtualRobot, write_truth
from ...sim.campaign_effects import CampaignEffects

__all__ = ["truth_path_for", "check_simulation_outputs", "simulate_tracker"]


def truth_path_for(measurements_path) -> Path:
    """``cell.csv`` -> ``cell.truth.json`` (other names: ``<name>.truth.json``)."""
    p = Path(measurements_path)
    stem = p.name[:-4] if p.name.lower().endswith(".csv") else p.name
    return p.with_name(stem + ".truth.json")


def check_simulation_outputs(out_path, overwrite: bool) -> Path:
    """The truth file's path for the simulated file ``out_path``, after checking before any work
    that neither exists (``FileExistsError`` unless ``overwrite``) and that the folder exists."""
    out_path = Path(out_path)
    truth_path = truth_path_for(out_path)
    if not overwrite:
        for p in (out_path, truth_path):
            if p.exists():
                raise FileExistsError(f"{p}: file exists; pass --overwrite to replace it")
    if not out_path.parent.is_dir() and str(out_path.parent):
        raise FileNotFoundError(f"{out_path}: directory {out_path.parent} does not exist")
    return truth_path


def simulate_tracker(robot, out_path, *, n_poses: int, noise_mm: float, seed: int, reflectors: int = 1,
                     joint_noise_deg: float = 0.0, ppm: float = 0.0, length_sigma_mm: float = 0.5,
                     angle_sigma_deg: float = 0.05, offset_sigma_deg: float = 0.05, margin: float = 0.05,
                     overwrite: bool = False, cell=None, effects: str = "ideal") -> dict:
    """Simulate a laser-tracker campaign of ``robot`` and write the measurement and truth files.

    robot: shipped robot name or robot file path. n_poses: random poses within the joint limits
    (``margin`` of each range kept free). noise_mm: tracker noise per coordinate [mm] (plus
    ``ppm`` um per m of distance). reflectors: 1 (one SMR off the flange axis) or 3 (a triangle;
    the file then also holds the fitted flange orientation). joint_noise_deg: encoder noise of the
    virtual robot [deg] (default 0: the only noise is the tracker's). length_sigma_mm /
    angle_sigma_deg / offset_sigma_deg: spread of the hidden true parameters around the nominal
    ones. seed: one integer; independent streams are derived for the robot, the tracker placement
    and the campaign (``numpy.random.SeedSequence(seed).spawn(3)``). effects: a preset of
    :class:`~robocal.sim.campaign_effects.CampaignEffects` -- ``ideal`` (default: the true robot
    is exactly a geometric model with other parameters, as before) or ``realistic`` (reducer
    transmission error, warm-up growth during the campaign, tracker scale error: effects the model
    lacks); the truth file then holds them under ``campaign_effects``, with the drawn phases, and
    ``robocal simulate execute`` applies them to the true robot.

    Nothing is written if either file exists (``FileExistsError``) unless ``overwrite``.
    Returns {``measurements``, ``truth`` (paths), ``n_poses``, ``robot``, ``truth_data``}.
    """
    out_path = Path(out_path)
    truth_path = check_simulation_outputs(out_path, overwrite)
    if cell is not None and not isinstance(cell, Cell) and Path(cell).resolve() in (out_path.resolve(),
                                                                                   truth_path.resolve()):
        raise ValueError(f"--out {out_path}: would replace the cell file {cell} (an input of this command)")
    if n_poses < 1:
        raise ValueError(f"n_poses must be at least 1, got {n_poses}")
    if reflectors not in (1, 3):
        raise ValueError(f"reflectors must be 1 or 3, got {reflectors}")
    if not noise_mm >= 0 or not joint_noise_deg >= 0:
        raise ValueError("noise levels must be >= 0")
    campaign_effects = CampaignEffects.preset(effects)
    nominal = load_robot(robot)
    s_robot, s_tracker, s_campaign = (np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(3))
    virtual = VirtualRobot.perturbed(nominal, s_robot, length_sigma_mm=length_sigma_mm,
                                     angle_sigma_deg=angle_sigma_deg, offset_sigma_deg=offset_sigma_deg,
                                     joint_noise_deg=joint_noise_deg, joint_noise_mm=0.0)
    if cell is not None and not isinstance(cell, Cell):
        cell = read_cell(cell, nominal)
    if cell is not None and reflectors == 1:  # the cell's reflector (the last tool point)
        reflectors = np.atleast_2d(cell.reflector_mm)
    at = None
    if cell is not None and cell.instrument is not None:  # the world frame is the robot base frame here
        T_base_cell = np.linalg.inv(cell.T_cell_base)
        at = T_base_cell[:3, :3] @ np.asarray(cell.instrument.position) + T_base_cell[:3, 3]
    tracker = LaserTracker.placed(s_tracker, reflectors, sigma_mm=noise_mm, ppm=ppm, position=at)
    meas, truth = tracker.campaign(virtual, n_poses, s_campaign, margin=margin, measurements_path=out_path,
                                   overwrite=overwrite, cell="default" if cell is None else cell,
                                   effects=campaign_effects)
    truth["seed"] = int(seed)
    truth["n_poses"] = int(n_poses)
    truth["simulation"] = {
        "seed_streams": "numpy.random.SeedSequence(seed).spawn(3): robot parameters, tracker placement, campaign",
        "length_sigma_mm": length_sigma_mm, "angle_sigma_deg": angle_sigma_deg,
        "offset_sigma_deg": offset_sigma_deg, "joint_noise_deg": joint_noise_deg, "margin": margin,
        "effects": campaign_effects.name,
        "cell": "default (floor-mounted, the tracker as instrument)" if cell is None else cell.source,
        "measurements_file": out_path.name,
    }
    write_truth(truth_path, truth, overwrite=overwrite)
    return {"measurements": out_path, "truth": truth_path, "n_poses": int(n_poses), "robot": nominal.name,
            "truth_data": truth}
