"""Batched rigid transforms and orientation conventions (see docs/conventions.md)."""

from ._basic import *  # noqa: F401,F403
from ._basic import __all__ as _basic_all
from ._orientation import *  # noqa: F401,F403
from ._orientation import __all__ as _orientation_all

__all__ = list(_basic_all) + list(_orientation_all)
