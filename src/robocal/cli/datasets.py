"""``robocal datasets``: list the real data sets and rerun their protocols (docs/datasets.md)."""

from __future__ import annotations

import json

import click

from ._common import allow_unconverged_option, finish_convergence

MODEL_CHOICES = ("geometric", "elastic-joint", "elastic-full")


@click.group("datasets")
def datasets():
    """The real measured data sets (docs/datasets.md): list them, rerun a protocol."""


@datasets.command("list")
@click.option("--root", type=click.Path(file_okay=False), default=None,
              help="Folder holding the data sets (default: $ROBOCAL_DATASETS or ../shared/datasets).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def list_cmd(root, as_json):
    """The known data sets, their robots and protocols, and whether they are present."""
    from ..workflows.datasets.run import list_datasets

    rows = list_datasets(root)
    if as_json:
        click.echo(json.dumps(rows, indent=2))
        return
    for r in rows:
        click.echo(f"{r['name']:18s} {'present' if r['present'] else 'ABSENT ':7s}  robot {r['robot']}")
        click.echo(f"{'':18s} {r['protocol']}")


@datasets.command("run")
@click.argument("name")
@click.option("--model", type=click.Choice(MODEL_CHOICES), default="geometric", show_default=True,
              help="geometric; elastic-joint (joint compliance under gravity, identified with the geometry); "
                   "elastic-full (+ lateral bending compliance of every joint).")
@click.option("--root", type=click.Path(file_okay=False), default=None,
              help="Folder holding the data sets (default: $ROBOCAL_DATASETS or ../shared/datasets).")
@click.option("--json", "as_json", is_flag=True, help="Print the record as JSON.")
@allow_unconverged_option
def run_cmd(name, model, root, as_json, allow_unconverged):
    """Run the protocol of data set NAME (see `robocal datasets list`) with --model; holdout errors in mm.

    Exit code 4 when one of the protocol's fits did not converge, unless --allow-unconverged."""
    import warnings

    from ..workflows.convergence import Convergence

    from ..io.datasets import DatasetError
    from ..workflows.datasets.run import DATASETS, list_datasets, run_dataset

    if name not in DATASETS:
        raise click.ClickException(f"unknown data set {name!r}; known: {', '.join(DATASETS)}")
    entry = next(r for r in list_datasets(root) if r["name"] == name)
    if not entry["present"]:
        raise click.ClickException(f"data set {name}: folder {entry['folder']}/raw not found (give --root DIR)")
    try:
        from ._progress import Progress

        with warnings.catch_warnings(record=True) as caught, Progress(f"datasets run {name}"):
            warnings.simplefilter("always")
            rec = run_dataset(name, model, root)
    except NotImplementedError as exc:
        raise click.ClickException(str(exc)) from None
    except DatasetError as exc:
        raise click.ClickException(str(exc)) from None
    del caught  # the solver's own warnings: summarised by rec["convergence"]
    conv = Convergence.from_dict(rec["convergence"])
    if as_json:
        click.echo(json.dumps(rec, indent=2))
        finish_convergence(conv, allow_unconverged)
        return
    rows = rec["sets"] if "sets" in rec else [dict(rec, set=name)]
    click.echo(f"{name} ({model}): {rec['protocol']}")
    click.echo(f"{'':18s}{'holdout RMS':>12}{'mean':>8}{'max':>8}   geometric RMS   nominal RMS  [mm]")
    for r in rows:
        label = r['set'] + (" (training)" if r.get("role") == "training" else "")
        click.echo(f"{label:18s}{r['holdout_rms_mm']:12.3f}{r['holdout_mean_mm']:8.3f}{r['holdout_max_mm']:8.2f}"
                   f"   {r['geometric']['rms']:13.3f}   {r['nominal']['rms']:11.3f}")
    click.echo(f"fits: {conv.n_fits}, not converged: {conv.n_not_converged}")
    finish_convergence(conv, allow_unconverged)
