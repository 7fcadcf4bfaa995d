"""Readers for the third-party real measured data sets, and their reference calibration protocols.

The data live outside the repository, in ``../shared/datasets`` relative to the repository root
(``/work/shared/datasets`` on the project machine; override with the ``ROBOCAL_DATASETS``
environment variable or the ``root`` argument). They are read in place, never copied. Each
folder's README gives source, license, units, traps and the reference numbers; docs/datasets.md
describes the protocols and how to reproduce the figures.

Readers (internal units: mm, rad; every malformed entry raises :class:`DatasetError` naming the
file and the row / column or YAML key path):

* :func:`read_boby_fanuc`         FANUC 6R, laser tracker, 3 SMRs, 36 poses;
* :func:`read_dlr_justin`         DLR Agile Justin (19 joints), Vicon, 2 hand markers, 500 poses;
* :func:`read_hilti_trailblazer`  Hilti Trailblazer (column + Doosan 6R), total station, one set.

Protocols (each returns plain dicts of holdout statistics, see docs/datasets.md):

* :func:`calibrate_boby`, :func:`calibrate_boby_seeds`  24/12 random splits, seeds 0-4;
* :func:`calibrate_justin`                              400/100 random split, seed 0;
* :func:`calibrate_hilti`, :func:`hilti_station_protocol`  fit on ``flat``, per-station Kabsch test.
"""

from __future__ import annotations

import csv
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "DatasetError",
    "RealDataset",
    "HILTI_SETS",
    "HILTI_CROSS_CMDS",
    "datasets_root",
    "read_boby_fanuc",
    "read_dlr_justin",
    "read_hilti_trailblazer",
    "error_stats",
    "boby_model",
    "calibrate_boby",
    "calibrate_boby_seeds",
    "calibrate_justin",
    "hilti_station_protocol",
    "calibrate_hilti",
]

#: The seven Hilti sets, in the order of the dataset README.
HILTI_SETS = ("flat", "pallet", "orthogonal_wood", "wood_left_track", "seesaw", "diagonal_wood", "outdoor")
#: ``doosan_cmd`` of the four 'CROSS' stationing points (the repository's StationingShape.CROSS) [m].
HILTI_CROSS_CMDS = ((0.25, 0.15, 0.48), (0.25, -0.15, 0.48), (0.4, 0.0, 0.48), (0.1, 0.0, 0.48))


class DatasetError(ValueError):
    """A data file is missing or malformed; the message names the file and the row / column / key."""


@dataclass
class RealDataset:
    """One real data set in robocal's internal units.

    joints: (N, n) controller joints [rad | mm] in the robot model's controller order;
    points: (N, K, 3) measured target positions in the instrument frame [mm] (NaN = not measured);
    targets: K target names; joint_names: n names; stations: (N,) station / group index;
    station_labels: one label per station (e.g. ``(height_m, solution_space)``);
    per_pose: dict of further (N, ...) arrays (protocol-specific: roles, flags, ids, times);
    metadata: dict (source file, instrument, units of the file, notes).
    """

    name: str
    joints: np.ndarray
    points: np.ndarray
    targets: tuple
    joint_names: tuple
    stations: np.ndarray
    station_labels: list = field(default_factory=list)
    per_pose: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)

    @property
    def n_poses(self) -> int:
        return len(self.joints)

    def subset(self, idx) -> "RealDataset":
        """The poses ``idx`` (index array or boolean mask); stations are kept as they are."""
        idx = np.asarray(idx)
        per = {k: v[idx] for k, v in self.per_pose.items()}
        return RealDataset(self.name, self.joints[idx], self.points[idx], self.targets, self.joint_names,
                           self.stations[idx], list(self.station_labels), per, dict(self.metadata))


# ---------------------------------------------------------------------------------------- location
def datasets_root(root=None) -> Path:
    """The folder holding the data sets: ``root`` if given, else ``$ROBOCAL_DATASETS``, else
    ``../shared/datasets`` relative to the repository root (this file is
    ``<repo>/src/robocal/io/datasets.py``; for a non-editable install, relative to the current
    directory taken as the repository root). The folder may not exist; callers check."""
    if root is not None:
        return Path(root)
    env = os.environ.get("ROBOCAL_DATASETS")
    if env:
        return Path(env)
    candidates = [Path(__file__).resolve().parents[3].parent / "shared" / "datasets",
                  Path.cwd().resolve().parent / "shared" / "datasets"]
    for c in candidates:
        if c.is_dir():
            return c
    return candidates[0]


