"""``robocal thermal ...`` end to end through CliRunner: simulate -> screen -> calibrate-sensor ->
compensate on a small seeded cell (20 cycles per run, the ideal preset: its truth files hold the
whole truth, so the compensation can be checked against them), the realistic preset's files, the
multi-seed ``experiment`` against the library; and one-line errors."""

import json
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

from robocal.cli.thermal import thermal
from robocal.io.programs.joint_table import JointProgram as Program, read_joint_program as read_program, \
    write_joint_program as write_program
from robocal.robots import load_robot
from robocal.robots.writer import save_robot
from robocal.thermal import frame_errors

ROBOT = "kuka_kr150_r3100"
CYCLES = 20


def run(*args):
    return CliRunner().invoke(thermal, [str(a) for a in args])


def ok(*args):
    r = run(*args)
    assert r.exit_code == 0, r.output
    return r


def as_json(r):
    return json.loads(r.stdout)


def true_model(truth):
    m = load_robot(truth["robot"])
    tp = truth["true_parameters"]
    return m.with_params([tp[n] for n in m.params.names])


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    """Simulate once, screen run 1, calibrate the sensor on run 1's cold sphere file."""
    d = tmp_path_factory.mktemp("thermal")
    sim = as_json(ok("simulate", "--seed", 2024, "--cycles", CYCLES, "--preset", "ideal", "--out", d, "--json"))
    screen = as_json(ok("screen", d / "run1", "--json"))
    sensor = d / "sensor.json"
    ok("calibrate-sensor", ROBOT, d / "run1" / "sphere_cold.csv", "--out", sensor)
    return {"dir": d, "sim": sim, "screen": screen, "sensor": sensor}


def test_simulate_writes_three_runs_and_a_program(cell):
    d, sim = cell["dir"], cell["sim"]
    assert [r["run"] for r in sim["runs"]] == [1, 2, 3]
    for r in sim["runs"]:
        assert r["cycles"] == CYCLES
        assert 0.05 < r["tcp_drift_max_mm"] < 0.6                     # the cell drifts 0.1-0.5 mm
        assert r["tcp_drift_3h_mm"] is None                           # 20 cycles: about 1-2 h
        for f in ("sphere_cold.csv", "sphere.csv", "monitor_cold.csv", "monitor.csv", "cycles.csv", "truth.json",
                  "setup.json"):
            assert (d / f"run{r['run']}" / f).is_file()
    prog = read_program(d / "program.csv", load_robot(ROBOT))
    assert len(prog) == sim["monitored_points"] == 34
    text = ok("simulate", "--cycles", 2, "--out", d / "small").output
    assert "TCP 3h mm" in text and "run1..run3" in text and "(realistic)" in text
    truth = json.loads((d / "small" / "run1" / "truth.json").read_text())
    assert truth["effects"]["name"] == "realistic" and truth["effects"]["hall"]["amplitude_K"] == 1.5
    assert json.loads((d / "run1" / "truth.json").read_text())["effects"]["hall"] is None


def _library_problem(run_dir, sensor):
    """The screening problem of a run directory built by the library, for comparison."""
    from robocal.thermal.screening import ScreeningProblem
    from robocal.io.thermal_files import read_sensor_json
    from robocal.workflows.thermal.inputs import load_run_dir

    run = load_run_dir(run_dir)
    s = read_sensor_json(sensor, run["model"])
    return ScreeningProblem.from_measurements(run["model"], s["T_sensor_base"], s["P_e"], run["q_sphere"],
                                              run["sphere_cold"], run["sphere"], run["q_monitor"],
                                              run["monitor_cold"], run["monitor"], run["T_flange_sensor"])


def test_screen_prints_the_librarys_screening(cell):
    """The command's table and lambdas are the library's on the same files (the figures
    themselves are a multi-seed matter: tests/test_thermal_realism.py)."""
    from robocal.thermal.screening import screen_parameters

    s = cell["screen"]
    assert len(s["selected"]) == 8
    assert s["steps"][0]["n_params"] == 24 and len(s["steps"]) == 24 - 8 + 1
    sensor = as_json(ok("screen", cell["dir"] / "run1", "--sensor", cell["sensor"], "--json"))
    prob = _library_problem(cell["dir"] / "run1", cell["sensor"])
    res = screen_parameters(prob, 8)
    assert sensor["selected"] == list(res.selected)
    assert [st["lambda"] for st in sensor["steps"]] == [round(st.lam, 2) for st in res.steps]
    ids = [f"p{i + 1:02d}" for i in range(prob.n_poses)]
    idx = [ids.index(p) for p in sensor["online_poses"]["screened"]]
    lam = sensor["lambda_percent"]
    assert lam["screened"] == pytest.approx(prob.with_poses(idx).evaluate(res.selected).lam)
    assert lam["before"] == pytest.approx(prob.evaluate(()).lam)
    assert len(s["online_poses"]["screened"]) == 6
    text = ok("screen", cell["dir"] / "run1", "--sensor", cell["sensor"], "--keep", 6).output
    assert "step" in text and "remaining" in text and "selected (6):" in text
    assert "before compensation" in text and "traditional" in text


