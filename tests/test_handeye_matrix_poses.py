"""Issue 30 item 5: flange poses as 4 x 4 matrices (one row-major matrix per line as the
robot-world-hand-eye datasets' RobotPosesVec.txt, or one per block of 4 lines), paired with the
images by order in natural name order (0, 1, 2, ..., 10, 11), the length unit declared; a
checkerboard given by squares instead of inner corners is named as such. Through the command line
on a simulated cell (rendered images, the simulator's hidden true camera pose)."""

from __future__ import annotations

import json
import shutil
import tempfile

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.main import main
from robocal.io.matrix_poses import MatrixPoseError, read_matrix_poses
from robocal.io.tcp_files import read_flange_poses_csv


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """12 rendered eye-in-hand images renamed 0.png ... 11.png (lexicographic order would put 10
    and 11 before 2) with the true flange poses in metres, one RobotPosesVec line each."""
    root = tmp_path_factory.mktemp("matrix")
    out = root / "cell"
    r = CliRunner().invoke(main, ["simulate", "camera", "--out", str(out), "--images", "12", "--seed", "6"])
    assert r.exit_code == 0, r.output
    poses = read_flange_poses_csv(out / "flange_poses.csv")
    images = root / "images"
    images.mkdir()
    for k, label in enumerate(poses.labels):
        shutil.copy(out / "images" / f"{label}.png", images / f"{k}.png")
    T_m = poses.T_base_flange.copy()
    T_m[:, :3, 3] /= 1000.0
    (root / "RobotPosesVec.txt").write_text(
        "\n".join("\t".join(f"{v:.9f}" for v in T.ravel()) for T in T_m) + "\n")
    blocks = "# length_unit: mm\n" + "\n\n".join(
        "\n".join(" ".join(f"{v:.6f}" for v in row) for row in T) for T in poses.T_base_flange)
    (root / "blocks.txt").write_text(blocks + "\n")
    truth = json.loads((out / "truth.json").read_text())
    return root, out, poses, truth


def _solve(root, out, truth, poses_file, *extra):
    with tempfile.TemporaryDirectory() as he:  # --out is required; the tests read the printed result
        return CliRunner().invoke(main, ["handeye", "solve", str(root / "images"), "--poses", str(root / poses_file),
                                         "--board", truth["board"], "--camera", str(out / "camera.json"),
                                         "--exact-poses", "--json", "--out", he, *extra])


@pytest.mark.parametrize("poses_file, extra", [("RobotPosesVec.txt", ["--length-unit", "m"]), ("blocks.txt", [])])
def test_matrix_pose_files_pair_by_natural_order(cell, poses_file, extra):
    root, out, poses, truth = cell
    r = _solve(root, out, truth, poses_file, *extra)
    assert r.exit_code == 0, r.output
    s = json.loads(r.stdout[r.stdout.index("{"):])
    assert [row["name"] for row in s["images"]] == [f"{k}.png" for k in range(12)]
    d = np.linalg.norm(np.array(s["camera_pose"]["position_mm"]) - truth["camera_pose"]["position_mm"])
    assert d < 1.0, d  # the right pairing: within the simulated robot noise's effect
    assert s["reprojection_rms_px"] < 2.0


def test_matrix_pose_file_errors_name_the_problem(cell, tmp_path):
    root, out, poses, truth = cell
    r = _solve(root, out, truth, "RobotPosesVec.txt")  # no unit declared
    assert r.exit_code == 1 and "--length-unit" in r.output and "no unit" in r.output
    r = _solve(root, out, truth, "RobotPosesVec.txt", "--length-unit", "mm")
    assert r.exit_code == 1 and "look like metres" in r.output
    lines = (root / "RobotPosesVec.txt").read_text().splitlines()
    (tmp_path / "short.txt").write_text("\n".join(lines[:-1]) + "\n")
    r = CliRunner().invoke(main, ["handeye", "solve", str(root / "images"), "--poses", str(tmp_path / "short.txt"),
                                  "--length-unit", "m", "--board", truth["board"], "--out", str(tmp_path / "he")])
    assert r.exit_code == 1 and "12 images" in r.output and "11 poses" in r.output and "by order" in r.output
    T = read_matrix_poses(root / "RobotPosesVec.txt", "m")
    (tmp_path / "transposed.txt").write_text("\n".join(" ".join(map(str, M.T.ravel())) for M in T) + "\n")
    with pytest.raises(MatrixPoseError, match="pose 1: last row") as exc:
        read_matrix_poses(tmp_path / "transposed.txt", "mm")
    assert exc.value.line == 1


def test_checkerboard_given_by_squares_is_named(tmp_path):
    """Rendered checkerboard with 9 x 6 inner corners, declared as 10 x 7 (its squares)."""
    out = tmp_path / "cb"
    r = CliRunner().invoke(main, ["simulate", "camera", "--out", str(out), "--images", "3", "--seed", "1",
                                  "--board", "checkerboard:9x6:25mm"])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["camera", "calibrate", str(out / "images"), "--board", "checkerboard:10x7:25mm",
                                  "--out", str(tmp_path / "cam")])
    assert r.exit_code == 1
    assert "inner corners: 9 x 6 found / 10 x 7 expected, did you give squares?" in r.output


def test_matrix_layouts_read_the_same_poses(tmp_path):
    """16 and 12 numbers per line (commas, semicolons, tabs), blocks of 4 and of 3 lines, with
    comments: the same poses in mm; a file unit that contradicts the option is refused."""
    from robocal.transforms import so3_exp

    rng = np.random.default_rng(0)
    T = np.tile(np.eye(4), (3, 1, 1))
    T[:, :3, :3] = so3_exp(rng.normal(0, 1, (3, 3)))
    T[:, :3, 3] = rng.uniform(-1.0, 1.0, (3, 3))  # metres
    layouts = {
        "16.txt": "\n".join(",".join(f"{v:.12f}" for v in M.ravel()) for M in T),
        "12.txt": "# flange poses\n" + "\n".join(";".join(f"{v:.12f}" for v in M[:3].ravel()) for M in T),
        "b4.txt": "\n\n".join("\n".join("\t".join(f"{v:.12f}" for v in row) for row in M) for M in T),
        "b3.txt": "\n".join("\n".join(" ".join(f"{v:.12f}" for v in row) for row in M[:3]) for M in T),
    }
    for name, text in layouts.items():
        (tmp_path / name).write_text(text + "\n")
        got = read_matrix_poses(tmp_path / name, "m")
        assert np.allclose(got[:, :3, 3], T[:, :3, 3] * 1000.0, atol=1e-6), name
        assert np.allclose(got[:, :3, :3], T[:, :3, :3], atol=1e-9), name
    (tmp_path / "declared.txt").write_text("# length_unit: mm\n" + layouts["16.txt"] + "\n")
    with pytest.raises(MatrixPoseError, match="declares length_unit mm, but m was given"):
        read_matrix_poses(tmp_path / "declared.txt", "m")
