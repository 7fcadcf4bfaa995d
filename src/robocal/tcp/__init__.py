"""Tool frame (TCF / TCP) calibration, thesis chapter 4 (see docs/tcp.md).

- :mod:`.touchup`: 4-point TCP (4-1 ... 4-4, any N >= 4 poses) and 7-point tool frame (4-5);
- :mod:`.parallel_barriers`: tool axis (4-6) and length (4-7) from two parallel light barriers;
- :mod:`.sensor`: cross-laser sensor calibration (4-15 ... 4-27) and the beta correction
  (4-28 ... 4-30);
- :mod:`.tool_data`: a tool frame as KUKA / FANUC / ABB / UR / Kawasaki tool data;
- :mod:`.cross_laser`: the cross-laser method (4-8 ... 4-14), a package: formulas, motions and
  their planning, event extraction and evaluation, the full recalibration cycle (its events file
  is read and written by :mod:`robocal.io.barrier_events`).

Frames: ``T_a_b`` is the pose of b in a; lengths in mm, angles in rad unless a name says ``_deg``.
"""

from .parallel_barriers import *  # noqa: F401,F403
from .sensor import *  # noqa: F401,F403
from .tool_data import *  # noqa: F401,F403
from .touchup import *  # noqa: F401,F403
