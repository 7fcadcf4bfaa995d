"""Thermal drift compensation (METHODS.md section 4; thesis chapter 3 and 5.1; docs/thermal.md).

* :mod:`.system_calibration` -- the sensor frame ``T_sensor_base`` and the sphere centre ``P_e``
  on the flange, by the thesis's linear/penalty method (3-14 ... 3-19) and by nonlinear least
  squares on the calibration core; their comparison.
* :mod:`.drift` -- the differential drift model ``P_warm - P_cold = M(q) dX`` (3-5 ... 3-7) and the
  SVD identification of a chosen parameter subset (3-8 ... 3-10) with rank checks.
* :mod:`.compensation` -- correcting a taught program for the warm robot by iterative IK, the
  online cycle (identify + correct), and the rule for when to measure again.
"""

from .compensation import (
    CompensationResult,
    CycleRecord,
    OnlineCycle,
    RemeasureDecision,
    RemeasureRule,
    compensate_program,
    online_cycle,
    predicted_drift,
)
from .drift import (
    DriftIdentificationError,
    DriftResult,
    RankDeficientError,
    drift_coefficients,
    identify_drift,
    predict_sphere,
    resolve_subset,
)
from .system_calibration import (
    MIN_SYSTEM_POSES,
    SystemCalibration,
    SystemCalibrationComparison,
    SystemCalibrationError,
    calibrate_system,
    calibrate_system_thesis,
    check_system_poses,
    compare_system_calibrations,
    design_sphere_poses,
    frame_errors,
    thesis_linear_system,
)

__all__ = [
    "MIN_SYSTEM_POSES", "CompensationResult", "CycleRecord", "DriftIdentificationError", "DriftResult",
    "OnlineCycle", "RankDeficientError", "RemeasureDecision", "RemeasureRule", "SystemCalibration",
    "SystemCalibrationComparison", "SystemCalibrationError", "calibrate_system", "calibrate_system_thesis",
    "check_system_poses", "compare_system_calibrations", "compensate_program", "design_sphere_poses",
    "drift_coefficients", "frame_errors", "identify_drift", "online_cycle", "predict_sphere",
"predicted_drift", "resolve_subset", "thesis_linear_system",
]
