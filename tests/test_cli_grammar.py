"""One grammar for the whole command line (docs/cli.md, issue 26), checked over every command by
click introspection, and the deprecated names that keep working for one release."""

import json

import click
import pytest
from click.testing import CliRunner

from robocal.cli import main
from robocal.cli._common import (EXIT_ERROR, EXIT_FAILED_RESULT, EXIT_NOT_CONVERGED, EXIT_OK,
                                 EXIT_MECHANICAL_FAULT, EXIT_TARGETS_NOT_REACHED, EXIT_USAGE)
from robocal.cli._grammar import (ARGUMENT, DEPRECATED, DEPRECATED_COMMANDS, OLD_FILE, ROBOT_ARGUMENT,
                                  OptionalRobotCommand, rewrite)

#: names the grammar replaced (docs/cli.md, "Deprecated names"); none may be declared any more
OLD_NAMES = {"--sigma", "--joint-noise-deg", "--joint-resolution", "--euler", "--convention", "--tcp", "--history",
             "--first-seed", "--tolerance", "--plot", "--tolerance-deg", "--events-out", "--sensor-out"}
#: option -> what its help must name (the unit or the kind of value)
UNIT_IN_HELP = {"--noise": "[mm]", "--joint-noise": "[deg]", "--time-tolerance": "[s]",
                "--distance-tolerance": "[mm]", "--angle-tolerance": "[deg]", "--tool": "[mm]"}
#: an optional robot that only overrides what the inputs say stays an option (docs/cli.md)
#: `controller import ur` takes the robot first *and* `--robot NAME`, the spelling issue 33 names
OPTIONAL_ROBOT_OPTION = {"controller import ur"}
#: commands that produce a result but have no --json yet (docs/cli.md lists them)
JSON_PENDING = set()
#: commands whose --out may be left out, and why (docs/cli.md, "output"); every other --out is required
OUT_OPTIONAL = {
    "demo": "a default folder, robocal-demo",
    "ik-train": "a default file next to the robot file",
    "controller diff": "the result is printed; --out adds the joint sets as a CSV file",
    "controller probe": "the result is printed; --out adds the fitted robot file",
    "thermal calibrate-sensor": "the result is printed; --out adds the sensor file for thermal compensate",
    "tcp simulate": "the study is printed; --out adds a simulated events file and sensor file",
}
#: commands that write files through options other than --out, --plots and --summary, and why
OTHER_OUTPUT_OPTIONS = {}
#: commands known to write output files (a folder or files); each has --out, --plots or --summary
WRITES_FILES = {"calibrate", "camera calibrate", "handeye solve", "self-calibrate", "closed-chain calibrate",
                "fleet calibrate", "iso9283 evaluate", "iso9283 plan", "simulate camera", "simulate self-calibration",
                "thermal simulate", "history", "fleet status", "controller diff"}


def commands():
    """(path, command) of every command of ``robocal`` (groups walked, hidden aliases skipped)."""
    out = []

    def walk(group, path, ctx):
        for name in group.list_commands(ctx):
            cmd = group.get_command(ctx, name)
            if cmd.hidden:
                continue
            sub = f"{path} {name}".strip()
            if isinstance(cmd, click.Group):
                walk(cmd, sub, click.Context(cmd, parent=ctx, info_name=name))
            else:
                out.append((sub, cmd))

    walk(main, "", click.Context(main, info_name="robocal"))
    return out


COMMANDS = commands()
IDS = [p for p, _ in COMMANDS]


def options(cmd):
    return [p for p in cmd.params if isinstance(p, click.Option)]


def names(cmd, hidden=True):
    """The option names of ``cmd`` (without hidden ones: a deprecated ``--plot FILE``, when ``hidden`` is False)."""
    return {o for p in options(cmd) if hidden or not p.hidden for o in p.opts + p.secondary_opts}


