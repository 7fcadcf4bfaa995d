"""``robocal import``: a tracker export and a controller joint log into a measurement file."""

from __future__ import annotations

import click

from ._common import _user_error
from ._json import json_option, set_json_result


@click.command("import")
@json_option
@click.argument("robot")
@click.argument("points_file", type=click.Path(dir_okay=False))
@click.option("--joints", "joints_file", required=True, type=click.Path(dir_okay=False),
              help="Controller joint log (CSV: id or time stamp + joint columns).")
@click.option("--format", "point_format", type=click.Choice(["tracker-csv", "sa-text"]), default="tracker-csv",
              show_default=True, help="Format of POINTS_FILE: a tracker CSV export or a SpatialAnalyzer text export.")
@click.option("--pair", type=click.Choice(["index", "id", "time"]), default="index", show_default=True,
              help="Pair points and joint rows by row order, by point name = pose id, or by time stamp.")
@click.option("--id-match", type=click.Choice(["exact", "number"]), default="exact", show_default=True,
              help="With --pair id: exact names, or the number in them (P017 = 17).")
@click.option("--time-tolerance", "tolerance_s", type=float, default=None, metavar="S", help="With --pair time: largest time difference [s].")
@click.option("--offset", "offset_s", type=float, default=0.0, show_default=True,
              help="With --pair time: added to the joint log's times [s] (a known clock difference).")
@click.option("--length-unit", type=click.Choice(["mm", "m", "in"]), default=None,
              help="Unit of the points (default: declared by the file, else detected and said).")
@click.option("--angle-unit", type=click.Choice(["deg", "rad"]), default=None,
              help="Unit of the joint log's angles (required unless its header names it, e.g. 'A1 [deg]').")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False), help="Measurement file (CSV) to write.")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
def import_cmd(points_file, joints_file, robot, point_format, pair, id_match, tolerance_s, offset_s, length_unit,
               angle_unit, out_file, overwrite):
    """Pair the tracker points of POINTS_FILE with a joint log of ROBOT (name or robot file) and write
    robocal's measurement file (docs/importers.md); `robocal calibrate ROBOT OUT` then reads it."""
    from ..workflows.importing import import_campaign

    try:
        r = import_campaign(points_file, joints_file, out_file, robot=robot, point_format=point_format, pair=pair,
                            tolerance_s=tolerance_s, offset_s=offset_s, id_match=id_match,
                            length_unit=length_unit, angle_unit=angle_unit, overwrite=overwrite)
    except (ValueError, KeyError, OSError) as exc:
        raise _user_error(exc) from None
    click.echo(r["pairing"].report().splitlines()[0])
    for u in r["pairing"].unmatched:
        click.echo(f"  not paired: {u}")
    for note in r["notes"]:
        click.echo(f"note: {note}")
    click.echo(f"wrote {r['file']}")
    set_json_result(dict(r, unmatched=[str(u) for u in r["pairing"].unmatched]))
