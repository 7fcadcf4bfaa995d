"""Universal Robots controller files: ``calibration.conf`` in, the ROS ``kinematics`` YAML in and out.

``calibration.conf`` (on the controller, ``/root/.urcontrol/``) holds the arm's factory calibration
in its ``[mounting]`` section: ``delta_theta``, ``delta_a``, ``delta_d``, ``delta_alpha`` (six
numbers each, metres and radians) that the controller adds to its nominal DH table,
``calibration_status`` (the file's own comment: 0 notInitialized, 1 notLinearised, 2 Linearised)
and ``joint_checksum`` (six hexadecimal 32-bit values; the controller streams six such values as the
``checksum`` of its ``KinematicsInfo``; UR does not document their meaning, robocal records them in
the robot file's provenance and does not interpret them).
The controller streams nominal + delta as its ``KinematicsInfo`` package
(``UniversalRobots/Universal_Robots_Client_Library``, ``kinematics_info.h``).

The ``kinematics`` YAML is the parameter file ``ur_description`` loads
(``UniversalRobots/Universal_Robots_ROS2_Description``, ``config/<type>/default_kinematics.yaml``,
``urdf/inc/ur_common.xacro``): six joint origins ``shoulder, upper_arm, forearm, wrist_1,
wrist_2, wrist_3`` with ``x, y, z`` [m] and URDF ``roll, pitch, yaw`` [rad] (``R = Rz(yaw)
Ry(pitch) Rx(roll)``, the ``rpy`` of a URDF ``<origin>``), each joint turning about its own z, and a
``hash``. The hash is *not* a checksum of the YAML's numbers: it is ``"calib_"`` followed by
libstdc++'s ``std::hash<std::string>`` of the controller's DH values printed with C++'s default
6 significant digits (``KinematicsInfo::toHash``); the driver compares it with the connected
robot's at start-up and only logs an error when they differ. :func:`ur_driver_hash` computes it
(it reproduces ``ur_description``'s published defaults, see tests).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .atomic import atomic_write_text
from .header import FileFormatError

__all__ = ["UrCalibration", "read_calibration_conf", "parse_calibration_conf", "ur_driver_hash",
           "UR_KINEMATICS_JOINTS", "write_kinematics_yaml", "kinematics_yaml_text", "read_kinematics_yaml", "parse_kinematics_yaml",
           "UrFileError", "CALIBRATION_STATUS"]

#: ``calibration_status`` values as the controller's file comments them.
CALIBRATION_STATUS = {0: "notInitialized", 1: "notLinearised", 2: "Linearised"}
#: Joint origin names of ur_description's kinematics YAML, base to flange.
UR_KINEMATICS_JOINTS = ("shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3")
_DELTAS = ("delta_theta", "delta_a", "delta_d", "delta_alpha")


class UrFileError(FileFormatError):
    """A UR controller file cannot be read; the message names the file, line and key."""

    def __init__(self, message: str):
        super().__init__(None, message)


@dataclass(frozen=True)
class UrCalibration:
    """The ``[mounting]`` section of a UR ``calibration.conf``.

    ``delta_theta``, ``delta_alpha`` (6,) [rad]; ``delta_a``, ``delta_d`` (6,) [m];
    ``calibration_status`` (int or None); ``joint_checksum`` (6 ints or None); ``origin`` the file.
    """

    delta_theta: np.ndarray
    delta_a: np.ndarray
    delta_d: np.ndarray
    delta_alpha: np.ndarray
    calibration_status: int | None = None
    joint_checksum: tuple | None = None
    origin: str = "<calibration.conf>"
    other: dict = field(default_factory=dict)

    @property
    def status_text(self) -> str:
        if self.calibration_status is None:
            return "not given"
        return CALIBRATION_STATUS.get(self.calibration_status, f"unknown ({self.calibration_status})")


def _number(text: str, where: str):
    t = text.strip()
    try:
        if re.fullmatch(r"[+-]?0[xX][0-9a-fA-F]+", t):
            return int(t, 16)
        v = float(t)
    except ValueError:
        raise UrFileError(f"{where}: {t!r} is not a number") from None
    if not math.isfinite(v):
        raise UrFileError(f"{where}: {t!r} is not a finite number")
    return v


def _value(text: str, where: str):
    t = text.strip()
    if t.startswith("["):
        if not t.endswith("]"):
            raise UrFileError(f"{where}: a list must end with ']' on the same line, got {t!r}")
        inner = t[1:-1].strip()
        return [] if not inner else [_number(x, where) for x in inner.split(",")]
    return _number(t, where)


def parse_calibration_conf(text: str, origin: str = "<calibration.conf>") -> UrCalibration:
    """Parse the text of a UR ``calibration.conf``; only its ``[mounting]`` section is used."""
    section, found, values, lines = None, False, {}, {}
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        m = re.fullmatch(r"\[([^\]]+)\]", line)
        if m:
            section = m.group(1).strip()
            found |= section == "mounting"
            continue
        if section != "mounting":
            continue
        if "=" not in line:
            raise UrFileError(f"{origin}, line {no}: expected 'key = value' in [mounting], got {raw.strip()!r}")
        key, val = (s.strip() for s in line.split("=", 1))
        where = f"{origin}, line {no} ({key})"
        try:
            values[key] = _value(val, where)
        except UrFileError:
            if key in _DELTAS or key in ("calibration_status", "joint_checksum"):
                raise
            values[key] = val  # other entries are kept as text
        lines[key] = no
    if not found:
        raise UrFileError(f"{origin}: no [mounting] section (is this a UR controller's calibration.conf?)")
    deltas = {}
    for key in _DELTAS:
        if key not in values:
            raise UrFileError(f"{origin}: [mounting] has no {key!r} (six numbers expected)")
        v = values[key]
        if not isinstance(v, list) or len(v) != 6:
            raise UrFileError(f"{origin}, line {lines[key]} ({key}): expected a list of 6 numbers, got {v!r}")
        deltas[key] = np.array([float(x) for x in v])
    status = values.get("calibration_status")
    if status is not None and (isinstance(status, list) or float(status) != int(status)):
        raise UrFileError(f"{origin}, line {lines['calibration_status']} (calibration_status): expected an integer")
    cs = values.get("joint_checksum")
    if cs is not None and (not isinstance(cs, list) or len(cs) != 6):
        raise UrFileError(f"{origin}, line {lines['joint_checksum']} (joint_checksum): expected 6 numbers")
    other = {k: v for k, v in values.items() if k not in _DELTAS and k not in ("calibration_status", "joint_checksum")}
    return UrCalibration(deltas["delta_theta"], deltas["delta_a"], deltas["delta_d"], deltas["delta_alpha"],
                         None if status is None else int(status),
                         None if cs is None else tuple(int(x) for x in cs), origin, other)


def read_calibration_conf(path) -> UrCalibration:
    """Read a UR ``calibration.conf`` file (see :func:`parse_calibration_conf`)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8", errors="strict")
    except UnicodeDecodeError as exc:
        raise UrFileError(f"{p}: not a text file ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise UrFileError(f"{p}: cannot read: {exc.strerror or exc}") from None
    return parse_calibration_conf(text, str(p))


# ---------------------------------------------------------------------------------------- hash
_M64 = (1 << 64) - 1


def _shift_mix(v: int) -> int:
    return v ^ (v >> 47)


def _libstdcxx_hash_bytes(data: bytes, seed: int = 0xC70F6907) -> int:
    """``std::_Hash_bytes`` of libstdc++ for 64-bit ``size_t`` (what ``std::hash<std::string>`` returns)."""
    mul = ((0xC6A4A793 << 32) + 0x5BD1E995) & _M64
    n = len(data)
    aligned = n & ~7
    h = (seed ^ (n * mul)) & _M64
    for p in range(0, aligned, 8):
        word = int.from_bytes(data[p:p + 8], "little")
        h = ((h ^ ((_shift_mix((word * mul) & _M64) * mul) & _M64)) * mul) & _M64
    if n & 7:
        h = ((h ^ int.from_bytes(data[aligned:], "little")) * mul) & _M64
    h = (_shift_mix(h) * mul) & _M64
    return _shift_mix(h)


def ur_driver_hash(theta, d, a, alpha) -> str:
    """The ``hash`` the UR ROS driver expects for a controller DH table (nominal + deltas).

    ``theta, alpha`` (6,) [rad]; ``d, a`` (6,) [m] -- the values of the controller's
    ``KinematicsInfo``. Each value is printed like C++'s default ``ostream << double`` (``%g``,
    6 significant digits) in the order theta, d, a, alpha per joint; the string is hashed with
    libstdc++'s ``std::hash`` (a driver built with another C++ library would print another hash).
    """
    text = "".join("%g%g%g%g" % (theta[i], d[i], a[i], alpha[i]) for i in range(len(theta)))
    return f"calib_{_libstdcxx_hash_bytes(text.encode('ascii'))}"


# ---------------------------------------------------------------------------------------- YAML
def _num(x: float) -> str:
    x = float(x)
    return "0" if x == 0.0 else repr(x)


def kinematics_yaml_text(origins, hash_value: str, comment: str = "") -> str:
    """The ``kinematics`` YAML of six joint origins.

    ``origins``: sequence of 6 ``(xyz [m] (3,), rpy [rad] (3,))``; ``hash_value`` the ``hash``
    entry (see the module docstring); ``comment`` optional ``#`` lines at the top.
    """
    if len(origins) != len(UR_KINEMATICS_JOINTS):
        raise ValueError(f"kinematics YAML: expected {len(UR_KINEMATICS_JOINTS)} joint origins, got {len(origins)}")
    out = [f"# {line}".rstrip() for line in comment.splitlines()] if comment else []
    out.append("kinematics:")
    for name, (xyz, rpy) in zip(UR_KINEMATICS_JOINTS, origins):
        out.append(f"  {name}:")
        for k, v in zip(("x", "y", "z"), xyz):
            out.append(f"    {k}: {_num(v)}")
        for k, v in zip(("roll", "pitch", "yaw"), rpy):
            out.append(f"    {k}: {_num(v)}")
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", hash_value):
        raise ValueError(f"kinematics YAML: hash {hash_value!r} must be letters, digits and _ . - only")
    out.append(f"  hash: {hash_value}")
    return "\n".join(out) + "\n"


def write_kinematics_yaml(path, origins, hash_value: str, comment: str = "", overwrite: bool = False) -> Path:
    """Write :func:`kinematics_yaml_text` atomically to ``path``."""
    return atomic_write_text(path, kinematics_yaml_text(origins, hash_value, comment), overwrite=overwrite)


def read_kinematics_yaml(path):
    """Read a ur_description ``kinematics`` YAML: ``(origins, hash)`` with ``origins`` a list of six
    ``(xyz [m] (3,), rpy [rad] (3,))`` in the order of :data:`UR_KINEMATICS_JOINTS`.

    Reads the block layout the driver's ``ur_calibration`` and robocal write (two-space indents,
    ``key: value`` lines); other YAML layouts raise :class:`UrFileError` naming the line.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise UrFileError(f"{p}: cannot read: {exc.strerror or exc}") from None
    return parse_kinematics_yaml(text, str(p))


def parse_kinematics_yaml(text: str, origin: str = "<kinematics.yaml>"):
    """:func:`read_kinematics_yaml` of a text; ``origin`` names it in errors."""
    p = origin
    top, joint, table, hash_value = None, None, {}, None
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.split("#", 1)[0].rstrip()
        if not line.strip():
            continue
        indent = len(line) - len(line.lstrip(" "))
        m = re.fullmatch(r"\s*([A-Za-z0-9_]+):\s*(.*)", line)
        if not m:
            raise UrFileError(f"{p}, line {no}: expected 'key: value', got {raw.strip()!r}")
        key, val = m.group(1), m.group(2).strip().strip("'\"")
        if indent == 0:
            top, joint = key, None
            continue
        if top != "kinematics":
            continue
        if not val:
            joint = key
            table[joint] = {}
            continue
        if key == "hash" and (joint is None or indent <= 2):
            hash_value, joint = val, None
            continue
        if joint is None:
            raise UrFileError(f"{p}, line {no}: {key!r} outside a joint entry")
        try:
            v = float(val)
        except ValueError:
            raise UrFileError(f"{p}, line {no} ({joint}.{key}): {val!r} is not a number") from None
        if not math.isfinite(v):
            raise UrFileError(f"{p}, line {no} ({joint}.{key}): not a finite number")
        table[joint][key] = v
    origins = []
    for name in UR_KINEMATICS_JOINTS:
        if name not in table:
            raise UrFileError(f"{p}: kinematics has no {name!r} entry (expected {', '.join(UR_KINEMATICS_JOINTS)})")
        e = table[name]
        missing = [k for k in ("x", "y", "z", "roll", "pitch", "yaw") if k not in e]
        if missing:
            raise UrFileError(f"{p}: kinematics.{name} lacks {', '.join(missing)}")
        origins.append((np.array([e["x"], e["y"], e["z"]]), np.array([e["roll"], e["pitch"], e["yaw"]])))
    return origins, hash_value