def test_screened_set_evaluated_on_the_other_runs(cell):
    sel = cell["screen"]["selected"]
    for k in (2, 3):
        r = as_json(ok("screen", cell["dir"] / f"run{k}", "--params", ",".join(sel), "--sensor", cell["sensor"],
                       "--json"))
        assert r["mode"] == "evaluate" and r["steps"] == [] and r["selected"] == sel
        prob = _library_problem(cell["dir"] / f"run{k}", cell["sensor"])
        assert r["lambda_percent"]["screened_all_poses"] == pytest.approx(prob.evaluate(sel).lam)
    one_line_error(run("screen", cell["dir"] / "run2", "--params", "a1,beta1"), "beta1", "fixed")


def test_calibrate_sensor_with_known_geometry_within_0_05_mm(cell, tmp_path):
    d = cell["dir"]
    truth = json.loads((d / "run1" / "truth.json").read_text())
    robot_file = tmp_path / "true_robot.toml"
    save_robot(true_model(truth), robot_file)
    out = tmp_path / "sensor_true.json"
    r = as_json(ok("calibrate-sensor", robot_file, d / "run1" / "sphere_cold.csv", "--method", "both",
                   "--truth", d / "run1" / "truth.json", "--out", out, "--json"))
    assert [x["method"] for x in r["results"]] == ["least-squares", "thesis-penalty"]
    s = json.loads(out.read_text())
    assert s["format"] == "robocal-thermal-sensor/1" and s["method"] == "least-squares"
    # independent check against the truth file
    model = true_model(truth)
    from robocal.io.measurements import read_measurements

    meas = read_measurements(d / "run1" / "sphere_cold.csv", robot=model)
    T = model.fk(meas.joints)
    q_centre = (T[:, :3, :3] @ np.array(truth["P_e_mm"]) + T[:, :3, 3]).mean(axis=0)
    e = frame_errors(s["T_sensor_base"], truth["T_sensor_base"], s["P_e_mm"], truth["P_e_mm"], at_base=q_centre)
    assert e["P_e_mm"] < 0.05 and e["at_point_mm"] < 0.05 and e["rotation_deg"] < 0.005
    assert r["errors"]["least-squares"]["P_e_mm"] == pytest.approx(e["P_e_mm"])
    # the nominal model: the frame absorbs the geometry errors, and the command says so
    text = ok("calibrate-sensor", ROBOT, d / "run1" / "sphere_cold.csv").output
    assert "T_sensor_base" in text and "P_e" in text and "std" in text and "note: residual RMS" in text


