"""``robocal controller probe | probe-program | diff`` (docs/controller.md); registered on the
``controller`` group by :mod:`robocal.cli.controller`."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

import click

FILE = click.Path(dir_okay=False, path_type=str)
_JSON = dict(is_flag=True, help="Print one JSON document to stdout instead of the text report.")
_UNITS = {"mm": ("mm", 1.0), "rad": ("deg", 180 / math.pi)}


def _show(value, unit):
    u, f = _UNITS[unit]
    return value * f, u


@click.command("probe-program", short_help="Write the program that prints a controller's own FK.")
@click.argument("robot")
@click.argument("language", type=click.Choice(["ur", "abb", "kuka", "doosan"]))
@click.option("--count", default=100, show_default=True, help="Number of joint sets to probe.")
@click.option("--seed", default=0, show_default=True, help="Seed of the joint sets (uniform within ROBOT's limits).")
@click.option("--host", default="192.168.0.10", show_default=True,
              help="PC that collects the lines (UR and Doosan programs send them over a socket).")
@click.option("--port", default=30005, show_default=True, help="Port of that PC.")
@click.option("--out", "out_file", required=True, type=FILE,
              help="Program file to write (.script, .mod, .src, .py -- the controller's language).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--json", "as_json", **_JSON)
def probe_program_cmd(robot, language, count, seed, host, port, out_file, overwrite, as_json):
    """Write the program that makes a controller compute its own flange pose at COUNT joint sets of
    ROBOT (no motion, no instrument) and print them as robocal-pair lines for `controller probe`."""
    from ..io.atomic import atomic_write_text
    from ..io.controller_pairs import CONTROLLERS
    from ..io.programs.probe import probe_program_text
    from ..workflows.controller.models import load_nominal, random_joints

    if count < 10:
        raise click.ClickException(f"--count must be at least 10 (50+ recommended), got {count}")
    model = load_nominal(robot)
    q = random_joints(model, count, seed)
    text = probe_program_text(language, q, host=host, port=port)
    atomic_write_text(out_file, text, overwrite=overwrite)
    c = CONTROLLERS[language]
    if as_json:
        import json

        click.echo(json.dumps({"status": "ok", "reasons": [], "file": out_file, "language": c["language"],
                               "function": c["function"], "count": count}, indent=2))
    else:
        click.echo(f"wrote {out_file}: {c['language']} program, {count} joint sets of {model.name}, "
                   f"{c['function']}; read its robocal-pair lines back with `robocal controller probe {robot} FILE`")


@click.command("probe-simulate", short_help="A virtual controller's answer to the probe program.")
@click.argument("robot")
@click.argument("language", type=click.Choice(["ur", "abb", "kuka", "doosan"]))
@click.option("--count", default=100, show_default=True, help="Number of joint sets (as probe-program draws them).")
@click.option("--seed", default=0, show_default=True, help="Seed of the joint sets (same as probe-program's).")
@click.option("--noise", "noise_mm", metavar="MM", default=0.01, show_default=True,
              help="Resolution of the printed positions [mm] (the virtual controller rounds to it).")
@click.option("--orientation-noise", "noise_deg", default=0.001, show_default=True,
              help="Resolution of the printed orientations [deg].")
@click.option("--out", "out_file", required=True, type=FILE, help="Pairs file to write (robocal-pair lines).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--json", "as_json", **_JSON)
def probe_simulate_cmd(robot, language, count, seed, noise_mm, noise_deg, out_file, overwrite, as_json):
    """A virtual controller whose hidden model is ROBOT answers the probe program of LANGUAGE:
    the robocal-pair lines it would print (for trying `controller probe` without a robot)."""
    from ..io.atomic import atomic_write_text
    from ..sim.controller import probe_pairs_text
    from ..workflows.controller.models import load_nominal, random_joints, refuse_same_path

    refuse_same_path(out_file, robot)
    model = load_nominal(robot)
    text = probe_pairs_text(model, random_joints(model, count, seed), language, resolution_mm=noise_mm,
                            resolution_deg=noise_deg)
    atomic_write_text(out_file, text, overwrite=overwrite)
    if as_json:
        import json

        click.echo(json.dumps({"status": "ok", "reasons": [], "file": out_file, "count": count, "controller": language,
                               "resolution_mm": noise_mm, "resolution_deg": noise_deg}, indent=2))
    else:
        click.echo(f"wrote {out_file}: {count} {language} pairs of a virtual controller running {model.name}")


@click.command("probe", short_help="Fit ROBOT to (joints, controller pose) pairs.")
@click.argument("robot")
@click.argument("pairs", type=FILE)
@click.option("--controller", "controller_name", default=None, type=click.Choice(["ur", "abb", "kuka", "doosan"]),
              help="Expected controller of the pairs (default: the one their lines name).")
@click.option("--noise", "noise_mm", metavar="MM", default=0.01, show_default=True,
              help="Resolution of the reported positions [mm] (the rounding of the controller's output).")
@click.option("--orientation-noise", "noise_deg", default=0.001, show_default=True,
              help="Resolution of the reported orientations [deg].")
@click.option("--flange", default="auto", show_default=True, type=click.Choice(["auto", "fixed", "free"]),
              help="The flange frame: fixed (ROBOT's, on joint 6's axis), free (fit its offset and tilt: a controller "
                   "whose flange convention differs), auto (free when the pairs show a constant flange offset over "
                   "2 mm / 0.5 deg).")
@click.option("--out", "out_file", default=None, type=FILE,
              help="Robot file to write with the fitted model (TOML; mm, deg); optional.")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--force", is_flag=True, help="Write the robot file even when a sanity gate fails (exit code 3 still).")
@click.option("--json", "as_json", **_JSON)
def probe_cmd(robot, pairs, controller_name, noise_mm, noise_deg, flange, out_file, overwrite, force, as_json):
    """Fit ROBOT's kinematics to PAIRS (joints, pose the controller computed for them): does the
    controller run the nominal model, which parameters does its compensation change and by how much,
    and what remains (about zero for a rigid model)."""
    from ..workflows.controller.models import refuse_same_path, save_model
    from ..workflows.controller.probe import probe_fit
    from .controller import _gate_exit

    if out_file is not None:
        refuse_same_path(out_file, pairs, robot)
        if Path(out_file).exists() and not overwrite:
            raise click.ClickException(f"{out_file}: output file exists; pass --overwrite to replace it")
    r = probe_fit(robot, pairs, controller=controller_name, noise_mm=noise_mm, noise_deg=noise_deg, flange=flange)
    v = r["verdict"]
    wrote = out_file is not None and (v.ok or force)
    if wrote:
        save_model(r["model"], out_file, overwrite=overwrite,
                   comment=f"The controller's model as probed from {pairs} ({len(r['pairs'].q)} pairs); "
                           f"residual after the fit {r['fit_residual']['position_mm']['max']:.4f} mm max.")
    sig = {k: c for k, c in r["changes"].items() if c["significant"]}
    payload = {"status": v.status, "reasons": list(v.reasons), "checks": v.checks,
               "controller": r["pairs"].controller, "pairs": int(len(r["pairs"].q)),
               "runs_nominal": r["runs_nominal"], "nominal_residual": r["nominal_residual"],
               "fit_residual": r["fit_residual"], "tolerance": r["tolerance"],
               "changed_parameters": sig, "all_parameters": r["changes"], "held": r["held"],
               "held_by_convention": r["held_by_convention"], "converged": r["converged"], "flange": r["flange"],
               "robot_file": out_file if wrote else None}
    if not as_json:
        nr, fr = r["nominal_residual"], r["fit_residual"]
        click.echo(f"{len(r['pairs'].q)} {r['pairs'].controller} pairs from {pairs}")
        click.echo(f"nominal {r['nominal'].name} vs the controller: max {nr['position_mm']['max']:.4f} mm, "
                   f"{nr['rotation_deg']['max']:.5f} deg (RMS {nr['position_mm']['rms']:.4f} mm)")
        fl = r["flange"]
        if fl["free"]:
            click.echo(f"the controller's flange frame differs from {r['nominal'].name}'s by a constant "
                       f"{fl['constant_offset_mm']:.3f} mm / {fl['constant_offset_deg']:.3f} deg: fitted as a free "
                       "flange frame (its x, y, roll, pitch)")
        if r["runs_nominal"]:
            click.echo("-> the controller runs the nominal model (differences within the output resolution)")
        else:
            click.echo(f"-> the controller does NOT run the nominal model; {len(sig)} parameters differ "
                       "(change +- 1 sigma):")
            for name, c in sig.items():
                val, u = _show(c["change"], c["unit"])
                s = "n/a" if c["sigma"] is None else f"{_show(c['sigma'], c['unit'])[0]:.5f}"
                click.echo(f"   {name:<8}{val:+12.5f} +- {s} {u}")
        click.echo(f"residual after the fit: max {fr['position_mm']['max']:.4f} mm, {fr['rotation_deg']['max']:.5f} "
                   f"deg (RMS {fr['position_mm']['rms']:.4f} mm; the resolution allows {r['tolerance']['mm']:.4f} mm)")
        if r["held"]:
            click.echo("not identifiable from these pairs (held at nominal): " + ", ".join(r["held"]))
        if wrote:
            click.echo(f"wrote {out_file}")
    _gate_exit(v, as_json, payload, wrote or out_file is None)


@click.command("diff", short_help="TCP difference of two models over the working range.")
@click.argument("model_a", metavar="MODEL_A")
@click.argument("model_b", metavar="MODEL_B")
@click.option("--cell", default=None, type=FILE,
              help="Cell file (robocal-cell/1, docs/cells.md): the joint sets are drawn among the poses MODEL_A can "
                   "take in the cell (mounting, obstacles, joint ranges); default: the whole common joint range.")
@click.option("--poses", "n_poses", default=2000, show_default=True, help="Random joint sets within both models' limits.")
@click.option("--seed", default=0, show_default=True, help="Seed of the joint sets.")
@click.option("--tool", default=None, metavar="X,Y,Z", help="TCP in the flange frame [mm] (default: the flange).")
@click.option("--out", "out_file", default=None, type=FILE,
              help="CSV file to write with every joint set [deg] and its TCP difference [mm, deg]; optional.")
@click.option("--plots", "plot_dir", default=None, type=click.Path(file_okay=False, path_type=str), metavar="DIR",
              help="Folder for accuracy_map.png: top and side views coloured by the TCP difference [mm], and its "
                   "histogram (created if needed); optional.")
@click.option("--plot", "plot_file", default=None, type=FILE, hidden=True,
              help="Deprecated: the accuracy map as this PNG file; use --plots DIR.")
@click.option("--overwrite", is_flag=True, help="Replace existing output files.")
@click.option("--json", "as_json", **_JSON)
def diff_cmd(model_a, model_b, cell, n_poses, seed, tool, out_file, plot_dir, plot_file, overwrite, as_json):
    """TCP difference between two robot models (nominal, the controller's, tracker-calibrated) over
    the working range: statistics and an accuracy map by reach and height."""
    import numpy as np

    from ..io.atomic import atomic_write_text
    from ..workflows.controller.models import refuse_same_path
    from ..workflows.controller.probe import model_diff

    tcp = None
    if tool:
        try:
            tcp = [float(v) for v in tool.split(",")]
        except ValueError:
            raise click.ClickException(f"--tool: expected X,Y,Z [mm], got {tool!r}") from None
        if len(tcp) != 3:
            raise click.ClickException(f"--tool: expected X,Y,Z [mm], got {tool!r}")
    if plot_dir is not None and plot_file is not None:
        raise click.UsageError("give --plots DIR (the deprecated --plot FILE is its older form), not both")
    if plot_dir is not None:
        plot_file = str(Path(plot_dir) / "accuracy_map.png")
    for f in (out_file, plot_file):
        if f is not None:
            refuse_same_path(f, model_a, model_b, cell)
            if Path(f).exists() and not overwrite:
                raise click.ClickException(f"{f}: output file exists; pass --overwrite to replace it")
    if n_poses < 10:
        raise click.ClickException(f"--poses must be at least 10, got {n_poses}")
    cell_model = None
    if cell is not None:
        from ..io.cell_file import read_cell
        from ..workflows.controller.models import load_nominal

        try:
            cell_model = read_cell(cell, load_nominal(model_a))
        except (ValueError, OSError) as exc:
            raise click.ClickException(str(exc)) from None
    try:
        r = model_diff(model_a, model_b, n_poses=n_poses, seed=seed, tool=tcp, cell=cell_model)
    except ValueError as exc:
        raise click.ClickException(" ".join(str(exc).split())) from None
    notes = []
    if cell is not None:
        notes.append(f"--cell {cell}: {n_poses} joint sets the robot can take in the cell")
    if r["bases_differ"]:
        notes.append("the models' [base] frames differ (e.g. a tracker frame); each TCP is compared in its own robot "
                     "base frame")
    if out_file is not None:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([f"q{k + 1}_deg" for k in range(r["q"].shape[1])] + ["tcp_difference_mm", "rotation_difference_deg"])
        for qq, e, a in zip(np.degrees(r["q"]), r["error_mm"], r["rotation_error_deg"]):
            w.writerow([f"{x:.6f}" for x in qq] + [f"{e:.6f}", f"{a:.6f}"])
        atomic_write_text(out_file, buf.getvalue(), overwrite=overwrite)
    if plot_file is not None:
        from ..report.plots import plot_accuracy_map

        if plot_dir is not None:
            Path(plot_dir).mkdir(parents=True, exist_ok=True)

        plot_accuracy_map(r["positions_mm"], r["error_mm"], plot_file,
                          f"{model_b} - {model_a}: TCP difference over {r['n']} joint sets")
    payload = {"status": "ok", "reasons": [], "a": model_a, "b": model_b, "plot": plot_file, "poses": r["n"],
               "tool_mm": r["tool_mm"], "position_mm": r["position_mm"], "rotation_deg": r["rotation_deg"],
               "base_aligned": r["base_aligned"],
               "accuracy_map": r["accuracy_map"], "parameter_differences": r["parameter_differences"],
               "notes": notes, "file": out_file}
    if as_json:
        import json

        click.echo(json.dumps(payload, indent=2))
        return
    p, a = r["position_mm"], r["rotation_deg"]
    click.echo(f"{model_b} - {model_a}: TCP difference over {r['n']} joint sets (each in its robot base frame)")
    click.echo(f"  position  RMS {p['rms']:.4f}  mean {p['mean']:.4f}  p95 {p['p95']:.4f}  max {p['max']:.4f} mm")
    click.echo(f"  rotation  RMS {a['rms']:.5f}  max {a['max']:.5f} deg")
    al = r["base_aligned"]
    click.echo(f"  after a best-fit base ({al['shift_of_base_mm']:.3f} mm, {al['rotation_of_base_deg']:.4f} deg): "
               f"RMS {al['position_mm']['rms']:.4f}, max {al['position_mm']['max']:.4f} mm, "
               f"{al['rotation_deg']['max']:.5f} deg")
    for label, title in (("by_reach", "reach from joint 1's axis"), ("by_height", "height")):
        click.echo(f"  by {title} [mm]:")
        for row in r["accuracy_map"][label]:
            click.echo(f"    {row['range_mm'][0]:8.0f} - {row['range_mm'][1]:8.0f}: RMS {row['rms']:.4f}, "
                       f"max {row['max']:.4f} mm ({row['n']} poses)")
    pd = r["parameter_differences"]
    if pd:
        big = sorted(pd.items(), key=lambda kv: -abs(kv[1] * (1 if r["a"].params.units[r["a"].params.index(kv[0])]
                                                               == "mm" else 1000)))[:8]
        click.echo("  largest parameter differences: " + ", ".join(
            f"{n} {_show(v, r['a'].params.units[r['a'].params.index(n)])[0]:+.4f} "
            f"{_show(v, r['a'].params.units[r['a'].params.index(n)])[1]}" for n, v in big))
    for n in notes:
        click.echo(f"note: {n}")
    for f in (out_file, plot_file):
        if f:
            click.echo(f"wrote {f}")
