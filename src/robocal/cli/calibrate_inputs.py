"""``robocal calibrate --format``: a tracker export and a joint log read directly (the options
of ``robocal import``), and the exit code of a solve that did not converge."""

from __future__ import annotations

import functools

import click

__all__ = ["EXIT_NOT_CONVERGED", "import_options", "read_export"]

from ._common import EXIT_NOT_CONVERGED  # noqa: E402  (the one exit-code table, cli/_common.py)

_OPTIONS = [
    click.option("--format", "point_format", type=click.Choice(["robocal", "tracker-csv", "sa-text"]),
                 default="robocal", show_default=True,
                 help="Format of DATA: robocal's measurement file, a tracker CSV export or a SpatialAnalyzer "
                      "text export (the last two need --joints; see `robocal import`)."),
    click.option("--joints", "joints_file", type=click.Path(dir_okay=False), default=None,
                 help="With --format tracker-csv|sa-text: the controller joint log."),
    click.option("--pair", type=click.Choice(["index", "id", "time"]), default="index", show_default=True,
                 help="With --format: pair points and joint rows by row order, pose id or time stamp."),
    click.option("--time-tolerance", "tolerance_s", type=float, default=None, metavar="S", help="With --pair time: largest gap [s]."),
    click.option("--length-unit", type=click.Choice(["mm", "m", "in"]), default=None,
                 help="With --format: unit of the points (default: declared by the file, else detected and said)."),
    click.option("--angle-unit", type=click.Choice(["deg", "rad"]), default=None,
                 help="With --format: unit of the joint log's angles (unless its header names it)."),
]


def import_options(f):
    """Decorate a command with the options of :data:`_OPTIONS` (in this order)."""
    for opt in reversed(_OPTIONS):
        f = opt(f)
    return functools.wraps(f)(f)


def read_export(robot, data, opts: dict):
    """The paired :class:`~robocal.io.Measurements` of a tracker export (``None`` for robocal's own
    format, which the calibration reads itself); notes go to stderr."""
    fmt = opts["point_format"]
    if fmt == "robocal":
        if opts["joints_file"]:
            raise ValueError("--joints is for --format tracker-csv or sa-text; DATA is robocal's measurement file")
        return None
    if not opts["joints_file"]:
        raise ValueError(f"--format {fmt} needs --joints (the controller joint log to pair the points with)")
    from ..workflows.importing import read_campaign

    r = read_campaign(data, opts["joints_file"], robot=robot, point_format=fmt, pair=opts["pair"],
                      tolerance_s=opts["tolerance_s"], length_unit=opts["length_unit"], angle_unit=opts["angle_unit"])
    click.echo(r["pairing"].report().splitlines()[0], err=True)
    for note in r["notes"]:
        click.echo(f"note: {note}", err=True)
    return r["measurements"]


def finish_calibration(r: dict, allow_unconverged: bool) -> None:
    """The common end of the calibration commands: notes, the files written, and the exit code
    (3: failed the sanity gates; 4: did not converge unless allowed, with one ``Warning:`` line)."""
    import sys

    from ._common import EXIT_FAILED_RESULT, _report_verdict, finish_convergence

    for note in r["notes"]:
        click.echo(f"note: {note}")
    click.echo("wrote " + ", ".join(str(p) for p in r["files"].values()))
    conv = r["convergence"]
    if not r["verdict"].ok:
        if not conv.converged:
            click.echo(f"Warning: {conv.warning()}", err=True)
        _report_verdict(r["verdict"])
        sys.exit(EXIT_FAILED_RESULT)
    finish_convergence(conv, allow_unconverged)
