"""How much of the simulated link bending and warm sag the 24 free parameters can describe
(tests/test_thermal_realism.py and docs/thermal.md "What is outside the model, measured")."""

from __future__ import annotations

import numpy as np

from .deformation import apply_link_twists, link_twists, sag_offsets
from .effects import LinkDeformation

__all__ = ["TRANSFER_MOTOR_TEMPERATURES_K", "deformation_transfer"]

#: the motor temperature rises [K] of joints 1-6 at which the transfer is measured
TRANSFER_MOTOR_TEMPERATURES_K = np.array([9.0, 25.0, 22.0, 16.0, 7.0, 5.0])


def deformation_transfer(cell, temps, which: str) -> tuple:
    """``(span, transfer, rms_mm)`` for the bending (``which="bend"``) or the warm sag (``"sag"``)
    alone of a :class:`~robocal.sim.thermal.simulator.ThermalCell` at motor temperatures ``temps``
    (6,) [K]: the share of the drift at the monitored points outside the 24-parameter span there,
    the share left there by the best parameter fit on the sphere poses, and the RMS drift there [mm]."""
    m, X, geom, dfm = cell.robot.true_model, cell.robot.true_model.params.values, cell.realism.geometry, LinkDeformation()
    fs = cell.T_flange_sensor
    pm = np.tile([0.0, 0.0, 250.0], (len(cell.q_monitor), 1)) @ fs[:3, :3].T + fs[:3, 3]  # held-sensor points
    ps = np.tile(cell.P_e, (len(cell.q_sphere), 1))
    tw = link_twists(geom, np.asarray(temps)[None], dfm, 6)[0]

    def moved(q):
        if which == "bend":
            return apply_link_twists(m, q, cell._flange(q, X), tw)
        return cell._flange(q + sag_offsets(m, q, geom, temps, dfm), X)

    def points(T, pts):
        return np.einsum("kij,kj->ki", T[:, :3, :3], pts) + T[:, :3, 3]

    def drift_and_jac(q, pts):
        k = np.arange(len(q))
        J = m.identification_jacobian(q, points=pts)[k, k][:, :, m.params.free].reshape(-1, 24)
        return (points(moved(q), pts) - points(cell._flange(q, X), pts)).ravel(), J

    dm, Jm = drift_and_jac(cell.q_monitor, pm)
    ds, Js = drift_and_jac(cell.q_sphere, ps)
    span = dm - Jm @ np.linalg.lstsq(Jm, dm, rcond=None)[0]
    transfer = dm - Jm @ np.linalg.lstsq(Js, ds, rcond=1e-10)[0]
    n = np.linalg.norm(dm)
    return float(np.linalg.norm(span) / n), float(np.linalg.norm(transfer) / n), float(np.sqrt(np.mean(dm ** 2)))