def test_the_walk_sees_every_command():
    assert len(COMMANDS) >= 37 and "fleet study monte-carlo" in IDS and "tcp calibrate-sensor" in IDS


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_no_old_names(path, cmd):
    visible = names(cmd, hidden=False)
    assert not visible & OLD_NAMES, f"{path}: {sorted(visible & OLD_NAMES)} (docs/cli.md)"
    hidden = names(cmd) - visible  # a hidden option is a deprecated name of the table
    assert hidden <= set(DEPRECATED.get(path, {})), f"{path}: hidden {sorted(hidden)} not in _grammar.DEPRECATED"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_robot_is_the_first_positional_argument(path, cmd):
    args = [p for p in cmd.params if isinstance(p, click.Argument)]
    robot_args = [i for i, a in enumerate(args) if a.name in ("robot", "robot_file")]
    assert robot_args in ([], [0]), f"{path}: the robot must be the first argument"
    if path not in OPTIONAL_ROBOT_OPTION:
        assert "--robot" not in names(cmd), f"{path}: --robot must be the first positional argument"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_positional_arguments_are_never_ambiguous(path, cmd):
    """One token is never 'either of two arguments': an optional robot comes only before required
    arguments (then the command counts them: OptionalRobotCommand), any other optional argument
    only last and after required ones."""
    args = [p for p in cmd.params if isinstance(p, click.Argument)]
    optional = [i for i, a in enumerate(args) if not a.required]
    if args and args[0].name == "robot" and not args[0].required:
        assert all(a.required for a in args[1:]), f"{path}: [ROBOT] followed by an optional argument"
        if len(args) > 1:
            assert isinstance(cmd, OptionalRobotCommand), f"{path}: [ROBOT] before required arguments"
        optional = optional[1:]
    assert optional in ([], [len(args) - 1]), f"{path}: an optional argument before others"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_json_is_a_flag_and_every_result_has_it(path, cmd):
    js = [p for p in options(cmd) if "--json" in p.opts]
    for p in js:
        assert p.is_flag, f"{path}: --json must be a flag printing JSON to stdout"
    if path not in JSON_PENDING:
        assert js, f"{path}: no --json"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_out_is_a_folder_unless_the_help_says_file(path, cmd):
    for p in options(cmd):
        if "--out" not in p.opts:
            continue
        is_folder = isinstance(p.type, click.Path) and not p.type.file_okay
        if is_folder:
            assert "folder" in p.help.lower(), f"{path}: --out is a folder: say so in its help"
        else:
            assert "file" in p.help.lower(), f"{path}: --out is a file only where its help says 'file'"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_out_is_required_unless_documented(path, cmd):
    """A command that writes its results needs --out: without it it would do the work and write
    nothing (issue 26: camera calibrate, handeye solve, self-calibrate did)."""
    out = [p for p in options(cmd) if "--out" in p.opts]
    if path in OUT_OPTIONAL:
        assert out and not out[0].required, f"{path}: listed in OUT_OPTIONAL but --out is required or absent"
    elif out:
        assert out[0].required, f"{path}: --out must be required (or listed with its reason in OUT_OPTIONAL)"
    writers = {"--out", "--plots", "--summary"} & names(cmd, hidden=False)
    if path in WRITES_FILES:
        assert writers, f"{path}: writes files but has no --out, --plots or --summary"
    others = {n for n in names(cmd, hidden=False) if n != "--out" and (n.endswith("-out") or n.startswith("--out-"))}
    assert bool(others) == (path in OTHER_OUTPUT_OPTIONS), f"{path}: output options {sorted(others)}"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_the_unit_is_in_the_help_not_in_the_name(path, cmd):
    """`--joint-noise DEG`, not `--joint-noise-deg` (docs/cli.md): no option name ends in a unit."""
    import re

    with_unit = sorted(n for n in names(cmd, hidden=False) - {"--deg", "--rad"}
                       if re.search(r"-(mm|deg|rad|s|px|m|hz|um|kg)$", n))
    assert not with_unit, f"{path}: {with_unit}: put the unit in the help"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_plots_is_a_folder(path, cmd):
    """One name for one concept: drift plots, accuracy maps go to ``--plots DIR`` (fleet status,
    history, controller diff); ``--plot FILE`` is a deprecated hidden alias only."""
    assert "--plot" not in names(cmd, hidden=False), f"{path}: --plot FILE; use --plots DIR"
    for p in options(cmd):
        if "--plots" in p.opts:
            assert isinstance(p.type, click.Path) and not p.type.file_okay, f"{path}: --plots is a folder"
            assert "folder" in p.help.lower(), f"{path}: --plots is a folder: say so in its help"


