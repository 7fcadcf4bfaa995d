"""Corrected joint targets in memory: what a nominal-model controller must command so that the
real (calibrated) robot reaches Cartesian targets ("program filtering")."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CorrectionOptions", "correct_targets"]


@dataclass(frozen=True)
class CorrectionOptions:
    """Settings of :func:`correct_targets`, all with defaults.

    Parameters
    ----------
    frame : {"world", "base"}, default "world"
        Frame of the targets: the calibrated model's world frame (for a model written by
        ``robocal calibrate``, the measurement instrument's frame) or the robot base frame.
    tolerance_mm : float, default 1e-7
        Position tolerance of the inverse kinematics [mm].
    max_iterations : int, default 200
        Iteration limit of the inverse kinematics per target.
    """

    frame: str = "world"
    tolerance_mm: float = 1e-7
    max_iterations: int = 200


def correct_targets(calibrated, targets, *, rotations=None, nominal=None, q_seed=None,
                    options: CorrectionOptions | None = None):
    """Joints that put the calibrated robot exactly on Cartesian targets.

    Parameters
    ----------
    calibrated : RobotModel or str
        The calibrated robot (e.g. :attr:`CalibrationResult.robot`, or its robot file).
    targets : array_like, shape (N, 4, 4) or (N, 3)
        Target poses, or positions [mm] (then the orientation is the nominal solution's).
    rotations : array_like, shape (N, 3, 3), optional
        Target orientations for position ``targets``.
    nominal : RobotModel or str, optional
        The model the controller runs; default the shipped robot the calibrated model names.
    q_seed : array_like, shape (N, n_joints) or (n_joints,), optional
        Starting joints [rad] (e.g. the taught joints), to stay on their branch.
    options : CorrectionOptions, optional
        Frame and solver settings.

    Returns
    -------
    CorrectedTargets
        ``q`` (N, n_joints) joints to command [rad, mm for prismatic joints], ``q_nominal``,
        ``T_filtered`` (N, 4, 4) Cartesian targets for a nominal-model controller [mm],
        ``converged`` (N,) bool and the remaining ``position_error_mm`` (N,).

    Raises
    ------
    robocal.InputError
        The two models have different joints, or the frame is unknown.
    """
    from ..calib.outputs import corrected_joint_targets
    from ..errors import InputError
    from .loading import load_robot

    o = options if options is not None else CorrectionOptions()
    cal = load_robot(calibrated) if isinstance(calibrated, str) else calibrated
    nom = load_robot(cal.name if nominal is None else nominal) if not hasattr(nominal, "fk") else nominal
    try:
        return corrected_joint_targets(cal, nom, targets, rotations, q_seed=q_seed, frame=o.frame,
                                       tol_mm=o.tolerance_mm, max_iterations=o.max_iterations)
    except ValueError as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(str(exc)) from None
