"""Read and write robot files (format ``robocal-robot/1``, see docs/robot-files.md)."""

from __future__ import annotations
from ..errors import InputFileError

import difflib
import math
import tomllib
from importlib import resources
from pathlib import Path

import numpy as np

from ..io.plausibility import REACH_LARGEST_MM, REACH_SMALLEST_MM, angle_unit_problem, length_unit_problem
from ..kinematics.links import ANGLE_PARAMS, MODEL_KINDS, Link, frame_from_xyz_rpy, link_param_names
from ..kinematics.model import EndEffector, RobotModel
from ..kinematics.parallel_axes import parallel_axis_pairs

__all__ = ["RobotFileError", "load_robot", "list_robots", "robot_path", "parse_robot", "frame_from_xyz_rpy"]

FORMAT = "robocal-robot/1"
_LENGTH = {"mm": 1.0, "m": 1000.0}
_ANGLE = {"deg": math.pi / 180.0, "rad": 1.0}


class RobotFileError(InputFileError):
    """A robot file is malformed; the message names the file and the offending entry."""


def _data_dir():
    return resources.files("robocal.robots") / "data"


def list_robots() -> list[str]:
    """Names of the robots shipped with robocal."""
    return sorted(p.name[:-5] for p in _data_dir().iterdir() if p.name.endswith(".toml"))


def robot_path(name_or_path) -> Path:
    """Path of a shipped robot by name, or the given file path; raises with close-name hints."""
    p = Path(str(name_or_path))
    if p.suffix.lower() in (".toml", ".urdf") or p.exists():
        if not p.is_file():
            raise RobotFileError(f"{p}: no such robot file")
        return p
    cand = _data_dir() / f"{name_or_path}.toml"
    if not cand.is_file():
        names = list_robots()
        close = difflib.get_close_matches(str(name_or_path), names, n=3, cutoff=0.4)
        hint = f" Did you mean: {', '.join(close)}?" if close else f" Known robots: {', '.join(names)}."
        raise RobotFileError(f"unknown robot {name_or_path!r}.{hint}")
    return Path(str(cand))


#: Parsed robot files by (path, modification time, size): a model never changes (its arrays are
#: read-only, ``replace``/``with_params`` return new models), so loading the same unchanged file
#: again returns the same object (~1.4 ms of TOML parsing and model building saved per load; a
#: fleet task loads its robot twice).
_LOADED: dict = {}
_LOADED_MAX = 64


def load_robot(name_or_path) -> RobotModel:
    """Load a shipped robot by name (see :func:`list_robots`) or a robot file by path: a robocal
    robot file (``.toml``, UTF-8 with or without a BOM) or a URDF (``.urdf``, every joint on the
    paths to its tip links; :func:`robocal.io.urdf.read_urdf`)."""
    path = robot_path(name_or_path)
    try:
        st = Path(path).stat()
        key = (str(path), st.st_mtime_ns, st.st_size)
    except OSError:
        key = None
    if key is not None and key in _LOADED:
        return _LOADED[key]
    model = _load_robot_file(path)
    if key is not None:
        if len(_LOADED) >= _LOADED_MAX:
            _LOADED.clear()
        _LOADED[key] = model
    return model


