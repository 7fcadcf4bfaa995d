"""``robocal calibrate --format``: a tracker export and a joint log read directly (the options
of ``robocal import``), and the exit code of a solve that did not converge."""

from __future__ import annotations

import functools

import click

__all__ = ["EXIT_NOT_CONVERGED", "PAIRING_OPTIONS", "import_options", "pairing_options", "read_export", "echo_pairing"]

from ._common import EXIT_NOT_CONVERGED  # noqa: E402  (the one exit-code table, cli/_common.py)

#: The pairing and reading options ``robocal import`` and ``robocal calibrate --format`` share.
PAIRING_OPTIONS = [
    click.option("--id-match", type=click.Choice(["exact", "number"]), default="exact", show_default=True,
                 help="With --pair id: exact names, or the number in them (P017 = 17)."),
    click.option("--offset", "offset_s", type=float, default=0.0, show_default=True,
                 help="With --pair time: added to the joint log's times [s] (a known clock difference)."),
    click.option("--name-fields", type=click.IntRange(0, 3), default=None,
                 help="With --format sa-text: number of name fields (collection, group, point) before X Y Z "
                      "(default: inferred from a constant field count)."),
    click.option("--joint-columns", default=None, metavar="NAMES",
                 help="The joint log's joint columns in order, comma separated (default: recognised by name: A1, "
                      "J1, joint_1, UR RTDE actual_q_0, KUKA $AXIS_ACT.A1 / AIPos_A1, ABB rob1_j1)."),
    click.option("--orientation", default=None, metavar="CONVENTION",
                 help="Convention of the export's orientation angles (rpy, kuka_abc, zyz, rotvec, ...; see "
                      "docs/importers.md); quaternion columns need none. Without it angle columns are not imported "
                      "(said in a note)."),
    click.option("--orientation-unit", type=click.Choice(["deg", "rad"]), default=None,
                 help="Unit [deg|rad] of the export's orientation angles when its header does not name it."),
]

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
    *PAIRING_OPTIONS,
]


def import_options(f):
    """Decorate a command with the options of :data:`_OPTIONS` (in this order)."""
    for opt in reversed(_OPTIONS):
        f = opt(f)
    return functools.wraps(f)(f)


def pairing_options(f):
    """Decorate a command with :data:`PAIRING_OPTIONS` (``robocal import``)."""
    for opt in reversed(PAIRING_OPTIONS):
        f = opt(f)
    return f


def joint_column_names(text):
    """``--joint-columns`` text as a list of names (``None`` when not given)."""
    if not text:
        return None
    return [c.strip() for c in str(text).split(",") if c.strip()]


def echo_pairing(r: dict, err: bool = False) -> None:
    """The pairing summary and the import's notes on the console."""
    for line in r["pairing"].summary():
        click.echo(line, err=err)
    for note in r["notes"]:
        click.echo(f"note: {note}", err=err)


def read_export(robot, data, opts: dict):
    """The paired :class:`~robocal.io.Measurements` of a tracker export (``None`` for robocal's own
    format, which the calibration reads itself); notes go to stderr."""
    fmt = opts["point_format"]
    if fmt == "robocal":
        given = [name for name, key, default in (("--joints", "joints_file", None), ("--orientation", "orientation", None),
                                                  ("--orientation-unit", "orientation_unit", None),
                                                  ("--name-fields", "name_fields", None),
                                                  ("--joint-columns", "joint_columns", None),
                                                  ("--id-match", "id_match", "exact"), ("--offset", "offset_s", 0.0))
                 if opts.get(key, default) != default]
        if given:
            raise ValueError(f"{', '.join(given)}: for --format tracker-csv or sa-text; DATA is robocal's measurement "
                             "file (its header declares its orientation columns)")
        return None
    if not opts["joints_file"]:
        raise ValueError(f"--format {fmt} needs --joints (the controller joint log to pair the points with)")
    from ..workflows.calibration.importing import read_campaign

    r = read_campaign(data, opts["joints_file"], robot=robot, point_format=fmt, pair=opts["pair"],
                      tolerance_s=opts["tolerance_s"], length_unit=opts["length_unit"], angle_unit=opts["angle_unit"],
                      offset_s=opts["offset_s"], id_match=opts["id_match"], name_fields=opts["name_fields"],
                      joint_columns=joint_column_names(opts["joint_columns"]), orientation=opts["orientation"],
                      orientation_unit=opts["orientation_unit"])
    echo_pairing(r, err=True)
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
