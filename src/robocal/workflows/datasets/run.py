"""``robocal datasets``: the real-data protocols by name, as plain JSON-ready records.

:func:`run_dataset` runs one protocol with one model (``geometric``, ``elastic-joint``,
``elastic-full``) and returns ``holdout_rms_mm``, ``holdout_mean_mm``, ``holdout_max_mm`` (the
chosen model), the geometric and nominal figures beside them, the training RMS and the protocol;
for ``hilti_trailblazer`` one such record per set under ``sets``; ``convergence``: how many of the
protocol's fits (every seed, every level) did not converge, with the reasons.
"""

from __future__ import annotations

from ...io.datasets import HILTI_SETS, datasets_root
from ..convergence import Convergence
from ._fitting import MODELS, recording_fits

__all__ = ["DATASETS", "list_datasets", "run_dataset"]

#: name -> (robot, protocol in one line)
DATASETS = {
    "boby_fanuc": ("fanuc_r2000ic_165f", "FANUC R-2000i, laser tracker, 3 SMRs, 36 poses; 24/12 random splits, "
                   "seeds 0-4, holdout over the 3 SMRs, mean over seeds"),
    "dlr_justin": ("dlr_justin19", "DLR Agile Justin, Vicon, 2 hand markers, 500 poses; 400/100 random split, seed 0, "
                   "both markers"),
    "hilti_trailblazer": ("hilti_trailblazer", "column + Doosan 6R, total station, 7 sets; fit on flat, per-station "
                          "Kabsch on the 4 CROSS points, errors of the evaluation points"),
}


def list_datasets(root=None) -> list:
    """``[{name, robot, protocol, present, folder}]`` for every known data set."""
    base = datasets_root(root)
    return [{"name": n, "robot": r, "protocol": p, "present": (base / n / "raw").is_dir(), "folder": str(base / n)}
            for n, (r, p) in DATASETS.items()]


def _record(stats: dict, geometric: dict, nominal: dict) -> dict:
    return {"holdout_rms_mm": stats["rms"], "holdout_mean_mm": stats["mean"], "holdout_max_mm": stats["max"],
            "geometric": {k: geometric[k] for k in ("rms", "mean", "max")},
            "nominal": {k: nominal[k] for k in ("rms", "mean", "max")}}


def run_dataset(name: str, model: str = "geometric", root=None) -> dict:
    """One protocol (docs/datasets.md) with ``model``; the JSON record of ``robocal datasets run``."""
    if name not in DATASETS:
        raise ValueError(f"unknown data set {name!r}; known: {', '.join(DATASETS)}")
    if model not in MODELS:
        raise ValueError(f"unknown model {model!r}; expected one of {', '.join(MODELS)}")
    out = {"dataset": name, "model": model, "robot": DATASETS[name][0], "protocol": DATASETS[name][1]}
    with recording_fits() as fits:
        _run(name, model, root, out)
    out["convergence"] = Convergence.of(
        [(f"fit {i + 1}", r) for i, r in enumerate(fits)],
        "raise the protocol's iteration cap (workflows/datasets) or start the elastic levels from the previous "
        "level's solution").as_dict()
    return out


def _run(name: str, model: str, root, out: dict) -> None:
    if name == "boby_fanuc":
        from .boby_fanuc import calibrate_boby_seeds

        r = calibrate_boby_seeds(range(5), root=root, model=model)
        out.update(_record(r["calibrated"], r["geometric"], r["nominal"]))
        out["train_rms_mm"] = [float(x) for x in r["train_rms"]]
        out["per_seed_holdout_rms_mm"] = [run["calibrated"]["rms"] for run in r["runs"]]
    elif name == "dlr_justin":
        from .dlr_justin import calibrate_justin

        r = calibrate_justin(0, root=root, model=model)
        out.update(_record(r["calibrated"], r["all"], r["nominal"]))
        out["train_rms_mm"] = float(r["calibrated"]["train_rms"])
    else:
        from .hilti_trailblazer import calibrate_hilti

        r = calibrate_hilti(root=root, model=model)
        out["train_rms_mm"] = float(r["result"].rms_after)
        out["sets"] = []
        for s in HILTI_SETS:
            c = r["calibrated"][s]["all"]
            # 'flat' is the training set: its errors are training errors, not held out (the keys
            # keep their names for compatibility; 'role' says which it is)
            rec = {"set": s, "role": "training" if s == "flat" else "holdout", "n": c["n"],
                   **_record(c, r["geometric"][s]["all"], r["nominal"][s]["all"]),
                   "p95_xy_mm": c["p95_xy"], "p95_z_mm": c["p95_z"]}
            out["sets"].append(rec)