@pytest.mark.parametrize("path,cmd", COMMANDS, ids=IDS)
def test_one_name_per_concept_with_its_unit(path, cmd):
    for p in options(cmd):
        for name, unit in UNIT_IN_HELP.items():
            if name in p.opts:
                assert p.help and unit in p.help, f"{path}: {name} must state {unit} in its help"
        if "--seed" in p.opts:
            assert p.type.name == "integer", f"{path}: --seed takes an integer"
        if "--deg" in p.opts:
            assert p.secondary_opts == ["--rad"] and "in and out" in p.help, f"{path}: --deg/--rad (docs/cli.md)"


def test_exit_code_table():
    assert (EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_FAILED_RESULT, EXIT_NOT_CONVERGED, EXIT_TARGETS_NOT_REACHED,
            EXIT_MECHANICAL_FAULT) == (0, 1, 2, 3, 4, 5, 6)


def test_every_deprecated_name_maps_to_a_declared_option():
    declared = dict(COMMANDS)
    for path, rules in DEPRECATED.items():
        cmd = declared[path]
        for old, rule in rules.items():
            if rule == ROBOT_ARGUMENT:
                first = [p for p in cmd.params if isinstance(p, click.Argument)][0]
                assert first.name == "robot", path
            elif rule[1] == ARGUMENT:
                assert rule[0].lower() in [p.name for p in cmd.params if isinstance(p, click.Argument)], path
            elif rule[1] == OLD_FILE:
                assert rule[0] in names(cmd, hidden=False) and old in names(cmd) - names(cmd, hidden=False), path
            else:
                new = rule if isinstance(rule, str) else rule[0]
                assert new in names(cmd), f"{path}: {old} -> {new}, which is not an option"
                # a plain rename of a name to itself would warn on every use of the new name
                assert not (isinstance(rule, str) and new == old), f"{path}: {old} -> {old}"
            if rule == ROBOT_ARGUMENT or isinstance(rule, str) or rule[1] in (ARGUMENT, OLD_FILE):
                assert old not in names(cmd, hidden=False), f"{path}: {old} is still a visible option"
    for group, renamed in DEPRECATED_COMMANDS.items():
        for new in renamed.values():
            assert f"{group} {new}" in declared


# ------------------------------------------------------------------------------ deprecated aliases
def test_rewrite_rules():
    rules = {"--sigma": "--noise", "--tcp": ("--tool", 3), "--robot": ROBOT_ARGUMENT, "--json": ("--summary", "value")}
    assert rewrite(["a", "--sigma", "0.1", "--sigma=0.2"], rules) == ["a", "--noise", "0.1", "--noise=0.2"]
    assert rewrite(["f", "--tcp", "12", "-7", "180", "--x"], rules) == ["f", "--tool", "12,-7,180", "--x"]
    assert rewrite(["p", "--robot", "ur10", "--x"], rules) == ["ur10", "p", "--x"]
    assert rewrite(["--json", "out.json", "--seed", "1"], rules) == ["--summary", "out.json", "--seed", "1"]
    assert rewrite(["--json", "--seed", "1"], rules) == ["--json", "--seed", "1"]
    assert rewrite(["--", "--sigma"], rules) == ["--", "--sigma"]


def _invoke(*args):
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r, r.stdout, r.stderr


def test_old_option_name_works_with_a_warning():
    q = ["0", "0.5", "-0.5", "0", "1", "0"]
    new, out_new, _ = _invoke("fk", "ur10", *q, "--orientation", "kuka_abc", "--json")
    old, out_old, err_old = _invoke("fk", "ur10", *q, "--euler", "kuka_abc", "--json")
    assert new.exit_code == old.exit_code == 0, old.output
    assert json.loads(out_old) == json.loads(out_new)
    assert "Warning: --euler is deprecated, use --orientation" in err_old


def test_a_current_name_never_warns_and_the_old_joint_noise_name_works(capsys):
    """The table once mapped --joint-noise to itself: the new name warned, the old one failed."""
    for path in ("self-calibrate", "simulate self-calibration"):
        assert rewrite(["r", "--joint-noise", "0.01"], DEPRECATED[path]) == ["r", "--joint-noise", "0.01"]
        assert "Warning" not in capsys.readouterr().err
        assert rewrite(["r", "--joint-noise-deg", "0.01"], DEPRECATED[path]) == ["r", "--joint-noise", "0.01"]
        assert "Warning: --joint-noise-deg is deprecated, use --joint-noise" in capsys.readouterr().err