def test_compensate_makes_the_warm_robot_reach_the_cold_poses(cell, tmp_path):
    d, s = cell["dir"], cell["screen"]
    run2 = d / "run2"
    truth = json.loads((run2 / "truth.json").read_text())
    c = CYCLES                                                          # the last, warmest-so-far cycle
    poses = ",".join(f"c{c:03d}-{p}" for p in s["online_poses"]["screened"])
    out = tmp_path / "corrected.csv"
    db = tmp_path / "history.sqlite"
    r = as_json(ok("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", run2 / "sphere.csv",
                   "--poses", poses, "--cold", run2 / "sphere_cold.csv", "--params", ",".join(s["selected"]),
                   "--program", d / "program.csv", "--out", out, "--db", db, "--robot-id", "cell3-kr150",
                   "--json"))
    assert r["n_poses"] == 6 and r["rank"] == 8 and r["condition_number"] < 100
    assert r["residual_rms_after_mm"] < 0.05 < r["residual_rms_before_mm"]
    assert all(p["std"] > 0 for p in r["parameters"])
    assert r["all_converged"] and len(r["points"]) == 34

    model = load_robot(ROBOT)
    taught = read_program(d / "program.csv", model)
    corrected = read_program(out, model)
    assert corrected.names == taught.names
    assert corrected.metadata["angle_unit"] == "deg" and "thermal drift" in corrected.metadata["note"]
    true = true_model(truth)
    X = true.params.values
    warm = true.with_params(X + np.array(truth["delta_true"][c - 1]))
    cold_pose = true.fk(taught.joints)
    before = np.linalg.norm(warm.fk(taught.joints)[:, :3, 3] - cold_pose[:, :3, 3], axis=1)
    after = np.linalg.norm(warm.fk(corrected.joints)[:, :3, 3] - cold_pose[:, :3, 3], axis=1)
    assert before.max() > 0.15
    assert after.max() < 0.1 and after.mean() < 0.05 and after.max() < 0.4 * before.max()

    from robocal.store import HistoryStore

    with HistoryStore.open(db) as store:
        (rec,) = store.cycles("cell3-kr150", kind="thermal_compensation")
        cyc = store.load_cycle(rec.id)
    assert set(cyc.parameters) == set(s["selected"])
    assert "residual_rms_after" in rec.metrics and "condition_number" in rec.metrics
    assert cyc.corrections_joints_after.shape == (34, 6) and len(cyc.points_mm) == 6
    assert np.allclose(cyc.corrections_joints_after, corrected.joints, atol=1e-12)

    # text output, no cold reference (predicted, with a note), position only
    out2 = tmp_path / "corrected2.csv"
    r2 = run("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", run2 / "sphere.csv", "--poses", poses,
             "--params", "a2,d4", "--program", d / "program.csv", "--out", out2, "--position-only")
    assert r2.exit_code == 0, r2.output
    assert "no --cold reference" in r2.output and "max dq deg" in r2.output and "wrote" in r2.output


def test_program_file_round_trip_and_units(tmp_path):
    model = load_robot(ROBOT)
    q = np.radians([[10.0, -80.0, 100.0, 5.0, 40.0, -20.0], [0.0, -90.0, 90.0, 0.0, 45.0, 0.0]])
    for unit in ("deg", "rad"):
        p = tmp_path / f"p_{unit}.csv"
        write_program(p, Program(q, ("a", "b"), model.controller_joints, {"angle_unit": unit}), model)
        back = read_program(p, model)
        assert np.allclose(back.joints, q, atol=1e-15) and back.names == ("a", "b")
    # columns in any order, no point column
    p = tmp_path / "reordered.csv"
    p.write_text("# format: robocal-program/1\n# robot: kuka_kr150_r3100\n# angle_unit: deg\n"
                 "A6,A5,A4,A3,A2,A1\n-20,40,5,100,-80,10\n")
    back = read_program(p, model)
    assert np.allclose(back.joints[0], q[0]) and back.names == ("1",)


# ---------------------------------------------------------------------------------------------- errors
def _program(tmp_path, unit="deg", values="10,-80,100,5,40,-20", cols="point,A1,A2,A3,A4,A5,A6", name="P1,"):
    p = tmp_path / f"prog_{unit}.csv"
    p.write_text(f"# format: robocal-program/1\n# robot: kuka_kr150_r3100\n# angle_unit: {unit}\n{cols}\n"
                 f"{name}{values}\n")
    return p


def one_line_error(r, *needles):
    assert r.exit_code != 0, r.output
    err = [ln for ln in r.output.splitlines() if ln.startswith("Error:")]
    assert len(err) == 1, r.output
    for n in needles:
        assert n in err[0], err[0]
    return err[0]


def test_errors_missing_files(cell, tmp_path):
    d = cell["dir"]
    one_line_error(run("calibrate-sensor", ROBOT, tmp_path / "nope.csv"), "nope.csv", "no such")
    one_line_error(run("screen", tmp_path / "nodir"), "nodir", "no such run directory")
    partial = tmp_path / "partial"
    shutil.copytree(d / "run1", partial)
    (partial / "setup.json").unlink()
    one_line_error(run("screen", partial), "missing setup.json")
    base = ["compensate", ROBOT, "--sphere", d / "run2" / "sphere.csv", "--params", "a2",
            "--program", d / "program.csv", "--out", tmp_path / "o.csv"]
    one_line_error(run(*base, "--sensor", tmp_path / "sensor.json"), "no such sensor calibration file")
    one_line_error(run(*base, "--sensor", cell["sensor"], "--cold", tmp_path / "cold.csv"), "cold.csv", "no such")
    one_line_error(run("calibrate-sensor", "kuka_kr150_r310", d / "run1" / "sphere_cold.csv"), "kuka_kr150_r3100")


