"""Hand-eye calibration (issue 14; METHODS.md section 3 "Hand-eye"): linear AX = XB solvers
(Tsai–Lenz, Park–Martin, Daniilidis) and AX = ZB (Shah), eye-in-hand and eye-to-hand, with
degeneracy checks. Conventions in :mod:`.motions`. Math only: numpy, no files, no OpenCV."""

from .ax_xb import daniilidis, park_martin, translation_least_squares, tsai_lenz
from .ax_zb import shah
from .motions import SETUPS, HandEyeError, check_motions, motion_pairs, robot_poses
from .solve import AX_XB_METHODS, solve_hand_eye, solve_robot_world_hand_eye

__all__ = ["SETUPS", "AX_XB_METHODS", "HandEyeError", "check_motions", "daniilidis", "motion_pairs",
           "park_martin", "robot_poses", "shah", "solve_hand_eye", "solve_robot_world_hand_eye",
           "translation_least_squares", "tsai_lenz"]