def test_old_three_number_form_works_with_a_warning(tmp_path):
    from robocal.workflows.calibration.simulate import simulate_tracker

    sim = simulate_tracker("ur10", tmp_path / "c.csv", n_poses=30, noise_mm=0.02, seed=1)
    r, _, err = _invoke("calibrate", "ur10", sim["measurements"], "--out", tmp_path / "o", "--no-report",
                        "--sigma", "0.02", "--tool", "0", "0", "0", "--holdout", "0")
    assert r.exit_code == 0, r.output
    assert "Warning: --sigma is deprecated, use --noise" in err
    assert "Warning: --tool V V V is deprecated, use --tool V,V,V" in err
    meta = json.loads((tmp_path / "o" / "result.json").read_text())["metadata"]
    assert meta["sigma_mm"] == 0.02 and meta["initial_target_mm"] == [0.0, 0.0, 0.0]


def test_old_robot_option_becomes_the_first_argument(tmp_path):
    r, out, err = _invoke("import", "--robot", "ur10", tmp_path / "missing.csv", "--joints", tmp_path / "log.csv",
                          "--out", tmp_path / "m.csv")
    assert "Warning: --robot is deprecated, use the first argument ROBOT" in err
    assert r.exit_code == 1 and "missing.csv" in r.output  # parsed; fails on the missing file


def test_old_command_name_works_with_a_warning(tmp_path):
    r, _, err = _invoke("tcp", "sensor-calibrate", tmp_path / "missing.csv")
    assert "Warning: sensor-calibrate is deprecated, use tcp calibrate-sensor" in err
    assert r.exit_code == 1
    assert "sensor-calibrate" not in CliRunner().invoke(main, ["tcp", "--help"]).output  # hidden


def test_old_names_are_not_in_the_help():
    out = CliRunner().invoke(main, ["calibrate", "--help"]).output
    assert "--noise" in out and "--sigma" not in out


def test_json_prints_one_document_on_stdout_and_the_text_on_stderr(tmp_path):
    csv = tmp_path / "c.csv"
    r, out, err = _invoke("simulate", "tracker", "ur10", "--poses", "40", "--noise", "0.02", "--seed", "2",
                          "--out", csv, "--json")
    assert r.exit_code == 0, r.output
    sim = json.loads(out)
    assert sim["n_poses"] == 40 and sim["measurements"] == str(csv) and "wrote" in err
    r, out, err = _invoke("calibrate", "ur10", csv, "--out", tmp_path / "cal", "--no-report", "--json")
    assert r.exit_code == 0, r.output
    doc = json.loads(out)
    assert doc == {**json.loads((tmp_path / "cal" / "result.json").read_text()), "files": doc["files"]}
    assert "held-out poses, after" in err


def test_progress_without_a_terminal_prints_counts_and_eta_every_few_seconds():
    import io
    import time

    from robocal.cli._progress import Progress

    log = io.StringIO()
    with Progress("samples", 4, every_s=0.05, file=log, tty=False) as bar:
        for _ in range(4):
            time.sleep(0.06)
            bar.update(1)
    lines = log.getvalue().splitlines()
    assert len(lines) >= 3 and all(line.startswith("samples: ") for line in lines)
    assert any("ETA" in line and "s elapsed" in line for line in lines)
    assert lines[-1].startswith("samples: 4/4 (100 %)") and lines[-1].endswith("done")
    quiet = io.StringIO()
    with Progress("quick", 2, every_s=10, file=quiet, tty=False) as bar:  # done within every_s: silent
        bar.update(2)
    assert quiet.getvalue() == ""


