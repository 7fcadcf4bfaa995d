"""The arm configuration a program states for a Cartesian target, read and written as its controller does.

A controller turns a Cartesian target into joints with its nominal model and the target's
configuration data. What is read here (the joint-space properties are those of
:func:`robocal.kinematics.arm_configuration.arm_signature`: ``back``, ``elbow_down``,
``wrist_negative``):

- KUKA ``S`` (status) bit 0: wrist centre behind axis 1 ("overhead area"), bit 1: ``A3 >= phi``
  (elbow up, i.e. not ``elbow_down``), bit 2: ``A5 <= 0``; ``T`` (turn) bit i: ``A(i+1) < 0``.
  ``S``/``T`` are written as a decimal number or as ``'B010'`` (binary); both are read. (Newer
  KUKA manuals define bit 2 relative to the zero position of A4; it equals the sign rule used here
  for ``|A4| < 90 deg``: a limitation for targets taught with A4 near 180 deg.)
- ABB ``confdata [cf1, cf4, cf6, cfx]``: ``cf1``, ``cf4``, ``cf6`` the quadrant
  ``floor(q / 90 deg)`` of axes 1, 4, 6; ``cfx = 4 * back + 2 * elbow_down + wrist_negative``
  (the table of the RAPID manual: wrist centre behind axis 1, behind the lower arm, axis 5 negative).
- FANUC ``CONFIG : 'F|N U|D T|B, t1, t4, t6'``: ``N`` (no flip) = ``J5 <= 0``, ``F`` (flip) =
  ``J5 > 0`` (as on an R-2000iB/165F: the same pose is ``NUT`` at J5 = -52 deg, ``FUT`` at
  J5 = +52 deg, J4 and J6 turned by 180 deg), ``D`` = elbow down, ``B`` = back; the turn numbers
  ``floor((q + 180 deg) / 360 deg)`` of J1, J4, J6.
- UR scripts and KRL targets without ``S``/``T``: no configuration data; the controller takes the
  solution nearest its current joints (:attr:`ArmConfiguration.nearest`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from ...errors import InputError

__all__ = ["ArmConfiguration", "configuration_of", "configuration_text", "ConfigurationError"]


class ConfigurationError(InputError):
    """A target's configuration data cannot be read."""


@dataclass(frozen=True)
class ArmConfiguration:
    """What a target's configuration data requires of the joints.

    signature: (back, elbow_down, wrist_negative) each True/False, or None when the data says
    nothing; wrist_le_zero: KUKA counts ``A5 = 0`` as negative. turns: tuple of ``(joint index,
    lo, hi)`` [rad]: the joint must lie in ``[lo, hi)``. nearest: no configuration data, take the
    solution nearest the current joints. text: the data as written.
    """

    signature: tuple = (None, None, None)
    turns: tuple = ()
    nearest: bool = False
    wrist_le_zero: bool = False
    text: str = ""

    def matches(self, sig, q) -> np.ndarray:
        """(M,) bool: which joint vectors ``q`` (M, 6) [rad] with signatures ``sig`` (M, 3) fit."""
        q = np.atleast_2d(q)
        sig = np.array(sig, copy=True)
        if self.wrist_le_zero:
            sig[:, 2] = q[:, 4] <= 0.0
        ok = np.ones(len(q), dtype=bool)
        for k, want in enumerate(self.signature):
            if want is not None:
                ok &= sig[:, k] == want
        for j, lo, hi in self.turns:
            ok &= (q[:, j] >= lo - 1e-9) & (q[:, j] < hi - 1e-9)
        return ok


def _kuka_int(text: str, what: str, name: str) -> int:
    t = text.strip().strip("'\"")
    try:
        if t[:1] in "Bb" and set(t[1:]) <= {"0", "1"} and t[1:]:
            return int(t[1:], 2)
        return int(float(t))
    except ValueError:
        raise ConfigurationError(f"{name}: {what} {text!r} is not a number or 'B0101' bit string") from None


def _krl(target) -> ArmConfiguration:
    s, t = target.config.get("S"), target.config.get("T")
    if s is None and t is None:
        return ArmConfiguration(nearest=True)
    sig, turns = (None, None, None), ()
    if s is not None:
        v = _kuka_int(s, "S", target.name)
        sig = (bool(v & 1), not bool(v & 2), bool(v & 4))
    if t is not None:
        v = _kuka_int(t, "T", target.name)
        turns = tuple((j, -math.inf, 0.0) if v >> j & 1 else (j, 0.0, math.inf) for j in range(6))
    return ArmConfiguration(signature=sig, turns=turns, wrist_le_zero=True, text=f"S {s}, T {t}")


