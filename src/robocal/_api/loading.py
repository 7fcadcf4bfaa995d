"""Load a robot and read a measurement file: the two inputs of :func:`robocal.calibrate`."""

from __future__ import annotations

from pathlib import Path

__all__ = ["load_robot", "read_measurements"]


def load_robot(name_or_path):
    """Load a robot model: a shipped robot by name or a robot file by path.

    Parameters
    ----------
    name_or_path : str or os.PathLike
        A shipped robot's name (``robocal robots`` lists them, e.g. ``"ur10"``, ``"kr16"``) or the
        path of a robot file (``robocal-robot/1`` TOML, or URDF).

    Returns
    -------
    RobotModel
        The kinematic model; its lengths in [mm], angles in [rad].

    Raises
    ------
    robocal.InputFileError
        The name is unknown or the file cannot be read (the message names file and field).
    """
    from ..robots import load_robot as _load

    try:
        return _load(name_or_path)
    except OSError as exc:
        raise _file_error(name_or_path, exc) from exc


def read_measurements(path, robot=None, *, drop_duplicates: bool = False):
    """Read a measurement file (``robocal-measurements/1`` CSV).

    Parameters
    ----------
    path : str or os.PathLike
        The measurement file: a header naming columns and units, one row per pose.
    robot : RobotModel or str, optional
        The robot the joints belong to (a model, a shipped name or a robot file). When given, the
        joint columns must be its controller joints and every value must lie within its limits.
    drop_duplicates : bool, default False
        Drop repeated pose ids and rows (keeping the first) instead of refusing the file.

    Returns
    -------
    Measurements
        ``joints`` (N, n_joints) [rad, mm for prismatic joints], ``points`` (N, k, 3) [mm] in the
        instrument frame, optional ``rotations`` (N, 3, 3), ``pose_ids`` (N,) and ``metadata``.

    Raises
    ------
    robocal.InputFileError
        The file cannot be read: the message names the file, row and column.
    """
    from ..io.measurements import read_measurements as _read

    model = None if robot is None else (load_robot(robot) if isinstance(robot, (str, Path)) else robot)
    try:
        return _read(path, robot=model, check_limits=model is not None, drop_duplicates=drop_duplicates)
    except OSError as exc:
        raise _file_error(path, exc) from exc


def _file_error(path, exc: OSError):
    """An :class:`~robocal.errors.InputFileError` naming the file for an operating-system error."""
    from ..errors import InputFileError

    text = str(exc)
    return InputFileError(text if str(path) in text else f"{path}: {exc.strerror or text}")