def test_optional_robot_before_a_required_argument(tmp_path):
    """thermal screen [ROBOT] RUN_DIR: with one argument it is the run folder, with two the robot comes first."""
    from robocal.cli.thermal import thermal

    captured = {}
    screen = thermal.commands["screen"]
    callback = screen.callback
    screen.callback = lambda **kw: captured.update(kw)
    try:
        for args, robot in (([str(tmp_path)], None), (["ur10", str(tmp_path)], "ur10"),
                            (["--keep", "5", str(tmp_path)], None), ([str(tmp_path), "--keep", "5"], None)):
            captured.clear()
            r = CliRunner().invoke(thermal, ["screen", *args])
            assert r.exit_code == 0, (args, r.output)
            assert captured["robot"] == robot and captured["run_dir"] == str(tmp_path), args
        r, _, err = _invoke("thermal", "screen", tmp_path, "--robot", "ur10")
        assert r.exit_code == 0 and captured["robot"] == "ur10" and "--robot is deprecated" in err
    finally:
        screen.callback = callback


# ------------------------------------------------------------ outputs, handeye solve's arguments
@pytest.mark.parametrize("args", [
    ["camera", "calibrate", "IMGS", "--board", "checkerboard:9x6:25mm"],
    ["handeye", "solve", "cal_data.yaml"],
    ["self-calibrate", "ur10", "--images", "IMGS", "--joints", "j.csv", "--frames", "f.csv", "--board",
     "checkerboard:9x6:25mm", "--camera-on", "flange", "--board-on", "world"],
], ids=["camera calibrate", "handeye solve", "self-calibrate"])
def test_a_command_that_writes_results_needs_out(args):
    """Without --out these did the work and wrote nothing (issue 26): now a usage error naming it."""
    r, _, err = _invoke(*args)
    assert r.exit_code == 2 and "Missing option '--out'" in err, r.output


def test_an_output_folder_that_is_an_input_is_refused_even_with_overwrite(tmp_path):
    from importlib.resources import files

    images = tmp_path / "imgs"
    images.mkdir()
    r, _, err = _invoke("camera", "calibrate", images, "--board", "checkerboard:9x6:25mm", "--out", images,
                        "--overwrite")
    assert r.exit_code == 1 and f"{images}: is an input of this command (the images)" in err, r.output
    robot = tmp_path / "cal" / "robot.toml"  # self-calibrate writes <out>/robot.toml: here its own input
    robot.parent.mkdir()
    robot.write_bytes((files("robocal.robots") / "data" / "ur10.toml").read_bytes())
    before = robot.read_bytes()
    r, _, err = _invoke("self-calibrate", robot, "--images", images, "--joints", tmp_path / "j.csv", "--frames",
                        tmp_path / "f.csv", "--board", "checkerboard:9x6:25mm", "--camera-on", "flange", "--board-on",
                        "world", "--out", robot.parent, "--overwrite")
    assert r.exit_code == 1 and "robot.toml: is an input of this command (ROBOT)" in err, r.output
    assert robot.read_bytes() == before
    calibrated = tmp_path / "cal" / "calibrated_robot.toml"  # robocal calibrate's own output name
    robot.rename(calibrated)
    r, _, err = _invoke("calibrate", calibrated, tmp_path / "c.csv", "--out", tmp_path / "cal", "--overwrite")
    assert r.exit_code == 1 and "calibrated_robot.toml: is an input of this command (ROBOT)" in err, r.output
    assert calibrated.read_bytes() == before


@pytest.fixture
def handeye_inputs(monkeypatch):
    """What ``handeye solve`` passes to its workflow (which stops there with a one-line error)."""
    import robocal.workflows.cameras.handeye_solve as workflow

    captured = {}

    def stop(**kwargs):
        captured.update(kwargs)
        raise ValueError("stopped by the test")

    monkeypatch.setattr(workflow, "solve_handeye", stop)
    return captured


