"""The hilti_trailblazer protocol: fit on ``flat``, then the dataset repository's per-station test
(Kabsch on the CROSS stationing points) on every set, nominal and calibrated."""

from __future__ import annotations

import dataclasses

import numpy as np

from ...calib import Target, rigid_fit
from ...calib.gravity import STANDARD_GRAVITY
from ...io.datasets import HILTI_SETS, DatasetError, RealDataset, read_hilti_trailblazer
from ...robots import load_robot
from ._fitting import PROTOCOL_MAX_ITERATIONS, elastic_model, error_stats, fit, param_names, points_in_base

__all__ = ["HILTI_ARM_JOINTS", "hilti_station_protocol", "calibrate_hilti"]

HILTI_ARM_JOINTS = tuple(f"dsr_joint{i}" for i in range(1, 7))


def hilti_station_protocol(model, point, ds: RealDataset, solution_spaces=(0, 7), min_cross: int = 4,
                           predict=None, tilt: bool = False) -> dict:
    """The repository's per-station test (example_kabsch.py) with ``model`` (base frame ignored)
    carrying the prism at ``point`` (3,) [mm] in its first end effector's frame.

    Per station (column height x solution space in ``solution_spaces``): rigid fit (Kabsch) of the
    predicted CROSS stationing points onto the measured ones, then errors of the station's
    evaluation points. Stations with fewer than ``min_cross`` CROSS points are skipped (listed).
    ``predict``: optional function of the joints (N, n) giving the prism positions (N, 3) [mm] in
    the robot base frame (an elastic model's predictions) instead of ``model`` and ``point``;
    with ``tilt`` it is called as ``predict(q, gravity)`` a second time, with the gravity of each
    station in its base frame from the first Kabsch fit (the total station's z is vertical), and
    the stations are fitted again: the deflection follows the tilt of the base.
    Returns ``{"all": stats over every evaluation point, "stations": [...], "skipped": [...]}``.
    """
    if predict is None:
        pred_base = points_in_base(model, ds.joints, [Target("prism", None, tuple(point))])[:, 0]
    else:
        pred_base = predict(ds.joints, STANDARD_GRAVITY) if tilt else predict(ds.joints)
    if tilt:
        g = np.tile(STANDARD_GRAVITY, (ds.n_poses, 1))
        for sel, T in _station_fits(ds, pred_base, solution_spaces, min_cross):
            g[sel] = T[:3, :3].T @ STANDARD_GRAVITY  # gravity in this station's base frame
        pred_base = predict(ds.joints, g)
    return _station_errors(ds, pred_base, solution_spaces, min_cross)


def _station_fits(ds, pred_base, solution_spaces, min_cross):
    """(poses of the station, Kabsch fit T_instrument_base) of every usable station."""
    per = ds.per_pose
    for g, (_, ss) in enumerate(ds.station_labels):
        sel = ds.stations == g
        cr = sel & per["cross"]
        if ss in solution_spaces and cr.sum() >= min_cross:
            yield sel, rigid_fit(pred_base[cr], ds.points[cr, 0])


def _station_errors(ds, pred_base, solution_spaces, min_cross) -> dict:
    per = ds.per_pose
    preds, meas, stations, skipped = [], [], [], []
    for g, (h, ss) in enumerate(ds.station_labels):
        if ss not in solution_spaces:
            continue
        sel = ds.stations == g
        cr = sel & per["cross"]
        ev = sel & (per["role"] == "evaluation")
        if cr.sum() < min_cross or not ev.any():
            skipped.append({"height_m": h, "solution_space": ss, "n_cross": int(cr.sum()), "n_eval": int(ev.sum())})
            continue
        T = rigid_fit(pred_base[cr], ds.points[cr, 0])  # Kabsch, as the repository's example
        pe = pred_base[ev] @ T[:3, :3].T + T[:3, 3]
        preds.append(pe)
        meas.append(ds.points[ev, 0])
        stations.append({"height_m": h, "solution_space": ss, **error_stats(pe, ds.points[ev, 0])})
    if not preds:
        raise DatasetError(f"{ds.name}: no station with {min_cross} CROSS stationing points and evaluation points")
    return {"all": error_stats(np.concatenate(preds), np.concatenate(meas)), "stations": stations, "skipped": skipped}


