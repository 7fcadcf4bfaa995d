"""``robocal tcp ...``: tool frame calibration commands (thesis ch. 4; docs/tcp.md).

Registered in ``robocal.cli`` with ``main.add_command(tcp)``. Every user error ends in one line
``Error: ...`` (``click.ClickException``) and a non-zero exit code.
"""

from __future__ import annotations

import json

import click
import numpy as np

from ..io.tcp_files import read_flange_poses_csv, read_parallel_barriers_file, read_sensor_points_csv
from ..tcp.parallel_barriers import parallel_barriers_tool
from ..tcp.sensor import calibrate_sensor
from ..tcp.tool_data import tool_data_all
from ..tcp.touchup import DEFAULT_MIN_SPREAD_DEG, four_point_tcp, leave_one_out_residuals, seven_point_tool_frame
from ..calib.sanity import barriers_verdict, sensor_verdict, seven_point_verdict, touchup_verdict
from ._grammar import POINT
from ._common import EXIT_FAILED_RESULT, _report_verdict, allow_unconverged_option, finish_convergence

tcp = click.Group(
    "tcp",
    help="Tool frame (TCP / TCF) calibration: touch-up 4/7-point, parallel light barriers, "
         "cross-laser sensor calibration (see docs/tcp.md).",
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _fail(exc) -> click.ClickException:
    return click.ClickException(" ".join(str(exc).split()))


def _v(a, fmt="{:.4f}") -> str:
    return "(" + ", ".join(fmt.format(float(x)) for x in np.ravel(a)) + ")"


def _echo_json(obj) -> None:
    click.echo(json.dumps(obj, indent=2))


def _echo_matrix(name, T) -> None:
    click.echo(f"{name} =")
    for row in T:
        click.echo("  " + " ".join(f"{x:12.6f}" for x in row))


def _print_tool_data(T) -> None:
    click.echo("tool data:")
    for td in tool_data_all(T).values():
        click.echo(f"  {td.title + ':':24s} {td.text}")


FILE = click.Path(dir_okay=False, path_type=str)


@tcp.command("four-point")
@click.argument("file", type=FILE)
@click.option("--min-spread", "min_spread", type=float, default=DEFAULT_MIN_SPREAD_DEG, show_default=True,
              help="Smallest orientation spread [deg] accepted before the poses are called degenerate.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@allow_unconverged_option
def four_point(file, min_spread, as_json, allow_unconverged):
    """TCP in the flange frame from N >= 4 flange poses touching one point (4-1 ... 4-4).

    FILE: flange-pose CSV (docs/tcp.md): '# orientation:', '# length_unit:', '# angle_unit:'
    header lines, then 'pose,x,y,z,<3 or 4 orientation columns>'.
    """
    try:
        poses = read_flange_poses_csv(file, min_rows=4)
        res = four_point_tcp(poses.T_base_flange, min_spread_deg=min_spread, labels=poses.labels)
    except ValueError as exc:
        raise _fail(exc) from None
    verdict = touchup_verdict(res.rms_mm, res.tcp_mm, loo_mm=leave_one_out_residuals(poses.T_base_flange),
                              labels=poses.labels)
    conv = _touchup_convergence(res)
    if as_json:
        d = res.to_dict()
        d.update(file=file, convention=poses.convention, status=verdict.status, reasons=list(verdict.reasons),
                 convergence=conv.as_dict())
        _echo_json(d)
        _exit_if_failed(verdict)
        finish_convergence(conv, allow_unconverged)
        return
    click.echo(f"4-point TCP from {res.n_poses} poses ({poses.convention}, {poses.length_unit})")
    click.echo(f"TCP (flange frame)      {_v(res.tcp_mm)} mm")
    if res.tcp_std_mm is not None:
        click.echo(f"TCP 1-sigma             {_v(res.tcp_std_mm)} mm")
    click.echo(f"reference point (base)  {_v(res.reference_point_mm)} mm")
    if res.sphere_center_mm is not None:
        click.echo(f"sphere fit (4-2)        centre {_v(res.sphere_center_mm)} mm, radius {res.sphere_radius_mm:.4f} mm")
    click.echo(f"orientation spread      {res.orientation_spread_deg:.2f} deg (noise gain {res.noise_gain:.2f})")
    click.echo("residual per pose (mm):")
    for lab, r, rv in zip(poses.labels, res.residuals_mm, res.residual_vectors_mm):
        click.echo(f"  {lab:>10s}  {r:8.4f}  {_v(rv)}")
    click.echo(f"rms {res.rms_mm:.4f} mm, max {res.residuals_mm.max():.4f} mm")
    _exit_if_failed(verdict)
    finish_convergence(conv, allow_unconverged)


def _touchup_convergence(touch):
    """The convergence of a touch-up least-squares fit (None: no fit was run)."""
    from ..workflows.convergence import Convergence

    if touch is None or touch.fit is None:
        return Convergence(0)
    return Convergence.of([("touch-up least squares", touch.fit)],
                          "touch the point from more orientations, tilted further about two axes")


def _exit_if_failed(verdict) -> None:
    if not verdict.ok:
        _report_verdict(verdict)
        raise SystemExit(EXIT_FAILED_RESULT)


@tcp.command("seven-point")
@click.argument("file", type=FILE)
@click.option("--tool", "tcp_xyz", type=POINT, default=None, metavar="X,Y,Z",
              help="Known TCP in the flange frame [mm]; then only P5, P6, P7 are needed.")
@click.option("--min-spread", "min_spread", type=float, default=DEFAULT_MIN_SPREAD_DEG, show_default=True,
              help="Smallest orientation spread [deg] of the touch-up poses.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@allow_unconverged_option
def seven_point(file, tcp_xyz, min_spread, as_json, allow_unconverged):
    """Tool frame (TCP and orientation) by the 7-point method (4-1 ... 4-5).

    FILE: flange-pose CSV; the last three rows are P5 (start), P6 (moved along the tool X
    direction), P7 (then moved along the tool Z direction), same flange orientation; all rows
    before them (>= 4) are touch-up poses for the TCP, unless --tool is given.
    """
    try:
        poses = read_flange_poses_csv(file, min_rows=3)
        T = poses.T_base_flange
        touch = None
        if tcp_xyz:
            t = np.array(tcp_xyz, dtype=float)
        else:
            if len(T) < 7:
                raise ValueError(f"{file}: need >= 4 touch-up poses + P5, P6, P7 (>= 7 rows), got {len(T)} rows; "
                                 "or give the TCP with --tool X,Y,Z")
            touch = four_point_tcp(T[:-3], min_spread_deg=min_spread, labels=poses.labels[:-3])
            t = touch.tcp_mm
        res = seven_point_tool_frame(T[-3:], t)
    except ValueError as exc:
        raise _fail(exc) from None
    conv = _touchup_convergence(touch)
    data = tool_data_all(res.T_flange_tool) if conv.may_write_model(allow_unconverged) else {}
    touch_verdict = None if touch is None else touchup_verdict(
        touch.rms_mm, touch.tcp_mm, loo_mm=leave_one_out_residuals(T[:-3]), labels=poses.labels[:-3])
    verdict = seven_point_verdict(res.orthogonality_error_deg, res.T_flange_tool, touch_verdict)
    if as_json:
        d = {"file": file, "convention": poses.convention, **res.to_dict(),
             "touch_up": None if touch is None else touch.to_dict(),
             "tool_data": {k: v.to_dict() for k, v in data.items()},
             "status": verdict.status, "reasons": list(verdict.reasons), "convergence": conv.as_dict()}
        _echo_json(d)
        _exit_if_failed(verdict)
        finish_convergence(conv, allow_unconverged)
        return
    if touch is not None:
        click.echo(f"TCP from {touch.n_poses} touch-up poses: {_v(touch.tcp_mm)} mm (rms {touch.rms_mm:.4f} mm, "
                   f"spread {touch.orientation_spread_deg:.1f} deg)")
        for lab, r in zip(poses.labels[:-3], touch.residuals_mm):
            click.echo(f"  {lab:>10s}  residual {r:8.4f} mm")
    else:
        click.echo(f"TCP given: {_v(t)} mm")
    click.echo(f"orientation from {', '.join(poses.labels[-3:])} (P5, P6, P7):")
    click.echo(f"  X/Z orthogonality error before orthonormalization {res.orthogonality_error_deg:+.3f} deg")
    click.echo(f"  flange orientation change over P5..P7 {res.flange_orientation_change_deg:.3f} deg")
    _echo_matrix("T_flange_tool", res.T_flange_tool)
    if data:
        _print_tool_data(res.T_flange_tool)
    _exit_if_failed(verdict)
    finish_convergence(conv, allow_unconverged)


@tcp.command("parallel-barriers")
@click.argument("file", type=FILE)
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def parallel_barriers(file, as_json):
    """Tool axis (4-6) and length (4-7) from two parallel light barriers.

    FILE: TOML with h_up, h_down (or delta_h), x_up = [x_up1..x_up4], x_down = [x_down1..x_down4],
    optionally z7 and x_up_vertical / x_down_vertical (docs/tcp.md).
    """
    try:
        kw = read_parallel_barriers_file(file)
        res = parallel_barriers_tool(**kw)
    except ValueError as exc:
        raise _fail(exc) from None
    verdict = barriers_verdict(res.tcp_mm, res.length_mm)
    if as_json:
        d = {"file": file, **res.to_dict(), "status": verdict.status, "reasons": list(verdict.reasons)}
        if res.tcp_mm is not None:
            d["tool_data"] = {k: v.to_dict() for k, v in tool_data_all(res.T_flange_tool).items()}
        _echo_json(d)
        _exit_if_failed(verdict)
        return
    click.echo(f"tool axis (flange frame, unit)  {_v(res.axis, '{:.6f}')}")
    click.echo(f"a (4-6)                         {_v(res.axis_raw_mm)} mm")
    click.echo(f"tilt from Z_e                   {res.tilt_deg:.3f} deg (psi {res.psi_deg:.2f} deg)")
    if res.vertical_residual_deg is not None:
        click.echo(f"tilt left after alignment       {res.vertical_residual_deg:.3f} deg")
    if res.length_mm is not None:
        click.echo(f"length D (4-7)                  {res.length_mm:.4f} mm")
        click.echo(f"TCP (flange frame)              {_v(res.tcp_mm)} mm")
        _print_tool_data(res.T_flange_tool)
    else:
        click.echo("length: not recorded (give z7 and h_up)")
    _exit_if_failed(verdict)


@tcp.command("calibrate-sensor")
@click.argument("file", type=FILE)
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def sensor_calibrate(file, as_json):
    """Cross-laser sensor frame from the block/unblock points (4-15 ... 4-27).

    FILE: CSV 'label,x,y,z' (mm, base frame) with labels A1-A4, B1-B4 (X beam), C1-C4, D1-D4
    (Y beam); see docs/tcp.md.
    """
    try:
        cal = calibrate_sensor(read_sensor_points_csv(file))
    except ValueError as exc:
        raise _fail(exc) from None
    verdict = sensor_verdict(cal.beta_deg, cal.gap_mm)
    if as_json:
        _echo_json({**cal.to_dict(), "status": verdict.status, "reasons": list(verdict.reasons)})
        _exit_if_failed(verdict)
        return
    click.echo(f"origin M (base)         {_v(cal.origin_mm)} mm")
    click.echo(f"X_s (X beam, A->B)      {_v(cal.x_axis, '{:.6f}')}")
    click.echo(f"Y beam (C->D)           {_v(cal.y_axis, '{:.6f}')}")
    click.echo(f"Y_s' (orthogonal)       {_v(cal.y_axis_orthogonal, '{:.6f}')}")
    click.echo(f"Z_s                     {_v(cal.z_axis, '{:.6f}')}")
    click.echo(f"beta                    {cal.beta_deg:.4f} deg ({cal.beta_deg - 90.0:+.4f} from 90)")
    click.echo(f"gap between the beams   {cal.gap_mm:.4f} mm")
    _echo_matrix("T_base_sensor", cal.T_base_sensor)
    _exit_if_failed(verdict)