def _load_robot_file(path) -> RobotModel:
    if Path(path).suffix.lower() == ".urdf":  # wherever a robot file is accepted (docs/robot-files.md)
        from ..io.urdf import UrdfError, read_urdf

        try:
            return read_urdf(path)
        except UrdfError as exc:
            raise RobotFileError(str(exc)) from None
        except UnicodeDecodeError as exc:
            raise RobotFileError(f"{path}: not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None
        except OSError as exc:
            raise RobotFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8-sig"))  # a UTF-8 BOM is accepted
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise RobotFileError(f"{path}: not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise RobotFileError(f"{path}: cannot read: {exc.strerror or exc}") from None
    return parse_robot(data, origin=str(path))


def _vec(where, d, key, n, default=None):
    if key not in d:
        if default is None:
            raise RobotFileError(f"{where}: missing key {key!r}")
        return list(default)
    v = d[key]
    if not isinstance(v, list) or len(v) != n or not all(isinstance(x, (int, float)) for x in v):
        raise RobotFileError(f"{where}: {key!r} must be a list of {n} numbers, got {v!r}")
    return [float(x) for x in v]


def _frame(where, d, lscale, ascale):
    if d is None:
        return np.eye(4)
    xyz = np.array(_vec(where, d, "xyz", 3, (0, 0, 0))) * lscale
    rpy = np.array(_vec(where, d, "rpy", 3, (0, 0, 0))) * ascale
    return frame_from_xyz_rpy(xyz, rpy)


def _check_units(origin, links, limits, lu: str, au: str) -> None:
    """The link lengths (their sum: the robot's reach) and the angles (parameters, revolute joint
    ``limits`` (n, 2) [rad]) fit the declared ``length_unit`` / ``angle_unit``
    (:mod:`robocal.io.plausibility`)."""
    lengths = [abs(v) for L in links for k, v in L.params.items() if k not in ANGLE_PARAMS]
    angles = [v for L in links for k, v in L.params.items() if k in ANGLE_PARAMS]
    limits = np.reshape(np.asarray(limits, dtype=float), (-1, 2))
    finite = limits[np.isfinite(limits).all(axis=1)]
    problem = (length_unit_problem([sum(lengths)], lu, what="the sum of the link lengths (the reach)",
                                   smallest_mm=REACH_SMALLEST_MM, largest_mm=REACH_LARGEST_MM, style="toml")
               or angle_unit_problem(np.concatenate([angles, finite.ravel()]), "rad" if au == "rad" else "none",
                                     what="the angle parameters and joint limits", style="toml")
               or (angle_unit_problem(finite, au, what="the joint limits", min_rows=3, style="toml")
                   if au == "deg" else None))
    if problem:
        raise RobotFileError(f"{origin}: {problem}")


def parse_robot(data: dict, origin: str = "<robot>") -> RobotModel:
    """Build a :class:`RobotModel` from the parsed TOML of a robot file."""
    kind, lu, au = _header(data, origin)
    ls, as_ = _LENGTH[lu], _ANGLE[au]
    entries = data.get("joints")
    if not isinstance(entries, list) or not entries:
        raise RobotFileError(f"{origin}: needs a non-empty [[joints]] list")
    links, names, limits_by_name, couplings = [], [], {}, []
    for i, j in enumerate(entries):
        link, where = _parse_joint(i, j, names, kind, ls, as_, origin)
        links.append(link)
        names.append(link.name)
        if link.joint_type != "fixed":
            couplings.append((where, _joint_coupling(where, j, link.name)))
            if "limits" in j:
                limits_by_name[link.name] = _joint_limits(where, j, link.joint_type, ls, as_)
    links = _with_parallel_betas(links)
    ctrl, coupling = _controller_coupling(data, origin, links, couplings)
    limits = _controller_limits(data, origin, links, ctrl, coupling, limits_by_name, ls, as_)
    _check_units(origin, links, [limits_by_name[L.name] for L in links
                                 if L.joint_type == "revolute" and L.name in limits_by_name], lu, au)
    T_world_base = _frame(f"{origin}: [base]", data.get("base"), ls, as_)
    ees = _end_effectors(data, origin, names, len(links), ls, as_)
    extra = {"length_unit": lu, "angle_unit": au, "origin": origin}
    radii = _link_radii(origin, entries, links, ls)
    if radii is not None:
        extra["link_radii_mm"] = radii
    if "elastic" in data:
        from .elastic_section import parse_elastic

        try:
            extra["elastic"] = parse_elastic(data["elastic"], origin, names,
                                             [L.name for L in links if L.moves], ls)
        except ValueError as exc:
            raise RobotFileError(str(exc)) from None
    try:
        return RobotModel(
            name=str(data.get("name", Path(origin).stem)), kind=kind, links=links, controller_joints=ctrl,
            coupling=coupling, limits=limits, T_world_base=T_world_base, end_effectors=ees,
            title=str(data.get("title", "")), source=str(data.get("source", "")),
            extra=extra,
        )
    except ValueError as exc:
        raise RobotFileError(f"{origin}: {exc}") from None


def _link_radii(origin, entries, links, ls):
    """(n_moving + 1,) capsule radius [mm] of the base and every moving link from the joints'
    optional ``link_radius`` (the base takes the first joint's; a joint without one its parent's),
    or None when no joint gives one (then the cell model's defaults apply, docs/cells.md)."""
    if not any("link_radius" in j for j in entries):
        return None
    out, last = [], None
    for j, link in zip(entries, links):
        if "link_radius" in j:
            v = j["link_radius"]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
                raise RobotFileError(f"{origin}: joint {link.name!r}: link_radius must be a positive number, got {v!r}")
            last = float(v) * ls
        if link.moves:
            out.append(last)
    first = next(v for v in out if v is not None)
    out = [first] + [first if v is None else v for v in out]
    return out


def _header(data: dict, origin: str):
    """(model kind, length unit, angle unit) of a robot file, checked."""
    fmt = data.get("format")
    if fmt != FORMAT:
        raise RobotFileError(f"{origin}: 'format' is {fmt!r}, expected {FORMAT!r}")
    kind = data.get("model")
    if kind not in MODEL_KINDS:
        raise RobotFileError(f"{origin}: 'model' is {kind!r}, expected one of {', '.join(MODEL_KINDS)}")
    lu, au = data.get("length_unit", "mm"), data.get("angle_unit", "deg")
    if lu not in _LENGTH:
        raise RobotFileError(f"{origin}: 'length_unit' is {lu!r}, expected 'mm' or 'm'")
    if au not in _ANGLE:
        raise RobotFileError(f"{origin}: 'angle_unit' is {au!r}, expected 'deg' or 'rad'")
    return kind, lu, au


def _parse_joint(i: int, j: dict, names: list, kind: str, ls: float, as_: float, origin: str):
    """The :class:`Link` of joint entry ``i`` (parameters in mm / rad) and its error prefix."""
    where = f"{origin}: joints[{i}]"
    name = j.get("name")
    if not isinstance(name, str) or not name:
        raise RobotFileError(f"{where}: missing 'name'")
    if name in names:
        raise RobotFileError(f"{where}: duplicate joint name {name!r}")
    where = f"{origin}: joint {name!r}"
    jtype = j.get("type", "revolute")
    if jtype not in ("revolute", "prismatic", "fixed"):
        raise RobotFileError(f"{where}: type {jtype!r}, expected revolute, prismatic or fixed")
    parent_name = j.get("parent")
    if parent_name is None:
        parent = i - 1
    elif parent_name in ("base", ""):
        parent = -1
    elif parent_name in names:
        parent = names.index(parent_name)
    else:
        raise RobotFileError(f"{where}: parent {parent_name!r} is not an earlier joint")
    if kind == "urdf" or (jtype == "fixed" and "xyz" in j):
        conv = "urdf" if kind == "urdf" else "frame"
        params, axis = _frame_joint_params(where, j, conv, jtype, ls, as_)
    else:
        conv = kind
        params, axis = _dh_joint_params(where, j, kind, jtype, ls, as_), (0.0, 0.0, 1.0)
    fixed = j.get("fixed", [])
    if not isinstance(fixed, list) or not all(isinstance(f, str) for f in fixed):
        raise RobotFileError(f"{where}: 'fixed' must be a list of parameter names")
    if conv in ("dh", "mdh") and "beta" in fixed and "beta" not in params:  # named, so it exists (value 0)
        params = _with_beta(conv, jtype, params)
    unknown = [f for f in fixed if f not in params]
    if unknown:
        raise RobotFileError(f"{where}: 'fixed' names unknown parameters {unknown}; this joint has {list(params)}")
    try:
        return Link(name, jtype, conv, params, parent, axis, frozenset(fixed)), where
    except ValueError as exc:
        raise RobotFileError(f"{origin}: {exc}") from None


def _with_beta(conv: str, jtype: str, params: dict) -> dict:
    """``params`` with ``beta = 0`` added in the convention's parameter order."""
    return {p: params.get(p, 0.0) for p in link_param_names(conv, jtype, has_beta=True)}


def _with_parallel_betas(links: list) -> list:
    """The links with Hayati's ``beta = 0`` added wherever two consecutive joint axes are (nearly)
    parallel and the file did not declare it (:mod:`robocal.kinematics.parallel_axes`): the
    parameter the geometry needs exists, and calibration can free it, whether or not it was
    written."""
    out = list(links)
    for pair in parallel_axis_pairs(out):
        L = out[pair.beta_link]
        if "beta" not in L.params:
            out[pair.beta_link] = Link(L.name, L.joint_type, L.convention,
                                       _with_beta(L.convention, L.joint_type, L.params), L.parent, L.axis, L.fixed)
    return out


def _frame_joint_params(where, j, conv, jtype, ls, as_):
    """xyz/rpy (+ joint offset) parameters and the unit axis of a URDF joint or a fixed frame."""
    xyz = _vec(where, j, "xyz", 3, (0, 0, 0))
    rpy = _vec(where, j, "rpy", 3, (0, 0, 0))
    params = dict(zip(("x", "y", "z"), (v * ls for v in xyz)))
    params.update(zip(("roll", "pitch", "yaw"), (v * as_ for v in rpy)))
    if conv == "urdf" and jtype != "fixed":
        off = "theta" if jtype == "revolute" else "d"
        params[off] = float(j.get(off, 0.0)) * (as_ if off == "theta" else ls)
    axis = _vec(where, j, "axis", 3, (0, 0, 1))
    n = math.sqrt(sum(a * a for a in axis))
    if n == 0:
        raise RobotFileError(f"{where}: 'axis' has zero length")
    return params, tuple(a / n for a in axis)


def _dh_joint_params(where, j, kind, jtype, ls, as_) -> dict:
    """The DH-family parameters of a joint entry [mm | rad] (``beta`` defaults to 0)."""
    expected = link_param_names(kind, jtype, has_beta="beta" in j or kind == "dh_beta")
    params = {}
    for p in expected:
        if p not in j:
            if p == "beta":
                params[p] = 0.0
                continue
            raise RobotFileError(f"{where}: missing parameter {p!r} (model {kind} needs {', '.join(expected)})")
        v = j[p]
        if not isinstance(v, (int, float)) or not math.isfinite(v):
            raise RobotFileError(f"{where}: parameter {p!r} must be a finite number, got {v!r}")
        params[p] = float(v) * (as_ if p in ANGLE_PARAMS else ls)
    return params


def _joint_coupling(where, j, name) -> dict:
    """Controller joint name -> coefficient of a moving joint (default: its own name, ``sign``)."""
    cpl = j.get("coupling")
    if cpl is None:
        sign = j.get("sign", 1)
        if sign not in (1, -1):
            raise RobotFileError(f"{where}: 'sign' must be 1 or -1, got {sign!r}")
        return {name: float(sign)}
    if not isinstance(cpl, dict) or not all(isinstance(v, (int, float)) for v in cpl.values()):
        raise RobotFileError(f"{where}: 'coupling' must map controller joint names to numbers")
    return cpl


def _joint_limits(where, j, jtype, ls, as_) -> list:
    lim = _vec(where, j, "limits", 2)
    scale = as_ if jtype == "revolute" else ls
    if lim[0] >= lim[1]:
        raise RobotFileError(f"{where}: limits {lim} must be [lower, upper] with lower < upper")
    return [lim[0] * scale, lim[1] * scale]


def _controller_coupling(data, origin, links, couplings):
    """Controller joint names and the coupling matrix (moving model joints x controller joints)."""
    moving_names = [L.name for L in links if L.moves]
    ctrl = data.get("controller_joints", moving_names)
    if not isinstance(ctrl, list) or not all(isinstance(c, str) for c in ctrl) or len(set(ctrl)) != len(ctrl):
        raise RobotFileError(f"{origin}: 'controller_joints' must be a list of distinct names")
    coupling = np.zeros((len(moving_names), len(ctrl)))
    for m, (where, cpl) in enumerate(couplings):
        for cname, coef in cpl.items():
            if cname not in ctrl:
                raise RobotFileError(f"{where}: coupling names controller joint {cname!r}, not in {ctrl}")
            coupling[m, ctrl.index(cname)] = float(coef)
    idle = [c for k, c in enumerate(ctrl) if not np.any(coupling[:, k])]
    if idle:
        raise RobotFileError(
            f"{origin}: 'controller_joints' lists {len(ctrl)} joints but {', '.join(map(repr, idle))} "
            f"drive{'s' if len(idle) == 1 else ''} no joint of the file ({len(moving_names)} moving joint(s): "
            f"{', '.join(moving_names) or 'none'}): a truncated robot file, or a joint without its [[joints]] entry")
    return ctrl, coupling


def _controller_limits(data, origin, links, ctrl, coupling, limits_by_name, ls, as_) -> np.ndarray:
    """(n_ctrl, 2) joint limits [rad | mm]: ``[controller_limits]`` first, else the joint entries'."""
    ctrl_limits = data.get("controller_limits", {})
    limits = np.tile([-np.inf, np.inf], (len(ctrl), 1))
    moving = [k for k, L in enumerate(links) if L.moves]
    for c, cname in enumerate(ctrl):
        if cname in ctrl_limits:
            lim = _vec(f"{origin}: controller_limits", ctrl_limits, cname, 2)
            # a controller joint's unit follows the first model joint it drives
            m = int(np.flatnonzero(coupling[:, c])[0]) if np.any(coupling[:, c]) else None
            pris = m is not None and links[moving[m]].joint_type == "prismatic"
            limits[c] = np.array(lim) * (ls if pris else as_)
        elif cname in limits_by_name:
            limits[c] = limits_by_name[cname]
    return limits


def _end_effectors(data, origin, names, n_links, ls, as_) -> list:
    """The ``[[end_effectors]]`` of a tree, or one flange / ``[tool]`` on the last joint."""
    if "end_effectors" not in data:
        tool = data.get("tool")
        return [EndEffector("flange" if tool is None else "tool", n_links - 1,
                            _frame(f"{origin}: [tool]", tool, ls, as_))]
    ees = []
    for i, e in enumerate(data["end_effectors"]):
        where = f"{origin}: end_effectors[{i}]"
        if e.get("link") not in names:
            raise RobotFileError(f"{where}: 'link' must name a joint entry, got {e.get('link')!r}")
        ees.append(EndEffector(str(e.get("name", f"ee{i}")), names.index(e["link"]), _frame(where, e, ls, as_)))
    return ees
