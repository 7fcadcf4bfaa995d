"""URDF import and export for serial and tree-shaped robots (URDF lengths are metres).

Import keeps every joint on the paths from the root link to the chosen tip links as a ``urdf``
link (origin xyz/rpy + axis), fixed joints as fixed frames, ``continuous`` joints as revolute
joints without limits, and ``<mimic>`` joints as model joints coupled to their leader
(``q = multiplier * q_leader``; a mimic offset becomes the joint offset).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..kinematics.convert import to_urdf_kind
from ..kinematics.links import OP_RU, OP_TU, Link, elementary_transforms, frame_from_xyz_rpy
from ..kinematics.model import EndEffector, RobotModel
from ..transforms import euler_from_matrix
from .atomic import atomic_write_text
from .header import FileFormatError

__all__ = ["read_urdf", "write_urdf", "UrdfError"]

_M_TO_MM = 1000.0


class UrdfError(FileFormatError):
    """A URDF file cannot be read or a model cannot be written as URDF; the message names the file
    (or the model) and the element, so ``path``, ``line`` and ``column`` are ``None``."""

    def __init__(self, message: str):
        super().__init__(None, message)


def _floats(where, text, n, default):
    if text is None:
        return list(default)
    try:
        vals = [float(v) for v in text.split()]
    except ValueError:
        raise UrdfError(f"{where}: expected {n} numbers, got {text!r}") from None
    if len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise UrdfError(f"{where}: expected {n} finite numbers, got {text!r}")
    return vals


def read_urdf(source, tips=None, name=None) -> RobotModel:
    """Read a URDF file (path or XML text) into a ``urdf``-kind :class:`RobotModel` [mm, rad].

    tips: names of the links that carry end effectors (default: every leaf link reached through
    at least one moving joint). Controller joints are the moving joints that are not mimics,
    in file order.
    """
    text = Path(source).read_text(encoding="utf-8") if not str(source).lstrip().startswith("<") else str(source)
    origin = str(source) if not str(source).lstrip().startswith("<") else "<urdf>"
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise UrdfError(f"{origin}: not valid XML: {exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"{origin}: root element is <{root.tag}>, expected <robot>")
    joints, child_of = _parse_joints(root, origin)
    tips, order = _kept_joints(root, joints, child_of, tips, origin)
    index = {jn: k for k, jn in enumerate(order)}
    ctrl, limits = _controller_joints(joints, order, origin)
    links = [_link(jn, joints[jn], index.get(child_of.get(joints[jn]["parent"]), -1), origin) for jn in order]
    ees = [EndEffector(t, index[child_of[t]], np.eye(4)) for t in tips]
    return RobotModel(name=name or root.get("name", "urdf_robot"), kind="urdf", links=links,
                      controller_joints=ctrl, coupling=_coupling(joints, order, ctrl, links), limits=limits,
                      T_world_base=np.eye(4), end_effectors=ees, title=root.get("name", ""),
                      source=f"imported from {origin}", extra={"length_unit": "m", "angle_unit": "rad"})


def _parse_joints(root, origin: str) -> tuple:
    """``(joints, child_of)``: joint name -> its fields (file units: m, rad), child link -> joint."""
    joints, child_of = {}, {}
    for j in root.findall("joint"):
        jname = j.get("name")
        where = f"{origin}: joint {jname!r}"
        jtype = j.get("type")
        if jtype not in ("revolute", "continuous", "prismatic", "fixed"):
            raise UrdfError(f"{where}: type {jtype!r} is not supported (revolute, continuous, prismatic, fixed)")
        parent = j.find("parent").get("link")
        child = j.find("child").get("link")
        o = j.find("origin")
        xyz = _floats(f"{where} origin xyz", None if o is None else o.get("xyz"), 3, (0, 0, 0))
        rpy = _floats(f"{where} origin rpy", None if o is None else o.get("rpy"), 3, (0, 0, 0))
        a = j.find("axis")
        axis = _floats(f"{where} axis", None if a is None else a.get("xyz"), 3, (1, 0, 0))
        lim = j.find("limit")
        mimic = j.find("mimic")
        joints[jname] = dict(type=jtype, parent=parent, child=child, xyz=xyz, rpy=rpy, axis=axis,
                             lower=None if lim is None or lim.get("lower") is None else float(lim.get("lower")),
                             upper=None if lim is None or lim.get("upper") is None else float(lim.get("upper")),
                             mimic=None if mimic is None else (mimic.get("joint"), float(mimic.get("multiplier", 1)),
                                                               float(mimic.get("offset", 0))))
        if child in child_of:
            raise UrdfError(f"{where}: link {child!r} has two parent joints (not a tree)")
        child_of[child] = jname
    if not joints:
        raise UrdfError(f"{origin}: no joints")
    return joints, child_of


def _kept_joints(root, joints: dict, child_of: dict, tips, origin: str) -> tuple:
    """``(tips, order)``: the tip links and the joints on the paths from the root link to them,
    parents first (stable in file order)."""
    links_all = {link.get("name") for link in root.findall("link")}
    roots = sorted({j["parent"] for j in joints.values()} - set(child_of))
    if len(roots) != 1:
        raise UrdfError(f"{origin}: expected one root link, found {roots}")
    children = {}
    for jn, j in joints.items():
        children.setdefault(j["parent"], []).append(jn)
    if tips is None:
        leaves = [link for link in links_all | set(child_of) if link not in children and link in child_of]
        tips = [link for link in sorted(leaves) if _has_moving_ancestor(link, child_of, joints)]
    keep, order = set(), []
    for tip in tips:
        if tip not in child_of:
            raise UrdfError(f"{origin}: tip link {tip!r} is not the child of any joint")
        link = tip
        while link in child_of:
            keep.add(child_of[link])
            link = joints[child_of[link]]["parent"]
    stack = [roots[0]]
    while stack:
        link = stack.pop(0)
        for jn in children.get(link, []):
            if jn in keep:
                order.append(jn)
                stack.append(joints[jn]["child"])
    return tips, order


def _controller_joints(joints: dict, order: list, origin: str) -> tuple:
    """``(controller joint names, limits (n, 2) [rad | mm])``: the kept non-mimic moving joints and
    the leaders of kept mimics, in file order; ``continuous`` joints without limits."""
    keep = set(order)
    leaders = {joints[jn]["mimic"][0] for jn in order if joints[jn]["mimic"] is not None}
    ctrl = [jn for jn, j in joints.items()
            if j["type"] != "fixed" and j["mimic"] is None and (jn in keep or jn in leaders)]
    missing = leaders - set(ctrl)
    if missing:
        raise UrdfError(f"{origin}: mimic joints follow {sorted(missing)}, which are missing or mimics themselves")
    limits = []
    for jn in ctrl:
        j = joints[jn]
        scale = 1.0 if j["type"] != "prismatic" else _M_TO_MM
        lo = -np.inf if j["lower"] is None or j["type"] == "continuous" else j["lower"] * scale
        hi = np.inf if j["upper"] is None or j["type"] == "continuous" else j["upper"] * scale
        limits.append((lo, hi))
    return ctrl, np.array(limits).reshape(-1, 2)


def _link(jn: str, j: dict, parent: int, origin: str) -> Link:
    """The ``urdf`` link of joint ``jn`` (origin in mm; a mimic offset becomes the joint offset)."""
    jtype = "revolute" if j["type"] == "continuous" else j["type"]
    params = dict(zip(("x", "y", "z"), (v * _M_TO_MM for v in j["xyz"])))
    params.update(zip(("roll", "pitch", "yaw"), j["rpy"]))
    if jtype == "fixed":
        return Link(jn, jtype, "urdf", params, parent, (0.0, 0.0, 1.0))
    n = np.linalg.norm(j["axis"])
    if n == 0:
        raise UrdfError(f"{origin}: joint {jn!r}: axis has zero length")
    off = 0.0 if j["mimic"] is None else j["mimic"][2]
    params["theta" if jtype == "revolute" else "d"] = off * (1.0 if jtype == "revolute" else _M_TO_MM)
    return Link(jn, jtype, "urdf", params, parent, tuple(np.asarray(j["axis"]) / n))


def _coupling(joints: dict, order: list, ctrl: list, links: list) -> np.ndarray:
    """(n_moving, n_controller): 1 for a joint driven by itself, the multiplier for a mimic."""
    coupling = np.zeros((sum(L.moves for L in links), len(ctrl)))
    m = 0
    for jn in order:
        j = joints[jn]
        if j["type"] == "fixed":
            continue
        if j["mimic"] is None:
            coupling[m, ctrl.index(jn)] = 1.0
        else:
            leader, mult, _ = j["mimic"]
            coupling[m, ctrl.index(leader)] = mult
        m += 1
    return coupling


def _has_moving_ancestor(link, child_of, joints) -> bool:
    while link in child_of:
        j = joints[child_of[link]]
        if j["type"] != "fixed":
            return True
        link = j["parent"]
    return False


def _fmt(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def write_urdf(model: RobotModel, path, overwrite: bool = False) -> Path:
    """Write ``model`` as URDF (converted exactly to a joint chain first). Atomic write.

    Joint couplings must be expressible in URDF: each model joint follows a single controller
    joint (sign flips become a flipped axis, other multipliers ``<mimic>``); sums of several
    controller joints (FANUC's J2/J3 interaction) are not, and raise :class:`UrdfError`.
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path}: exists; pass overwrite=True to replace it")
    m = to_urdf_kind(model)
    robot = ET.Element("robot", name=m.name)
    ET.SubElement(robot, "link", name="world")
    ET.SubElement(robot, "link", name="base_link")
    j = ET.SubElement(robot, "joint", name="world_to_base", type="fixed")
    ET.SubElement(j, "parent", link="world")
    ET.SubElement(j, "child", link="base_link")
    _origin(j, m.T_world_base[:3, 3], m.T_world_base[:3, :3])
    moving = {int(k): i for i, k in enumerate(m.moving)}
    for k, L in enumerate(m.links):
        ET.SubElement(robot, "link", name=f"{L.name}_link")
        j = ET.SubElement(robot, "joint", name=L.name, type=L.joint_type)
        ET.SubElement(j, "parent", link="base_link" if L.parent < 0 else f"{m.links[L.parent].name}_link")
        ET.SubElement(j, "child", link=f"{L.name}_link")
        p = L.params
        T = frame_from_xyz_rpy([p["x"], p["y"], p["z"]], [p["roll"], p["pitch"], p["yaw"]])
        if L.joint_type == "fixed":
            _origin(j, T[:3, 3], T[:3, :3])
        else:
            _moving_joint(j, m, L, T, m.coupling[moving[k]])
    for e in m.end_effectors:
        ET.SubElement(robot, "link", name=e.name)
        j = ET.SubElement(robot, "joint", name=f"{e.name}_fixed", type="fixed")
        ET.SubElement(j, "parent", link="base_link" if e.link < 0 else f"{m.links[e.link].name}_link")
        ET.SubElement(j, "child", link=e.name)
        _origin(j, e.T_link_ee[:3, 3], e.T_link_ee[:3, :3])
    ET.indent(robot)
    data = ET.tostring(robot, encoding="unicode")
    atomic_write_text(path, '<?xml version="1.0"?>\n<!-- written by robocal; lengths in metres -->\n' + data + "\n",
                      overwrite=overwrite)
    return path


