"""ISO 9283 characteristics, instrument adequacy, the test plan and its simulated execution."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.performance.adequacy import figure_adequacy, parse_mpe
from robocal.performance.iso9283 import (
    distance_characteristics,
    multidirectional_variation,
    path_characteristics,
    pose_characteristics,
)
from robocal.performance.iso_cube import iso_test_poses
from robocal.transforms import rot_z


def test_pose_characteristics_by_hand():
    # four attained positions around commanded (0, 0, 0); by hand: barycentre (1, 0, 0) -> AP = 1;
    # distances from it: 1, 1, 1, 1 -> l_mean = 1, S_l = 0 -> RP = 1
    P = np.array([[2.0, 0, 0], [0.0, 0, 0], [1.0, 1, 0], [1.0, -1, 0]])
    c = pose_characteristics(P, [0, 0, 0])
    assert c.barycentre_mm == pytest.approx([1, 0, 0], abs=1e-12)
    assert c.AP_mm == pytest.approx(1.0, abs=1e-12)
    assert c.RP_mm == pytest.approx(1.0, abs=1e-12)
    # distances 1, 2 from barycentre (0,0,0) of [[1,0,0],[-1,0,0],[0,2,0],[0,-2,0]]: l = 1,1,2,2;
    # mean 1.5, S = sqrt(4 * 0.25 / 3) = 0.57735..., RP = 1.5 + 3 * 0.57735 = 3.2320508...
    c2 = pose_characteristics([[1, 0, 0], [-1, 0, 0], [0, 2, 0], [0, -2, 0]], [0, 0, 1])
    assert c2.AP_mm == pytest.approx(1.0, abs=1e-12)
    assert c2.AP_xyz_mm == pytest.approx([0, 0, -1], abs=1e-12)
    assert c2.RP_mm == pytest.approx(1.5 + 3 * math.sqrt(1 / 3), abs=1e-9)


def test_orientation_figures_by_hand():
    # rotations about z of +0.1, -0.1, +0.3 deg around a commanded identity: AP_c = 0.1 deg,
    # S_c = std(0.1, -0.1, 0.3) = 0.2 deg -> RP_c = 0.6 deg; a and b are zero
    R = np.array([rot_z(math.radians(a)) for a in (0.1, -0.1, 0.3)])
    c = pose_characteristics(np.zeros((3, 3)) + [[0, 0, 0], [0, 0, 1e-3], [0, 0, 2e-3]], [0, 0, 0], R, np.eye(3))
    assert c.AP_abc_deg == pytest.approx([0, 0, 0.1], abs=1e-9)
    assert c.RP_abc_deg == pytest.approx([0, 0, 0.6], abs=1e-9)


def test_distance_and_multidirectional_by_hand():
    a = np.array([[0, 0, 0], [0, 0, 0], [0, 0, 0.0]])
    b = np.array([[10.1, 0, 0], [10.2, 0, 0], [10.3, 0, 0]])        # attained distances 10.1, 10.2, 10.3
    d = distance_characteristics(a, b, [0, 0, 0], [10, 0, 0])
    assert d["D_c_mm"] == pytest.approx(10.0, abs=1e-12)
    assert d["AD_mm"] == pytest.approx(0.2, abs=1e-9)               # 10.2 - 10
    assert d["RD_mm"] == pytest.approx(3 * 0.1, abs=1e-9)           # S_D = 0.1
    assert d["AD_x_mm"] == pytest.approx(-0.2, abs=1e-9)            # D_x = x1 - x2 = -10.2 vs -10
    v = multidirectional_variation([np.zeros((2, 3)), np.ones((2, 3)) * [3, 4, 0], np.ones((2, 3)) * [0, 1, 0]])
    assert v["vAP_mm"] == pytest.approx(5.0, abs=1e-12)


def test_path_characteristics_by_hand():
    # commanded line along x; two cycles offset by +0.1 and +0.3 mm in y: barycentre offset 0.2 mm
    # everywhere -> AT = 0.2; l = 0.1, 0.1 -> S = 0 -> RT = 0.1
    x = np.linspace(0, 100, 201)
    paths = [np.stack([x, np.full_like(x, dy), np.zeros_like(x)], axis=1) for dy in (0.1, 0.3)]
    pts = np.array([[20.0, 0, 0], [50.0, 0, 0], [80.0, 0, 0]])
    r = path_characteristics(pts, np.tile([1.0, 0, 0], (3, 1)), paths)
    assert r.AT_mm == pytest.approx(0.2, abs=1e-9)
    assert r.RT_mm == pytest.approx(0.1, abs=1e-9)


def test_test_poses_are_on_the_diagonal_plane_at_ten_percent():
    P = iso_test_poses([100, 0, 500], 400)
    assert P[0] == pytest.approx([100, 0, 500])
    diag = math.sqrt(400 ** 2 + (400 * math.sqrt(2)) ** 2)          # plane: 400 x 400*sqrt(2)
    corner = np.array([100 - 200, -200, 500 - 200])
    assert np.linalg.norm(P[1] - corner) == pytest.approx(0.1 * diag, rel=1e-12)
    n = np.cross(P[2] - P[1], P[4] - P[1])
    assert abs(np.dot(n, P[3] - P[1])) < 1e-6                        # the five are coplanar


def test_mpe_and_adequacy_flip_where_theory_says():
    m = parse_mpe("15um+6um/m")
    assert m.at(4000) == pytest.approx(0.039)
    # an RP of 0.03 mm cannot be stated with this tracker at 4 m (its MPE exceeds the figure itself)
    assert not figure_adequacy(0.03, m, 4000)["adequate"]
    # an RP of 0.2 mm can (0.039 <= 25 % of 0.2) ...
    assert figure_adequacy(0.2, m, 4000)["adequate"]
    # ... and an RP of 0.03 mm with a CMM-class instrument (1 um + 1 um/m) at 1 m too
    assert figure_adequacy(0.03, parse_mpe("1um + 1um/m"), 1000)["adequate"]
    assert parse_mpe("0.015mm+0.006mm/m").B_mm_per_m == pytest.approx(0.006)
    with pytest.raises(ValueError, match="15um\\+6um/m"):
        parse_mpe("15 + 6")


@pytest.fixture(scope="module")
def iso_run(tmp_path_factory):
    """Plan, simulate and evaluate the ISO test of an IRB 140 through the command line (the set-up
    docs/iso9283.md's adequacy figures are produced from: robocal.docs.figure_producers_pages)."""
    from robocal.docs.figure_producers_pages import iso9283_simulated_run

    d = tmp_path_factory.mktemp("iso")
    plan, out = iso9283_simulated_run(d)
    return d, plan, out


def test_plan_poses_are_feasible(iso_run):
    from robocal.robots import load_robot

    d, plan, _ = iso_run
    protocol = json.loads((d / "plan" / "protocol.json").read_text())
    model = load_robot("abb_irb140")
    q = np.array([p["joints_rad"] for p in protocol["poses"].values()]
                 + [p["joints_rad"] for p in protocol["approach_points"].values()])
    assert np.all(model.within_limits(q))
    assert np.all(model.link_frames(q)[..., 2, 3] >= 0.0)               # nothing below the mounting plane
    T = model.fk(q[:5])
    P = np.array([p["position_mm"] for p in protocol["poses"].values()])
    assert np.abs(T[:, :3, 3] - P).max() < 1e-3                          # the joints reach the poses
    assert plan["cube"]["edge_mm"] >= 300


def test_every_figure_equals_the_truth_within_the_instrument_uncertainty(iso_run):
    _, _, out = iso_run
    meas, true = out["run.csv"]["runs"][0], out["run.truth.csv"]["runs"][0]
    U = 0.015 + 0.006 * 4.2        # the MPE at the largest test distance (< 4.2 m)
    keys = ["AP_mm", "RP_mm", "vAP_mm", "AD_mm", "RD_mm", "dAP_mm", "dRP_mm", "AT_mm_line", "RT_mm_line",
            "AT_mm_circle", "RT_mm_circle"]
    for k in keys:
        assert k in meas["summary"], k
        assert abs(meas["summary"][k] - true["summary"][k]) <= U, (k, meas["summary"][k], true["summary"][k])
    # the simulated effects show where they must: backlash -> vAP well above zero; the circle is
    # driven 0.05 mm inside its radius on top of the geometric error
    assert true["summary"]["vAP_mm"] > 0.01
    assert true["summary"]["RP_a_deg"] > 0
    # a tracker cannot state an IRB 140's repeatability: the adequacy says so
    assert not meas["adequacy"]["RP_mm.P1"]["adequate"]
    assert meas["adequacy"]["AP_mm.P1"]["adequate"]


def test_evaluate_refuses_a_measurement_file_of_another_plan(iso_run, tmp_path):
    d, _, _ = iso_run
    bad = tmp_path / "bad.csv"
    bad.write_text("# format: robocal-iso9283-measurements/1\n# frame: base\n# length_unit: mm\n"
                   "id,time_s,x,y,z\nfoo.c01.P9,0,1,2,3\n")
    r = CliRunner().invoke(main, ["iso9283", "evaluate", str(d / "plan"), str(bad), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1 and "not in the plan" in r.output
    bad.write_text("# format: robocal-iso9283-measurements/1\n# length_unit: mm\nid,time_s,x,y,z\n")
    r = CliRunner().invoke(main, ["iso9283", "evaluate", str(d / "plan"), str(bad), "--out", str(tmp_path / "o")])
    assert r.exit_code == 1 and "frame: base" in r.output


def test_before_after_with_a_calibrated_program(tmp_path):
    """A tracker campaign, a calibration, the ISO test before and after the correction: AP drops."""
    run = CliRunner().invoke
    assert run(main, ["simulate", "tracker", "abb_irb140", "--poses", "60", "--seed", "5",
                      "--out", str(tmp_path / "c.csv")]).exit_code == 0
    r = run(main, ["calibrate", "abb_irb140", str(tmp_path / "c.csv"), "--out", str(tmp_path / "cal")])
    assert r.exit_code == 0, r.output
    assert run(main, ["iso9283", "plan", "abb_irb140", "--out", str(tmp_path / "plan"), "--cycles", "5",
                      "--path-cycles", "3"]).exit_code == 0
    for name, extra in (("before.csv", []), ("after.csv", ["--calibrated", str(tmp_path / "cal" / "calibrated_robot.toml")])):
        r = run(main, ["simulate", "iso9283", "abb_irb140", str(tmp_path / "plan"), "--seed", "5",
                       "--truth", str(tmp_path / "c.truth.json"), "--out", str(tmp_path / name)] + extra)
        assert r.exit_code == 0, r.output
    r = run(main, ["iso9283", "evaluate", str(tmp_path / "plan"), str(tmp_path / "before.csv"),
                   str(tmp_path / "after.csv"), "--out", str(tmp_path / "ev"), "--json"])
    assert r.exit_code == 0, r.output
    res = json.loads(r.output)
    before, after = res["runs"][0]["summary"], res["runs"][1]["summary"]
    assert before["AP_mm"] > 0.5
    assert after["AP_mm"] < 0.25 * before["AP_mm"], (before["AP_mm"], after["AP_mm"])
    assert after["AT_mm_line"] < before["AT_mm_line"]
    assert {row["characteristic"] for row in res["comparison"]} >= {"AP_mm", "RP_mm", "AD_mm"}


def test_report_has_the_figures(iso_run):
    """The HTML report parses; per pose three projected views (every attained position, the
    barycentre, the RP circle), the drift plot and the two path plots are there as SVG."""
    import re
    import xml.etree.ElementTree as ET
    from html.parser import HTMLParser

    d, _, out = iso_run
    text = (d / "ev-run.csv" / "report.html").read_text(encoding="utf-8")

    class Figures(HTMLParser):
        def __init__(self):
            super().__init__()
            self.depth, self.start, self.svgs, self.headings, self._h3 = 0, None, [], [], False

        def handle_starttag(self, tag, attrs):
            if tag == "svg":
                if self.depth == 0:
                    self.start = self.getpos()
                self.depth += 1
            self._h3 = tag == "h3"

        def handle_endtag(self, tag):
            if tag == "svg":
                self.depth -= 1
                if self.depth == 0:
                    self.svgs.append(self.start)

        def handle_data(self, data):
            if self._h3:
                self.headings.append(data)
                self._h3 = False

    f = Figures()
    f.feed(text)
    run = out["run.csv"]["runs"][0]
    n_cycles = len(run["attained_mm"]["P1"])
    assert n_cycles == 30
    assert len(f.svgs) == 5 * 3 + 1 + 2
    assert any(h.startswith("P1: attained positions") for h in f.headings)
    assert "drift of P1: AP and RP per block" in f.headings
    assert any(h.startswith("path circle: deviation") for h in f.headings)
    # every figure is well-formed SVG; P1's x-y view has one dot per cycle, the barycentre and the RP circle
    starts = [m.start() for m in re.finditer("<svg xmlns", text)] + [len(text)]
    svgs = [text[a:b].split("</div>")[0] for a, b in zip(starts[:-1], starts[1:])]
    trees = [ET.fromstring(s) for s in svgs]
    ns = "{http://www.w3.org/2000/svg}"
    p1 = trees[0]
    assert len(p1.findall(f".//{ns}circle")) == n_cycles + 1
    assert len(p1.findall(f".//{ns}polyline")) == 2           # the RP circle and the line to the commanded pose
    assert "RP" in "".join(p1.itertext())


@pytest.mark.parametrize("language", ["krl", "rapid", "tp", "urscript"])
def test_plan_as_a_robot_program_round_trips(language, tmp_path):
    """The ISO test written as a controller program reads back (by the language's own reader) as
    the plan's joint targets, in driving order."""
    from robocal.io.programs import read_program
    from robocal.io.programs.joint_table import read_joint_program
    from robocal.robots import load_robot

    r = CliRunner().invoke(main, ["iso9283", "plan", "abb_irb140", "--out", str(tmp_path / "p"), "--cycles", "2",
                                  "--path-cycles", "2", "--language", language])
    assert r.exit_code == 0, r.output
    model = load_robot("abb_irb140")
    table = read_joint_program(tmp_path / "p" / "program.csv", model)
    suffix = {"krl": ".dat", "rapid": ".mod", "tp": ".ls", "urscript": ".script"}[language]
    prog = read_program(tmp_path / "p" / f"iso9283{suffix}")
    q = np.array([t.joints for t in prog.targets if t.kind == "joint"])
    assert q.shape == table.joints.shape
    assert np.abs(q - table.joints).max() < np.radians(1e-3)   # written with 3 decimals of a degree (UR: rad)


def test_plan_respects_a_cell_obstacle(tmp_path):
    """A table in front of the robot: the cube moves or shrinks so that no pose and no link meets it."""
    from robocal.calib.cell import feasible
    from robocal.io.cell_file import read_cell
    from robocal.robots import load_robot

    cell = tmp_path / "cell.toml"
    cell.write_text('format = "robocal-cell/1"\nlength_unit = "mm"\nangle_unit = "deg"\nclearance = 10.0\n'
                    '[mounting]\nkind = "floor"\nxyz = [0.0, 0.0, 0.0]\nplane = true\n'
                    '[[box]]\nname = "table"\nmin = [300.0, -600.0, 0.0]\nmax = [900.0, 600.0, 250.0]\n')
    r = CliRunner().invoke(main, ["iso9283", "plan", "abb_irb140", "--out", str(tmp_path / "p"), "--cycles", "2",
                                  "--path-cycles", "2", "--cell", str(cell), "--json"])
    assert r.exit_code == 0, r.output
    plan = json.loads(r.output)
    model = load_robot("abb_irb140")
    c = read_cell(cell, model)
    protocol = json.loads((tmp_path / "p" / "protocol.json").read_text())
    q = np.array([p["joints_rad"] for p in protocol["poses"].values()]
                 + [p["joints_rad"] for p in protocol["approach_points"].values()]
                 + protocol["paths"]["line"]["joints_rad"] + protocol["paths"]["circle"]["joints_rad"])
    assert feasible(c, model, q).all()
    # the cube's lowest face is above the table where it overlaps it in x and y
    lo = np.array(plan["cube"]["centre_mm"]) - plan["cube"]["edge_mm"] / 2
    hi = np.array(plan["cube"]["centre_mm"]) + plan["cube"]["edge_mm"] / 2
    overlaps = lo[0] < 900 and hi[0] > 300
    assert not overlaps or lo[2] > 250


def test_figures_equal_the_truth_within_the_stated_uncertainty_over_20_seeds(tmp_path):
    """Issue 32 acceptance: over 20 seeds (true robot, repeatability effects and tracker noise all
    redrawn), every characteristic evaluated from the tracker's file equals the one evaluated from
    the instrument-free truth within the instrument's MPE at the test's distance (the uncertainty
    the evaluation states)."""
    from robocal.io.iso9283_files import read_iso_measurements, write_iso_measurements
    from robocal.robots import load_robot
    from robocal.sim.iso9283 import simulate_iso_run
    from robocal.workflows.performance.iso9283_evaluate import evaluate_iso_run
    from robocal.workflows.performance.iso9283_plan import build_iso_plan
    from robocal.workflows.performance.iso9283_simulate import true_model_for

    model = load_robot("abb_irb140")
    plan = build_iso_plan(model, cycles=10, path_cycles=3, drift_hours=0.5)
    mpe = parse_mpe("15um+6um/m")
    station = np.asarray(plan["cube"]["centre_mm"]) + [3000.0, 0.0, 0.0]
    worst = {}
    for seed in range(20):
        true = true_model_for(model, seed=seed)
        rows, true_rows = simulate_iso_run(true, plan, seed=np.random.default_rng(100 + seed), mpe=mpe,
                                           instrument_at_mm=station)
        out = {}
        for name, r in (("m", rows), ("t", true_rows)):
            path = write_iso_measurements(tmp_path / f"{name}{seed}.csv", r)
            out[name] = evaluate_iso_run(plan, read_iso_measurements(path), mpe=mpe, instrument_at_mm=station)
        for k, v in out["m"]["summary"].items():
            if not k.endswith("_mm") and "_mm_" not in k:
                continue  # orientation figures: the simulated tracker measures position only
            U = max(a["U_mm"] for a in out["m"]["adequacy"].values())
            worst[k] = max(worst.get(k, 0.0), abs(v - out["t"]["summary"][k]) / U)
    assert set(worst) >= {"AP_mm", "RP_mm", "vAP_mm", "AD_mm", "RD_mm", "dAP_mm", "dRP_mm", "AT_mm_line",
                          "RT_mm_circle"}
    assert max(worst.values()) <= 1.0, worst



def test_evaluate_gate_names_an_unregistered_instrument(iso_run, tmp_path):
    """Measurements in the tracker's own frame (not registered to the base: every point shifted by
    a metre) are not a robot 1000 mm off: the gate fails (exit 3) and names the likely cause."""
    d, _, _ = iso_run
    lines = (d / "run.csv").read_text().splitlines()
    head = [i for i, s in enumerate(lines) if s.startswith("id,")][0]
    out = lines[:head + 1]
    for s in lines[head + 1:]:
        v = s.split(",")
        v[2] = f"{float(v[2]) + 1000.0:.5f}"
        out.append(",".join(v))
    (tmp_path / "shifted.csv").write_text("\n".join(out) + "\n")
    r = CliRunner().invoke(main, ["iso9283", "evaluate", str(d / "plan"), str(tmp_path / "shifted.csv"),
                                  "--out", str(tmp_path / "ev"), "--json"])
    assert r.exit_code == 3, r.output
    res = json.loads(r.stdout)["runs"][0]
    assert res["status"] == "failed" and any("not registered to the robot's base frame" in x for x in res["reasons"])
    assert json.loads((d / "ev-run.csv" / "iso9283.json").read_text())["runs"][0]["status"] == "ok"


def test_plan_refuses_to_write_over_its_own_cell_file(tmp_path):
    """An output that is one of the command's inputs is refused even with --overwrite (docs/cli.md):
    a cell file saved where the plan writes program.csv stays as it was."""
    out = tmp_path / "o"
    out.mkdir()
    cell = out / "program.csv"
    cell.write_text('format = "robocal-cell/1"\n', encoding="utf-8")
    r = CliRunner().invoke(main, ["iso9283", "plan", "ur10", "--out", str(out), "--cell", str(cell), "--overwrite"])
    assert r.exit_code == 1
    assert "is an input of this command (--cell)" in r.output
    assert cell.read_text(encoding="utf-8") == 'format = "robocal-cell/1"\n'
    assert not (out / "protocol.json").exists()
