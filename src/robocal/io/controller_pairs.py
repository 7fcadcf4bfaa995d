"""Probe pairs: (joints, pose the controller computes for them), written by controller programs.

A probe program (``robocal controller probe-program``, :mod:`robocal.io.programs.probe`) asks the
controller for the flange pose of each joint set with its own forward kinematics -- UR
``get_forward_kin``, ABB ``CalcRobT``, KUKA ``FORWARD`` (the pose ``$POS_ACT`` shows at
``$AXIS_ACT``), Doosan ``fkin`` -- and prints one line per joint set::

    robocal-pair,<controller>,<index>,<6 joint values>,<6 or 7 pose values>

in the controller's own units and orientation convention (:data:`CONTROLLERS`). A UR RTDE
recording (``actual_q_*`` and ``actual_TCP_pose_*`` columns, TCP zero) is read as pairs too. Anything before
``robocal-pair`` on a line (log time stamps, a socket listener's prefix) and brackets or a ``p``
in front of lists (URScript's ``to_str``) are ignored, so a controller log or a socket transcript
can be read as it is.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..transforms import transform_from_pose
from .header import FileFormatError

__all__ = ["CONTROLLERS", "ProbePairs", "read_probe_pairs", "parse_probe_pairs", "pair_line", "ProbePairsError"]

#: Per controller: joint unit, pose length unit, orientation convention (robocal.transforms name),
#: its angle unit, and the controller function the program calls.
CONTROLLERS = {
    "ur": {"joint_unit": "rad", "length_unit": "m", "orientation": "rotvec", "angle_unit": "rad",
           "function": "get_forward_kin(q, p[0,0,0,0,0,0]) (the pose get_actual_tcp_pose reports there, TCP zero)",
           "language": "URScript"},
    "abb": {"joint_unit": "deg", "length_unit": "mm", "orientation": "quaternion", "angle_unit": "deg",
            "function": "CalcRobT(jointtarget, tool0 \\WObj:=wobj0)", "language": "RAPID"},
    "kuka": {"joint_unit": "deg", "length_unit": "mm", "orientation": "kuka_abc", "angle_unit": "deg",
             "function": "FORWARD(E6AXIS, ERR) with $TOOL = $NULLFRAME, $BASE = $ROBROOT ($POS_ACT at $AXIS_ACT)",
             "language": "KRL"},
    "doosan": {"joint_unit": "deg", "length_unit": "mm", "orientation": "zyz", "angle_unit": "deg",
               "function": "fkin(posj, ref=DR_BASE)", "language": "DRL"},
}
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


class ProbePairsError(FileFormatError):
    """A probe-pairs file cannot be read; the message names the file and line."""


@dataclass(frozen=True)
class ProbePairs:
    """Pairs read back: ``q`` (N, n) [rad], ``T`` (N, 4, 4) controller flange poses [mm],
    ``index`` (N,) the program's numbering, ``controller`` its name, ``origin`` the file."""

    q: np.ndarray
    T: np.ndarray
    index: np.ndarray
    controller: str
    origin: str


def pair_line(controller: str, index: int, q_ctrl, pose_values, digits: int = 10) -> str:
    """One ``robocal-pair`` line in the controller's units (as its program would print it)."""
    vals = list(q_ctrl) + list(pose_values)
    return f"robocal-pair,{controller},{index}," + ",".join(f"{float(v):.{digits}g}" for v in vals)


