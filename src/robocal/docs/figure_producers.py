"""The producers of the documented figures (:mod:`robocal.docs.figures`): each reruns one
dataset protocol, study or simulation with the project's own workflow functions and returns its
numbers as a flat ``{field: value}`` dict. Cached: figures that share a run compute it once."""

from __future__ import annotations

import functools
import json
import re
import tempfile
from pathlib import Path

from .figure_producers_bench import BENCH_PRODUCERS
from .figure_producers_cli import CLI_PRODUCERS
from .figure_producers_handeye import HANDEYE_PRODUCERS
from .figure_producers_pages import PAGES_DATASETS_NEEDED, PAGES_PRODUCERS, SLOW_PAGES_PRODUCERS
from .figure_producers_datasets import DATASET_PRODUCERS, DATASETS_NEEDED, SLOW_DATASET_PRODUCERS, report_text
from .figure_producers_setups import SETUP_PRODUCERS
from .figure_producers_speed import SLOW_SPEED_PRODUCERS, SPEED_PRODUCERS
from .figure_producers_testing import SLOW_TESTING_PRODUCERS, TESTING_PRODUCERS
from .figure_producers_thermal import THERMAL_PRODUCERS

__all__ = ["PRODUCERS", "SLOW_PRODUCERS", "datasets_needed", "repository_root"]


def repository_root() -> Path:
    """The repository (``README.md``, ``docs/``, ``benchmarks/``, ``tests/data``): this file is
    ``src/robocal/docs/figure_producers.py``."""
    return Path(__file__).resolve().parents[3]


def _flat(obj, prefix: str = "") -> dict:
    """Every number of a nested record as ``{"a.b.c": value}``; list items are named by their
    ``set`` / ``seed`` field when they have one, else by their index."""
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            out.update(_flat(v, f"{prefix}{k}."))
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            name = v.get("set", v.get("seed", i)) if isinstance(v, dict) else i
            out.update(_flat(v, f"{prefix}{name}."))
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        out[prefix[:-1]] = float(obj)
    return out


