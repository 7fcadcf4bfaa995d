"""Robot library: robot definitions as TOML data files, their loader and writer."""

from .loader import RobotFileError, frame_from_xyz_rpy, list_robots, load_robot, parse_robot, robot_path
from .writer import robot_to_toml, save_robot

__all__ = ["RobotFileError", "frame_from_xyz_rpy", "list_robots", "load_robot", "parse_robot", "robot_path",
           "robot_to_toml", "save_robot"]