def _file(root, *parts) -> Path:
    p = datasets_root(root).joinpath(*parts)
    if not p.is_file():
        raise DatasetError(f"{p}: no such file (data sets are read from {datasets_root(root)}; "
                           f"see docs/datasets.md)")
    return p


def _number(text, where) -> float:
    try:
        v = float(text)
    except ValueError:
        raise DatasetError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise DatasetError(f"{where}: {text!r} is not a finite number")
    return v


# ---------------------------------------------------------------------------------------- boby_fanuc
def read_boby_fanuc(root=None, path=None) -> RealDataset:
    """``boby_fanuc/raw/N1N2N3Jval.csv``: 21 whitespace-separated columns per row.

    Columns 0-8: SMR N1, N2, N3 xyz [mm] in the tracker frame; 9-14: zeros (ignored); 15-20:
    J1..J6 [deg] in FANUC's controller convention (J3 against the horizontal) - returned in rad,
    to be used with ``fanuc_r2000ic_165f`` unchanged (the J2/J3 coupling is in the model).
    """
    p = Path(path) if path is not None else _file(root, "boby_fanuc", "raw", "N1N2N3Jval.csv")
    rows = []
    with open(p, encoding="utf-8") as fh:
        for line_no, line in enumerate(fh, 1):
            cells = line.split()
            if not cells:
                continue
            if len(cells) != 21:
                raise DatasetError(f"{p}: line {line_no}: expected 21 whitespace-separated columns "
                                   f"(SMR N1..N3 xyz mm, 6 zeros, J1..J6 deg), got {len(cells)}")
            rows.append([_number(c, f"{p}: line {line_no}, column {i}") for i, c in enumerate(cells)])
    if not rows:
        raise DatasetError(f"{p}: no data rows")
    a = np.array(rows)
    points = a[:, :9].reshape(-1, 3, 3)
    joints = np.deg2rad(a[:, 15:21])
    return RealDataset(
        name="boby_fanuc", joints=joints, points=points, targets=("N1", "N2", "N3"),
        joint_names=("J1", "J2", "J3", "J4", "J5", "J6"), stations=np.zeros(len(a), dtype=int),
        station_labels=["tracker"], per_pose={"row": np.arange(len(a))},
        metadata={"file": str(p), "instrument": "laser tracker", "frame": "tracker",
                  "file_units": "mm, deg (FANUC J2/J3 convention)", "robot": "fanuc_r2000ic_165f"})


# ---------------------------------------------------------------------------------------- dlr_justin
_NUM_RE = re.compile(r"[\[\]]")


def _numpy_printed(text, n, where) -> np.ndarray:
    body = _NUM_RE.sub(" ", text).split()
    if len(body) != n:
        raise DatasetError(f"{where}: expected {n} numbers in a numpy-printed array, got {len(body)}")
    return np.array([_number(b, where) for b in body])


def read_dlr_justin(root=None, path=None) -> RealDataset:
    """``dlr_justin/raw/measurements.csv``: columns ``index, joints, markers``.

    ``joints``: numpy-printed vector of the 19 commanded joints [rad] (controller order of
    ``dlr_justin19``); ``markers``: numpy-printed 2x3 array [right; left] in the Vicon frame [m],
    returned in mm as targets ``right`` and ``left``.
    """
    p = Path(path) if path is not None else _file(root, "dlr_justin", "raw", "measurements.csv")
    joints, markers, index = [], [], []
    with open(p, newline="", encoding="utf-8") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise DatasetError(f"{p}: empty file") from None
        if [h.strip() for h in header] != ["", "joints", "markers"]:
            raise DatasetError(f"{p}: line 1: expected header ',joints,markers', got {','.join(header)!r}")
        for rec in reader:
            line = reader.line_num
            if not rec:
                continue
            if len(rec) != 3:
                raise DatasetError(f"{p}: record ending on line {line}: expected 3 cells (index, joints, "
                                   f"markers), got {len(rec)}")
            index.append(int(_number(rec[0], f"{p}: line {line}, column 'index'")))
            joints.append(_numpy_printed(rec[1], 19, f"{p}: record ending on line {line}, column 'joints'"))
            mk = _numpy_printed(rec[2], 6, f"{p}: record ending on line {line}, column 'markers'")
            if np.max(np.abs(mk)) > 50.0:
                raise DatasetError(f"{p}: record ending on line {line}, column 'markers': {mk.tolist()} is not "
                                   f"plausible in metres")
            markers.append(mk)
    if not joints:
        raise DatasetError(f"{p}: no data rows")
    pts = np.array(markers).reshape(-1, 2, 3) * 1000.0
    from ..robots import load_robot  # noqa: PLC0415 (only for the joint names)

    names = load_robot("dlr_justin19").controller_joints
    return RealDataset(
        name="dlr_justin", joints=np.array(joints), points=pts, targets=("right", "left"), joint_names=names,
        stations=np.zeros(len(pts), dtype=int), station_labels=["vicon"], per_pose={"index": np.array(index)},
        metadata={"file": str(p), "instrument": "Vicon", "frame": "vicon", "file_units": "rad, m",
                  "robot": "dlr_justin19", "note": "joints are commanded values; head joints always 0"})


