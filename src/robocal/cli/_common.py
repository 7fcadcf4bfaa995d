"""Helpers shared by the command modules: argument parsing and one-line user errors."""

from __future__ import annotations

import math

import click
import numpy as np

from ..robots import RobotFileError, load_robot

#: The one exit-code table of every command (docs/cli.md, docs/reliability.md):
#: 0 success; 1 an error (one ``Error:`` line); 2 a usage error (click's own code); 3 a result that
#: FAILED its sanity gates (written with ``status: failed``, no robot/camera/tool file unless
#: ``--force``); 4 a solver that did not converge (no output model unless ``--allow-unconverged``);
#: 5 targets not reached (``correct``: some corrected targets are out of reach); 6 a mechanical fault
#: suspected (``verify``: one joint's offset explains the misfit).
EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_FAILED_RESULT, EXIT_NOT_CONVERGED, EXIT_TARGETS_NOT_REACHED = 0, 1, 2, 3, 4, 5
EXIT_MECHANICAL_FAULT = 6

JOINTS_ARG = dict(nargs=-1, type=str, required=True)
NUMBERS_CONTEXT = {"ignore_unknown_options": True, "allow_interspersed_args": True}


def _robot(name):
    try:
        return load_robot(name)
    except RobotFileError as exc:
        raise click.ClickException(str(exc)) from None


def _numbers(values, what):
    out = []
    for i, v in enumerate(values, 1):
        try:
            x = float(v)
        except ValueError:
            raise click.ClickException(f"{what} {i}: {v!r} is not a number") from None
        if not math.isfinite(x):
            raise click.ClickException(f"{what} {i}: {v!r} is not a finite number")
        out.append(x)
    return np.array(out)


def _prismatic(model):
    return model.prismatic_joints


def _joints_from_cli(model, values, deg):
    q = _numbers(values, "joint")
    if len(q) != model.n_joints:
        raise click.ClickException(
            f"{model.name} has {model.n_joints} joints ({', '.join(model.controller_joints)}), got {len(q)} values")
    pris = _prismatic(model)
    if deg:
        q = np.where(pris, q, np.radians(q))
    lo, hi = model.limits[:, 0], model.limits[:, 1]
    bad = np.flatnonzero((q < lo - 1e-12) | (q > hi + 1e-12))
    if bad.size:
        j = int(bad[0])
        scale, unit = (1.0, "mm") if pris[j] else ((180 / math.pi, "deg") if deg else (1.0, "rad"))
        raise click.ClickException(
            f"joint {model.controller_joints[j]} = {q[j] * scale:.6g} {unit} is outside its limits "
            f"[{lo[j] * scale:.6g}, {hi[j] * scale:.6g}] {unit}" + ("" if deg else " (pass --deg for degrees)"))
    return q


def _user_error(exc) -> click.ClickException:
    """One line ``Error: ...`` from an exception of the library (file, value, name problems)."""
    msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    return click.ClickException(" ".join(str(msg).split()))


def _names(values):
    """Parameter names from repeated options, each comma or space separated."""
    return [n for v in values for n in v.replace(",", " ").split()]


def _step_printer(i, n, text):
    click.echo(f"[{i}/{n}] {text}", err=True)


def _report_verdict(verdict) -> None:
    """Print a failed :class:`~robocal.calib.sanity.Verdict` to stderr: ``FAILED:`` and its reasons."""
    click.echo("FAILED: the result did not pass the sanity gates (exit code 3):", err=True)
    for reason in verdict.reasons:
        click.echo(f"  - {reason}", err=True)


def _item_progress(i: int, n: int, text: str) -> None:
    """Progress over images or items on stderr: ``[i/n] text`` (camera, hand-eye, self-calibration, simulators)."""
    click.echo(f"[{i}/{n}] {text}", err=True)


def allow_unconverged_option(f):
    """The ``--allow-unconverged`` flag of every command that fits something (one help text); the
    command runs with the solver's own ``NotConvergedWarning`` silenced: it reports non-convergence
    in one ``Warning:`` line (:func:`finish_convergence`)."""
    import functools

    @functools.wraps(f)
    def quiet(*args, **kwargs):
        import warnings

        from ..calib.solve import NotConvergedWarning

        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=NotConvergedWarning)
            return f(*args, **kwargs)

    return click.option("--allow-unconverged", is_flag=True,
                        help="Accept a fit that did not converge: write its model file and exit 0 "
                             f"(otherwise no model file is written and the exit code is {EXIT_NOT_CONVERGED}).")(quiet)


def finish_convergence(convergence, allow_unconverged: bool) -> None:
    """The end of every fitting command when its fits did not all converge
    (:class:`~robocal.workflows.convergence.Convergence`): one ``Warning:`` line on stderr with the
    reason and what to try; exit 4 unless ``allow_unconverged``. Does nothing when all converged."""
    if convergence is None or convergence.converged:
        return
    click.echo(f"Warning: {convergence.warning()}", err=True)
    if not allow_unconverged:
        import sys

        sys.exit(EXIT_NOT_CONVERGED)
