"""The 6-DoF tool frame: the measured frame (a 6-D probe, a reflector nest) in the flange frame."""

from __future__ import annotations

from .manifolds import FramesBlock

__all__ = ["ToolFrame"]

class ToolFrame(FramesBlock):
    """``T_flange_measured`` (1, 4, 4) [mm]: the frame a 6-D instrument measures, written in the
    frame of an end effector (default the model's first, the flange), left-perturbed.

    Variables ``tool.rx, tool.ry, tool.rz`` [rad] (rotation vector of the rotation) and
    ``tool.x, tool.y, tool.z`` [mm] (the measured frame's origin). ``end_effector``: name or index
    of the end effector carrying the tool. Identifiability group ``"targets"`` (a tool frame is
    ranked like a target point: kept in preference to the geometry it trades off with, e.g. the
    last joint's offset against ``tool.rz``).
    """

    group = "targets"

    def __init__(self, initial, *, name: str = "tool", end_effector=None, free=True, prior=None):
        super().__init__(name, initial, labels=[name], free=free, prior=prior)
        if self.n_frames != 1:
            raise ValueError(f"{name}: a tool frame is one (4, 4) transform, got {self.n_frames}")
        self.end_effector = end_effector

    @property
    def rotation_names(self) -> tuple:
        """The three rotation variables (free only these when target points carry the origin)."""
        return self.names[:3]