# ---------------------------------------------------------------------------------------- hilti
def _yaml_load(p: Path):
    try:
        import yaml
    except ImportError:
        raise DatasetError(f"{p}: reading the Hilti data needs PyYAML (pip install 'robocal[yaml]')") from None
    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    try:
        with open(p, encoding="utf-8") as fh:
            return yaml.load(fh, Loader=loader)
    except yaml.YAMLError as exc:
        raise DatasetError(f"{p}: not valid YAML: {exc}") from None


def _vector(d, key, n, where) -> np.ndarray:
    if not isinstance(d, dict) or key not in d:
        raise DatasetError(f"{where}: missing key {key!r}")
    v = d[key]
    if not isinstance(v, list) or len(v) != n:
        raise DatasetError(f"{where}/{key}: expected a list of {n} numbers, got {v!r}")
    out = np.empty(n)
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise DatasetError(f"{where}/{key}[{i}]: {x!r} is not a number")
        out[i] = _number(x, f"{where}/{key}[{i}]")
    return out


def read_hilti_trailblazer(name: str = "flat", root=None, path=None) -> RealDataset:
    """One Hilti Trailblazer set, ``hilti_trailblazer/raw/<name>.yaml`` (needs PyYAML).

    Every measurement of every column height and solution space becomes one pose: joints
    (column [mm], dsr_joint1..6 [rad]), the prism position [mm] in the total-station frame
    (target ``prism``). ``stations`` index the (height, solution space) groups in file order,
    ``station_labels[g] = (height_m, solution_space)``. ``per_pose`` holds ``height_index`` (one
    per column height, file order), ``height_m``, ``solution_space``, ``role`` ('stationing' |
    'evaluation'), ``cross`` (stationing point of the CROSS shape, first four per station as in
    the repository's reader), ``upside_down``, ``id``, ``time``, ``doosan_cmd`` (N, 3) [m],
    ``accel_base``, ``accel_column`` (N, 3) [m/s^2].
    """
    if path is None:
        if name not in HILTI_SETS:
            raise DatasetError(f"unknown Hilti set {name!r}; have {', '.join(HILTI_SETS)}")
        p = _file(root, "hilti_trailblazer", "raw", f"{name}.yaml")
    else:
        p = Path(path)
    data = _yaml_load(p)
    expected_joints = ["column_prismatic_joint"] + [f"dsr_joint{i}" for i in range(1, 7)]
    if not isinstance(data, dict) or data.get("joint_names") != expected_joints:
        got = data.get("joint_names") if isinstance(data, dict) else type(data).__name__
        raise DatasetError(f"{p}: joint_names: expected {expected_joints}, got {got!r}")
    heights = data.get("column_heights")
    if not isinstance(heights, dict) or not heights:
        raise DatasetError(f"{p}: column_heights: expected a non-empty mapping height -> solution_spaces")
    cross = [tuple(c) for c in HILTI_CROSS_CMDS]
    cols = {k: [] for k in ("joints", "points", "stations", "height_index", "height_m", "solution_space", "role",
                            "cross", "upside_down", "id", "time", "doosan_cmd", "accel_base", "accel_column")}
    labels = []
    for hi, (h, hd) in enumerate(heights.items()):
        hwhere = f"{p}: column_heights/{h}"
        height = _number(h, hwhere)
        sss = hd.get("solution_spaces") if isinstance(hd, dict) else None
        if not isinstance(sss, dict):
            raise DatasetError(f"{hwhere}: missing mapping 'solution_spaces'")
        for ss, sd in sss.items():
            swhere = f"{hwhere}/solution_spaces/{ss}"
            if not isinstance(sd, dict):
                raise DatasetError(f"{swhere}: expected a mapping with stationing/evaluation_measurements")
            if isinstance(ss, bool) or not isinstance(ss, int):
                raise DatasetError(f"{swhere}: solution space {ss!r} is not an integer")
            g = len(labels)
            labels.append((height, ss))
            n_cross = 0
            for role in ("stationing", "evaluation"):
                key = f"{role}_measurements"
                if key not in sd:
                    raise DatasetError(f"{swhere}: missing key {key!r}")
                meas = sd[key] or []
                if not isinstance(meas, list):
                    raise DatasetError(f"{swhere}/{key}: expected a list")
                for i, m in enumerate(meas):
                    where = f"{swhere}/{key}[{i}]"
                    js = _vector(m, "joint_states", 7, where)
                    if not 0.5 < js[0] < 10.0:
                        raise DatasetError(f"{where}/joint_states[0]: column position {float(js[0])!r} is not a "
                                           f"plausible height in metres")
                    pp = _vector(m, "prism_position", 3, where)
                    if np.max(np.abs(pp)) > 500.0:
                        raise DatasetError(f"{where}/prism_position: {pp.tolist()} is not plausible in metres")
                    cmd = _vector(m, "doosan_cmd", 3, where)
                    ud = m.get("upside_down")
                    if not isinstance(ud, bool):
                        raise DatasetError(f"{where}/upside_down: expected true/false, got {ud!r}")
                    is_cross = role == "stationing" and tuple(cmd.tolist()) in cross and n_cross < 4
                    n_cross += bool(is_cross)
                    cols["joints"].append(np.concatenate([[js[0] * 1000.0], js[1:]]))
                    cols["points"].append(pp * 1000.0)
                    cols["stations"].append(g)
                    cols["height_index"].append(hi)
                    cols["height_m"].append(height)
                    cols["solution_space"].append(ss)
                    cols["role"].append(role)
                    cols["cross"].append(is_cross)
                    cols["upside_down"].append(ud)
                    cols["id"].append(int(m.get("id", -1)))
                    cols["time"].append(float(m.get("time", float("nan"))))
                    cols["doosan_cmd"].append(cmd)
                    cols["accel_base"].append(_vector(m, "tilt_sensor_base_accel", 3, where))
                    cols["accel_column"].append(_vector(m, "tilt_sensor_column_accel", 3, where))
    if not cols["joints"]:
        raise DatasetError(f"{p}: no measurements")
    per = {k: np.array(v) for k, v in cols.items() if k not in ("joints", "points", "stations")}
    return RealDataset(
        name=f"hilti_trailblazer/{p.stem}", joints=np.array(cols["joints"]), points=np.array(cols["points"])[:, None, :],
        targets=("prism",), joint_names=tuple(expected_joints), stations=np.array(cols["stations"]),
        station_labels=labels, per_pose=per,
        metadata={"file": str(p), "instrument": "Hilti PLT 300 total station (0.75 mm per axis)",
                  "frame": "total station", "file_units": "column m, joints rad, prism m", "robot": "hilti_trailblazer",
                  "license": "CC BY-NC-SA 3.0"})


