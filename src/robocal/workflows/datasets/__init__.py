"""The reference calibration protocols of the real data sets (docs/datasets.md), one module per
data set; the data are read by :mod:`robocal.io.datasets`.

* :func:`calibrate_boby`, :func:`calibrate_boby_seeds`  24/12 random splits, seeds 0-4;
* :func:`calibrate_justin`                              400/100 random split, seed 0;
* :func:`calibrate_hilti`, :func:`hilti_station_protocol`  fit on ``flat``, per-station Kabsch test.

Each returns plain dicts of holdout statistics (:func:`error_stats`);
``python -m robocal.workflows.datasets`` prints them all (:func:`report`).
"""

from ._fitting import error_stats
from .boby_fanuc import boby_model, calibrate_boby, calibrate_boby_seeds
from .dlr_justin import JUSTIN_CHAIN_LINKS, calibrate_justin
from .hilti_trailblazer import HILTI_ARM_JOINTS, calibrate_hilti, hilti_station_protocol
from .report import report

__all__ = [
    "error_stats",
    "boby_model",
    "calibrate_boby",
    "calibrate_boby_seeds",
    "JUSTIN_CHAIN_LINKS",
    "calibrate_justin",
    "HILTI_ARM_JOINTS",
    "hilti_station_protocol",
    "calibrate_hilti",
    "report",
]
