"""The boby_fanuc protocol: 24 / 12 random splits (seeds 0-4), nominal vs calibrated DH + beta."""

from __future__ import annotations

import numpy as np

from ...calib import Target
from ...io.datasets import read_boby_fanuc
from ...kinematics.links import Link
from ...robots import load_robot
from ._fitting import elastic_model, fit, holdout_stats, random_split, with_state_targets

__all__ = ["boby_model", "calibrate_boby", "calibrate_boby_seeds"]


def boby_model():
    """``fanuc_r2000ic_165f`` with Hayati's beta on link 2 (the parallel J2/J3 pair), and the free
    set of the reference fit: every DH parameter except link 1's theta, d and all of link 6."""
    m = load_robot("fanuc_r2000ic_165f")
    links = list(m.links)
    L = links[1]
    links[1] = Link(L.name, L.joint_type, L.convention, {**L.params, "beta": 0.0}, L.parent, L.axis, L.fixed)
    m = m.replace(links=links, kind="dh_beta")
    free = [n for n in m.params.names if n not in ("theta1", "d1") and not n.endswith("6")]
    return m.with_free([n in free for n in m.params.names])


def calibrate_boby(seed: int = 0, n_train: int = 24, data=None, root=None, prior: float = 1e-3,
                   model: str = "geometric") -> dict:
    """The boby_fanuc protocol for one seed: random ``n_train`` training poses, the rest held out.

    ``nominal``: nominal DH, base + 3 tool points fitted on the training poses; ``calibrated``:
    plus the DH parameters of :func:`boby_model` (auto-identifiable set, Tikhonov ``prior``).
    ``model="elastic-joint"``: then, from the geometric solution, the geometry and a joint
    compliance per joint with lumped gravity parameters, identified together
    (:func:`~robocal.workflows.datasets._fitting.elastic_model`); ``geometric`` keeps the geometric
    figures and ``calibrated`` is the elastic one.
    Returns ``{"seed", "nominal": stats, "calibrated": stats, "geometric": stats, "train_rms",
    "result"}`` with holdout statistics over the 3 SMR points of every held-out pose
    (:func:`~robocal.workflows.datasets.error_stats`)."""
    elastic = elastic_model(model)
    ds = read_boby_fanuc(root) if data is None else data
    tr, te = random_split(ds.n_poses, n_train, seed)
    model = boby_model()
    # initial tool points: all three at the flange centre, 250 mm out (nothing dataset-specific)
    targets = [Target(n, None, (0.0, 0.0, 250.0)) for n in ds.targets]
    p0, r0 = fit(model, ds.joints[tr], targets, ds.points[tr], free=[])
    targets = with_state_targets(targets, r0.state)
    p1, r1 = fit(model, ds.joints[tr], targets, ds.points[tr], free=None, base_initial=r0.state.bases, prior=prior)
    out = {"seed": seed, "train": tr, "test": te, "result": r1, "nominal_result": r0, "train_rms": r1.rms_after,
           "nominal_train_rms": r0.rms_after}
    for key, p, r in (("nominal", p0, r0), ("calibrated", p1, r1)):
        out[key] = holdout_stats(p, r, ds, te)
    out["geometric"] = out["calibrated"]
    if elastic is not None:
        p2, r2 = fit(model.with_params(r1.state.params), ds.joints[tr], with_state_targets(targets, r1.state),
                     ds.points[tr], free=None, base_initial=r1.state.bases, prior=prior, elastic=elastic)
        out.update(result=r2, train_rms=r2.rms_after, calibrated=holdout_stats(p2, r2, ds, te))
    return out


def calibrate_boby_seeds(seeds=range(5), root=None, **kw) -> dict:
    """:func:`calibrate_boby` for each seed; ``nominal`` / ``calibrated`` hold the means over seeds
    of rms, mean and max, ``runs`` the per-seed results."""
    ds = read_boby_fanuc(root)
    runs = [calibrate_boby(s, data=ds, **kw) for s in seeds]
    out = {"runs": runs}
    for key in ("nominal", "geometric", "calibrated"):
        out[key] = {s: float(np.mean([r[key][s] for r in runs])) for s in ("rms", "mean", "max")}
    out["train_rms"] = [r["train_rms"] for r in runs]
    return out
