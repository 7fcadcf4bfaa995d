"""The dlr_justin protocol: a 400 / 100 random split (seed 0), three levels of identified parameters."""

from __future__ import annotations

from ...calib import Target
from ...io.datasets import read_dlr_justin
from ...robots import load_robot
from ._fitting import elastic_model, fit, holdout_stats, param_names, random_split, with_state_targets

__all__ = ["JUSTIN_CHAIN_LINKS", "calibrate_justin"]

JUSTIN_CHAIN_LINKS = ("torso_0", "torso_1", "torso_2", "torso_3") + tuple(f"right_j{i}" for i in range(1, 8)) + \
    tuple(f"left_j{i}" for i in range(1, 8))


def _free_sets(model) -> dict:
    """Parameters of each level: none; the 18 joint offsets; every modified-DH parameter of the
    chain (beta where consecutive axes are parallel)."""
    full = []
    by_name = {L.name: k for k, L in enumerate(model.links)}
    for ln in JUSTIN_CHAIN_LINKS:
        L = model.links[by_name[ln]]
        kinds = ("alpha", "a", "theta", "d") + (("beta",) if abs(L.params["alpha"]) < 1e-9 else ())
        full += param_names(model, [ln], kinds)
    return {"nominal": [], "offsets": param_names(model, JUSTIN_CHAIN_LINKS, ("theta",)), "all": full}


def calibrate_justin(seed: int = 0, n_train: int = 400, data=None, root=None, prior: float = 1e-3,
                     levels=("nominal", "offsets", "all"), model: str = "geometric") -> dict:
    """The dlr_justin protocol: random ``n_train`` / rest split (``seed``), both hand markers.

    Levels (each starting from the previous one's solution): ``nominal`` = base + 2 marker
    offsets; ``offsets`` = + the 18 joint offsets (torso incl. the passive joint, both arms);
    ``all`` = + every modified-DH parameter (alpha, a, theta, d; beta where consecutive axes are
    parallel) of the torso and both arms, weak prior; with ``model="elastic-joint"`` one more
    level ``elastic`` = the same geometry + a torsional compliance per joint of the torso and both
    arms with lumped gravity parameters, identified together; ``model="elastic-full"`` the
    level ``full`` instead: the same + two lateral (bending) compliances per joint (LM needs
    ~190 iterations here with Nielsen's damping rule: the lumped model is bilinear). Returns ``{level: holdout stats}``
    plus ``calibrated`` (the last level), ``results`` (per level) and the split."""
    elastic = elastic_model(model)
    extra_level = None if elastic is None else ("full" if elastic.lateral else "elastic")
    if extra_level is not None and extra_level not in levels:
        levels = tuple(levels) + (extra_level,)
    ds = read_dlr_justin(root) if data is None else data
    tr, te = random_split(ds.n_poses, n_train, seed)
    model = load_robot("dlr_justin19")
    # initial marker offsets in the hand (TCP) frames, from the dataset site [mm]
    targets = [Target("right", "right", (-100.0, -30.0, 100.0)), Target("left", "left", (-100.0, 30.0, 50.0))]
    free_sets = _free_sets(model)
    free_sets["elastic"] = free_sets["full"] = free_sets["all"]
    out = {"train": tr, "test": te, "results": {}}
    base, state_targets = None, targets
    for lev in levels:
        el = elastic if lev in ("elastic", "full") else None
        # the lumped elastic levels (bilinear: compliances x gravity parameters, 214 unknowns, condition
        # ~1e5-1e6) use Nielsen's damping rule: with the tenfold one nearly every step was refused once
        # before one was taken (docs/elastic.md)
        p, r = fit(model, ds.joints[tr], state_targets, ds.points[tr], free=free_sets[lev], base_initial=base,
                   prior=prior if lev in ("all", "elastic", "full") else 0.0, elastic=el,
                   damping="gain" if el is not None else None)
        if lev != levels[-1]:
            # next level starts from this solution
            model = r.model.replace(T_world_base=model.T_world_base)
            base, state_targets = r.state.bases, with_state_targets(state_targets, r.state)
        out["results"][lev] = r
        out[lev] = holdout_stats(p, r, ds, te)
        out[lev]["train_rms"] = r.rms_after
    out["calibrated"] = out[levels[-1]]
    return out
