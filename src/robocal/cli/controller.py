"""``robocal controller ...``: the controller's own model in and out (docs/controller.md).

``import ur`` reads a UR ``calibration.conf`` into an exact, well-conditioned robot file;
``import ur-kinematics`` reads ur_description's kinematics YAML back; ``export ur|urdf|table``
write a robot file for the ROS driver, as URDF or as a neutral table; ``probe`` fits a model to
(joints, pose the controller reports) pairs; ``probe-program`` writes the controller program that
collects those pairs; ``diff`` compares two models over the working range. Every command takes
``--json`` (one JSON document on stdout) and exits 3 when its sanity gates fail (no output file
unless ``--force``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import click

from ._common import EXIT_FAILED_RESULT, _report_verdict

controller = click.Group(
    "controller",
    help="The controller's own model in and out: UR factory calibration import, export for the ROS driver, "
         "URDF and tables, probing a controller's hidden model, model diff (docs/controller.md).",
    context_settings={"help_option_names": ["-h", "--help"]},
)
import_group = click.Group("import", help="Read a controller's own model into a robot file.")
export_group = click.Group("export", help="Write a robot file for a controller, driver or other tool.")
controller.add_command(import_group)
controller.add_command(export_group)

FILE = click.Path(dir_okay=False, path_type=str)
_JSON = dict(is_flag=True, help="Print one JSON document to stdout instead of the text report.")


def _echo_json(obj) -> None:
    click.echo(json.dumps(obj, indent=2, allow_nan=False))


def _gate_exit(verdict, as_json, payload, wrote) -> None:
    """Print the result and leave with exit code 3 when the verdict failed."""
    if as_json:
        _echo_json(payload)
    if not verdict.ok:
        if not as_json:
            _report_verdict(verdict)
            if not wrote:
                click.echo("no output file written (pass --force to write it anyway)", err=True)
        raise SystemExit(EXIT_FAILED_RESULT)


def _deg(x):
    return math.degrees(x)


def _split_robot_conf(args, robot_opt):
    """(robot, conf) from the positional arguments (either order) and ``--robot``."""
    args = list(args)
    if robot_opt is not None:
        if len(args) != 1:
            raise click.UsageError("with --robot give one positional argument, the CALIBRATION_CONF file")
        return robot_opt, args[0]
    if len(args) != 2:
        raise click.UsageError("expected ROBOT and CALIBRATION_CONF (or CALIBRATION_CONF with --robot NAME)")

    def looks_like_conf(p):
        path = Path(p)
        if not path.is_file() or path.suffix == ".toml":
            return False
        try:
            return "[mounting]" in path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            return False

    a, b = args
    if looks_like_conf(a) and not looks_like_conf(b):
        return b, a
    return a, b


@import_group.command("ur", short_help="UR calibration.conf -> exact, well-conditioned robot file.")
@click.argument("args", nargs=-1, required=True, metavar="ROBOT CALIBRATION_CONF")
@click.option("--robot", "robot_opt", default=None, metavar="NAME",
              help="The arm type's nominal robot (alias of the ROBOT argument), e.g. ur10, ur10e or a DH robot file.")
@click.option("--out", "out_file", required=True, type=FILE, help="Robot file to write (TOML; lengths mm, angles deg).")
@click.option("--checks", "n_check", default=1000, show_default=True,
              help="Random joint sets (within the limits, rad internally) at which the FK is checked.")
@click.option("--seed", default=0, show_default=True, help="Seed of the check's joint sets.")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--force", is_flag=True, help="Write the robot file even when a sanity gate fails (exit code 3 still).")
@click.option("--json", "as_json", **_JSON)
def import_ur_cmd(args, robot_opt, out_file, n_check, seed, overwrite, force, as_json):
    """Read a UR controller's factory calibration (calibration.conf, its [mounting] deltas) on the
    nominal ROBOT and write the controller's exact kinematics as a well-conditioned MDH + beta
    robot file. ROBOT and CALIBRATION_CONF may come in either order."""
    from ..workflows.controller.models import controller_comment, import_ur, refuse_same_path, save_model

    robot, conf = _split_robot_conf(args, robot_opt)
    refuse_same_path(out_file, conf, robot)
    if Path(out_file).exists() and not overwrite:
        raise click.ClickException(f"{out_file}: output file exists; pass --overwrite to replace it")
    r = import_ur(conf, robot, n_check=n_check, seed=seed)
    v = r["verdict"]
    wrote = v.ok or force
    if wrote:
        save_model(r["model"], out_file, overwrite=overwrite, comment=controller_comment(r))
    cal = r["calibration"]
    payload = {"status": v.status, "reasons": list(v.reasons), "checks": v.checks,
               "robot_file": out_file if wrote else None, "nominal": r["nominal"].name,
               "calibration_status": cal.calibration_status, "calibration_status_text": cal.status_text,
               "joint_checksum": [f"0x{c:x}" for c in cal.joint_checksum] if cal.joint_checksum else None,
               "ur_driver_hash": r["hash"],
               "controller_dh": {k: [float(x) for x in r["dh"][k]] for k in ("theta", "d", "a", "alpha")},
               "controller_dh_units": {"theta": "rad", "d": "m", "a": "m", "alpha": "rad"},
               "fk_check": r["agreement"],
               "parameters": {n: float(x) for n, x in zip(r["model"].params.names, r["model"].params.values)},
               "parameter_units": dict(zip(r["model"].params.names, r["model"].params.units)),
               "difference_from_nominal": r["difference"]}
    if not as_json:
        m = r["model"]
        click.echo(f"{cal.origin}: calibration_status {cal.calibration_status} ({cal.status_text}); "
                   f"UR driver hash {r['hash']}")
        click.echo(f"controller DH (nominal {r['nominal'].name} + deltas), largest |d| = "
                   f"{max(abs(x) for x in r['dh']['d']):.3f} m -> well-conditioned MDH + beta:")
        click.echo(f"{'joint':<6}{'alpha deg':>12}{'a mm':>12}{'beta deg':>11}{'theta deg':>11}{'d mm':>12}"
                   f"   change from nominal")
        for k, L in enumerate(m.links):
            p = L.params
            ch = ", ".join(f"{n}{k + 1} {r['difference'][f'{n}{k + 1}'] * (180 / math.pi if n in ('alpha', 'beta', 'theta') else 1):+.4f}"
                           for n in ("alpha", "a", "beta", "theta", "d")
                           if abs(r["difference"][f"{n}{k + 1}"]) > 1e-9)
            click.echo(f"{L.name:<6}{_deg(p['alpha']):12.5f}{p['a']:12.4f}{_deg(p['beta']):11.5f}"
                       f"{_deg(p['theta']):11.5f}{p['d']:12.4f}   {ch}")
        a = r["agreement"]
        click.echo(f"FK equals the controller's DH + deltas to {a['max_mm']:.2e} mm / {a['max_rad']:.2e} rad at "
                   f"{a['n']} random joint sets")
        if wrote:
            click.echo(f"wrote {out_file}")
    _gate_exit(v, as_json, payload, wrote)


@import_group.command("ur-kinematics", short_help="ur_description kinematics YAML -> robot file.")
@click.argument("robot")
@click.argument("yaml_file", type=FILE, metavar="KINEMATICS_YAML")
@click.option("--out", "out_file", required=True, type=FILE, help="Robot file to write (TOML; mm, deg).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--force", is_flag=True, help="Write the robot file even when the FK check fails (exit code 3 still).")
@click.option("--json", "as_json", **_JSON)
def import_ur_kinematics_cmd(robot, yaml_file, out_file, overwrite, force, as_json):
    """Read ur_description's kinematics YAML (as written by ur_calibration or `robocal controller
    export ur`) for the arm type ROBOT into a well-conditioned MDH + beta robot file."""
    from ..workflows.controller.models import model_from_kinematics_yaml, origins_fk, random_joints, refuse_same_path, save_model
    from ..workflows.controller.models import _pose_errors

    refuse_same_path(out_file, yaml_file, robot)
    if Path(out_file).exists() and not overwrite:
        raise click.ClickException(f"{out_file}: output file exists; pass --overwrite to replace it")
    r = model_from_kinematics_yaml(yaml_file, robot)
    q = random_joints(r["model"], 1000, 0)
    dp, ang = _pose_errors(origins_fk(r["origins"], q), r["model"].fk(q))
    from ..calib.sanity import Verdict

    ok = dp.max() <= 1e-9 and ang.max() <= 1e-12
    v = Verdict(() if ok else (f"the robot file's FK differs from the YAML chain's by {dp.max():.3g} mm / "
                               f"{ang.max():.3g} rad (limit 1e-9 mm, 1e-12 rad)",), {})
    payload = {"status": v.status, "reasons": list(v.reasons), "robot_file": out_file if ok or force else None,
               "hash": r["hash"], "fk_check": {"n": 1000, "max_mm": float(dp.max()), "max_rad": float(ang.max())}}
    if ok or force:
        save_model(r["model"], out_file, overwrite=overwrite,
                   comment=f"Read from the ur_description kinematics YAML {yaml_file} (hash {r['hash']}).")
    if not as_json:
        click.echo(f"{yaml_file} (hash {r['hash']}): FK of the robot file equals the YAML chain's to "
                   f"{dp.max():.2e} mm / {ang.max():.2e} rad at 1000 random joint sets")
        if ok or force:
            click.echo(f"wrote {out_file}")
    _gate_exit(v, as_json, payload, ok or force)


@export_group.command("ur", short_help="Robot file -> ur_description kinematics YAML.")
@click.argument("model_file", type=FILE, metavar="MODEL")
@click.option("--out", "out_file", required=True, type=FILE,
              help="kinematics YAML file to write (ur_description's format: metres, radians).")
@click.option("--hash", "hash_value", default=None,
              help="The hash entry: the controller's calib_... (printed by `controller import ur`) when MODEL is the "
                   "controller's own calibration; default robocal_<fingerprint>, which the driver reports as not "
                   "matching the robot.")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--force", is_flag=True, help="Write the file even when its FK check fails (exit code 3 still).")
@click.option("--json", "as_json", **_JSON)
def export_ur_cmd(model_file, out_file, hash_value, overwrite, force, as_json):
    """Write MODEL (a 6-joint robot file ending at the flange) as the kinematics parameter file that
    ur_robot_driver / ur_description load, checked against the model's FK (1e-9 mm) before it is written."""
    from ..workflows.controller.models import export_ur

    r = export_ur(model_file, out_file, hash_value=hash_value, overwrite=overwrite, force=force)
    a, v = r["agreement"], r["verdict"]
    payload = {"status": v.status, "reasons": list(v.reasons), "checks": v.checks,
               "file": None if r["file"] is None else str(r["file"]), "hash": r["hash"], "fk_check": a,
               "base_left_out": r["base_left_out"]}
    if not as_json:
        click.echo(f"the kinematics file's chain equals the model's FK to {a['max_mm']:.2e} mm / {a['max_rad']:.2e} rad "
                   f"at {a['n']} random joint sets")
        if r["file"] is not None:
            click.echo(f"wrote {r['file']} (hash {r['hash']})")
        if r["base_left_out"]:
            click.echo("note: the model's [base] (robot base in the instrument frame) is not part of the kinematics "
                       "file; the file runs from the robot base to the flange")
    _gate_exit(v, as_json, payload, r["file"] is not None)


@export_group.command("urdf", short_help="Robot file -> URDF, checked against the model.")
@click.argument("model_file", type=FILE, metavar="MODEL")
@click.option("--out", "out_file", required=True, type=FILE, help="URDF file to write (metres, radians).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--force", is_flag=True, help="Write the file even when its FK check fails (exit code 3 still).")
@click.option("--json", "as_json", **_JSON)
def export_urdf_cmd(model_file, out_file, overwrite, force, as_json):
    """Write MODEL as URDF (calibrated joint origins), checked against the model's FK (1e-6 mm) before
    it is written."""
    from ..workflows.controller.models import export_urdf

    r = export_urdf(model_file, out_file, overwrite=overwrite, force=force)
    a, v = r["agreement"], r["verdict"]
    payload = {"status": v.status, "reasons": list(v.reasons), "checks": v.checks,
               "file": None if r["file"] is None else str(r["file"]), "fk_check": a}
    if not as_json:
        click.echo(f"the URDF read back equals the model's FK to {a['max_mm']:.2e} mm / {a['max_rad']:.2e} rad at "
                   f"{a['n']} random joint sets")
        if r["file"] is not None:
            click.echo(f"wrote {r['file']}")
    _gate_exit(v, as_json, payload, r["file"] is not None)


@export_group.command("table", short_help="Robot file -> DH / MDH table with units (CSV).")
@click.argument("model_file", type=FILE, metavar="MODEL")
@click.option("--out", "out_file", required=True, type=FILE,
              help="CSV file to write: one row per joint, columns named with units (theta_deg, d_mm, ...).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--json", "as_json", **_JSON)
def export_table_cmd(model_file, out_file, overwrite, as_json):
    """Write MODEL's kinematic parameters as a controller-neutral DH / MDH table with units."""
    from ..workflows.controller.models import export_table

    r = export_table(model_file, out_file, overwrite=overwrite)
    if as_json:
        _echo_json({"status": "ok", "reasons": [], "file": str(r["file"]), "kind": r["kind"]})
    else:
        click.echo(f"wrote {r['file']} ({r['kind']} table, mm and deg)")



def _register_probe_commands() -> None:
    """probe, probe-program and diff live in cli/controller_probe.py (imports inside the commands)."""
    from .controller_probe import diff_cmd, probe_cmd, probe_program_cmd, probe_simulate_cmd

    for cmd in (probe_cmd, probe_program_cmd, probe_simulate_cmd, diff_cmd):
        controller.add_command(cmd)


_register_probe_commands()
