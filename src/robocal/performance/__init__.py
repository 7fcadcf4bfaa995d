"""Robot performance as a plant accepts it: ISO 9283 characteristics, the ISO test cube and poses,
measuring-instrument adequacy, and the quick verification of a calibrated robot.

Pure numerics (numpy/scipy): no files, no plots (those live in ``robocal.workflows`` and
``robocal.report``). Lengths mm, angles in the unit each name states.
"""

from .adequacy import InstrumentMPE, figure_adequacy, parse_mpe
from .iso9283 import (
    PathCharacteristics,
    PoseCharacteristics,
    distance_characteristics,
    drift_characteristics,
    multidirectional_variation,
    orientation_deviations_deg,
    path_characteristics,
    pose_characteristics,
)
from .iso_cube import IsoCube, iso_cube_points, iso_test_poses
from .verify import VerificationResult, verify_positions

__all__ = [
    "InstrumentMPE", "figure_adequacy", "parse_mpe",
    "PathCharacteristics", "PoseCharacteristics", "distance_characteristics", "drift_characteristics",
    "multidirectional_variation", "orientation_deviations_deg", "path_characteristics", "pose_characteristics",
    "IsoCube", "iso_cube_points", "iso_test_poses",
    "VerificationResult", "verify_positions",
]