def _moving_joint(j, m: RobotModel, L: Link, T, row) -> None:
    """Origin, axis, limits or ``<mimic>`` of the URDF joint ``j`` for the moving link ``L`` of the
    ``urdf``-kind model ``m`` (``T``: its origin (4, 4) [mm]; ``row``: its coupling row)."""
    jt = L.joint_type
    off = L.params.get("theta", 0.0) if jt == "revolute" else L.params.get("d", 0.0)
    axis = np.asarray(L.axis, dtype=float)
    nz = np.flatnonzero(row)
    if len(nz) != 1:
        raise UrdfError(f"{m.name}: joint {L.name!r} is driven by {len(nz)} controller joints "
                        f"({[m.controller_joints[i] for i in nz]}); URDF cannot express this coupling")
    leader, coef = m.controller_joints[nz[0]], float(row[nz[0]])
    if off != 0.0:
        # fold the constant offset into the origin (the motion about the axis commutes with it)
        T = T @ elementary_transforms(OP_RU if jt == "revolute" else OP_TU, off, axis)
    _origin(j, T[:3, 3], T[:3, :3])
    if leader == L.name or (abs(coef) == 1.0 and leader not in {x.name for x in m.links}):
        if coef < 0:
            axis = -axis
        ET.SubElement(j, "axis", xyz=_fmt(axis))
        c = m.controller_joints.index(leader)
        lo, hi = m.limits[c] * (1.0 if jt == "revolute" else 1.0 / _M_TO_MM)
        if coef < 0:
            lo, hi = -hi, -lo
        if np.isfinite(lo) and np.isfinite(hi):
            ET.SubElement(j, "limit", lower=repr(float(lo)), upper=repr(float(hi)), effort="0", velocity="0")
        elif jt == "revolute":
            j.set("type", "continuous")
    else:
        ET.SubElement(j, "axis", xyz=_fmt(axis))
        ET.SubElement(j, "limit", lower="-1e9", upper="1e9", effort="0", velocity="0")
        ET.SubElement(j, "mimic", joint=leader, multiplier=repr(coef), offset="0")


def _origin(elem, xyz_mm, R):
    rpy = euler_from_matrix(np.asarray(R, dtype=float), "rpy")
    ET.SubElement(elem, "origin", xyz=_fmt(np.asarray(xyz_mm) / _M_TO_MM), rpy=_fmt(rpy))
