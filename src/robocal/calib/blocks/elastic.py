"""Parameter blocks of the elastic model: joint compliances and lumped gravity (mass) parameters.

Joint deflection (docs/elastic.md): ``dtheta_j = s_j c_j tau_j(q)`` with ``tau`` the generalised
gravity force (:class:`~robocal.calib.gravity.GravityTorques`), linear in the bodies' lumped
parameters ``theta_b = (m_b, h_b)``.

* :class:`JointCompliance` (group ``compliance``): ``c_j`` per model joint, ``compliance.<joint>``
  in **mrad/kNm** for revolute joints (``s = 1e-6`` rad per N m) and **mm/kN** for prismatic ones
  (``s = 1e-3`` mm per N);
* :class:`GravityParameters` (group ``gravity``): per body ``gravity.<body>.hx, .hy, .hz`` [kg m]
  (first moment in the link frame) then ``gravity.<body>.m`` [kg] (masses last, see below).

Identifiability. With a mass model (the gravity block fixed) the deflection is linear in ``c``:
every ``c_j`` whose torque varies over the poses is identifiable; one whose torque does not vary
(a vertical axis carrying no offset load) has no effect on the measurements beyond a joint
offset and is reported as such. Without a mass model only the products ``c_j tau_j`` are seen:
``c -> a c, theta -> theta / a`` gives the same deflections, so one global scale is never
identifiable from gravity alone (the identifiability analysis holds one mass, the last in column
order, at its initial value and names it), unless a known payload changes between poses. Of the
first moments, only components that produce a torque about some carrying joint's axis are seen.
"""

from __future__ import annotations

import numpy as np

from .manifolds import VectorBlock

__all__ = ["JointCompliance", "LateralCompliance", "GravityParameters", "COMPLIANCE_UNITS"]

#: reported unit and scale to SI (rad per N m, mm per N) of revolute / prismatic compliances
COMPLIANCE_UNITS = {True: ("mrad/kNm", 1e-6), False: ("mm/kN", 1e-3)}


class JointCompliance(VectorBlock):
    """Compliances ``c`` (n,) of the model joints ``joints`` (indices into ``model.moving``).

    names ``compliance.<link name>``; units mrad/kNm (revolute) or mm/kN (prismatic); ``scale``
    (n,) converts ``c * tau`` [unit * N m | N] to the joint's deflection [rad | mm].
    """

    group = "compliance"

    def __init__(self, model, joints, initial=None, *, free=True, prior=None, name="compliance"):
        self.joints = np.asarray(joints, dtype=int)
        links = [model.links[int(model.moving[j])] for j in self.joints]
        revolute = [L.joint_type == "revolute" for L in links]
        units = [COMPLIANCE_UNITS[r][0] for r in revolute]
        self.scale = np.array([COMPLIANCE_UNITS[r][1] for r in revolute])
        names = [f"{name}.{L.name}" for L in links]
        initial = np.zeros(len(names)) if initial is None else initial
        super().__init__(name, names, units, initial, free=free, prior=prior)


class LateralCompliance(VectorBlock):
    """Lateral (bending) compliances of the model joints ``joints``: two per joint, about the axes
    ``e1``, ``e2`` perpendicular to the joint axis (:class:`~robocal.calib.gravity.GravityTorques`,
    ``lateral=True``): ``dphi = 1e-6 sum_a c_a M_a e_a`` [rad] with ``M_a`` the bending moment
    [N m]. Names ``lateral.<joint>.1``, ``.2``; unit mrad/kNm; group ``compliance``."""

    group = "compliance"

    def __init__(self, model, joints, initial=None, *, free=True, prior=None, name="lateral"):
        self.joints = np.asarray(joints, dtype=int)
        links = [model.links[int(model.moving[j])] for j in self.joints]
        names = [f"{name}.{L.name}.{a}" for L in links for a in (1, 2)]
        initial = np.zeros(len(names)) if initial is None else initial
        super().__init__(name, names, ["mrad/kNm"] * len(names), initial, free=free, prior=prior)


class GravityParameters(VectorBlock):
    """Lumped parameters of bodies carried by links ``body_links`` (indices into ``model.links``).

    value (B, 4): per body (m [kg], hx, hy, hz [kg m]); variables ordered first moments of every
    body, then the masses (so the identifiability analysis, keeping columns in order, holds a mass
    for the scale gauge rather than a first moment at zero). ``body_names`` default the link names.
    """

    group = "gravity"

    def __init__(self, model, body_links, initial=None, *, free=True, prior=None, name="gravity",
                 body_names=None):
        self.body_links = np.asarray(body_links, dtype=int)
        B = len(self.body_links)
        self.body_names = list(body_names) if body_names is not None else \
            [model.links[int(k)].name for k in self.body_links]
        names = [f"{name}.{b}.{c}" for b in self.body_names for c in ("hx", "hy", "hz")] + \
            [f"{name}.{b}.m" for b in self.body_names]
        units = ["kg m"] * (3 * B) + ["kg"] * B
        value = np.zeros((B, 4)) if initial is None else np.asarray(initial, dtype=float).reshape(B, 4)
        # order of variables -> (B, 4) layout: h's first, masses last
        self._order = np.concatenate([(np.arange(B)[:, None] * 4 + np.arange(1, 4)).ravel(), np.arange(B) * 4])
        super().__init__(name, names, units, value[:, :].ravel()[self._order], free=free, prior=prior)

    def theta(self, value) -> np.ndarray:
        """(B, 4) = (m, hx, hy, hz) per body from the block value (its variables' order)."""
        out = np.empty(self.size)
        out[self._order] = value
        return out.reshape(-1, 4)

    def variable_jacobian(self, d_theta) -> np.ndarray:
        """Derivatives w.r.t. the (B, 4) layout (..., B, 4) reordered to the variables (..., size)."""
        flat = d_theta.reshape(d_theta.shape[:-2] + (-1,))
        return flat[..., self._order]
