"""Robot programs in and out (see docs/robot-programs.md).

:func:`read_program` reads the Cartesian and joint targets of KUKA KRL (``.src``/``.dat``), ABB
RAPID (``.mod``), FANUC TP (``.ls``) and UR script files into :class:`ProgramTarget` objects
(pose [mm] or joints [rad], configuration verbatim, tool/base ids, character spans of the numbers).
:func:`write_program` writes the same program with new target values, replacing only the numbers
that changed; the output never overwrites the input.

:mod:`.joint_table` reads and writes robocal's own ``robocal-program/1`` (a taught program as a
table of joint values, used by ``robocal thermal``): :func:`read_joint_program`,
:func:`write_joint_program`, :class:`JointProgram`.
"""

from .joint_table import JOINT_PROGRAM_FORMAT, JointProgram, JointProgramFileError, read_joint_program, write_joint_program
from .reader import PROGRAM_FORMATS, SUFFIXES, parse_program, read_program
from .target import Program, ProgramTarget, Skipped
from .writer import updated_text, write_program

__all__ = [
    "JOINT_PROGRAM_FORMAT",
    "JointProgram",
    "JointProgramFileError",
    "read_joint_program",
    "write_joint_program",
    "PROGRAM_FORMATS",
    "SUFFIXES",
    "Program",
    "ProgramTarget",
    "Skipped",
    "parse_program",
    "read_program",
    "updated_text",
    "write_program",
]
