"""Batched rigid transforms and orientation conventions (see docs/conventions.md).

Private modules, each importing only the ones listed before it: ``_checks`` (input checks),
``_quaternion`` (quaternions, rotation-vector logarithm), ``_basic`` (SO(3)/SE(3) primitives),
``_orientation`` (Euler conventions, poses at the boundary with declared units).
"""

from ._basic import *  # noqa: F401,F403
from ._basic import __all__ as _basic_all
from ._checks import *  # noqa: F401,F403
from ._checks import __all__ as _checks_all
from ._orientation import *  # noqa: F401,F403
from ._orientation import __all__ as _orientation_all
from ._quaternion import *  # noqa: F401,F403
from ._quaternion import __all__ as _quaternion_all

__all__ = list(_checks_all) + list(_basic_all) + list(_quaternion_all) + list(_orientation_all)
