"""Geometric calibration in memory: :func:`calibrate`, its options and its result.

``robocal calibrate`` runs exactly this function and then :meth:`CalibrationResult.save`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["CalibrationOptions", "CalibrationResult", "calibrate"]


@dataclass(frozen=True)
class CalibrationOptions:
    """Settings of :func:`calibrate` (the options of ``robocal calibrate``), all with defaults.

    Parameters
    ----------
    free : tuple of str, optional
        Parameters to identify (e.g. ``("a2", "a3", "theta2")``). Default: every parameter the
        robot file does not list as fixed.
    free_all : bool, default False
        Identify every kinematic parameter (ignore the robot file's fixed lists).
    frames_only : bool, default False
        Hold the whole geometry; fit only the base (instrument) and tool frames (a calibrated
        robot moved to a new cell).
    fix : tuple of str, default ()
        Parameters held at their nominal values.
    holdout : float, default 0.2
        Fraction of poses held out for validation, in [0, 1) (a seeded random split).
    seed : int, default 0
        Seed of the held-out split and of the particle swarm.
    method : {"lm", "svd", "ipso", "ipso+lm"}, default "lm"
        Solver: Levenberg-Marquardt, SVD least squares, the improved particle swarm, or the swarm
        followed by Levenberg-Marquardt.
    loss : {"linear", "huber", "cauchy"}, default "linear"
        Loss per pose (``huber`` and ``cauchy`` down-weight outlier poses).
    noise_mm : float, optional
        Measurement noise per coordinate [mm]; default: estimated from the residuals.
    tool_mm : tuple of 3 float, optional
        Initial target point in the flange frame [mm]; default the flange origin.
    rotation_weight : float, optional
        6-D measurements: mm that one rad of orientation error counts [mm/rad] (default 100).
    use_orientation : bool, default True
        Use the file's orientation columns (a 6-D fit with a tool frame) when it has them.
    prior_sigma : tuple of 2 float, optional
        ``(mm, deg)``: a weak Gaussian prior on the geometry around nominal, lengths [mm] and
        angles [deg]; default no prior.
    train_ids, holdout_ids : tuple of str, default ()
        A given protocol: the pose ids to calibrate on and to validate on (instead of the split).
    max_iterations : int, default 1000
        Iteration limit of the solver.
    drop_duplicates : bool, default False
        Drop repeated poses when reading a file (otherwise they are an error).
    particles : int, default 20
        Particle swarm: swarm size.
    generations : int, default 2000
        Particle swarm: number of generations.
    elastic : {"joint", "full"}, optional
        Also identify joint compliance under gravity (docs/elastic.md).
    payload : str, optional
        With ``elastic``: the payload carried during the measurements, ``"KG@X,Y,Z"`` (mass [kg]
        at the centre of mass [mm] in the flange frame).
    """

    free: tuple | None = None
    free_all: bool = False
    frames_only: bool = False
    fix: tuple = ()
    holdout: float = 0.2
    seed: int = 0
    method: str = "lm"
    loss: str = "linear"
    noise_mm: float | None = None
    tool_mm: tuple | None = None
    rotation_weight: float | None = None
    use_orientation: bool = True
    prior_sigma: tuple | None = None
    train_ids: tuple = ()
    holdout_ids: tuple = ()
    max_iterations: int = 1000
    drop_duplicates: bool = False
    particles: int = 20
    generations: int = 2000
    elastic: str | None = None
    payload: str | None = None


class CalibrationResult:
    """The outcome of :func:`calibrate`: the calibrated robot and every number about it.

    Attributes
    ----------
    robot : RobotModel
        The calibrated model (identified geometry; its base is the robot base in the measurement
        instrument's frame). The nominal model is never changed.
    nominal : RobotModel
        The model the calibration started from.
    parameters : dict of str to float
        Identified value of every solver variable (kinematic parameters, base frame, target
        points) [mm or rad, as ``units``].
    sigma : dict of str to float
        One standard deviation of each variable [mm or rad]; NaN where not identifiable.
    units : dict of str to str
        Unit of each variable, ``"mm"`` or ``"rad"``.
    targets_mm : numpy.ndarray, shape (k, 3)
        The identified target points (reflectors) in the flange frame [mm].
    identifiability : dict
        ``identifiable`` (names) and ``dropped`` (name and why) of the solver variables.
    holdout : dict or None
        Held-out position errors ``before`` and ``after`` (``rms``, ``mean``, ``p95``, ``max``
        [mm]) and ``n_poses``; None without held-out poses.
    rms_before_mm, rms_after_mm : float
        RMS position error on the calibration poses before and after [mm].
    converged : bool
        The solver met its convergence criterion.
    status : {"ok", "failed"}
        The sanity gates' verdict; ``reasons`` lists one sentence per failed gate.
    result : dict
        Everything ``result.json`` holds (JSON-ready).
    """

    def __init__(self, computed: dict):
        self._computed = computed
        r = computed["calibration_result"]
        rd = computed["result"]
        self.robot = computed["robot"]
        self.nominal = computed["nominal"]
        self.parameters = {n: float(v) for n, v in zip(r.names, r.values)}
        self.sigma = {n: float(s) for n, s in zip(r.names, r.std)}
        self.units = dict(zip(r.names, r.units))
        self.targets_mm = r.state.targets.copy()
        self.identifiability = rd["identifiability"]
        self.holdout = computed["validation"]
        self.rms_before_mm = float(r.rms_before)
        self.rms_after_mm = float(r.rms_after)
        self.converged = bool(computed["convergence"].converged) if "convergence" in computed else \
            bool(r.converged) and not computed["convergence_warnings"]
        self.status = computed["verdict"].status
        self.reasons = list(computed["verdict"].reasons)
        self.result = rd

    def __repr__(self) -> str:
        return (f"CalibrationResult(robot={self.nominal.name!r}, rms_after_mm={self.rms_after_mm:.4f}, "
                f"converged={self.converged}, status={self.status!r})")

    def save(self, folder, *, overwrite: bool = False, report: bool = True, force: bool = False,
             progress=None, allow_unconverged: bool = False) -> dict:
        """Write the outputs of ``robocal calibrate`` into ``folder``.

        Parameters
        ----------
        folder : str or os.PathLike
            Output folder (created if needed): ``result.json``, ``residuals.csv``, ``accuracy_map.csv``, ``calibrated_robot.toml``,
            ``calibrated_robot.urdf`` and ``report.html``.
        overwrite : bool, default False
            Replace existing output files.
        report : bool, default True
            Write ``report.html`` (its plots take longer than the solve).
        force : bool, default False
            Write the calibrated robot files even when the result failed the sanity gates.
        progress : callable, optional
            ``progress(step, total, text)``, called between steps.
        allow_unconverged : bool, default False
            Write the calibrated robot files even when a fit did not converge.

        Returns
        -------
        dict of str to pathlib.Path
            The files written, by kind (``result``, ``robot``, ``urdf``, ``report``).

        Raises
        ------
        robocal.OutputExistsError
            An output file exists and ``overwrite`` is false (nothing is written).
        """
        return self._write(folder, overwrite=overwrite, report=report, force=force, progress=progress,
                           allow_unconverged=allow_unconverged)["files"]

    def _write(self, folder, **kwargs) -> dict:
        """:meth:`save` returning everything ``robocal calibrate`` prints (notes, verdict, files)."""
        from ..workflows.calibration.calibrate import write_calibration

        return write_calibration(self._computed, folder, **kwargs)


def calibrate(robot, measurements, *, options: CalibrationOptions | None = None, progress=None,
              swarm_progress=None, name: str | None = None) -> CalibrationResult:
    """Calibrate a robot's kinematics from measurements, in memory (no files are written).

    Splits the poses into calibration and held-out poses, identifies the kinematic parameters,
    the base frame in the instrument frame and the target point(s) on the flange, validates on the
    held-out poses and applies the sanity gates.

    Parameters
    ----------
    robot : str, os.PathLike or RobotModel
        The nominal robot: a shipped name, a robot file, or a loaded model.
    measurements : str, os.PathLike or Measurements
        A measurement file (``robocal-measurements/1``) or measurements already read
        (:func:`robocal.read_measurements`): joints (N, n_joints) [rad], points (N, k, 3) [mm].
    options : CalibrationOptions, optional
        Solver and protocol settings; default ``CalibrationOptions()``.
    progress : callable, optional
        ``progress(step, total, text)``: called between steps and about once a second in a solve.
    swarm_progress : callable, optional
        ``swarm_progress(generation, best_cost)`` of the particle swarm methods.
    name : str, optional
        How the result names the measurements (default: the file's path, or the ``source`` of
        measurements read before).

    Returns
    -------
    CalibrationResult
        The calibrated model ``.robot``, ``.sigma``, ``.identifiability``, ``.holdout``,
        ``.converged`` and ``.save(folder)``.

    Raises
    ------
    robocal.InputFileError
        A file cannot be read (the message names file, row and column).
    robocal.InputError
        The options or the measurements cannot work (too few poses, unknown parameter names).
    """
    from ..io.measurements import Measurements
    from ..kinematics import RobotModel
    from ..workflows.calibration.calibrate import compute_calibration
    from .loading import load_robot

    o = options if options is not None else CalibrationOptions()
    nominal = robot if isinstance(robot, RobotModel) else load_robot(robot)
    robot_label = nominal.name if isinstance(robot, RobotModel) else robot
    if isinstance(measurements, Measurements):
        meas, data_label = measurements, measurements.metadata.get("source", "measurements in memory")
    else:
        meas, data_label = _read(nominal, measurements, o, progress), measurements
    data_label = data_label if name is None else name
    computed = compute_calibration(
        nominal, meas, robot_label=robot_label, data_label=data_label,
        free=list(o.free) if o.free is not None else None, frames_only=o.frames_only,
        free_all=o.free_all, fix=list(o.fix), holdout=o.holdout, seed=o.seed, loss=o.loss, sigma_mm=o.noise_mm,
        tool=o.tool_mm, method=o.method, rotation_weight=o.rotation_weight, prior=o.prior_sigma,
        train_ids=o.train_ids, holdout_ids=o.holdout_ids, use_orientation=o.use_orientation,
        max_iterations=o.max_iterations, particles=o.particles, generations=o.generations,
        swarm_progress=swarm_progress, elastic=o.elastic, payload=o.payload, progress=progress)
    return CalibrationResult(computed)


def _read(nominal, path, options: CalibrationOptions, progress=None):
    """The measurements of ``path`` as :func:`calibrate` reads them (joint limits of ``nominal``
    checked; a line of progress first for a large file)."""
    from .loading import read_measurements

    size_mb = Path(path).stat().st_size / 1e6 if Path(path).is_file() else 0.0
    if progress is not None and size_mb > 10.0:  # a large file takes seconds to read: say so
        progress(1, 6, f"reading {path} ({size_mb:.0f} MB)")
    return read_measurements(path, nominal, drop_duplicates=options.drop_duplicates)
