"""Robot library: robot definitions as TOML data files, and their loader."""

from .loader import RobotFileError, frame_from_xyz_rpy, list_robots, load_robot, parse_robot, robot_path

__all__ = ["RobotFileError", "frame_from_xyz_rpy", "list_robots", "load_robot", "parse_robot", "robot_path"]