def _rapid(target) -> ArmConfiguration:
    conf = target.config.get("conf")
    if conf is None:
        return ArmConfiguration(nearest=True)
    try:
        cf1, cf4, cf6, cfx = (int(float(x)) for x in conf.strip("[] ").split(","))
    except ValueError:
        raise ConfigurationError(f"{target.name}: confdata {conf!r}: expected [cf1,cf4,cf6,cfx] integers") from None
    if not 0 <= cfx <= 7:
        raise ConfigurationError(f"{target.name}: confdata cfx = {cfx}; expected 0..7")
    q90 = math.pi / 2
    turns = tuple((j, c * q90, (c + 1) * q90) for j, c in ((0, cf1), (3, cf4), (5, cf6)))
    return ArmConfiguration(signature=(bool(cfx & 4), bool(cfx & 2), bool(cfx & 1)), turns=turns, text=conf)


_FANUC = re.compile(r"^\s*([FN])\s*([UD])\s*([TB])\s*(?:,\s*(-?\d+)\s*,\s*(-?\d+)\s*,\s*(-?\d+))?\s*$", re.I)


def _fanuc(target) -> ArmConfiguration:
    conf = target.config.get("CONFIG")
    if conf is None:
        return ArmConfiguration(nearest=True)
    m = _FANUC.match(conf)
    if m is None:
        raise ConfigurationError(f"{target.name}: CONFIG {conf!r}: expected 'N U T, 0, 0, 0' (F|N U|D T|B, turns)")
    flip, elbow, side = (g.upper() for g in m.groups()[:3])
    turns = ()
    if m.group(4) is not None:
        turns = tuple((j, (2 * int(n) - 1) * math.pi, (2 * int(n) + 1) * math.pi)
                      for j, n in ((0, m.group(4)), (3, m.group(5)), (5, m.group(6))))
    return ArmConfiguration(signature=(side == "B", elbow == "D", flip == "N"), turns=turns, wrist_le_zero=True,
                            text=conf)


def configuration_of(target, fmt: str) -> ArmConfiguration:
    """The :class:`ArmConfiguration` of a Cartesian ``target`` of a program in format ``fmt``."""
    reader = {"krl": _krl, "rapid": _rapid, "fanuc": _fanuc}.get(fmt)
    return ArmConfiguration(nearest=True) if reader is None else reader(target)


def configuration_text(target, fmt: str, q, sig) -> dict:
    """The configuration data (``{key: text}``, keys as in ``target.config``) that states joints
    ``q`` (6,) [rad] with signature ``sig`` (3,) in the style of the target's own data; ``{}``
    when the format has none."""
    q = np.asarray(q, dtype=float)
    back, down, neg = (bool(x) for x in sig)
    if fmt == "krl" and ("S" in target.config or "T" in target.config):
        s = int(back) | (0 if down else 2) | (4 if q[4] <= 0 else 0)
        t = sum(1 << j for j in range(6) if q[j] < 0)
        out = {}
        for key, v in (("S", s), ("T", t)):
            old = target.config.get(key)
            if old is not None:
                binary = old.strip().strip("'\"")[:1] in "Bb" and not old.strip()[:1].isdigit()
                out[key] = f"'B{v:0{len(old.strip().strip(chr(39))) - 1}b}'" if binary else str(v)
        return out
    if fmt == "rapid" and "conf" in target.config:
        quad = [math.floor(q[j] / (math.pi / 2) + 1e-12) for j in (0, 3, 5)]
        return {"conf": f"[{quad[0]},{quad[1]},{quad[2]},{4 * back + 2 * down + neg}]"}
    if fmt == "fanuc" and "CONFIG" in target.config:
        turns = [math.floor((q[j] + math.pi) / (2 * math.pi) + 1e-12) for j in (0, 3, 5)]
        return {"CONFIG": f"{'N' if q[4] <= 0 else 'F'} {'D' if down else 'U'} {'B' if back else 'T'}, "
                          f"{turns[0]}, {turns[1]}, {turns[2]}"}
    return {}
