"""Every registered figure of README.md and docs/ regenerated from its source and compared with the
printed value.

Each :class:`Figure` names the file, a regular expression whose first group is the printed number,
the producer that recomputes it (a dataset protocol, a simulation, a search) and the tolerance: half
a unit of the last printed digit plus a relative part stated per figure (cross-machine floating point
and solver stopping points). Producers are cached, so figures sharing a protocol run it once.

Usage::

    python -m robocal.docs.figures              # print the table (fast figures)
    python -m robocal.docs.figures --check      # exit 1 when a figure drifted beyond its tolerance
    python -m robocal.docs.figures --all        # include the slow ones (elastic-full on Justin, Hilti)

The fast figures also run in the test suite (``tests/test_doc_figures.py``); the slow ones run there
when ``ROBOCAL_SLOW=1`` is set (before each release).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import re
import sys
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Figure", "FIGURES", "PRODUCERS", "SLOW_PRODUCERS", "check_figure", "check_figures", "datasets_needed", "printed_value", "repository_root"]


def repository_root() -> Path:
    """The repository (``README.md`` and ``docs/``): this file is ``src/robocal/docs/figures.py``."""
    return Path(__file__).resolve().parents[3]


@dataclass(frozen=True)
class Figure:
    """One documented number.

    Attributes
    ----------
    key : str
        Identifier (``file:what``).
    file : str
        Path relative to the repository root.
    pattern : str
        Regular expression; its first group is the printed number.
    producer : str
        Name of the producer in :data:`PRODUCERS`.
    field : str
        Key of the producer's result dict.
    rel_tol : float
        Relative tolerance on top of half a unit of the last printed digit.
    slow : bool
        Longer than ~30 s: run with ``--all`` / ``ROBOCAL_SLOW=1``.
    note : str
        What the figure is (e.g. "training data", not a holdout).
    """

    key: str
    file: str
    pattern: str
    producer: str
    field: str
    rel_tol: float = 0.005
    slow: bool = False
    note: str = ""


# ----------------------------------------------------------------------------------------- producers
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
    for s in r.get("sets", []):
        out[f"{s['set']}.holdout_rms_mm"] = s["holdout_rms_mm"]
    return out


@functools.lru_cache(maxsize=None)
def _closed_chain(n_seeds: int, plates: int, known_spacing: bool) -> dict:
    """docs/closed-chain.md: the study per seed (flattened) and its medians over the seeds."""
    import numpy as np

    from ..workflows.calibration.closed_chain_study import run_study

    rows = run_study(range(n_seeds), plates=plates, known_spacing=known_spacing)
    out = _flat(rows)
    for k in ("closed_chain", "tracker", "nominal"):
        out[f"median.{k}"] = float(np.median([r["workspace_rms_mm"][k] for r in rows]))
    out["median.ratio"] = float(np.median([r["ratio_closed_chain_to_tracker"] for r in rows]))
    out["median.max_abs_z"] = float(np.median([r["max_abs_z"] for r in rows]))
    out["max.max_abs_z"] = float(max(r["max_abs_z"] for r in rows))
    out["n_not_converged"] = float(sum(r["n_not_converged"] for r in rows))
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
def _benchmark_table(script: str, *args) -> dict:
    """The Markdown table a script of ``benchmarks/`` prints from its ``run(*args)`` (the accuracy
    studies kept there for their OpenCV / SciPy peers), as :func:`_markdown_rows` with two label
    cells."""
    import contextlib
    import importlib.util
    import io

    path = repository_root() / "benchmarks" / script
    spec = importlib.util.spec_from_file_location(f"_robocal_figures_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        module.run(*args)
    return _markdown_rows(buf.getvalue(), label_cells=2)


@functools.lru_cache(maxsize=None)
def _printed_table(module: str, function: str) -> dict:
    """The Markdown table a workflow function returns as text, as :func:`_markdown_rows`."""
    import importlib

    return _markdown_rows(getattr(importlib.import_module(f"robocal.{module}"), function)())


@functools.lru_cache(maxsize=None)
def _datasets_report() -> dict:
    """``python -m robocal.workflows.datasets``'s text: Justin's middle level and boby's seeds."""
    from ..workflows.datasets.report import report

    text = report()
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
    lambda [%] as ``{rms|max}.{screening|evaluation}.{column}.{median|q25|q75|min|max}``."""
    from ..workflows.thermal.seeds import run_thermal_seeds

    r = run_thermal_seeds(preset=preset, seeds=20, first_seed=1, n_cycles=90, resamples=20)
    return {**_flat(r["tables"]), "n_not_converged": float(r["fits"]["not_converged"])}


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
    (count of seeds), ``floor_mm``, ``nominal_mm``."""
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
            out[f"{m}.at_floor"] = float(r["at_floor"].split("/")[0])
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
            "n_within_noise": float(len(r["within_noise"]))}


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
def _iso_cube(robot: str) -> dict:
    from ..performance.iso_cube import largest_iso_cube
    from ..robots import load_robot

    c = largest_iso_cube(load_robot(robot))
    return {"edge_mm": c.edge_mm, "centre_x_mm": float(c.centre_mm[0]), "centre_z_mm": float(c.centre_mm[2])}


