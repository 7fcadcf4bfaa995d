"""The ``[elastic]`` section of a robot file: joint compliances, the mass model or the lumped
gravity parameters, and gravity (docs/robot-files.md, docs/elastic.md).

```toml
[elastic]
gravity = [0.0, 0.0, -9.80665]        # m/s^2 in the robot base frame (default: base z up)
compliance = { A2 = 0.25, A3 = 0.4 }  # per moving joint: mrad/kNm (revolute), mm/kN (prismatic)
lateral = { A2 = [0.1, 0.05] }        # optional (the full model): bending about e1, e2 [mrad/kNm]

[elastic.masses]                      # a mass model: per joint entry (its link frame)
A2 = { mass = 280.0, com = [-600.0, 0.0, 150.0] }   # kg; centre of mass in length_unit

[elastic.lumped]                      # or: lumped gravity parameters identified from data
A2 = [280.0, -168.0, 0.0, 42.0]       # m [kg], first moment hx, hy, hz [kg m] in the link frame
```

Read into ``model.extra["elastic"]`` as an :class:`~robocal.calib.elastic.ElasticDescription`.
"""

from __future__ import annotations

import math

import numpy as np

from ..calib.elastic import ElasticDescription, bodies_from_masses
from ..calib.gravity import STANDARD_GRAVITY

__all__ = ["parse_elastic", "elastic_lines"]


def _number(where, v):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ValueError(f"{where}: expected a finite number, got {v!r}")
    return float(v)


def parse_elastic(section, origin: str, link_names, moving_names, length_scale: float) -> ElasticDescription:
    """The :class:`ElasticDescription` of an ``[elastic]`` table; ``ValueError`` naming the entry."""
    where = f"{origin}: [elastic]"
    if not isinstance(section, dict):
        raise ValueError(f"{where}: must be a table")
    unknown = set(section) - {"gravity", "compliance", "lateral", "masses", "lumped"}
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {sorted(unknown)}; expected gravity, compliance, lateral, masses, "
                         "lumped")
    g = section.get("gravity", list(STANDARD_GRAVITY))
    if not isinstance(g, list) or len(g) != 3:
        raise ValueError(f"{where}: 'gravity' must be [gx, gy, gz] in m/s^2, got {g!r}")
    g = [_number(f"{where}: gravity", x) for x in g]
    if not 9.0 < float(np.linalg.norm(g)) < 10.5:
        raise ValueError(f"{where}: 'gravity' {g} has magnitude {np.linalg.norm(g):.4g}; expected ~9.81 m/s^2")
    comp = section.get("compliance", {})
    if not isinstance(comp, dict):
        raise ValueError(f"{where}: 'compliance' must map joint names to numbers")
    compliance = {}
    for n, v in comp.items():
        if n not in moving_names:
            raise ValueError(f"{where}.compliance: {n!r} is not a moving joint; joints: {', '.join(moving_names)}")
        compliance[n] = _number(f"{where}.compliance.{n}", v)
    lateral = None
    if "lateral" in section:
        lat = section["lateral"]
        if not isinstance(lat, dict):
            raise ValueError(f"{where}: 'lateral' must map joint names to [c1, c2]")
        lateral = {}
        for n, v in lat.items():
            if n not in moving_names:
                raise ValueError(f"{where}.lateral: {n!r} is not a moving joint; joints: {', '.join(moving_names)}")
            if not isinstance(v, list) or len(v) != 2:
                raise ValueError(f"{where}.lateral.{n}: expected [c1, c2] in mrad/kNm, got {v!r}")
            lateral[n] = tuple(_number(f"{where}.lateral.{n}", x) for x in v)
    if "masses" in section and "lumped" in section:
        raise ValueError(f"{where}: give either [elastic.masses] (a mass model) or [elastic.lumped], not both")
    masses = {}
    for n, e in section.get("masses", {}).items():
        w = f"{where}.masses.{n}"
        if n not in link_names:
            raise ValueError(f"{w}: not a joint entry of this robot")
        if not isinstance(e, dict) or "mass" not in e:
            raise ValueError(f"{w}: expected {{ mass = kg, com = [x, y, z] }}")
        m = _number(f"{w}.mass", e["mass"])
        if m < 0:
            raise ValueError(f"{w}.mass: {m} kg is negative")
        com = e.get("com", [0.0, 0.0, 0.0])
        if not isinstance(com, list) or len(com) != 3:
            raise ValueError(f"{w}.com: expected [x, y, z], got {com!r}")
        com_mm = [_number(f"{w}.com", x) * length_scale for x in com]
        if max(abs(x) for x in com_mm) > 10000:
            raise ValueError(f"{w}.com: {com_mm} mm is more than 10 m from the link frame (length_unit?)")
        masses[n] = (m, com_mm)
    bodies = bodies_from_masses(masses)
    for n, v in section.get("lumped", {}).items():
        w = f"{where}.lumped.{n}"
        if n not in link_names:
            raise ValueError(f"{w}: not a joint entry of this robot")
        if not isinstance(v, list) or len(v) != 4:
            raise ValueError(f"{w}: expected [m kg, hx, hy, hz kg m], got {v!r}")
        bodies[n] = tuple(_number(w, x) for x in v)
    return ElasticDescription(compliance, bodies, mass_model="lumped" not in section, g=tuple(g), lateral=lateral)


def _num(x: float) -> str:
    return repr(float(round(x, 12)))


def elastic_lines(desc: ElasticDescription, length_scale: float) -> list:
    """The TOML lines of ``desc`` (lengths in the file's unit, ``length_scale`` mm per unit)."""
    out = ["", "[elastic]", "gravity = [" + ", ".join(_num(x) for x in desc.g) + "]",
           "compliance = { " + ", ".join(f'"{n}" = {_num(v)}' for n, v in desc.compliance.items()) + " }"
           + "  # mrad/kNm (revolute), mm/kN (prismatic)"]
    if desc.lateral:
        out.append("lateral = { " + ", ".join(f'"{n}" = [{_num(a)}, {_num(b)}]' for n, (a, b) in desc.lateral.items())
                   + " }  # bending about e1, e2 [mrad/kNm]")
    if desc.mass_model:
        out += ["", "[elastic.masses]  # kg; centre of mass in the link frame"]
        for n, (m, hx, hy, hz) in desc.bodies.items():
            com = [h * 1000.0 / m / length_scale if m > 0 else 0.0 for h in (hx, hy, hz)]
            out.append(f'"{n}" = {{ mass = {_num(m)}, com = [' + ", ".join(_num(c) for c in com) + "] }")
    else:
        out += ["", "[elastic.lumped]  # identified: m [kg], first moment hx, hy, hz [kg m] in the link frame"]
        for n, v in desc.bodies.items():
            out.append(f'"{n}" = [' + ", ".join(_num(x) for x in v) + "]")
    return out
