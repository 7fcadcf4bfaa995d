"""Simulator: a virtual robot with hidden true parameters and virtual instruments.

Used by tests and demos, never by the numeric core. Instruments produce the same
:class:`~robocal.io.Measurements` and files as real ones.
"""

from .robot import VirtualRobot, as_rng, controller_joint_prismatic, parameter_kinds
from .tracker import LaserTracker, fit_rotations, reflector_triangle, write_truth

__all__ = [
    "VirtualRobot",
    "LaserTracker",
    "as_rng",
    "controller_joint_prismatic",
    "fit_rotations",
    "parameter_kinds",
    "reflector_triangle",
    "write_truth",
]