# ---------------------------------------------------------------------------------------- helpers
def _points_in_base(model, q, targets) -> np.ndarray:
    """Target positions (N, K, 3) in the robot base frame (the model's ``T_world_base`` ignored)."""
    m = model.replace(T_world_base=np.eye(4))
    T = m.fk_all(np.asarray(q, dtype=float))  # (N, E, 4, 4)
    out = np.empty((len(T), len(targets), 3))
    for k, t in enumerate(targets):
        e = model.end_effector_index(t.end_effector)
        out[:, k] = (T[:, e, :3, :3] @ np.asarray(t.point, dtype=float)) + T[:, e, :3, 3]
    return out


def error_stats(predicted, measured) -> dict:
    """Position errors |measured - predicted| over all measured points: rms, mean, max [mm], n;
    plus p95_xy and p95_z (95th percentiles of the xy norm and of |z|, the Hilti metric)."""
    d = (np.asarray(measured, dtype=float) - np.asarray(predicted, dtype=float)).reshape(-1, 3)
    d = d[np.all(np.isfinite(d), axis=1)]
    e = np.linalg.norm(d, axis=1)
    return {"rms": float(np.sqrt(np.mean(e**2))), "mean": float(e.mean()), "max": float(e.max()), "n": int(len(e)),
            "p95_xy": float(np.percentile(np.linalg.norm(d[:, :2], axis=1), 95)),
            "p95_z": float(np.percentile(np.abs(d[:, 2]), 95))}