def test_errors_wrong_units(cell, tmp_path):
    d = cell["dir"]
    bad = tmp_path / "sphere_inch.csv"
    bad.write_text((d / "run1" / "sphere_cold.csv").read_text().replace("# length_unit: mm", "# length_unit: inch"))
    one_line_error(run("calibrate-sensor", ROBOT, bad), "length_unit", "inch")
    args = ["compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv",
            "--poses", "c020-*", "--cold", d / "run2" / "sphere_cold.csv", "--params", "a2,d4",
            "--out", tmp_path / "o.csv"]
    one_line_error(run(*args, "--program", _program(tmp_path, unit="degree")), "angle_unit", "degree")
    # degrees declared as radians: more than two turns, or outside the joint limits
    one_line_error(run(*args, "--program", _program(tmp_path, unit="rad")), "look like degrees")
    one_line_error(run(*args, "--program", _program(tmp_path, unit="rad", values="1,-8,1,0,0.5,0")),
                   "outside its limits")
    one_line_error(run(*args, "--program", _program(tmp_path, cols="point,A1,A2,A3,A4,A5,J6")), "J6",
                   "did you mean A6")


def test_errors_too_few_sphere_poses(cell, tmp_path):
    d = cell["dir"]
    one_line_error(run("calibrate-sensor", ROBOT, d / "run1" / "sphere_cold.csv", "--poses", "p01,p02,p03,p04"),
                   "at least 5 poses", "got 4")
    one_line_error(run("calibrate-sensor", ROBOT, d / "run1" / "sphere_cold.csv", "--poses", "x*"),
                   "no pose id matches")
    one_line_error(run("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv",
                       "--poses", "c020-p01,c020-p02", "--cold", d / "run2" / "sphere_cold.csv",
                       "--params", ",".join(cell["screen"]["selected"]), "--program", d / "program.csv",
                       "--out", tmp_path / "o.csv"), "8 parameters cannot be identified from 2 poses")


def test_errors_unknown_parameter_names(cell, tmp_path):
    d = cell["dir"]
    one_line_error(run("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv",
                       "--poses", "c020-*", "--cold", d / "run2" / "sphere_cold.csv", "--params", "a2,alpa4",
                       "--program", d / "program.csv", "--out", tmp_path / "o.csv"),
                   "unknown parameter 'alpa4'", "did you mean alpha4")
    assert not (tmp_path / "o.csv").exists()


def test_errors_existing_output_without_overwrite(cell, tmp_path):
    d = cell["dir"]
    existing = tmp_path / "exists.csv"
    existing.write_text("keep me\n")
    one_line_error(run("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv",
                       "--poses", "c020-*", "--cold", d / "run2" / "sphere_cold.csv", "--params", "a2,d4",
                       "--program", d / "program.csv", "--out", existing), "exists.csv", "--overwrite")
    one_line_error(run("calibrate-sensor", ROBOT, d / "run1" / "sphere_cold.csv", "--out", existing),
                   "--overwrite")
    assert existing.read_text() == "keep me\n"
    one_line_error(run("simulate", "--cycles", 2, "--out", d), "--overwrite")
    ok("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv",
       "--poses", "c020-*", "--cold", d / "run2" / "sphere_cold.csv", "--params", "a2,d4",
       "--program", d / "program.csv", "--out", existing, "--overwrite")
    assert existing.read_text().startswith("# format: robocal-program/1")


def test_experiment_json_is_the_librarys_multi_seed_table():
    from robocal.workflows.thermal.seeds import run_thermal_seeds

    r = as_json(ok("experiment", "--seeds", 2, "--seed", 5, "--cycles", 10, "--json"))
    lib = run_thermal_seeds(preset="realistic", seeds=2, first_seed=5, n_cycles=10)
    assert r["settings"]["preset"] == "realistic" and r["settings"]["seeds"] == 2
    for st in ("rms", "max"):
        for role in ("screening", "evaluation"):
            assert set(r["lambda"][st][role]) == {"before", "traditional", "screened"}
            for col, v in r["lambda"][st][role].items():
                assert v["median"] == pytest.approx(lib["tables"][st][role][col]["median"])
                assert v["q25"] <= v["median"] <= v["q75"] and v["n"] == (2 if role == "screening" else 4)
    assert r["selection_frequency"] == pytest.approx(lib["selection"])
    assert sum(r["selection_frequency"].values()) == pytest.approx(8.0)       # 8 parameters per seed
    assert [s["seed"] for s in r["per_seed"]] == [5, 6]
    assert r["fits"] == {"n": 2, "not_converged": 0}  # the system calibration behind each seed's figures
    text = ok("experiment", "--seeds", 1, "--cycles", 8, "--preset", "ideal").output
    assert "rms residual < 0.1 mm (thesis)" in text and "every cycle < 0.1 mm (strict)" in text
    assert "system calibrations (least squares, one per seed): 0 of 1 did not converge" in text
    assert "selection frequency over seeds" in text
    assert run("experiment", "--preset", "warm").exit_code != 0
    assert run("experiment", "--seeds", 0).exit_code != 0


