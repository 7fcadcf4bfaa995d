"""Issue 29: sanity gates of the tool-frame commands (exit 3 with the reason, a clean case passing):
leave-one-out on touch-up (one of seven poses 5 mm off), tool length on every method (a
parallel-barrier file in mm declared as metres), tool axis consistency on seven-point (P6/P7
swapped). Truth: poses built from a known TCP (tests/test_tcp_formulas.py's cell)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.tcp import tcp as tcp_cli
from robocal.tcp.touchup import four_point_tcp, leave_one_out_residuals
from robocal.transforms import rot_x, rot_z
from test_tcp_formulas import (
    H_DOWN,
    H_UP,
    R_FLANGE_STEP3,
    R_FLANGE_STEP12,
    TCP_TRUE,
    _barrier_events,
    _touch_poses,
    _transform,
    _write_pose_csv,
)


def _seven(rng, noise=0.05):
    T = _touch_poses(7, rng, noise=noise)
    return T


def test_leave_one_out_finds_the_pose_that_touched_another_spot():
    T = _seven(np.random.default_rng(3))
    T[4, :3, 3] += np.array([3.0, -4.0, 0.0])  # 5 mm off
    fit = four_point_tcp(T)
    assert fit.rms_mm < 5.0 and np.linalg.norm(fit.tcp_mm - TCP_TRUE) > 0.5  # the old gate passed this
    miss, rms = leave_one_out_residuals(T)
    assert int(np.argmax(miss / np.maximum(1.0, 5 * rms))) == 4 and miss[4] > 4.0 and rms[4] < 0.2


def test_four_point_with_one_pose_5_mm_off_fails_naming_it(tmp_path):
    T = _seven(np.random.default_rng(3))
    ok = _write_pose_csv(tmp_path / "ok.csv", T)
    r = CliRunner().invoke(tcp_cli, ["four-point", ok, "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["status"] == "ok"
    T[4, :3, 3] += np.array([3.0, -4.0, 0.0])
    bad = _write_pose_csv(tmp_path / "bad.csv", T)
    r = CliRunner().invoke(tcp_cli, ["four-point", bad])
    assert r.exit_code == 3, r.output
    assert "leave-one-out: P5 misses by" in r.output and "touched another spot" in r.output


def _seven_point_file(tmp_path, swap=False):
    T4 = _touch_poses(5, np.random.default_rng(13), noise=0.02)
    R_bf = rot_x(math.radians(1.0)) @ rot_z(math.radians(10.0)).T
    p5 = np.array([700.0, 50.0, 420.0])
    # tool Z points down in the base here (the tool hangs from the flange): the Z move goes along -z
    tool_z_base = R_bf @ (TCP_TRUE / np.linalg.norm(TCP_TRUE))
    p6 = p5 + 50.0 * np.array([1.0, 0.0, 0.0])
    p7 = p6 + 40.0 * tool_z_base
    moves = [p5, p7, p6] if swap else [p5, p6, p7]
    T = np.concatenate([T4, [_transform(R_bf, p) for p in moves]])
    return _write_pose_csv(tmp_path / ("swapped.csv" if swap else "seven.csv"), T)


def test_seven_point_with_p6_and_p7_swapped_fails(tmp_path):
    r = CliRunner().invoke(tcp_cli, ["seven-point", _seven_point_file(tmp_path), "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["status"] == "ok"
    r = CliRunner().invoke(tcp_cli, ["seven-point", _seven_point_file(tmp_path, swap=True)])
    assert r.exit_code == 3, r.output
    assert "P6 and P7 swapped" in r.output


def _barrier_file(path, unit="mm"):
    axis_f = np.array([-0.04, 0.06, 1.0])
    axis_f /= np.linalg.norm(axis_f)
    e12 = _barrier_events(R_FLANGE_STEP12, axis_f, np.zeros(3), 3.0, z_flange=600.0)
    e3 = _barrier_events(R_FLANGE_STEP3, axis_f, np.zeros(3), 3.0, z_flange=600.0)
    path.write_text(f"""length_unit = "{unit}"
h_up = {H_UP}
h_down = {H_DOWN}
x_up = {json.dumps([float(x) for x in (*e12['up'], *e3['up'])])}
x_down = {json.dumps([float(x) for x in (*e12['down'], *e3['down'])])}
z7 = {H_UP + 160.0}
""")
    return str(path)


def test_parallel_barriers_in_mm_declared_as_metres_is_refused(tmp_path):
    r = CliRunner().invoke(tcp_cli, ["parallel-barriers", _barrier_file(tmp_path / "mm.toml"), "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["length_mm"] == pytest.approx(160.0)
    r = CliRunner().invoke(tcp_cli, ["parallel-barriers", _barrier_file(tmp_path / "m.toml", unit="m")])
    assert r.exit_code == 3, r.output
    assert "the tool length D: 1.6e+05 mm from the flange (limit 2000 mm)" in r.output
