"""Hand-eye calibration (issue 14; METHODS.md section 3 "Hand-eye"): linear AX = XB solvers
(Tsai–Lenz, Park–Martin, Daniilidis) and AX = ZB (Shah), eye-in-hand and eye-to-hand, with
degeneracy checks; PnP; camera calibration and the hand-eye refinement on the calibration core
with back-projection residuals. Conventions in :mod:`.motions`. Math only: numpy, no files, no OpenCV."""

from .ax_xb import daniilidis, park_martin, translation_least_squares, tsai_lenz
from .ax_zb import shah
from .backprojection import rms_px, target_plane_residuals
from .camera_calibration import CameraCalibration, calibrate_camera, initial_intrinsics
from .motions import SETUPS, HandEyeError, check_motions, motion_pairs, robot_poses
from .pnp import solve_pnp
from .refine import LINEAR_METHODS, HandEyeRefinement, joint_offset_names, mean_transform, refine_hand_eye
from .solve import AX_XB_METHODS, solve_hand_eye, solve_robot_world_hand_eye

__all__ = ["SETUPS", "AX_XB_METHODS", "LINEAR_METHODS", "CameraCalibration", "HandEyeError", "HandEyeRefinement",
           "calibrate_camera", "check_motions", "daniilidis", "initial_intrinsics", "joint_offset_names",
           "mean_transform", "motion_pairs", "park_martin", "refine_hand_eye", "rms_px", "robot_poses", "shah",
           "solve_hand_eye", "solve_pnp", "solve_robot_world_hand_eye", "target_plane_residuals",
           "translation_least_squares", "tsai_lenz"]