PRODUCERS = {
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
    "handeye/fair_comparison": lambda: _benchmark_table("handeye_fair_comparison.py", list(range(20))),
    "fleet/pose_sets": _fleet_pose_sets,
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

_N = r"([−-]?[0-9]+(?:\.[0-9]+)?(?:e[−+-]?[0-9]+)?)"


def _cell(row: str, col: int, pos: int = 0, after: str = "") -> str:
    """Pattern of the ``pos``-th number in cell ``col`` (0 = the first cell after the label) of the
    Markdown table row whose label cells are ``row`` (e.g. ``"realistic | cross-laser"``), the
    first such row after the text ``after``."""
    start = (re.escape(after) + r"(?s:.*?)\n\| ") if after else r"(?m)^\| "
    return (start + re.escape(row) + r" \|" + r"[^|\n]*\|" * col
            + r"(?:[^0-9|\n]*?[0-9][0-9.]*(?:e[−+-]?[0-9]+)?)" * pos + r"[^0-9|\n]*?" + _N)


def _table(file: str, rows: dict, producer: str, columns: list, *, prefix: str = "", rel_tol: float = 0.005,
           slow: bool = False, note: str = "", after: str = "", short: bool = True) -> list:
    """Figures of a table: ``rows`` label -> field prefix, ``columns`` [(col, pos, field suffix)]."""
    out = []
    for label, key in rows.items():
        for col, pos, field in columns:
            f = f"{key}.{field}" if key else field
            out.append(Figure(f"{prefix}{(label.split(' (')[0] if short else label).replace(' | ', '/')} {f}", file, _cell(label, col, pos, after),
                              producer, f, rel_tol=rel_tol, slow=slow, note=note))
    return out
_ROW_BOBY = r"\| boby_fanuc \(mean over seeds 0-4\) \| "
_ROW_JUSTIN = r"\| dlr_justin \(seed 0\) \| "

FIGURES = [
    Figure("datasets:boby geometric rms", "docs/datasets.md", _ROW_BOBY + _N, "boby_fanuc/geometric", "holdout_rms_mm"),
    Figure("datasets:boby geometric mean", "docs/datasets.md", _ROW_BOBY + r"[0-9.]+ / " + _N, "boby_fanuc/geometric",
           "holdout_mean_mm"),
    Figure("datasets:boby elastic-joint rms", "docs/datasets.md", _ROW_BOBY + r"[0-9.]+ / [0-9.]+ / [0-9.]+ \| \*\*" + _N,
           "boby_fanuc/elastic-joint", "holdout_rms_mm", rel_tol=0.01),
    Figure("datasets:justin geometric mean", "docs/datasets.md", _ROW_JUSTIN + r"[0-9.]+ / " + _N,
           "dlr_justin/geometric", "holdout_mean_mm"),
    Figure("datasets:justin elastic-joint mean", "docs/datasets.md",
           _ROW_JUSTIN + r"[0-9.]+ / [0-9.]+ / [0-9.]+ \| [0-9.]+ / " + _N, "dlr_justin/elastic-joint",
           "holdout_mean_mm", rel_tol=0.01, slow=True),
    Figure("datasets:justin elastic-full mean (README headline)", "docs/datasets.md",
           _ROW_JUSTIN + r"[0-9.]+ / [0-9.]+ / [0-9.]+ \| [0-9.]+ / [0-9.]+ / [0-9.]+ [^|]*\| \*\*[0-9.]+ / " + _N,
           "dlr_justin/elastic-full", "holdout_mean_mm", rel_tol=0.01, slow=True),
    Figure("self-calibration:nao max |error/sigma|", "docs/self-calibration.md",
           r"9 identifiable offsets\s+within max \|error/sigma\| = " + _N, "nao/simulated", "max_abs_z", rel_tol=0.02),
    Figure("self-calibration:nao rms px", "docs/self-calibration.md", r"= [0-9.]+, RMS " + _N + r" px per coordinate \(regenerated",
           "nao/simulated", "rms_px_per_coordinate", rel_tol=0.01),
    Figure("iso9283:irb140 cube", "docs/iso9283.md", r"IRB 140 cube " + _N + " mm", "iso_cube/abb_irb140", "edge_mm",
           rel_tol=0.0),
    Figure("iso9283:kr150 cube", "docs/iso9283.md", r"KR 150 R3100 " + _N + " mm", "iso_cube/kuka_kr150_r3100",
           "edge_mm", rel_tol=0.0),
]


# datasets.md: the protocols' tables (``python -m robocal.workflows.datasets`` prints them)
_METRICS3 = [(0, 0, "rms"), (1, 0, "mean"), (2, 0, "max")]
FIGURES += _table("docs/datasets.md", {"nominal (robocal)": "nominal"}, "boby_fanuc/geometric", _METRICS3,
                  prefix="datasets:boby ")
FIGURES += _table("docs/datasets.md", {"calibrated (robocal)": "geometric"}, "boby_fanuc/geometric",
                  [(1, 0, "mean"), (2, 0, "max")], prefix="datasets:boby ")
FIGURES += _table("docs/datasets.md", {"nominal, base + 2 marker offsets": "nominal"}, "dlr_justin/geometric",
                  _METRICS3, prefix="datasets:justin ")
FIGURES += _table("docs/datasets.md", {"+ all modified-DH params of torso and arms (alpha, a, theta, d; beta where "
                                       "alpha = 0), prior 1e-3": ""}, "dlr_justin/geometric",
                  [(0, 0, "geometric.rms"), (1, 0, "geometric.mean"), (2, 0, "geometric.max"), (3, 0, "train_rms_mm")],
                  prefix="datasets:justin ")
_HILTI_SETS = {"flat (275, training data)": "sets.flat", "pallet (316)": "sets.pallet",
               "orthogonal_wood (255)": "sets.orthogonal_wood", "wood_left_track (273)": "sets.wood_left_track",
               "seesaw (300)": "sets.seesaw", "diagonal_wood (313)": "sets.diagonal_wood",
               "outdoor (324, 9 C)": "sets.outdoor"}
FIGURES += [dataclasses.replace(f, note="training data" if "flat" in f.key else "holdout")
            for f in _table("docs/datasets.md", _HILTI_SETS, "hilti_trailblazer/geometric",
                            [(0, 0, "nominal.rms"), (0, 3, "nominal.max"), (1, 0, "geometric.rms"), (1, 1, "p95_xy_mm"),
                             (1, 2, "p95_z_mm"), (1, 3, "geometric.mean"), (1, 4, "geometric.max")],
                            prefix="datasets:hilti ")]
FIGURES += _table("docs/datasets.md", {"boby_fanuc (mean over seeds 0-4)": ""}, "boby_fanuc/elastic-joint",
                  [(1, 1, "holdout_mean_mm"), (1, 2, "holdout_max_mm")], prefix="datasets:boby elastic-joint ",
                  rel_tol=0.01)
FIGURES += _table("docs/datasets.md", {"boby_fanuc (mean over seeds 0-4)": ""}, "boby_fanuc/elastic-full",
                  [(2, 0, "holdout_rms_mm"), (2, 1, "holdout_mean_mm"), (2, 2, "holdout_max_mm")],
                  prefix="datasets:boby elastic-full ", rel_tol=0.01, slow=True)
for _col, _model, _slow in ((0, "geometric", False), (1, "elastic-joint", True), (2, "elastic-full", True)):
    for _label, _sets in (("hilti flat (training set) / pallet / orthogonal_wood (RMS)",
                           ("flat", "pallet", "orthogonal_wood")),
                          ("hilti wood_left_track / seesaw / diagonal_wood / outdoor (RMS)",
                           ("wood_left_track", "seesaw", "diagonal_wood", "outdoor"))):
        FIGURES += [Figure(f"datasets:hilti {_model} {s} rms", "docs/datasets.md", _cell(_label, _col, k),
                           f"hilti_trailblazer/{_model}", f"sets.{s}.holdout_rms_mm", rel_tol=0.01, slow=_slow,
                           note="training data" if s == "flat" else "holdout")
                    for k, s in enumerate(_sets)]

# closed-chain.md: ``python -m robocal.workflows.calibration.closed_chain_study --seeds 10`` and the variants
FIGURES += _table("docs/closed-chain.md", {str(s): str(s) for s in range(10)}, "closed_chain/study",
                  [(0, 0, "E_OP_before_mm"), (0, 1, "E_OP_after_mm"), (1, 0, "workspace_rms_mm.nominal"),
                   (2, 0, "workspace_rms_mm.closed_chain"), (3, 0, "workspace_rms_mm.tracker"),
                   (4, 0, "workspace_rms_mm.true_model"), (5, 0, "ratio_closed_chain_to_tracker"), (6, 0, "max_abs_z")],
                  prefix="closed-chain:seed ", rel_tol=0.01, slow=True, after="| seed | E_OP before / after")
FIGURES += [
    Figure("closed-chain:median ratio", "docs/closed-chain.md", r"Median ratio closed chain / tracker: " + _N,
           "closed_chain/study", "median.ratio", rel_tol=0.01, slow=True),
    Figure("closed-chain:largest z", "docs/closed-chain.md", r"for all 22 parameters \(largest " + _N,
           "closed_chain/study", "max.max_abs_z", rel_tol=0.01, slow=True),
    Figure("closed-chain:median of the largest z", "docs/closed-chain.md", r"the maxima \(median " + _N,
           "closed_chain/study", "median.max_abs_z", rel_tol=0.01, slow=True),
]
for _p, _k, _label in ((1, False, "1 | no | 40"), (1, True, "1 | 50 mm | 40"), (2, False, "2 | no | 80"),
                       (2, True, "2 | 50 mm | 80")):
    FIGURES += _table("docs/closed-chain.md", {_label: ""}, f"closed_chain/{_p}-{'spacing' if _k else 'free'}",
                      [(0, 0, "median.closed_chain"), (1, 0, "median.tracker"), (2, 0, "median.ratio"),
                       (3, 0, "max.max_abs_z")], prefix="closed-chain:variant ", rel_tol=0.01, slow=True)

# tcp.md: ``robocal tcp accuracy --preset realistic|ideal --seeds 20 --repeats 10`` and ``--budget``
_Q = ["median", "q25", "q75"]
for _preset in ("realistic", "ideal"):
    for _m, _lab in (("cross_laser", "cross-laser"), ("parallel_barriers", "parallel barriers")):
        _cols = [(c, k, f"{metric}.{q}") for c, metric in enumerate(("repeatability_mm", "accuracy_mm", "check_mm",
                                                                      "axis_accuracy_deg"))
                 for k, q in enumerate(_Q)]
        FIGURES += _table("docs/tcp.md", {f"{_preset} | {_lab}": _m}, f"tcp/{_preset}",
                          _cols + [(4, 0, "cycle_s.median")], prefix="tcp:", rel_tol=0.01, slow=True)
_BUDGET = {"ideal": "ideal", "+ I/O 125 Hz, late, jitter": "I/O 125 Hz, late, jitter",
           "+ absolute error": "absolute error", "+ dirty beams": "dirty beams", "+ tool runout": "tool runout",
           "+ measuring arm": "measuring arm", "realistic (all)": "realistic"}
for _c, _m in enumerate(("cross_laser", "parallel_barriers")):
    FIGURES += _table("docs/tcp.md", {k: f"{v}.{_m}" for k, v in _BUDGET.items()}, "tcp/budget",
                      [(_c, k, f"{metric}.median") for k, metric in
                       enumerate(("repeatability_mm", "accuracy_mm", "check_mm", "axis_accuracy_deg"))],
                      prefix="tcp:budget ", rel_tol=0.01, slow=True, after="Error budget (`--budget`)")


# elastic.md: the three protocols with the three models (``robocal datasets run NAME --model M --json``)
_HOLDOUT3 = ("holdout_rms_mm", "holdout_mean_mm", "holdout_max_mm")
_ELASTIC_ROWS = {"dlr_justin (400/100, seed 0)": ("dlr_justin", ""), "boby_fanuc (24/12, seeds 0-4)": ("boby_fanuc", ""),
                 **{f"hilti {s}" + (" (training set)" if s == "flat" else ""): ("hilti_trailblazer", f"sets.{s}")
                    for s in ("flat", "pallet", "orthogonal_wood", "wood_left_track", "seesaw", "diagonal_wood",
                              "outdoor")}}
for _col, _model in enumerate(("geometric", "elastic-joint", "elastic-full")):
    for _label, (_ds, _key) in _ELASTIC_ROWS.items():
        FIGURES += [dataclasses.replace(f, key=f"elastic:{_model} {f.key}",
                                        note="training data" if "flat" in _label else "holdout")
                    for f in _table("docs/elastic.md", {_label: _key}, f"{_ds}/{_model}",
                                    [(_col, k, field) for k, field in enumerate(_HOLDOUT3)], rel_tol=0.01,
                                    slow=_model != "geometric" and _ds == "dlr_justin"
                                    or _model == "elastic-full" and _ds == "hilti_trailblazer")]
FIGURES += [
    Figure("elastic:justin train rms geometric", "docs/elastic.md", r"Training RMS: Justin " + _N,
           "dlr_justin/geometric", "train_rms_mm"),
    Figure("elastic:justin train rms joint", "docs/elastic.md", r"Training RMS: Justin [0-9.]+ → " + _N,
           "dlr_justin/elastic-joint", "train_rms_mm", rel_tol=0.01, slow=True),
    Figure("elastic:justin train rms full", "docs/elastic.md", r"Training RMS: Justin [0-9.]+ → [0-9.]+ \(joint\) → " + _N,
           "dlr_justin/elastic-full", "train_rms_mm", rel_tol=0.01, slow=True),
]
for _model, _pat in (("elastic-joint", r"0\.276 mm RMS \(per seed "), ("elastic-full", r"0\.320 mm \(per seed ")):
    FIGURES += [Figure(f"elastic:boby {_model} seed {k}", "docs/elastic.md", _pat + r"(?:[0-9.]+,\s+)" * k + _N,
                       f"boby_fanuc/{_model}", f"per_seed_holdout_rms_mm.{k}", rel_tol=0.01) for k in range(5)]


# self-calibration.md: the NAO H25 acceptance (tests/test_self_calibration_nao.py's setup)
FIGURES += [
    Figure("self-calibration:nao acceptance max |z|", "docs/self-calibration.md",
           r"the other 9 within\s+max \|error / sigma\| = " + _N, "nao/acceptance", "max_abs_z", rel_tol=0.02),
    Figure("self-calibration:nao acceptance rms", "docs/self-calibration.md",
           r"reprojection RMS per coordinate " + _N + r" px for 0\.3 px", "nao/acceptance", "rms_px_per_coordinate"),
]
_NAO = {"theta1 HeadYaw": "theta1", "theta4 LShoulderPitch": "theta4", "theta5 LShoulderRoll": "theta5",
        "theta6 LElbowYaw": "theta6", "theta7 LElbowRoll": "theta7", "theta9 RShoulderPitch": "theta9",
        "theta10 RShoulderRoll": "theta10", "theta11 RElbowYaw": "theta11", "theta12 RElbowRoll": "theta12"}
for _label, _p in _NAO.items():
    _cols = [(0, 0, f"truth.{_p}")]
    for _c, _fit in ((1, "both"), (2, "left_hand"), (3, "right_hand")):
        if _c == 1 or (_fit == "left_hand") == (_label.split()[1][0] == "L") or _p == "theta1":
            _cols += [(_c, 0, f"{_fit}.{_p}.error_deg"), (_c, 1, f"{_fit}.{_p}.sigma_deg")]
    FIGURES += [dataclasses.replace(f, rel_tol=0.02) for f in
                _table("docs/self-calibration.md", {_label: ""}, "nao/acceptance", _cols, prefix="self-calibration:nao ")]


# datasets.md: Justin's middle level, boby's seeds (the report's text) and the positioner's table
FIGURES += _table("docs/datasets.md", {"+ 18 joint offsets (torso incl. passive joint, both arms)": "justin_offsets"}, "datasets/report",
                  [(0, 0, "rms"), (1, 0, "mean"), (2, 0, "max"), (3, 0, "train")], prefix="datasets:justin ")
FIGURES += [Figure(f"datasets:boby seed {k} {what}", "docs/datasets.md",
                   r"\(calibrated holdout RMS / train RMS\): " + r"(?:[0-9.]+/[0-9.]+,\s+)" * k
                   + (_N if what == "holdout" else r"[0-9.]+/" + _N), "datasets/report", f"boby_seed{k}.{what}")
            for k in range(5) for what in ("holdout", "train")]
for _label, _spec in (("nominal DH (base + target mount fitted)", ((0, 3), (1, 1), (2, 3), (3, 2))),
                      ("calibrated (+ the identifiable DH parameters)", ((0, 3), (1, 1), (2, 3), (3, 2)))):
    FIGURES += [Figure(f"datasets:positioner {_label.split(' (')[0]} {c}.{k}", "docs/datasets.md",
                       _cell(_label, c, k), "ros_industrial_positioner/table", f"{_label}|{c}|{k}")
                for c, n in _spec for k in range(n)]


# thermal.md section 6: lambda over 20 seeds; per row the count of numbers in each column's cell
# (median, q25, q75[, min, max])
for _row, _counts in (("realistic, rms | screening", (5, 5, 5, 5)), ("realistic, rms | evaluation", (5, 5, 5, 5)),
                      ("realistic, strict | screening", (3, 3, 3, 3)), ("realistic, strict | evaluation", (3, 3, 3, 3)),
                      ("ideal, rms | screening", (3, 3, 3, 3)), ("ideal, rms | evaluation", (5, 3, 5, 3)),
                      ("ideal, strict | screening", (3, 3, 3, 3)), ("ideal, strict | evaluation", (3, 3, 3, 3))):
    _preset, _rest = _row.split(", ")
    _stat, _role = _rest.split(" | ")
    FIGURES += _table("docs/thermal.md", {_row: f"{'rms' if _stat == 'rms' else 'max'}.{_role}"}, f"thermal/{_preset}",
                      [(c, k, f"{col}.{q}") for c, col in enumerate(("before", "traditional", "screened", "stable"))
                       for k, q in enumerate(("median", "q25", "q75", "min", "max")[:_counts[c]])],
                      prefix="thermal:", rel_tol=0.0)


# iso9283.md "In the demo" and README.md: ``robocal demo --poses 100`` (seed 7)
FIGURES += [Figure(f"iso9283:demo {what} {k}", "docs/iso9283.md", pat, "demo/poses100", f"iso.{field}.{k}")
            for what, field, text in (("AP", "AP_mm", r"AP "), ("AT line", "AT_mm_line", r"AT \(line\) "),
                                      ("AT circle", "AT_mm_circle", r"AT \(circle\) "))
            for k, pat in (("before", r"seed 7\)(?s:.*?)" + text + _N),
                           ("after", r"seed 7\)(?s:.*?)" + text + r"[0-9.]+ → " + _N))]
FIGURES += [
    Figure("iso9283:demo RP", "docs/iso9283.md", r"seed 7\)(?s:.*?)RP " + _N + " mm before and after", "demo/poses100",
           "iso.RP_mm.before"),
    Figure("readme:demo AP before", "README.md", r"corrected program \(AP " + _N, "demo/poses100", "iso.AP_mm.before"),
    Figure("readme:demo AP after", "README.md", r"corrected program \(AP [0-9.]+ -> " + _N, "demo/poses100",
           "iso.AP_mm.after"),
]


# cells.md "Measured": plan-poses in the default cell (the time column is machine-dependent: not checked)
for _r in ("ur10", "kuka_kr150_r3100", "abb_irb140"):
    FIGURES += _table("docs/cells.md", {_r: ""}, f"plan_poses/{_r}",
                      [(0, 0, "draws"), (1, 0, "d_efficiency"), (1, 1, "lost_percent"), (2, 0, "path_deg"),
                       (2, 1, "path_unordered_deg")], prefix="cells:plan-poses ", rel_tol=0.0,
                      after="robocal plan-poses ROBOT --count 40")


# calibration.md "IPSO against LM" (the time column is machine-dependent: not checked)
for _e, _heading in (("deg", "#### ER10L-C10, joint noise +-0.1 deg"), ("rad", "#### ER10L-C10, joint noise +-0.1 rad"),
                     ("tracker", "#### UR10 (DH + beta) tracker simulation"), ("x30", "#### ER10L, errors x30"),
                     ("slip", "#### ER10L, theta4 slipped by 180 deg")):
    FIGURES += _table("docs/calibration.md", {m: m for m in ("lm", "ipso", "ipso+lm")}, f"ipso/{_e}",
                      [(0, 0, "holdout_mm"), (1, 0, "holdout_deg"), (2, 0, "param_mm"), (3, 0, "param_mrad"),
                       (5, 0, "at_floor")], prefix=f"calibration:ipso {_e} ", rel_tol=0.01, after=_heading)
    FIGURES.append(Figure(f"calibration:ipso {_e} floor", "docs/calibration.md",
                          re.escape(_heading) + r"(?s:.*?)noise floor \(true model\) " + _N, f"ipso/{_e}", "floor_mm",
                          rel_tol=0.01))
    if _e != "tracker":
        FIGURES.append(Figure(f"calibration:ipso {_e} nominal", "docs/calibration.md",
                              re.escape(_heading) + r"(?s:.*?)nominal model " + _N, f"ipso/{_e}", "nominal_mm",
                              rel_tol=0.01))


# controller.md: the UR driver's three test arms (the FK difference is rounding: checked to its order
# of magnitude, 0-10x the printed value)
for _label, _p in (("UR10", "ur10"), ("UR10e (a)", "ur10e_a"), ("UR10e (b, `algorithm.rst`)", "ur10e_b")):
    FIGURES += _table("docs/controller.md", {_label: ""}, f"ur_import/{_p}", [(0, 0, "largest_d_m")],
                      prefix="controller:", rel_tol=0.0, after="| arm (test case) |", short=False)
    FIGURES += _table("docs/controller.md", {_label: ""}, f"ur_import/{_p}", [(1, 0, "fk_max_mm"), (1, 1, "fk_max_rad")],
                      prefix="controller:", rel_tol=9.0, after="| arm (test case) |",
                      note="floating-point rounding: order of magnitude", short=False)


# fleet.md: the pose-set study
_FLEET = r"--candidates 800 --workers 2`\s+gave "
FIGURES += [Figure(f"fleet:pose-sets {k}", "docs/fleet.md", _FLEET + r"(?:[0-9.]+ / )" * i + _N, "fleet/pose_sets",
                   f"spread.{k}", rel_tol=0.01) for i, k in enumerate(("min", "median", "max"))]
FIGURES += [Figure("fleet:pose-sets campaign spread", "docs/fleet.md", r"with a campaign spread of " + _N + " %",
                   "fleet/pose_sets", "relative_spread_percent", rel_tol=0.05),
            Figure("fleet:pose-sets within noise", "docs/fleet.md", r"all " + _N + r" sets\s+within noise",
                   "fleet/pose_sets", "n_within_noise", rel_tol=0.0)]


# handeye.md "A fair comparison": ``python benchmarks/handeye_fair_comparison.py --seeds 20`` (accuracy
# figures of a script kept in benchmarks/ for its OpenCV and SciPy peers)
_HE_METHODS = ("**robocal default (auto)**", "robocal --exact-poses", "robocal prior 0.05 mm / 0.01 deg",
               "solvePnP + SciPy least_squares (12 unknowns)",
               *(f"OpenCV {k}" for k in ("TSAI", "PARK", "HORAUD", "ANDREFF", "DANIILIDIS", "RW_SHAH", "RW_LI")))
for _level in ("none (0 / 0)", "0.02 mm / 0.004 deg", "0.2 mm / 0.03 deg", "1 mm / 0.1 deg",
               "systematic 0.5 mm/m + 0.02 mm / 0.004 deg"):
    for _m in _HE_METHODS:
        _cols = [(0, 0), (1, 0)] + ([] if _m.startswith("**") else [(2, 0)])
        FIGURES += [Figure(f"handeye:fair {_level} {_m.strip('*')} {c}", "docs/handeye.md", _cell(f"{_level} | {_m}", c, k),
                           "handeye/fair_comparison", f"{_level} | {_m}|{c}|{k}", rel_tol=0.02 if c < 2 else 0.0)
                    for c, k in _cols]


# self-calibration.md "Figures": the Justin tree (tests/test_self_calibration.py's setup)
FIGURES += [
    Figure("self-calibration:justin max |z|", "docs/self-calibration.md",
           r"\| identifiable joint offsets \(13\) within 3 reported sigma \| max \\\|error/sigma\\\| = " + _N,
           "justin/self_calibration", "max_abs_z", rel_tol=0.02),
    Figure("self-calibration:justin rms", "docs/self-calibration.md",
           r"\| reprojection RMS per coordinate / simulated noise \| " + _N, "justin/self_calibration",
           "rms_px_per_coordinate"),
]
for _label, _fit in (("head_j1 offset, both arms together", "both"), ("head_j1 offset, left arm alone", "left"),
                     ("head_j1 offset, right arm alone", "right")):
    FIGURES += _table("docs/self-calibration.md", {_label: f"{_fit}.head_j1"}, "justin/self_calibration",
                      [(0, 0, "error_deg"), (0, 1, "sigma_deg")], prefix="self-calibration:justin ", rel_tol=0.02)


def datasets_needed(producer: str) -> tuple:
    """The data sets (folders under ``robocal.io.datasets.datasets_root()``) a producer reads."""
    head = producer.split("/")[0]
    if head in ("boby_fanuc", "dlr_justin", "hilti_trailblazer"):
        return (head,)
    return {"datasets": ("boby_fanuc", "dlr_justin", "hilti_trailblazer"),
            "ros_industrial_positioner": ("ros_industrial_handeye",)}.get(head, ())


#: producers longer than ~10 s of CPU: their figures run with ``--all`` / ``ROBOCAL_SLOW=1``
SLOW_PRODUCERS = {"dlr_justin/elastic-joint", "dlr_justin/elastic-full", "hilti_trailblazer/elastic-full", "fleet/pose_sets",
                  "handeye/fair_comparison",
                  *(p for p in PRODUCERS if p.startswith(("closed_chain/", "tcp/", "thermal/", "ipso/")))}
FIGURES = [dataclasses.replace(f, slow=f.producer in SLOW_PRODUCERS) for f in FIGURES]


# ----------------------------------------------------------------------------------------- checking
def printed_value(fig: Figure, root: Path | None = None) -> tuple[float, int]:
    """The number as printed in the file, and its count of decimals.

    Raises
    ------
    robocal.errors.InputFileError
        If the pattern no longer matches (the text was edited: update the registry with it).
    """
    from ..errors import InputFileError

    root = root or repository_root()
    text = (root / fig.file).read_text(encoding="utf-8")
    m = re.search(fig.pattern, text)
    if not m:
        raise InputFileError(f"{fig.file}: the figure {fig.key!r} is no longer where its pattern looks "
                             f"({fig.pattern!r}); update robocal/docs/figures.py with the text")
    s = m.group(1).replace("−", "-")
    mantissa, _, exponent = s.partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return float(s), decimals - int(exponent or 0)


def check_figure(fig: Figure, root: Path | None = None) -> dict:
    """Regenerate one figure and compare: ``key, file, printed, computed, tolerance, ok, note``."""
    printed, decimals = printed_value(fig, root)
    computed = float(PRODUCERS[fig.producer]()[fig.field])
    tol = 0.5 * 10 ** (-decimals) + fig.rel_tol * abs(printed)
    return {"key": fig.key, "file": fig.file, "printed": printed, "computed": computed, "tolerance": tol,
            "ok": abs(computed - printed) <= tol, "note": fig.note}


def check_figures(*, include_slow: bool = False, only=None, root: Path | None = None) -> list[dict]:
    """Regenerate and compare (:func:`check_figure`); ``only``: texts one of which each key contains."""
    return [check_figure(fig, root) for fig in FIGURES
            if not (fig.slow and not include_slow) and not (only and not any(o in fig.key for o in only))]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m robocal.docs.figures", description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 when a figure drifted beyond its tolerance")
    ap.add_argument("--all", action="store_true", help="include the slow figures")
    ap.add_argument("--only", action="append", help="only figures whose key contains this text")
    a = ap.parse_args(argv)
    rows = []
    for fig in FIGURES:
        if (fig.slow and not a.all) or (a.only and not any(o in fig.key for o in a.only)):
            continue
        try:
            rows.append(check_figure(fig))
        except Exception as exc:  # one broken producer or pattern must not hide the other figures
            rows.append({"key": fig.key, "file": fig.file, "printed": float("nan"), "computed": float("nan"),
                         "tolerance": float("nan"), "ok": False, "note": f"error: {type(exc).__name__}: {exc}"})
    print(f"{'figure':<52}{'printed':>10}{'computed':>12}{'tol':>9}  ok")
    for r in rows:
        print(f"{r['key']:<52}{r['printed']:>10g}{r['computed']:>12.5g}{r['tolerance']:>9.2g}  "
              f"{'yes' if r['ok'] else 'NO'}" + (f"  ({r['note']})" if r["note"] == "training data"
                                                 or r["note"].startswith("error") else ""))
    bad = [r for r in rows if not r["ok"]]
    if bad:
        print(f"{len(bad)} figure(s) drifted: {', '.join(r['key'] for r in bad)}", file=sys.stderr)
    return 1 if (a.check and bad) else 0


if __name__ == "__main__":  # pragma: no cover
    from .._blas_threads import single_thread_blas

    single_thread_blas()  # numpy is not imported yet here (robocal/_blas_threads.py)
    sys.exit(main())
