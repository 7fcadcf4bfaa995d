"""``robocal simulate self-calibration``: a simulated camera self-calibration run written as a user
would record it (issue 15; docs/self-calibration-simulator.md).

All files land in one folder, all or nothing (:func:`.outputs.staged_outputs`): ``images/``,
``joint_log.csv`` (robocal-joint-log/1), ``frames.csv`` (robocal-frames/1), ``camera.json``,
``truth.json``; see :mod:`robocal.sim.cameras.self_calibration`.
"""

from __future__ import annotations

import os
from pathlib import Path

from ...robots import load_robot
from ...sim.cameras.self_calibration import OUTPUT_NAMES, simulate_self_calibration
from ..outputs import check_output_folder, staged_outputs

__all__ = ["simulate_self_calibration_files"]


def simulate_self_calibration_files(robot, out_dir, *, chains=None, overwrite: bool = False, progress=None,
                                    **options) -> dict:
    """Simulate and write a run into ``out_dir``. ``chains``: default ``("left_hand", "right_hand")``
    for a robot with a ``camera_top`` end effector, else ``("world",)`` (a board fixed in the world,
    the camera on the robot's first end effector). ``options``: the keywords of
    :func:`~robocal.sim.cameras.self_calibration.simulate_self_calibration`. Returns a summary dict."""
    model = load_robot(robot)
    if chains is None:
        names = [e.name for e in model.end_effectors]
        chains = tuple(n for n in ("left_hand", "right_hand") if n in names) if "camera_top" in names else ("world",)
        if not chains:
            raise ValueError(f"robot {model.name}: name the board-holding end effectors with chains=; "
                             f"it has {names}")
    out = Path(out_dir)
    check_output_folder(out, OUTPUT_NAMES, {"ROBOT": robot} if isinstance(robot, (str, Path)) else {}, overwrite)
    with staged_outputs(out, OUTPUT_NAMES, overwrite=overwrite) as stage:
        run = simulate_self_calibration(model, chains=tuple(chains), out_dir=stage, progress=progress, **options)
        old_images = out / "images"
        if overwrite and old_images.is_dir():
            os.replace(old_images, stage / ".replaced-images")  # removed with the staging folder
    return {"out_dir": out, "run": run, "robot": model.name, "chains": run.chains, "n_images": run.n_images,
            "n_full": int(run.fully_visible.sum()), "board": run.board.spec,
            "files": {n: out / n for n in OUTPUT_NAMES}}
