"""Station frames: the robot base in the instrument frame, one rigid frame per station."""

from __future__ import annotations

from .manifolds import FramesBlock

__all__ = ["StationFrames"]


class StationFrames(FramesBlock):
    """One frame ``T_instrument_base`` (4, 4) [mm] per station (pose group), left-perturbed.

    Variables ``base.rx .. base.z`` for one station, ``base0.*``, ``base1.*`` ... for several
    (``name`` sets the prefix). Identifiability group ``"base"``.
    """

    group = "base"

    def __init__(self, initial, *, name: str = "base", labels=None, free=True, prior=None):
        super().__init__(name, initial, labels=labels, free=free, prior=prior)