def test_handeye_solve_takes_the_robot_first_and_one_data_argument(tmp_path, handeye_inputs):
    """`handeye solve [ROBOT] DATA`: DATA is a cal_data.yaml, or with --poses/--joints the images'
    folder; ROBOT only with --joints. One token is never either."""
    out = ["--out", tmp_path / "he"]
    board = ["--board", "checkerboard:9x6:25mm"]
    cases = [(["cal_data.yaml"], dict(cal_data="cal_data.yaml", images=None, robot=None, poses=None)),
             (["imgs", "--poses", "p.csv", *board], dict(cal_data=None, images="imgs", robot=None, poses="p.csv")),
             (["ur10", "imgs", "--joints", "j.csv", *board], dict(cal_data=None, images="imgs", robot="ur10",
                                                                  joints="j.csv"))]
    for args, expected in cases:
        handeye_inputs.clear()
        r, _, err = _invoke("handeye", "solve", *args, *out)
        assert r.exit_code == 1 and "stopped by the test" in err, (args, r.output)
        assert {k: handeye_inputs[k] for k in expected} == expected, args
        assert handeye_inputs["out_dir"] == str(tmp_path / "he")
    for args, message in ((["ur10", "cal_data.yaml"], "is used only with --joints"),
                          (["imgs", "--joints", "j.csv", *board], "--joints needs ROBOT before DATA"),
                          (["imgs", "--poses", "p.csv"], "--board SPEC is needed"),
                          (["imgs", "--poses", "p.csv", "--joints", "j.csv", *board], "not both")):
        r, _, err = _invoke("handeye", "solve", *args, *out)
        assert r.exit_code == 2 and message in err, (args, r.output)


def test_handeye_solve_old_robot_and_images_options_work_with_a_warning(tmp_path, handeye_inputs):
    r, _, err = _invoke("handeye", "solve", "--joints", "j.csv", "--robot", "ur10", "--images", "imgs", "--board",
                        "checkerboard:9x6:25mm", "--out", tmp_path / "he")
    assert r.exit_code == 1 and "stopped by the test" in err, r.output
    assert handeye_inputs["robot"] == "ur10" and handeye_inputs["images"] == "imgs"
    assert handeye_inputs["joints"] == "j.csv" and handeye_inputs["cal_data"] is None
    assert "Warning: --robot is deprecated, use the first argument ROBOT" in err
    assert "Warning: --images is deprecated, use the argument DATA" in err
    handeye_inputs.clear()
    r, _, err = _invoke("handeye", "solve", "--poses", "p.csv", "--images=imgs", "--board", "checkerboard:9x6:25mm",
                        "--out", tmp_path / "he")
    assert r.exit_code == 1 and handeye_inputs["images"] == "imgs" and handeye_inputs["robot"] is None, r.output
    help_text = CliRunner().invoke(main, ["handeye", "solve", "--help"]).output
    assert "[ROBOT] DATA" in help_text and "--images" not in help_text and "--robot " not in help_text


def test_rewrite_of_an_option_into_an_argument_and_of_a_kept_file_option():
    rules = {"--images": ("DATA", ARGUMENT), "--plot": ("--plots", OLD_FILE)}
    assert rewrite(["--images", "d", "--board", "b"], rules) == ["--board", "b", "d"]
    assert rewrite(["--images=d", "x"], rules) == ["x", "d"]
    assert rewrite(["--plot", "f.png"], rules) == ["--plot", "f.png"]  # kept: the hidden option writes the file


def test_controller_diff_plots_folder_and_old_plot_file(tmp_path):
    r, _, err = _invoke("controller", "diff", "ur10", "ur10_dh_beta", "--poses", 20, "--plots", tmp_path / "maps",
                        "--json")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "maps" / "accuracy_map.png").read_bytes()[:4] == b"\x89PNG" and "Warning" not in err
    r, _, err = _invoke("controller", "diff", "ur10", "ur10_dh_beta", "--poses", 20, "--plot", tmp_path / "m.png")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "m.png").read_bytes()[:4] == b"\x89PNG"
    assert "Warning: --plot FILE is deprecated, use --plots DIR" in err


def test_tcp_simulate_out_folder_and_old_file_options(tmp_path):
    r, _, err = _invoke("tcp", "simulate", "none", "--collisions", 1, "--no-beta-correction", "--out", tmp_path / "sim")
    assert r.exit_code == 0, r.output
    assert (tmp_path / "sim" / "events.csv").is_file() and (tmp_path / "sim" / "sensor.json").is_file()
    r, _, err = _invoke("tcp", "simulate", "none", "--collisions", 1, "--no-beta-correction", "--events-out",
                        tmp_path / "ev.csv")
    assert r.exit_code == 0 and (tmp_path / "ev.csv").is_file(), r.output
    assert "Warning: --events-out FILE is deprecated, use --out DIR" in err
