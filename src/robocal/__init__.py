"""robocal: keep industrial robots accurate over their working life.

The public API is the names in ``__all__`` (docs/api.md, docs/tutorial.md); everything else is
private by path and may change. The names are imported on first use, so ``import robocal`` stays
fast (no numba, scipy or matplotlib until a calibration runs).

>>> import robocal
>>> robot = robocal.load_robot("ur10")
>>> robot.n_joints
6
"""

__version__ = "0.1.0"

# public name -> module that defines it (relative to this package)
_PUBLIC = {
    "load_robot": "._api.loading",
    "read_measurements": "._api.loading",
    "calibrate": "._api.calibration",
    "CalibrationOptions": "._api.calibration",
    "CalibrationResult": "._api.calibration",
    "correct_targets": "._api.correction",
    "CorrectionOptions": "._api.correction",
    "calibrate_hand_eye": "._api.handeye",
    "HandEyeOptions": "._api.handeye",
    "HandEyeResult": "._api.handeye",
    "calibrate_tool": "._api.tool",
    "ToolOptions": "._api.tool",
    "RobocalError": ".errors",
    "InputError": ".errors",
    "InputFileError": ".errors",
    "NotIdentifiableError": ".errors",
    "NotConvergedError": ".errors",
    "SanityGateError": ".errors",
    "OutputExistsError": ".errors",
    "RobocalWarning": ".errors",
}

__all__ = list(_PUBLIC)


def __getattr__(name):
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'robocal' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