def test_compensate_refuses_a_moved_sensor(cell, tmp_path):
    """Sphere centres from a sensor that was knocked 40 mm: the identified 'drift' is not heat, the
    result fails the sanity gates (exit 3, status failed), and no corrected program is written
    unless --force."""
    d, s = cell["dir"], cell["screen"]
    run2 = d / "run2"
    poses = ",".join(f"c{CYCLES:03d}-{p}" for p in s["online_poses"]["screened"])
    text = (run2 / "sphere.csv").read_text().splitlines()
    head = [i for i, ln in enumerate(text) if ln.startswith("pose,")][0]
    cols = text[head].split(",")
    ix = cols.index("x")
    moved = text[:head + 1] + [",".join(f"{float(v) + 40.0!r}" if k == ix else v for k, v in enumerate(ln.split(",")))
                               for ln in text[head + 1:] if ln.strip()]
    (tmp_path / "moved.csv").write_text("\n".join(moved) + "\n")
    args = ["compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", tmp_path / "moved.csv", "--poses", poses,
            "--cold", run2 / "sphere_cold.csv", "--params", ",".join(s["selected"]), "--program", d / "program.csv",
            "--out", tmp_path / "corrected.csv", "--json"]
    r = run(*args)
    assert r.exit_code == 3, r.output
    res = json.loads(r.output[r.output.index("{"):r.output.rindex("}") + 1])
    assert res["status"] == "failed" and res["out"] is None and res["reasons"]
    assert not (tmp_path / "corrected.csv").exists()
    r = run(*args, "--force")
    assert r.exit_code == 3 and (tmp_path / "corrected.csv").exists()


def test_calibrate_sensor_that_does_not_converge_exits_4_without_a_sensor_file(cell, tmp_path, lm_one_iteration):
    """Issue 25: the convergence policy (every LM solve stopped after one iteration)."""
    r = run("calibrate-sensor", ROBOT, cell["dir"] / "run1" / "sphere_cold.csv", "--out", tmp_path / "s.json")
    assert r.exit_code == 4, r.output
    assert sum(line.startswith("Warning:") for line in r.output.splitlines()) == 1
    assert not (tmp_path / "s.json").exists()
    r = run("calibrate-sensor", ROBOT, cell["dir"] / "run1" / "sphere_cold.csv", "--out", tmp_path / "s.json",
            "--allow-unconverged")
    assert r.exit_code == 0 and (tmp_path / "s.json").exists()


def test_compensate_exits_5_when_a_corrected_point_is_not_reached(cell, tmp_path, monkeypatch):
    """Issue 25: a correction whose joints do not converge is reported as `robocal correct` does:
    the table flags the points, one stderr line names them, exit code 5 (no iteration allowed here)."""
    import robocal.thermal as thermal_pkg

    compensate = thermal_pkg.compensate_program
    monkeypatch.setattr(thermal_pkg, "compensate_program", lambda *a, **k: compensate(*a, **{**k, "max_iterations": 0}))
    d, s = cell["dir"], cell["screen"]
    poses = ",".join(f"c{CYCLES:03d}-{p}" for p in s["online_poses"]["screened"])
    r = run("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv", "--poses", poses,
            "--cold", d / "run2" / "sphere_cold.csv", "--params", ",".join(s["selected"]), "--program",
            d / "program.csv", "--out", tmp_path / "c.csv")
    assert r.exit_code == 5, r.output
    assert "not converged" in r.output and "not reached:" in r.output


def test_a_damaged_history_database_is_named_before_the_program_is_written(cell, tmp_path):
    """Issue 29: with a corrupt --history database the corrected program was written first."""
    d = cell["dir"]
    db = tmp_path / "history.sqlite"
    db.write_bytes(b"SQLite format 3\x00" + bytes(range(256)) * 8)
    r = run("compensate", ROBOT, "--sensor", cell["sensor"], "--sphere", d / "run2" / "sphere.csv",
            "--poses", "c020-*", "--cold", d / "run2" / "sphere_cold.csv", "--params", "a2,d4",
            "--program", d / "program.csv", "--out", tmp_path / "o.csv", "--db", db)
    one_line_error(r, "history.sqlite", "nothing written")
    assert not (tmp_path / "o.csv").exists()