def calibrate_hilti(root=None, sets=HILTI_SETS, prior: float = 1e-2, data=None,
                    max_iterations: int = PROTOCOL_MAX_ITERATIONS,
                    model: str = "geometric", tilt: bool = False) -> dict:
    """Fit the Trailblazer on ``flat`` (every point: stationing and evaluation, all solution spaces),
    one base frame per column height (5), 6-dof perturbations of the URDF origins of dsr_joint2..6,
    joint offsets of dsr_joint1..5 and the prism offset, weak prior (``prior`` 1e-2 per scaled unit:
    the figures equal those of 1e-3 to 0.01 mm, but LM converges in ~10 instead of ~110 iterations
    along the nearly redundant origin directions); then run
    :func:`hilti_station_protocol` on every set with the nominal URDF and with the calibrated model.

    ``model="elastic-joint"``: then, from the geometric solution, the same geometry + a torsional
    compliance per joint (column and arm) with lumped gravity parameters, identified together on
    ``flat``; its predictions (deflections included) go through the same per-station test. With
    ``tilt`` gravity is taken per station in its base frame (from the base frames on ``flat``,
    from each test station's Kabsch fit; the total station's z is vertical) instead of along the
    base z. Measured: ``tilt`` makes every set 0.0-0.4 mm worse (docs/elastic.md), so it is off.

    Returns ``{"result", "model", "prism", "nominal": {set: protocol}, "calibrated": {set: protocol},
    "geometric": {set: protocol}}``.
    ``data`` may map set names to already read :class:`~robocal.io.datasets.RealDataset`."""
    elastic = elastic_model(model)
    data = dict(data or {})
    for s in set(sets) | {"flat"}:
        if s not in data:
            data[s] = read_hilti_trailblazer(s, root)
    flat = data["flat"]
    model = load_robot("hilti_trailblazer")
    free = param_names(model, HILTI_ARM_JOINTS[1:], ("x", "y", "z", "roll", "pitch", "yaw")) + \
        param_names(model, HILTI_ARM_JOINTS[:5], ("theta",))
    targets = [Target("prism", None, (0.0, 0.0, 0.0))]  # offset from the nominal prism (the [tool] frame)
    stations = flat.per_pose["height_index"]
    _, res = fit(model, flat.joints, targets, flat.points, free=free, stations=stations, prior=prior,
                 max_iterations=max_iterations)
    cal = res.model
    out = {"result": res, "model": cal, "prism": res.state.targets[0], "nominal": {}, "calibrated": {}}
    for s in sets:
        out["nominal"][s] = hilti_station_protocol(model, (0.0, 0.0, 0.0), data[s])
        out["calibrated"][s] = hilti_station_protocol(cal, res.state.targets[0], data[s])
    out["geometric"] = dict(out["calibrated"])
    if elastic is not None:
        prism = [Target("prism", None, tuple(res.state.targets[0]))]
        if tilt:  # gravity in each height's base frame, the total station's z being vertical
            g_flat = np.einsum("nji,j->ni", res.state.bases[stations, :3, :3], STANDARD_GRAVITY)
            elastic = dataclasses.replace(elastic, g=g_flat)
        prob, res_e = fit(model.with_params(res.state.params), flat.joints, prism, flat.points, free=free,
                          stations=stations, base_initial=res.state.bases, prior=prior, elastic=elastic,
                          max_iterations=max_iterations)
        in_base = res_e.state._replace(bases=np.eye(4)[None])

        def predict(q, gravity=None):
            return prob.predict_points(in_base, q=q, gravity=gravity)[:, 0]

        out.update(result=res_e, model=res_e.model, prism=res_e.state.targets[0])
        for s in sets:
            out["calibrated"][s] = hilti_station_protocol(None, None, data[s], predict=predict, tilt=tilt)
    return out