def _param_names(model, link_names, kinds) -> list:
    """Model parameter names ``<kind><k+1>`` of the named links (those that exist)."""
    by_name = {L.name: k for k, L in enumerate(model.links)}
    out = []
    for ln in link_names:
        k = by_name[ln]
        for p in kinds:
            if p in model.links[k].params:
                out.append(f"{p}{k + 1}")
    return out


def _fit(model, q, targets, points, free, stations=None, base_initial=None, prior=0.0, **kw):
    from ..calib import CalibrationProblem, solve

    if base_initial is None:
        base_initial = "fit"  # rigid fit of the initial model's predictions, per station
    prob = CalibrationProblem(model, q, targets, points, free=free, stations=stations, base_initial=base_initial)
    return prob, solve(prob, prior_weight=prior, **kw)


def _with_state_targets(targets, state):
    from ..calib import Target

    return [Target(t.name, t.end_effector, tuple(state.targets[k]), t.free) for k, t in enumerate(targets)]


# ---------------------------------------------------------------------------------------- boby protocol
def boby_model():
    """``fanuc_r2000ic_165f`` with Hayati's beta on link 2 (the parallel J2/J3 pair), and the free
    set of the reference fit: every DH parameter except link 1's theta, d and all of link 6."""
    from ..kinematics.links import Link
    from ..robots import load_robot

    m = load_robot("fanuc_r2000ic_165f")
    links = list(m.links)
    L = links[1]
    links[1] = Link(L.name, L.joint_type, L.convention, {**L.params, "beta": 0.0}, L.parent, L.axis, L.fixed)
    m = m.replace(links=links, kind="dh_beta")
    free = [n for n in m.params.names if n not in ("theta1", "d1") and not n.endswith("6")]
    return m.with_free([n in free for n in m.params.names])


def calibrate_boby(seed: int = 0, n_train: int = 24, data=None, root=None, prior: float = 1e-3) -> dict:
    """The boby_fanuc protocol for one seed: random ``n_train`` training poses, the rest held out.

    ``nominal``: nominal DH, base + 3 tool points fitted on the training poses; ``calibrated``:
    plus the DH parameters of :func:`boby_model` (auto-identifiable set, Tikhonov ``prior``).
    Returns ``{"seed", "nominal": stats, "calibrated": stats, "train_rms", "result"}`` with
    holdout statistics over the 3 SMR points of every held-out pose (:func:`error_stats`)."""
    from ..calib import Target

    ds = read_boby_fanuc(root) if data is None else data
    rng = np.random.default_rng(seed)
    perm = rng.permutation(ds.n_poses)
    tr, te = np.sort(perm[:n_train]), np.sort(perm[n_train:])
    model = boby_model()
    # initial tool points: all three at the flange centre, 250 mm out (nothing dataset-specific)
    targets = [Target(n, None, (0.0, 0.0, 250.0)) for n in ds.targets]
    p0, r0 = _fit(model, ds.joints[tr], targets, ds.points[tr], free=[])
    targets = _with_state_targets(targets, r0.state)
    p1, r1 = _fit(model, ds.joints[tr], targets, ds.points[tr], free=None, base_initial=r0.state.bases, prior=prior)
    out = {"seed": seed, "train": tr, "test": te, "result": r1, "nominal_result": r0, "train_rms": r1.rms_after,
           "nominal_train_rms": r0.rms_after}
    for key, p, r in (("nominal", p0, r0), ("calibrated", p1, r1)):
        out[key] = error_stats(p.predict_points(r.state, q=ds.joints[te], stations=np.zeros(len(te), int)),
                               ds.points[te])
    return out


