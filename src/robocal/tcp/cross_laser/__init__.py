"""The cross-laser tool-frame recalibration (thesis 4.2, 4.3.2): plan the motions, evaluate them.

Two light barriers cross at the sensor origin ``O_s`` (see :mod:`robocal.tcp.sensor` for the
sensor frame and the beta correction). The robot holds the tool perpendicular to the beam plane
and moves it on circles of radius ``R`` at constant speed; the four beam interruptions split the
period into four arcs, from which the circle centre follows. Two circles ``dz`` apart give the
tool axis, a third circle after re-aligning the axis with ``Z_s`` centres it, and vertical moves
through the beams give the TCP. The result is the 5-D tool frame in the flange frame.

Frames and signs (all verified against the simulator :mod:`robocal.sim.tool.light_barrier` in
``tests/test_cross_laser.py``):

- Sensor frame S = the orthogonal frame ``T_base_sensor`` of the calibration (X_s along the X
  beam, Y_s' orthogonal to it in the beam plane, Z_s = X_s x Y_beam). Circles run about ``+Z_s``
  (counter-clockwise seen from +Z_s) unless ``direction = -1``; angle 0 is ``+X_s``.
- The four arcs are named by the quadrant they sweep (thesis figure 4-5): ``angle 1`` between the
  crossing of the X beam on its ``+X_s`` half ("X+") and the crossing of the Y beam on its
  positive half ("Y+"), ``angle 2`` Y+ -> X-, ``angle 3`` X- -> Y-, ``angle 4`` Y- -> X+.
  With these names (4-9) gives ``d_x = R cos((a3 + a4)/2)`` = signed distance of the circle centre
  to the X beam, positive on the +Y_s' side, and ``d_y = R cos((a2 + a3)/2)`` = signed distance
  to the Y beam, positive on the +X_s side; the centre is ``(d_y, d_x)`` for orthogonal beams and
  :func:`robocal.tcp.sensor.center_from_beam_distances` (4-29) otherwise (the beta correction).
- The tool's axis direction ``a`` points from the flange to the tip (the tool frame's Z axis).

Beyond the thesis (documented, switchable):

- *arc-width correction*: the tool is a cylinder of radius r, so each beam is blocked over an
  arc, and the crossing time is taken as the middle of the blocked interval. On a circle the
  middle of the blocked arc is not the crossing of the beam line: exactly, it is the crossing of
  a circle of radius ``R cos(delta/2)`` (delta = the blocked arc of that beam, the same for both
  crossings of one beam). (4-9) therefore uses ``R cos(delta/2)``; without it the centre is
  scaled by ``cos(delta/2)`` (1 % for r = 3 mm, R = 25 mm).
- (4-14) is applied in the flange frame: ``t = R_base_flange^T (O_s - p_e)``; the thesis
  subtracts base-frame coordinates (METHODS.md section 7).
- The tool axis is obtained as two points on the axis in the flange frame (one per circle),
  which is (4-11, 4-12) for the thesis's flange orientation and valid for any orientation.
  (4-12) printed as ``(d_y2 - d_y1, d_x1 - d_x2, dz)`` is the mirror image of the axis in x and y;
  combined with (4-13) and (4-10), whose ``R`` has the z column ``(-dx, -dy, dz)/|.|``, the
  thesis's chain still yields the right axis (see :func:`axis_vector_thesis`).

Modules, each importing only the ones listed before it:

- :mod:`.formulas`: the thesis's equations (4-8 ... 4-14) and the beta correction, on numbers;
- :mod:`.motions`: the programmed flange motions (circles, lines) and their trapezoidal timing;
- :mod:`.inputs`: what the method is given: the sensor frame and the settings;
- :mod:`.events`: barrier events and motion records; blocked intervals, beam crossings, arcs;
- :mod:`.planning`: the motion plan of steps 1-4 (where the circles and lines go);
- :mod:`.evaluation`: one circle or the step-4 vertical moves evaluated from their events;
- :mod:`.procedure`: the recalibration that strings plan, execution and evaluation together.

The events file (``robocal-barrier-events/1``) is read and written by
:mod:`robocal.io.barrier_events`.

Units: mm, s, rad inside. ``T_a_b`` = pose of b in a.
"""

from . import evaluation, events, formulas, inputs, motions, planning, procedure
from .evaluation import *  # noqa: F401,F403
from .events import *  # noqa: F401,F403
from .formulas import *  # noqa: F401,F403
from .inputs import *  # noqa: F401,F403
from .motions import *  # noqa: F401,F403
from .planning import *  # noqa: F401,F403
from .procedure import *  # noqa: F401,F403

__all__ = [*events.__all__, *motions.__all__, *inputs.__all__, *formulas.__all__, *planning.__all__,
           *evaluation.__all__, *procedure.__all__]
