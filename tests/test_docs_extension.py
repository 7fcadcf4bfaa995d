"""The "Adding a measurement kind" section of docs/calibration.md runs as written: its toy block
passes the finite-difference check, registers itself, and calibrates a simulated robot."""

import re
from pathlib import Path

import numpy as np

from robocal.calib.residuals import RESIDUAL_BLOCKS, jacobian_errors, perturbed_values
from robocal.robots import load_robot
from robocal.sim import VirtualRobot

DOC = Path(__file__).resolve().parent.parent / "docs" / "calibration.md"


def _section_code():
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## Adding a measurement kind", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_docs_extension_example_runs_and_calibrates():
    define, use = _section_code()
    ns = {"__name__": "docs_calibration_example"}
    exec(compile(define, str(DOC), "exec"), ns)
    cls = ns["PivotDistanceResidual"]
    assert RESIDUAL_BLOCKS["docs_calibration_example.PivotDistanceResidual"] is cls
    toy = cls.example(np.random.default_rng(0))
    errors = jacobian_errors(toy, perturbed_values(toy, np.random.default_rng(1)))
    assert max(errors.values()) < 1e-6, errors

    # a simulated ball bar: UR10 with perturbed geometry, pivot 600 mm in front of the base
    nominal = load_robot("ur10")
    robot = VirtualRobot.perturbed(nominal, 21, joint_noise_deg=0.0)
    rng = np.random.default_rng(22)
    q = robot.random_configurations(200, rng, margin=0.1)
    T = robot.true_model.replace(T_world_base=np.eye(4)).fk(q)
    ball = T[:, :3, :3] @ np.array([0.0, 0.0, 120.0]) + T[:, :3, 3]
    pivot_true = np.array([600.0, 100.0, 200.0])
    lengths = np.linalg.norm(ball - pivot_true, axis=1) + rng.normal(0, 0.002, len(q))
    ns.update(model=nominal, q=q, lengths=lengths, pivot_guess=pivot_true + [3.0, -2.0, 1.0])
    exec(compile(use, str(DOC), "exec"), ns)
    problem, result = ns["problem"], ns["result"]
    assert result.converged
    before = result.residuals_before * 0.002
    after = result.residuals_after * 0.002
    assert np.sqrt(np.mean(before**2)) > 0.5
    assert np.sqrt(np.mean(after**2)) < 0.003  # the 0.002 mm noise
    per = result.identifiability.by_block()
    # a distance to a pivot cannot tell a turn of the whole arm about base z (theta1) or a lift (d1)
    # from a move of the pivot; ranked as a target, the pivot keeps its 3 variables
    assert {"theta1", "d1"} <= {d["name"] for d in per["geometry"]["dropped"]}
    assert per["pivot"]["identifiable"] == ["pivot.x", "pivot.y", "pivot.z"]
    assert problem.kinds == ("pivot_distance",)