def calibrate_boby_seeds(seeds=range(5), root=None, **kw) -> dict:
    """:func:`calibrate_boby` for each seed; ``nominal`` / ``calibrated`` hold the means over seeds
    of rms, mean and max, ``runs`` the per-seed results."""
    ds = read_boby_fanuc(root)
    runs = [calibrate_boby(s, data=ds, **kw) for s in seeds]
    out = {"runs": runs}
    for key in ("nominal", "calibrated"):
        out[key] = {s: float(np.mean([r[key][s] for r in runs])) for s in ("rms", "mean", "max")}
    out["train_rms"] = [r["train_rms"] for r in runs]
    return out


# ---------------------------------------------------------------------------------------- justin protocol
JUSTIN_CHAIN_LINKS = ("torso_0", "torso_1", "torso_2", "torso_3") + tuple(f"right_j{i}" for i in range(1, 8)) + \
    tuple(f"left_j{i}" for i in range(1, 8))


def calibrate_justin(seed: int = 0, n_train: int = 400, data=None, root=None, prior: float = 1e-3,
                     levels=("nominal", "offsets", "all")) -> dict:
    """The dlr_justin protocol: random ``n_train`` / rest split (``seed``), both hand markers.

    Levels (each starting from the previous one's solution): ``nominal`` = base + 2 marker
    offsets; ``offsets`` = + the 18 joint offsets (torso incl. the passive joint, both arms);
    ``all`` = + every modified-DH parameter (alpha, a, theta, d; beta where consecutive axes are
    parallel) of the torso and both arms, weak prior. Returns ``{level: holdout stats}`` plus
    ``results`` (per level) and the split."""
    from ..calib import Target
    from ..robots import load_robot

    ds = read_dlr_justin(root) if data is None else data
    rng = np.random.default_rng(seed)
    perm = rng.permutation(ds.n_poses)
    tr, te = np.sort(perm[:n_train]), np.sort(perm[n_train:])
    model = load_robot("dlr_justin19")
    # initial marker offsets in the hand (TCP) frames, from the dataset site [mm]
    targets = [Target("right", "right", (-100.0, -30.0, 100.0)), Target("left", "left", (-100.0, 30.0, 50.0))]
    offsets = _param_names(model, JUSTIN_CHAIN_LINKS, ("theta",))
    full = []
    by_name = {L.name: k for k, L in enumerate(model.links)}
    for ln in JUSTIN_CHAIN_LINKS:
        L = model.links[by_name[ln]]
        kinds = ("alpha", "a", "theta", "d") + (("beta",) if abs(L.params["alpha"]) < 1e-9 else ())
        full += _param_names(model, [ln], kinds)
    free_sets = {"nominal": [], "offsets": offsets, "all": full}
    out = {"train": tr, "test": te, "results": {}}
    base, state_targets = None, targets
    for lev in levels:
        p, r = _fit(model, ds.joints[tr], state_targets, ds.points[tr], free=free_sets[lev], base_initial=base,
                    prior=prior if lev == "all" else 0.0)
        if lev != levels[-1]:
            # next level starts from this solution
            model = r.model.replace(T_world_base=model.T_world_base)
            base, state_targets = r.state.bases, _with_state_targets(state_targets, r.state)
        out["results"][lev] = r
        out[lev] = error_stats(p.predict_points(r.state, q=ds.joints[te], stations=np.zeros(len(te), int)),
                               ds.points[te])
        out[lev]["train_rms"] = r.rms_after
    return out


# ---------------------------------------------------------------------------------------- hilti protocol
HILTI_ARM_JOINTS = tuple(f"dsr_joint{i}" for i in range(1, 7))


def hilti_station_protocol(model, point, ds: RealDataset, solution_spaces=(0, 7), min_cross: int = 4) -> dict:
    """The repository's per-station test (example_kabsch.py) with ``model`` (base frame ignored)
    carrying the prism at ``point`` (3,) [mm] in its first end effector's frame.

    Per station (column height x solution space in ``solution_spaces``): rigid fit (Kabsch) of the
    predicted CROSS stationing points onto the measured ones, then errors of the station's
    evaluation points. Stations with fewer than ``min_cross`` CROSS points are skipped (listed).
    Returns ``{"all": stats over every evaluation point, "stations": [...], "skipped": [...]}``.
    """
    from ..calib import Target, rigid_fit

    tg = [Target("prism", None, tuple(point))]
    pred_base = _points_in_base(model, ds.joints, tg)[:, 0]
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