@functools.lru_cache(maxsize=None)
def _dataset(name: str, model: str) -> dict:
    """``robocal datasets run NAME --model MODEL --json``, flattened (:func:`_flat`); Hilti's sets
    also as ``{set}.holdout_rms_mm``."""
    from ..workflows.datasets.run import run_dataset

    r = run_dataset(name, model)
    out = _flat(r)
    train = [v for k, v in out.items() if re.fullmatch(r"train_rms_mm\.\d+", k)]
    if train:  # per-seed training RMS: their range and mean
        out.update({"train_rms_mm.min": min(train), "train_rms_mm.max": max(train),
                    "train_rms_mm.mean": sum(train) / len(train)})
    for s in r.get("sets", []):
        out[f"{s['set']}.holdout_rms_mm"] = s["holdout_rms_mm"]
    its = r["convergence"].get("iterations") or []
    if its and its[-1] is not None:  # the solver iterations of the protocol's last fit (its top level)
        out["iterations.last"] = its[-1]
    seeds = len(r.get("per_seed_holdout_rms_mm", []) or [])
    if its and seeds > 1 and len(its) % seeds == 0:  # per seed: the last fit of each seed's levels
        last = its[len(its) // seeds - 1::len(its) // seeds]
        out.update({f"iterations.per_seed_last.{k}": v for k, v in enumerate(last)})
        done = [v for v, bad in zip(last, _not_converged_seeds(r, len(its) // seeds, seeds)) if not bad]
        if done:
            out["iterations.per_seed_last_converged.min"] = min(done)
            out["iterations.per_seed_last_converged.max"] = max(done)
    return out


def _not_converged_seeds(r: dict, fits_per_seed: int, seeds: int) -> list:
    """Per seed: whether the last fit of its levels is among the protocol's non-converged fits."""
    bad = {int(m.group(1)) for m in (re.match(r"fit (\d+):", x) for x in r["convergence"]["reasons"]) if m}
    return [(k + 1) * fits_per_seed in bad for k in range(seeds)]


@functools.lru_cache(maxsize=None)
def _closed_chain(n_seeds: int, plates: int, known_spacing: bool) -> dict:
    """docs/closed-chain.md: the study per seed (flattened) and its medians over the seeds; ``n_fits`` /
    ``n_not_converged`` (all seeds' fits), ``n_within_3_sigma`` (seeds with every parameter within 3 sigma)."""
    import numpy as np

    from ..workflows.calibration.closed_chain_study import run_study

    rows = run_study(range(n_seeds), plates=plates, known_spacing=known_spacing)
    out = _flat(rows)
    for k in ("closed_chain", "tracker", "nominal"):
        out[f"median.{k}"] = float(np.median([r["workspace_rms_mm"][k] for r in rows]))
    for k in ("closed_chain", "tracker", "nominal", "true_model"):
        vals = [r["workspace_rms_mm"][k] for r in rows]
        out[f"median.{k}"], out[f"min.{k}"], out[f"max.{k}"] = float(np.median(vals)), min(vals), max(vals)
    ratios = [r["ratio_closed_chain_to_tracker"] for r in rows]
    out["median.ratio"], out["min.ratio"], out["max.ratio"] = float(np.median(ratios)), min(ratios), max(ratios)
    out["removed_percent"] = 100.0 * (1.0 - out["median.closed_chain"] / out["median.nominal"])
    out["median.max_abs_z"] = float(np.median([r["max_abs_z"] for r in rows]))
    out["max.max_abs_z"] = float(max(r["max_abs_z"] for r in rows))
    out["n_not_converged"] = float(sum(r["n_not_converged"] for r in rows))
    out["n_fits"] = float(sum(r["n_fits"] for r in rows))
    # seeds whose every checked parameter lies within 3 reported sigma (the study's own count)
    out["n_within_3_sigma"] = float(sum(r["max_abs_z"] < 3 for r in rows))
    return out


@functools.lru_cache(maxsize=None)
def _tcp_accuracy(preset: str) -> dict:
    """docs/tcp.md: ``robocal tcp accuracy --preset PRESET --seeds 20 --repeats 10 --json``'s summary."""
    from ..workflows.tool.accuracy import tcp_accuracy_study

    return _flat(tcp_accuracy_study(preset=preset, seeds=20, first_seed=1, repeats=10)["summary"])


@functools.lru_cache(maxsize=None)
def _tcp_budget() -> dict:
    """docs/tcp.md: ``robocal tcp accuracy --budget --seeds 10 --repeats 5 --json`` (both methods)."""
    from ..workflows.tool.accuracy import METHODS, tcp_error_budget

    return _flat(tcp_error_budget(seeds=10, first_seed=1, repeats=5, methods=METHODS))


@functools.lru_cache(maxsize=None)
def _nao_simulated() -> dict:
    """docs/self-calibration.md, second NAO test: nao-model's simulator, seed 3, 40 views per hand."""
    import numpy as np

    from ..handeye.self_calibration import assign_carriers, solve_self_calibration
    from ..io.capture_times import match_capture_times
    from ..sim.cameras.self_calibration import simulate_self_calibration

    run = simulate_self_calibration("nao_h25", n_images_per_chain=40, pixel_noise=0.3, joint_noise_deg=0.0, seed=3)
    q, _, _ = match_capture_times(run.frame_times, run.log_times, run.log_joints, tolerance=0.06)
    uv = run.image_points.copy()
    w, h = run.camera.image_size
    uv[~((uv[..., 0] >= 0) & (uv[..., 0] <= w - 1) & (uv[..., 1] >= 0) & (uv[..., 1] <= h - 1))] = np.nan
    idx = np.flatnonzero(np.all(np.isfinite(uv[..., 0]), axis=1))
    X = run.board.object_points()
    on, _, _ = assign_carriers(run.robot, q[idx], uv[idx], X, run.camera, ("left_hand", "right_hand"),
                               camera_end_effector="camera_top")
    res = solve_self_calibration(run.robot, q[idx], uv[idx], X, run.camera, on, camera_end_effector="camera_top",
                                 pixel_sigma=0.3)
    z = [(v - run.joint_offsets_rad[r["joint"]]) / s
         for r, v, s in zip(res.joint_report, res.joint_offsets, res.joint_offset_sigma) if r["identifiable"]]
    return {"max_abs_z": float(max(abs(x) for x in z)), "n_identifiable": len(z),
            "rms_px_per_coordinate": float(res.rms_px / np.sqrt(2))}


@functools.lru_cache(maxsize=None)
def _nao_acceptance() -> dict:
    """docs/self-calibration.md, NAO H25 acceptance (the setup of ``tests/test_self_calibration_nao.py``):
    40 views per hand, offsets uniform in +-3 deg (seed 25), 0.3 px; both arms and each arm alone.
    Fields ``max_abs_z``, ``rms_px_per_coordinate``, ``{both|left_hand|right_hand}.{param}.error_deg``
    / ``.sigma_deg`` and ``truth.{param}`` [deg]."""
    import numpy as np

    from ..camera import Camera
    from ..handeye.refine import joint_offset_names
    from ..handeye.self_calibration import solve_self_calibration
    from ..io.boards import parse_board
    from ..robots import load_robot
    from ..sim.cameras.self_calibration_views import simulate_corner_views
    from ..transforms import so3_exp, transforms_from

    cam = Camera(556.8, 556.8, 319.5, 239.5, (0.0, 0.0, 0.0, 0.0, 0.0), "brown", (640, 480))
    hands = ("left_hand", "right_hand")
    m = load_robot("nao_h25")
    rng = np.random.default_rng(25)
    pn = list(m.params.names)
    truth = m.params.values.copy()
    offsets = {n: np.radians(rng.uniform(-3.0, 3.0)) for n in joint_offset_names(m)}
    for n, v in offsets.items():
        truth[pn.index(n)] += v
    board = parse_board("checkerboard:5x4:12mm")
    X = board.object_points()
    mounts = {h: transforms_from(so3_exp(np.array([0.02, np.pi / 2, -0.03])), np.array([20.0, 2.0, -1.0]))
              for h in hands}
    T_ee_camera = transforms_from(so3_exp(np.array([0.005, -0.01, 0.008])), np.array([1.0, -0.5, 0.8]))
    q, on, uv = simulate_corner_views(m.with_params(truth), cam, X, camera_end_effector="camera_top",
                                      T_ee_camera=T_ee_camera, boards=mounts, n_per_carrier=40, rng=rng,
                                      pixel_noise=0.3, front_z=board.front_z, pitch_mm=board.pitch_mm)
    kw = dict(camera_end_effector="camera_top", pixel_sigma=0.3)
    fits = {"both": solve_self_calibration(m, q, uv, X, cam, on, **kw),
            **{h: solve_self_calibration(m, q[on == h], uv[on == h], X, cam, on[on == h], **kw) for h in hands}}
    out = {f"truth.{n}": float(np.degrees(v)) for n, v in offsets.items()}
    for name, res in fits.items():
        held = {r["name"] for r in res.joint_report if not r["identifiable"]}
        for n, v, s in zip(res.joint_offset_names, res.joint_offsets, res.joint_offset_sigma):
            if n not in held:
                out[f"{name}.{n}.error_deg"] = float(np.degrees(v - offsets[n]))
                out[f"{name}.{n}.sigma_deg"] = float(np.degrees(s))
                if name == "both":
                    out["max_abs_z"] = max(out.get("max_abs_z", 0.0), abs(float((v - offsets[n]) / s)))
    out["rms_px_per_coordinate"] = float(fits["both"].rms_px / np.sqrt(2))
    out["n_not_converged"] = float(sum(not r.converged for r in fits.values()))
    return out


_NUMBER = re.compile(r"[−-]?[0-9]+(?:\.[0-9]+)?(?:e[−+-]?[0-9]+)?")


def _markdown_rows(text: str, label_cells: int = 1) -> dict:
    """Every Markdown table row of ``text`` as ``{"label|col|pos": number}`` (label = the first
    ``label_cells`` cells joined by " | ", col counted from the cell after them, pos = the number's
    place in its cell)."""
    out = {}
    for line in text.splitlines():
        if not line.startswith("|") or line.startswith("|---"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        label = " | ".join(cells[:label_cells])
        for col, cell in enumerate(cells[label_cells:]):
            for pos, s in enumerate(_NUMBER.findall(cell)):
                out[f"{label}|{col}|{pos}"] = float(s.replace("−", "-"))
    return out


@functools.lru_cache(maxsize=None)
def _benchmark_text(script: str, *args) -> str:
    """What a script of ``benchmarks/`` prints from its ``run(*args)`` (the accuracy studies kept
    there for their OpenCV / SciPy peers). ``args`` are hashable (the cache); a tuple is passed on
    as a list."""
    import contextlib
    import importlib.util
    import io

    path = repository_root() / "benchmarks" / script
    spec = importlib.util.spec_from_file_location(f"_robocal_figures_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        module.run(*(list(a) if isinstance(a, tuple) else a for a in args))
    return buf.getvalue()


@functools.lru_cache(maxsize=None)
def _benchmark_table(script: str, *args) -> dict:
    """The Markdown table of :func:`_benchmark_text` as :func:`_markdown_rows` with two label cells."""
    return _markdown_rows(_benchmark_text(script, *args), label_cells=2)


@functools.lru_cache(maxsize=None)
def _handeye_study(seeds: int) -> dict:
    """docs/handeye.md "The paper's study": ``python benchmarks/handeye_study.py --seeds SEEDS``'s
    medians as ``{model}.{images}.{refined|linear}.{rot_deg|trans_mm}`` (the script's ``study``;
    its progress lines on stderr are dropped)."""
    import contextlib
    import importlib.util
    import io

    path = repository_root() / "benchmarks" / "handeye_study.py"
    spec = importlib.util.spec_from_file_location("_robocal_figures_handeye_study", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    with contextlib.redirect_stderr(io.StringIO()):
        res = module.study(seeds)
    out = {}
    for (model, n), v in res.items():
        for k, field in enumerate(("refined.rot_deg", "refined.trans_mm", "linear.rot_deg", "linear.trans_mm")):
            out[f"{model}.{n}.{field}"] = float(v[k])
    return out


@functools.lru_cache(maxsize=None)
def _printed_table(module: str, function: str) -> dict:
    """The Markdown table a workflow function returns as text, as :func:`_markdown_rows`."""
    import importlib

    return _markdown_rows(getattr(importlib.import_module(f"robocal.{module}"), function)())


@functools.lru_cache(maxsize=None)
def _datasets_report() -> dict:
    """``python -m robocal.workflows.datasets``'s text: Justin's middle level and boby's seeds."""
    text = report_text()
    out = {}
    m = re.search(r"\+ 18 joint offsets\s+" + r"([0-9.]+)\s+" * 3 + r"\(train ([0-9.]+)\)", text)
    if m:
        out.update(zip(("justin_offsets.rms", "justin_offsets.mean", "justin_offsets.max", "justin_offsets.train"),
                       map(float, m.groups())))
    for s, cal, train in re.findall(r"seed ([0-9]+): nominal [0-9.]+, calibrated ([0-9.]+) \(train ([0-9.]+)\)", text):
        out[f"boby_seed{s}.holdout"], out[f"boby_seed{s}.train"] = float(cal), float(train)
    return out


@functools.lru_cache(maxsize=None)
def _thermal_seeds(preset: str) -> dict:
    """docs/thermal.md section 6: ``robocal thermal experiment --preset PRESET --seeds 20 --resamples 20``;
    lambda [%] as ``{rms|max}.{screening|evaluation}.{column}.{median|q25|q75|min|max}``; the share of
    runs in the thesis's order [%] as ``ordering.{rms|max}.{role}.{strict_order|screened_not_worse}``;
    the share of seeds that screen a parameter [%] as ``selection.{name}``; ``n_screened_equals_stable``: the
    seeds whose full-run screened set equals the set selected by bootstrap frequency."""
    from ..workflows.thermal.seeds import run_thermal_seeds

    r = run_thermal_seeds(preset=preset, seeds=20, first_seed=1, n_cycles=90, resamples=20)
    # per seed: the screened lambda [%] (rms statistic) of its evaluation runs, lowest first
    per_seed = {f"seed.{x['seed']}.evaluation.screened.{k}": v for x in r["per_seed"]
                for k, v in enumerate(sorted(row["lambda"]["rms"]["screened"] for row in x["rows"]
                                             if row["role"] == "evaluation"))}
    # seeds whose full-run screened set is the set selected by bootstrap frequency (order ignored)
    same = sum(x["stable"] is not None and set(x["screened"]) == set(x["stable"]) for x in r["per_seed"])
    return {**_flat(r["tables"]), "n_not_converged": float(r["fits"]["not_converged"]),
            "n_screened_equals_stable": float(same),
            **{f"ordering.{k}": 100.0 * v for k, v in _flat(r["ordering"]).items()},
            **{f"selection.{k}": 100.0 * float(v) for k, v in r["selection"].items()},
            **{f"bootstrap.{k}": 100.0 * float(v) for k, v in (r["bootstrap_frequency"] or {}).items()},
            **per_seed}


@functools.lru_cache(maxsize=None)
def _demo() -> dict:
    """``robocal demo --poses 100`` (seed 7) in a temporary folder: the ISO 9283 comparison as
    ``iso.{characteristic}.{before|after}``."""
    import tempfile

    from ..workflows.demo import run_demo

    with tempfile.TemporaryDirectory() as tmp:
        r = run_demo(Path(tmp) / "demo", seed=7, n_poses=100)
    return {f"iso.{c['characteristic']}.{k}": float(c[k]) for c in r["iso9283"]["comparison"]
            for k in ("before", "after")}


@functools.lru_cache(maxsize=None)
def _plan_poses(robot: str) -> dict:
    """docs/cells.md: ``robocal plan-poses ROBOT --count 40 --candidates 800 --tracker-at 2500,0,500``
    (default cell, seed 0) without writing the file: draws, D-efficiency, path lengths [deg]."""
    import numpy as np

    from ..robots import load_robot
    from ..workflows.calibration.plan_poses import plan_cell, plan_in_cell

    model = load_robot(robot)
    r = plan_in_cell(model, plan_cell(model, None, np.array([2500.0, 0.0, 500.0]), None), count=40, candidates=800,
                     seed=0)
    return {"draws": float(r["draws"]), "d_efficiency": float(r["d_efficiency"]),
            "lost_percent": 100.0 * (1.0 - float(r["d_efficiency"])),
            "path_deg": float(np.degrees(r["path_rad"])), "path_unordered_deg": float(np.degrees(r["path_rad_unordered"]))}


@functools.lru_cache(maxsize=None)
def _ipso(experiment: str) -> dict:
    """docs/calibration.md "IPSO against LM": one experiment of
    ``python -m robocal.workflows.calibration.ipso_study --seeds 20`` (``deg``, ``rad``, ``tracker``:
    20 seeds; ``x30``, ``slip``: 5 seeds): ``{method}.{figure}`` medians, ``{method}.at_floor``
    and ``{method}.not_at_floor`` (counts of seeds), ``floor_mm``, ``nominal_mm``."""
    import numpy as np

    from ..workflows.calibration.ipso_study import compare, er10l_experiment, tracker_experiment

    runs = {"deg": (lambda s: er10l_experiment(s, "deg"), range(20), {}),
            "rad": (lambda s: er10l_experiment(s, "rad"), range(20), {}),
            "tracker": (tracker_experiment, range(20), {}),
            "x30": (lambda s: er10l_experiment(s, "deg", error_scale=30.0), range(5), dict(box_rad=0.3, box_mm=1.5)),
            "slip": (lambda s: er10l_experiment(s, "deg", slip={"theta4": np.pi}), range(5), dict(box_rad=np.pi))}
    make, seeds, options = runs[experiment]
    table = compare(make, seeds, **options)
    out = {"floor_mm": table["floor_mm"], "nominal_mm": table["nominal_mm"]}
    for m, r in table.items():
        if isinstance(r, dict):
            out.update({f"{m}.{k}": float(v) for k, v in r.items() if isinstance(v, (int, float))})
            at, n = (int(x) for x in r["at_floor"].split("/"))
            out[f"{m}.at_floor"], out[f"{m}.not_at_floor"] = float(at), float(n - at)
    return out


@functools.lru_cache(maxsize=None)
def _ur_import(conf: str, robot: str) -> dict:
    """docs/controller.md: ``robocal controller import ur ROBOT tests/data/controller/CONF --json``:
    the largest controller ``d`` [m] and the FK check over 1000 joint sets [mm, rad]."""
    import numpy as np

    from ..workflows.controller.models import import_ur

    r = import_ur(repository_root() / "tests" / "data" / "controller" / conf, robot, n_check=1000, seed=0)
    d_m = np.asarray(r["dh"]["d"], float)  # the controller's table is in metres
    return {"largest_d_m": float(np.max(np.abs(d_m))), "fk_max_mm": float(r["agreement"]["max_mm"]),
            "fk_max_rad": float(r["agreement"]["max_rad"])}


@functools.lru_cache(maxsize=None)
def _fleet_pose_sets() -> dict:
    """docs/fleet.md: ``robocal fleet study pose-sets ur10 --sets 12 --count 40 --candidates 800``
    (serial: every sample has its own seed, so the figures do not depend on the workers)."""
    from ..workflows.fleet.study import pose_set_selection

    r = pose_set_selection("ur10", sets=12, count=40, candidates=800)
    return {**{f"spread.{k}": float(v) for k, v in r["spread_mm"].items()},
            "relative_spread_percent": 100.0 * float(r["best"]["relative_spread"]),
            "n_within_noise": float(len(r["within_noise"])),
            "holdout_rms_mm.min": min(float(x["holdout_rms_mm"]) for x in r["sets"]),
            "holdout_rms_mm.max": max(float(x["holdout_rms_mm"]) for x in r["sets"])}


@functools.lru_cache(maxsize=None)
def _justin_self_calibration() -> dict:
    """docs/self-calibration.md "Figures": the DLR Justin tree (the setup of
    ``tests/test_self_calibration.py``): 25 views per arm, offsets uniform in +-3 deg (seed 15), 0.3 px.
    Fields ``max_abs_z``, ``n_identifiable``, ``rms_px_per_coordinate``, ``{both|left|right}.head_j1.error_deg``
    (absolute) / ``.sigma_deg``."""
    import numpy as np

    from ..camera import Camera
    from ..handeye.refine import joint_offset_names
    from ..handeye.self_calibration import solve_self_calibration
    from ..io.boards import parse_board
    from ..robots import load_robot
    from ..sim.cameras.self_calibration_views import simulate_corner_views
    from ..transforms import so3_exp, transforms_from

    cam = Camera(800.0, 800.0, 319.5, 239.5, (-0.1, 0.05, 0.0, 0.0, 0.0), "brown", (640, 480))
    boards = {"left": transforms_from(so3_exp(np.array([0.1, -0.2, 0.3])), np.array([10.0, 20.0, 120.0])),
              "right": transforms_from(so3_exp(np.array([-0.2, 0.1, 2.0])), np.array([-15.0, 5.0, 110.0]))}
    mount = transforms_from(so3_exp(np.array([0.01, -0.02, 0.015])), np.array([3.0, -2.0, 5.0]))
    m = load_robot("dlr_justin19")
    rng = np.random.default_rng(15)
    pn = list(m.params.names)
    truth = m.params.values.copy()
    offsets = {}
    for n in joint_offset_names(m):
        if m.links[int(n[5:]) - 1].name.startswith(("head", "left", "right")):
            offsets[n] = np.radians(rng.uniform(-3.0, 3.0))
            truth[pn.index(n)] += offsets[n]
    board = parse_board("checkerboard:7x4:25mm")
    X = board.object_points()
    q, carriers, uv = simulate_corner_views(m.with_params(truth), cam, X, camera_end_effector="head", T_ee_camera=mount,
                                            boards=boards, n_per_carrier=25, rng=rng, pixel_noise=0.3,
                                            front_z=board.front_z, pitch_mm=board.pitch_mm)
    c = np.asarray(carriers)
    kw = dict(camera_end_effector="head", pixel_sigma=0.3)
    fits = {"both": solve_self_calibration(m, q, uv, X, cam, list(carriers), **kw),
            **{a: solve_self_calibration(m, q[c == a], uv[c == a], X, cam, c[c == a], **kw) for a in ("left", "right")}}
    both = fits["both"]
    held = {r["name"] for r in both.joint_report if not r["identifiable"]}
    z = [(v - offsets[n]) / s for n, v, s in zip(both.joint_offset_names, both.joint_offsets, both.joint_offset_sigma)
         if n in offsets and n not in held]
    out = {"max_abs_z": float(np.max(np.abs(z))), "n_identifiable": float(len(z)),
           "rms_px_per_coordinate": float(both.rms_px / np.sqrt(2))}
    for name, res in fits.items():
        k = res.joint_offset_names.index("theta23")  # head_j1
        out[f"{name}.head_j1.error_deg"] = float(np.degrees(abs(res.joint_offsets[k] - offsets["theta23"])))
        out[f"{name}.head_j1.sigma_deg"] = float(np.degrees(res.joint_offset_sigma[k]))
    return out


@functools.lru_cache(maxsize=None)
def _iso_wear() -> dict:
    """docs/iso9283.md: the worn / healthy IRB 140 (the page's commands through the command line, in
    a temporary folder): ``{worn|healthy}.{k}.{AP|RP|U}`` [mm] for the tests k = 0, 1, 2, recorded in
    a history database, and ``robocal fleet status --at 2026-11-27T00:00Z``'s ISO trends
    ``status.{robot}.{AP|RP}.{trend_now_mm|last_mm|slope_mm_per_30_days}`` (a fixed date: the trend
    at "now" would depend on the day it is run)."""
    from .figure_producers_cli import run_cli as run

    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        run("iso9283", "plan", "abb_irb140", "--out", d / "plan", "--cycles", 10, "--path-cycles", 2)
        run("simulate", "tracker", "abb_irb140", "--poses", 10, "--seed", 3, "--out", d / "c.csv")
        for robot, noise in (("worn", (0.002, 0.005, 0.008)), ("healthy", (0.002, 0.002, 0.002))):
            for k, jn in enumerate(noise):
                csv = d / f"{robot}{k}.csv"
                run("simulate", "iso9283", "abb_irb140", d / "plan", "--seed", 10 + k, "--truth", d / "c.truth.json",
                    "--out", csv, "--joint-noise", jn, "--instrument-at", "3500,0,300")
                res = json.loads(run("iso9283", "evaluate", d / "plan", csv, "--out", d / f"ev-{robot}{k}", "--mpe",
                                     "15um+6um/m", "--instrument-at", "3500,0,300", "--db", d / "h.sqlite",
                                     "--robot-id", robot, "--time", f"2026-0{1 + 2 * k}-02T08:00Z", "--temperature",
                                     21 + k, "--instrument", "AT960", "--json"))["runs"][0]
                s = res["summary"]
                pose = max(res["pose"], key=lambda p: res["pose"][p]["RP_mm"])
                out.update({f"{robot}.{k}.AP": s["AP_mm"], f"{robot}.{k}.RP": s["RP_mm"],
                            f"{robot}.{k}.U": res["adequacy"][f"RP_mm.{pose}"]["U_mm"]})
        status = json.loads(run("fleet", "status", "--db", d / "h.sqlite", "--rp-tolerance", 0.15, "--ap-tolerance", 2,
                                "--no-plots", "--at", "2026-11-27T00:00Z", "--json", ok=(0, 3)))
    for row in status["robots"]:
        for sym, item in row.get("iso", {}).items():
            out[f"status.{row['robot']}.{sym}.trend_now_mm"] = item["trend_now_mm"]
            out[f"status.{row['robot']}.{sym}.last_mm"] = item["last_mm"]
            out[f"status.{row['robot']}.{sym}.slope_mm_per_30_days"] = 30.0 * item["slope_mm_per_day"]
    ap = [v for k, v in out.items() if k.startswith("status.") and k.endswith("AP.trend_now_mm")]
    out["status.AP.trend_now_mm.min"], out["status.AP.trend_now_mm.max"] = min(ap), max(ap)
    out["status.flagged"] = float(len(status["flagged"]))
    out["AP.min"] = min(v for k, v in out.items() if k.count(".") == 2 and k.endswith(".AP"))
    return out


@functools.lru_cache(maxsize=None)
def _beta_error() -> dict:
    """docs/tcp.md (4-30): the x error when the sensor's beta is ignored, d_x = d_y = 5 mm, per
    beta - 90 deg (``de.{k}``, k = the table's columns), and where it reaches 0.1 mm [deg]."""
    import numpy as np

    from ..tcp.sensor import beta_error_mm, beta_error_threshold_deg

    out = {f"de.{k}": float(beta_error_mm(5.0, np.radians(90.0 + b), d_to_y_beam=5.0))
           for k, b in enumerate((-5.0, -2.0, -1.2, -1.0, -0.5, 0.5, 1.0, 1.2, 2.0, 5.0))}
    lo, hi = beta_error_threshold_deg()
    return {**out, "threshold_low_deg": -float(lo), "threshold_high_deg": float(hi)}


@functools.lru_cache(maxsize=None)
def _tcp_collisions() -> dict:
    """docs/tcp.md collision study: ``robocal tcp simulate --collisions 10 --seed 0 --json``, each
    variant's summary as ``{variant}.{tcp_rms_mm|tcp_max_mm|axis_rms_deg|axis_max_deg|cycle_max_s}``."""
    import json

    from click.testing import CliRunner

    from ..cli import main as cli

    r = CliRunner().invoke(cli, ["tcp", "simulate", "--collisions", "10", "--seed", "0", "--json"],
                           catch_exceptions=False)
    if r.exit_code != 0:
        raise RuntimeError(f"robocal tcp simulate: exit {r.exit_code}: {r.output[-500:]}")
    return {f"{name}.{k}": float(v) for name, var in json.loads(r.stdout)["variants"].items()
            for k, v in var["summary"].items()}


@functools.lru_cache(maxsize=None)
def _handeye_vs_opencv() -> dict:
    """docs/handeye.md "Accuracy against OpenCV" (the setup of ``tests/test_handeye_refine.py``):
    15 simulated poses, 0.3 px, 0.05 mm / 0.01 deg robot noise, seeds 0-4 per set-up; OpenCV's linear
    methods on robocal's per-image target poses. Medians ``{setup}.{method}.{rot_deg|trans_mm}``."""
    import cv2
    import numpy as np

    from ..handeye import refine_hand_eye
    from ..handeye.refine import rotation_error_deg
    from ..sim.cameras.handeye_points import simulate_hand_eye
    from ..transforms import invert_transforms

    def pose(R, t):
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R, np.ravel(t)
        return T

    hand_eye = {"TSAI": cv2.CALIB_HAND_EYE_TSAI, "PARK": cv2.CALIB_HAND_EYE_PARK, "HORAUD": cv2.CALIB_HAND_EYE_HORAUD,
                "ANDREFF": cv2.CALIB_HAND_EYE_ANDREFF, "DANIILIDIS": cv2.CALIB_HAND_EYE_DANIILIDIS}
    robot_world = {"SHAH": cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH, "LI": cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI}
    out = {}
    for setup in ("eye_in_hand", "eye_to_hand"):
        errors = {}
        for seed in range(5):
            sim = simulate_hand_eye(seed, setup=setup, n_images=15, pixel_noise=0.3, pose_noise_mm=0.05,
                                    pose_noise_deg=0.01)
            res = refine_hand_eye(sim.T_base_flange, sim.image_points, sim.target_points, sim.camera, setup=setup)
            F = sim.T_base_flange if setup == "eye_in_hand" else invert_transforms(sim.T_base_flange)
            C = res.T_camera_target
            found = {"robocal": res.camera_pose}
            found.update({k: pose(*cv2.calibrateHandEye(list(F[:, :3, :3]), list(F[:, :3, 3]), list(C[:, :3, :3]),
                                                        list(C[:, :3, 3]), method=m)) for k, m in hand_eye.items()})
            G = invert_transforms(F)
            for k, m in robot_world.items():
                _, _, R_gc, t_gc = cv2.calibrateRobotWorldHandEye(list(C[:, :3, :3]), list(C[:, :3, 3]),
                                                                  list(G[:, :3, :3]), list(G[:, :3, 3]), method=m)
                found[k] = invert_transforms(pose(R_gc, t_gc)[None])[0]
            for k, T in found.items():
                errors.setdefault(k, []).append((rotation_error_deg(T, sim.camera_pose),
                                                 float(np.linalg.norm(T[:3, 3] - sim.camera_pose[:3, 3]))))
        for k, v in errors.items():
            rot, trans = np.median(np.asarray(v, float), axis=0)
            out[f"{setup}.{k}.rot_deg"], out[f"{setup}.{k}.trans_mm"] = float(rot), float(trans)
    return out


@functools.lru_cache(maxsize=None)
def _iso_cube(robot: str) -> dict:
    from ..performance.iso_cube import largest_iso_cube
    from ..robots import load_robot

    c = largest_iso_cube(load_robot(robot))
    return {"edge_mm": c.edge_mm, "centre_x_mm": float(c.centre_mm[0]), "centre_z_mm": float(c.centre_mm[2])}


PRODUCERS = {
    **CLI_PRODUCERS,
    **BENCH_PRODUCERS,
    **THERMAL_PRODUCERS,
    **SETUP_PRODUCERS,
    **SPEED_PRODUCERS,
    **HANDEYE_PRODUCERS,
    **DATASET_PRODUCERS,
    **TESTING_PRODUCERS,
    **PAGES_PRODUCERS,
    "boby_fanuc/geometric": lambda: _dataset("boby_fanuc", "geometric"),
    "boby_fanuc/elastic-joint": lambda: _dataset("boby_fanuc", "elastic-joint"),
    "dlr_justin/geometric": lambda: _dataset("dlr_justin", "geometric"),
    "dlr_justin/elastic-joint": lambda: _dataset("dlr_justin", "elastic-joint"),
    "dlr_justin/elastic-full": lambda: _dataset("dlr_justin", "elastic-full"),
    "nao/simulated": _nao_simulated,
    "nao/acceptance": _nao_acceptance,
    "justin/self_calibration": _justin_self_calibration,
    "datasets/report": _datasets_report,
    "demo/poses100": _demo,
    "handeye/vs_opencv": _handeye_vs_opencv,
    "tcp/collisions": _tcp_collisions,
    "tcp/beta_error": _beta_error,
    "iso9283/wear": _iso_wear,
    "handeye/fair_comparison": lambda: _benchmark_table("handeye_fair_comparison.py", tuple(range(20))),
    "fleet/pose_sets": _fleet_pose_sets,
    "handeye/study": lambda: _handeye_study(16),
    "ur_import/ur10": lambda: _ur_import("ur10_driver_test.conf", "ur10"),
    "ur_import/ur10e_a": lambda: _ur_import("ur10e_driver_test_a.conf", "ur10e"),
    "ur_import/ur10e_b": lambda: _ur_import("ur10e_driver_test_b.conf", "ur10e"),
    **{f"ipso/{e}": functools.partial(_ipso, e) for e in ("deg", "rad", "tracker", "x30", "slip")},
    **{f"plan_poses/{r}": functools.partial(_plan_poses, r) for r in ("ur10", "kuka_kr150_r3100", "abb_irb140")},
    "ros_industrial_positioner/table": lambda: _printed_table("workflows.datasets.ros_industrial_positioner",
                                                              "positioner_table"),
    "iso_cube/abb_irb140": lambda: _iso_cube("abb_irb140"),
    "iso_cube/kuka_kr150_r3100": lambda: _iso_cube("kuka_kr150_r3100"),
    "hilti_trailblazer/geometric": lambda: _dataset("hilti_trailblazer", "geometric"),
    "boby_fanuc/elastic-full": lambda: _dataset("boby_fanuc", "elastic-full"),
    "hilti_trailblazer/elastic-joint": lambda: _dataset("hilti_trailblazer", "elastic-joint"),
    "hilti_trailblazer/elastic-full": lambda: _dataset("hilti_trailblazer", "elastic-full"),
    "closed_chain/study": lambda: _closed_chain(10, 2, True),
    **{f"closed_chain/{p}-{'spacing' if k else 'free'}": functools.partial(_closed_chain, 5, p, k)
       for p in (1, 2) for k in (False, True)},
    "tcp/realistic": lambda: _tcp_accuracy("realistic"),
    "tcp/ideal": lambda: _tcp_accuracy("ideal"),
    "tcp/budget": _tcp_budget,
    "thermal/realistic": lambda: _thermal_seeds("realistic"),
    "thermal/ideal": lambda: _thermal_seeds("ideal"),
}


def datasets_needed(producer: str) -> tuple:
    """The data sets (folders under ``robocal.io.datasets.datasets_root()``) a producer reads."""
    if producer in DATASETS_NEEDED:
        return DATASETS_NEEDED[producer]
    if producer in PAGES_DATASETS_NEEDED:
        return PAGES_DATASETS_NEEDED[producer]
    head = producer.split("/")[0]
    if producer.startswith(("handeye/default_real/", "handeye/camera_real/", "handeye/gate_shifted",
                            "handeye/variants_real/")):
        return ("ros_industrial_handeye",)
    if head in ("boby_fanuc", "dlr_justin", "hilti_trailblazer"):
        return (head,)
    return {"datasets": ("boby_fanuc", "dlr_justin", "hilti_trailblazer"),
            "ros_industrial_positioner": ("ros_industrial_handeye",),
            "ros_handeye": ("ros_industrial_handeye",), "camera": ("ros_industrial_handeye",)}.get(head, ())



#: producers longer than ~10 s of CPU: their figures run with ``--all`` / ``ROBOCAL_SLOW=1``
SLOW_PRODUCERS = {*SLOW_SPEED_PRODUCERS, *SLOW_PAGES_PRODUCERS, "dlr_justin/elastic-joint", "dlr_justin/elastic-full", "hilti_trailblazer/elastic-full", "fleet/pose_sets",
                  "handeye/fair_comparison", "handeye/study", *BENCH_PRODUCERS, *SLOW_DATASET_PRODUCERS, "ik_net/cli_example",
                  # thermal.md: the experiment with one effect alone (~6-10 s each), the ideal drift; testing.md's at-the-robot
                  # UR10 (~4 s) and gripper cases (~2 s each; slow to keep the fast set's added CPU under ~8 s) (figsC)
                  *(p for p in THERMAL_PRODUCERS if p.startswith("thermal_alone/")), "thermal_drift/ideal",
                  "program_at_robot/ur", "program_at_robot/krl_gripper", "program_at_robot/krl_gripper_ideal",
                  "system_calibration/thermal_100", "system_calibration/thermal_100_off_model",
                  # 3-6 s each: slow only to keep the CPU the suite's figures added on 2026-11-27 under 20 s
                  "thermal_cli/compensate", "tutorial/calibrate", "handeye/rendered", "self_calibration/industrial",
                  "tcp/realistic", "tcp/ideal", "tcp/budget",
                  # docs/handeye.md: camera calibrate on the real sets, ~2-5 s CPU each
                  "handeye/camera_real/test_set_charuco", "handeye/camera_real/test_set_10x10",
                  "handeye/variants_real/test_set_charuco", "handeye/variants_real/test_set_10x10",
                  "handeye/gate_shifted", "handeye/study_summary", "handeye/fair_counts", "handeye/board_shape",
                  "handeye/detection_rendered", *SLOW_TESTING_PRODUCERS,
                  *(p for p in PRODUCERS if p.startswith(("closed_chain/", "thermal/", "ipso/")))}