def parse_probe_pairs(text: str, origin: str = "<pairs>", controller: str | None = None,
                      n_joints: int = 6) -> ProbePairs:
    """Read the ``robocal-pair`` lines of ``text`` (other lines are ignored).

    ``controller``: expected controller name (default: the one the lines name; mixed names raise).
    """
    if "robocal-pair" not in text and "actual_q_0" in text and "actual_TCP_pose_0" in text:
        return _parse_rtde(text, origin, controller, n_joints)
    rows, found = [], None
    records = [(no, chunk) for no, raw in enumerate(text.splitlines(), 1)
               for chunk in raw.split("robocal-pair")[1:]]  # a record per occurrence, several per line allowed
    for no, chunk in records:
        rest = chunk.lstrip(" ,;:")
        name = re.match(r"([A-Za-z]+)", rest)
        if not name:
            raise ProbePairsError(None, f"{origin}, line {no}: 'robocal-pair' without a controller name")
        cname = name.group(1).lower()
        if cname not in CONTROLLERS:
            raise ProbePairsError(None, f"{origin}, line {no}: unknown controller {cname!r} "
                                        f"(expected one of {', '.join(CONTROLLERS)})")
        if found is None:
            found = cname
        elif cname != found:
            raise ProbePairsError(None, f"{origin}, line {no}: controller {cname!r} after {found!r} lines")
        nums = [float(x) for x in _NUMBER.findall(rest[len(cname):])]
        n_pose = 7 if CONTROLLERS[cname]["orientation"] == "quaternion" else 6
        if len(nums) != 1 + n_joints + n_pose:
            raise ProbePairsError(None, f"{origin}, line {no}: expected index, {n_joints} joints and {n_pose} pose "
                                        f"values ({1 + n_joints + n_pose} numbers), got {len(nums)}")
        if not all(math.isfinite(v) for v in nums):
            raise ProbePairsError(None, f"{origin}, line {no}: a value is not finite")
        rows.append((no, nums))
    if not rows:
        raise ProbePairsError(None, f"{origin}: no 'robocal-pair' lines (see docs/controller.md, probing)")
    if controller is not None and found != controller:
        raise ProbePairsError(None, f"{origin}: the lines come from a {found!r} program, expected {controller!r}")
    c = CONTROLLERS[found]
    arr = np.array([r[1] for r in rows])
    q = arr[:, 1:1 + n_joints]
    if c["joint_unit"] == "deg":
        q = np.radians(q)
    pose = arr[:, 1 + n_joints:]
    try:
        T = transform_from_pose(pose, c["orientation"], c["length_unit"], c["angle_unit"])
    except ValueError as exc:
        raise ProbePairsError(None, f"{origin}: {exc}") from None
    return ProbePairs(q, T, arr[:, 0].astype(int), found, origin)


def _parse_rtde(text: str, origin: str, controller, n_joints: int) -> ProbePairs:
    """Pairs from a UR RTDE recording (``record.py`` of UR's RTDE client: a header naming the columns,
    space or comma separated) with ``actual_q_0..5`` [rad] and ``actual_TCP_pose_0..5`` [m, rotation
    vector rad] -- both from the same controller cycle, so each row is a pair. The installation's TCP
    must be zero (the flange) while recording."""
    if controller not in (None, "ur"):
        raise ProbePairsError(None, f"{origin}: an RTDE recording comes from a UR controller, not {controller!r}")
    lines = [ln for ln in text.splitlines() if ln.strip()]
    head_at = next(i for i, ln in enumerate(lines) if "actual_q_0" in ln)
    sep = "," if "," in lines[head_at] else None
    header = [h.strip() for h in lines[head_at].split(sep)]
    try:
        qc = [header.index(f"actual_q_{k}") for k in range(n_joints)]
        pc = [header.index(f"actual_TCP_pose_{k}") for k in range(6)]
    except ValueError as exc:
        raise ProbePairsError(None, f"{origin}: RTDE header lacks a column ({exc})") from None
    rows = []
    for no, ln in enumerate(lines[head_at + 1:], head_at + 2):
        cells = [c.strip() for c in ln.split(sep)]
        try:
            rows.append([float(cells[k]) for k in qc + pc])
        except (ValueError, IndexError):
            raise ProbePairsError(None, f"{origin}, row {no}: expected numbers in the actual_q / actual_TCP_pose "
                                        "columns") from None
    if not rows:
        raise ProbePairsError(None, f"{origin}: the RTDE recording has no rows")
    arr = np.array(rows)
    if not np.isfinite(arr).all():
        raise ProbePairsError(None, f"{origin}: a value is not finite")
    T = transform_from_pose(arr[:, n_joints:], "rotvec", "m", "rad")
    return ProbePairs(arr[:, :n_joints], T, np.arange(len(arr)), "ur", origin)


def read_probe_pairs(path, controller: str | None = None, n_joints: int = 6) -> ProbePairs:
    """Read a probe-pairs file (a controller log or socket transcript, see the module docstring)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise ProbePairsError(None, f"{p}: cannot read: {exc.strerror or exc}") from None
    return parse_probe_pairs(text, str(p), controller, n_joints)
