"""Reader of ``hilti_trailblazer``: the Hilti Trailblazer (lifting column + Doosan 6R) measured by a
total station, seven sets of YAML files (needs PyYAML)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import DatasetError, RealDataset, dataset_file, number

__all__ = ["HILTI_SETS", "HILTI_CROSS_CMDS", "read_hilti_trailblazer"]

#: The seven Hilti sets, in the order of the dataset README.
HILTI_SETS = ("flat", "pallet", "orthogonal_wood", "wood_left_track", "seesaw", "diagonal_wood", "outdoor")
#: ``doosan_cmd`` of the four 'CROSS' stationing points (the repository's StationingShape.CROSS) [m].
HILTI_CROSS_CMDS = ((0.25, 0.15, 0.48), (0.25, -0.15, 0.48), (0.4, 0.0, 0.48), (0.1, 0.0, 0.48))

_JOINTS = ("column_prismatic_joint",) + tuple(f"dsr_joint{i}" for i in range(1, 7))
_PER_POSE = ("height_index", "height_m", "solution_space", "role", "cross", "upside_down", "id", "time",
             "doosan_cmd", "accel_base", "accel_column")
_COLUMN_M = (0.5, 10.0)   # plausible column heights [m]
_PRISM_MAX_M = 500.0      # a prism farther from the station is not in metres


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


def _vector(d, key: str, n: int, where: str) -> np.ndarray:
    """``d[key]``: a list of ``n`` numbers; ``where`` is the YAML key path of ``d``."""
    if not isinstance(d, dict) or key not in d:
        raise DatasetError(f"{where}: missing key {key!r}")
    v = d[key]
    if not isinstance(v, list) or len(v) != n:
        raise DatasetError(f"{where}/{key}: expected a list of {n} numbers, got {v!r}")
    out = np.empty(n)
    for i, x in enumerate(v):
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise DatasetError(f"{where}/{key}[{i}]: {x!r} is not a number")
        out[i] = number(x, f"{where}/{key}[{i}]")
    return out


def _measurement(m, where: str) -> dict:
    """One measurement of the YAML file, checked: joints [column mm, rad], prism [mm], the rest
    as in the file (``doosan_cmd`` [m], accelerations [m/s^2])."""
    js = _vector(m, "joint_states", 7, where)
    if not _COLUMN_M[0] < js[0] < _COLUMN_M[1]:
        raise DatasetError(f"{where}/joint_states[0]: column position {float(js[0])!r} is not a "
                           f"plausible height in metres")
    pp = _vector(m, "prism_position", 3, where)
    if np.max(np.abs(pp)) > _PRISM_MAX_M:
        raise DatasetError(f"{where}/prism_position: {pp.tolist()} is not plausible in metres")
    cmd = _vector(m, "doosan_cmd", 3, where)
    ud = m.get("upside_down")
    if not isinstance(ud, bool):
        raise DatasetError(f"{where}/upside_down: expected true/false, got {ud!r}")
    return {"joints": np.concatenate([[js[0] * 1000.0], js[1:]]), "points": pp * 1000.0, "doosan_cmd": cmd,
            "upside_down": ud, "id": int(m.get("id", -1)), "time": float(m.get("time", float("nan"))),
            "accel_base": _vector(m, "tilt_sensor_base_accel", 3, where),
            "accel_column": _vector(m, "tilt_sensor_column_accel", 3, where)}


def _read_station(sd, where: str, station: dict, cols: dict) -> None:
    """Append the measurements of one (height, solution space) group to ``cols``; ``station``
    holds the values shared by its poses. The first four stationing points at a CROSS command
    are marked ``cross`` (as the repository's reader does)."""
    cross = [tuple(c) for c in HILTI_CROSS_CMDS]
    n_cross = 0
    for role in ("stationing", "evaluation"):
        key = f"{role}_measurements"
        if key not in sd:
            raise DatasetError(f"{where}: missing key {key!r}")
        meas = sd[key] or []
        if not isinstance(meas, list):
            raise DatasetError(f"{where}/{key}: expected a list")
        for i, m in enumerate(meas):
            row = {**station, **_measurement(m, f"{where}/{key}[{i}]"), "role": role}
            row["cross"] = role == "stationing" and tuple(row["doosan_cmd"].tolist()) in cross and n_cross < 4
            n_cross += bool(row["cross"])
            for k, v in row.items():
                cols[k].append(v)


def _read_heights(heights: dict, p: Path) -> tuple:
    """``(cols, station_labels)``: every measurement of every column height and solution space."""
    cols = {k: [] for k in ("joints", "points", "stations") + _PER_POSE}
    labels = []
    for hi, (h, hd) in enumerate(heights.items()):
        hwhere = f"{p}: column_heights/{h}"
        height = number(h, hwhere)
        sss = hd.get("solution_spaces") if isinstance(hd, dict) else None
        if not isinstance(sss, dict):
            raise DatasetError(f"{hwhere}: missing mapping 'solution_spaces'")
        for ss, sd in sss.items():
            swhere = f"{hwhere}/solution_spaces/{ss}"
            if not isinstance(sd, dict):
                raise DatasetError(f"{swhere}: expected a mapping with stationing/evaluation_measurements")
            if isinstance(ss, bool) or not isinstance(ss, int):
                raise DatasetError(f"{swhere}: solution space {ss!r} is not an integer")
            station = {"stations": len(labels), "height_index": hi, "height_m": height, "solution_space": ss}
            labels.append((height, ss))
            _read_station(sd, swhere, station, cols)
    return cols, labels


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
        p = dataset_file(root, "hilti_trailblazer", "raw", f"{name}.yaml")
    else:
        p = Path(path)
    data = _yaml_load(p)
    if not isinstance(data, dict) or data.get("joint_names") != list(_JOINTS):
        got = data.get("joint_names") if isinstance(data, dict) else type(data).__name__
        raise DatasetError(f"{p}: joint_names: expected {list(_JOINTS)}, got {got!r}")
    heights = data.get("column_heights")
    if not isinstance(heights, dict) or not heights:
        raise DatasetError(f"{p}: column_heights: expected a non-empty mapping height -> solution_spaces")
    cols, labels = _read_heights(heights, p)
    if not cols["joints"]:
        raise DatasetError(f"{p}: no measurements")
    per = {k: np.array(cols[k]) for k in _PER_POSE}
    return RealDataset(
        name=f"hilti_trailblazer/{p.stem}", joints=np.array(cols["joints"]), points=np.array(cols["points"])[:, None, :],
        targets=("prism",), joint_names=_JOINTS, stations=np.array(cols["stations"]),
        station_labels=labels, per_pose=per,
        metadata={"file": str(p), "instrument": "Hilti PLT 300 total station (0.75 mm per axis)",
                  "frame": "total station", "file_units": "column m, joints rad, prism m", "robot": "hilti_trailblazer",
                  "license": "CC BY-NC-SA 3.0"})