def calibrate_hilti(root=None, sets=HILTI_SETS, prior: float = 1e-2, data=None, max_iterations: int = 100) -> dict:
    """Fit the Trailblazer on ``flat`` (every point: stationing and evaluation, all solution spaces),
    one base frame per column height (5), 6-dof perturbations of the URDF origins of dsr_joint2..6,
    joint offsets of dsr_joint1..5 and the prism offset, weak prior (``prior`` 1e-2 per scaled unit:
    the figures equal those of 1e-3 to 0.01 mm, but LM converges in ~10 instead of ~110 iterations
    along the nearly redundant origin directions); then run
    :func:`hilti_station_protocol` on every set with the nominal URDF and with the calibrated model.

    Returns ``{"result", "model", "prism", "nominal": {set: protocol}, "calibrated": {set: protocol}}``.
    ``data`` may map set names to already read :class:`RealDataset`."""
    from ..calib import Target
    from ..robots import load_robot

    data = dict(data or {})
    for s in set(sets) | {"flat"}:
        if s not in data:
            data[s] = read_hilti_trailblazer(s, root)
    flat = data["flat"]
    model = load_robot("hilti_trailblazer")
    free = _param_names(model, HILTI_ARM_JOINTS[1:], ("x", "y", "z", "roll", "pitch", "yaw")) + \
        _param_names(model, HILTI_ARM_JOINTS[:5], ("theta",))
    targets = [Target("prism", None, (0.0, 0.0, 0.0))]  # offset from the nominal prism (the [tool] frame)
    stations = flat.per_pose["height_index"]
    prob, res = _fit(model, flat.joints, targets, flat.points, free=free, stations=stations, prior=prior,
                     max_iterations=max_iterations)
    cal = res.model
    out = {"result": res, "model": cal, "prism": res.state.targets[0], "nominal": {}, "calibrated": {}}
    for s in sets:
        out["nominal"][s] = hilti_station_protocol(model, (0.0, 0.0, 0.0), data[s])
        out["calibrated"][s] = hilti_station_protocol(cal, res.state.targets[0], data[s])
    return out


# ---------------------------------------------------------------------------------------- report
def report(root=None) -> str:
    """All three protocols as a plain-text table (``python -m robocal.io.datasets``)."""
    f = "{rms:6.3f} {mean:6.3f} {max:6.2f}"
    lines = ["dataset / model                           holdout RMS   mean    max  [mm]"]
    r = calibrate_boby_seeds(range(5), root=root)
    lines.append("boby_fanuc (24/12, mean over seeds 0-4)")
    for k in ("nominal", "calibrated"):
        lines.append(f"  {k:38s} " + f.format(**r[k]))
    for run in r["runs"]:
        lines.append(f"    seed {run['seed']}: nominal {run['nominal']['rms']:.3f}, calibrated "
                     f"{run['calibrated']['rms']:.3f} (train {run['train_rms']:.3f})")
    r = calibrate_justin(0, root=root)
    lines.append("dlr_justin (400/100, seed 0, both markers)")
    for k, label in (("nominal", "base + 2 markers"), ("offsets", "+ 18 joint offsets"), ("all", "+ all DH (prior)")):
        lines.append(f"  {label:38s} " + f.format(**r[k]) + f"   (train {r[k]['train_rms']:.2f})")
    r = calibrate_hilti(root=root)
    lines.append(f"hilti_trailblazer (fit on flat: train RMS {r['result'].rms_after:.2f} mm; per-station CROSS Kabsch, "
                 f"ss 0/7)")
    lines.append("  set               n   nominal RMS/p95xy/p95z   calibrated RMS/p95xy/p95z  mean   max")
    for s in HILTI_SETS:
        n, c = r["nominal"][s]["all"], r["calibrated"][s]["all"]
        lines.append(f"  {s:16s} {c['n']:4d}   {n['rms']:5.2f} {n['p95_xy']:5.1f} {n['p95_z']:5.1f}        "
                     f"{c['rms']:5.2f} {c['p95_xy']:5.1f} {c['p95_z']:5.1f}   {c['mean']:5.2f} {c['max']:5.1f}")
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover
    print(report())
