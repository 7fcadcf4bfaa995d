"""The tolerance an effect the model lacks allows, to first order (issue 25, item 4).

A least-squares fit of data that carry a small effect ``e`` the model cannot represent lands, to
first order, at ``truth + J^+ e`` (``J``: the Jacobian of the model's predictions with respect to
the fitted variables at the solution). With ``e`` taken from the simulator's hidden truth
(noise-free predictions with the effect minus without), a test can state "within k sigma of truth
plus that bias" -- a claim the simulator does not make true by construction.

Jacobians here are finite differences of the simulator's geometry, not the solver's code. The
tracker and 6-D campaigns' helpers (``tracker_campaign_bias``, ``six_d_fit_bias``,
``poses_with_effects`` and what they use) live in
:mod:`robocal.sim.first_order` and the camera self-calibration helpers (``corner_views``,
``self_calibration_offset_bias``) in :mod:`robocal.sim.cameras.self_calibration_effects`, where the
documented figures (robocal.docs.figures) use them too.
"""

from __future__ import annotations


from robocal.sim.cameras.self_calibration_effects import (  # noqa: F401 (moved to the library; re-exported)
    corner_views,
    self_calibration_offset_bias,
)
from robocal.sim.first_order import (  # noqa: F401 (the tracker helpers moved to the library; re-exported)
    NO_EFFECTS,
    REALISTIC,
    STEP,
    campaign_effect_points,
    first_order_bias,
    poses_with_effects,
    six_d_fit_bias,
    tracker_campaign_bias,
    twist,
)
