"""The elastic part of ``robocal calibrate --elastic joint [--payload KG@x,y,z]`` (docs/elastic.md).

* :func:`elastic_option` -- the :class:`~robocal.calib.elastic.ElasticModel` of the options: the
  robot file's mass model (``[elastic.masses]``) when it has one, else lumped gravity parameters;
* :func:`parse_payload` -- ``KG@x,y,z`` (kg, mm in the flange frame);
* :func:`elastic_summary` -- the ``elastic`` section of result.json (compliances with sigma, what
  is not identifiable and why, the payload);
* :func:`with_elastic` -- the calibrated model carrying its ``[elastic]`` section;
* :func:`torque_plot` -- the report's residuals-against-gravity-torque plot, before and after.
"""

from __future__ import annotations

import math

import numpy as np

from ...calib.elastic import ElasticModel, Payload, elastic_description
from ...calib.errors import ProblemError
from ...calib.sanity import elastic_reasons

__all__ = ["ELASTIC_CHOICES", "elastic_option", "parse_payload", "elastic_summary", "with_elastic", "torque_plot"]

ELASTIC_CHOICES = ("joint", "full")


def parse_payload(text: str) -> Payload:
    """``KG@x,y,z`` -> :class:`Payload` (mass [kg], centre of mass [mm] in the flange frame)."""
    s = str(text).strip()
    mass_txt, at, com_txt = s.partition("@")
    if not mass_txt.strip():
        raise ProblemError(f"--payload {s!r}: the mass is missing; expected KG@x,y,z (kg, mm in the flange frame)")
    try:
        mass = float(mass_txt)
    except ValueError:
        raise ProblemError(f"--payload {s!r}: mass {mass_txt!r} is not a number of kg; expected KG@x,y,z") from None
    com = (0.0, 0.0, 0.0)
    if at:
        parts = com_txt.split(",")
        try:
            com = tuple(float(v) for v in parts)
        except ValueError:
            raise ProblemError(f"--payload {s!r}: centre of mass {com_txt!r} must be three numbers x,y,z [mm]") from None
        if len(com) != 3:
            raise ProblemError(f"--payload {s!r}: centre of mass needs three numbers x,y,z [mm], got {len(com)}")
    if not math.isfinite(mass) or mass <= 0:
        raise ProblemError(f"--payload {s!r}: a payload needs a mass > 0 kg")
    return Payload(mass, com).checked()


def elastic_option(nominal, kind: str | None, payload: Payload | None) -> ElasticModel | None:
    """The elastic model of ``--elastic KIND`` (None without it)."""
    if kind is None:
        if payload is not None:
            raise ProblemError("--payload needs --elastic joint (a payload only matters for the deflection model)")
        return None
    if kind not in ELASTIC_CHOICES:
        raise ProblemError(f"--elastic {kind!r}: expected one of {', '.join(ELASTIC_CHOICES)}")
    lateral = kind == "full"
    desc = nominal.extra.get("elastic")
    if desc is not None and desc.mass_model and desc.bodies:
        masses = {n: (b[0], [h * 1000.0 / b[0] if b[0] > 0 else 0.0 for h in b[1:]]) for n, b in desc.bodies.items()}
        return ElasticModel(masses=masses, payload=payload, g=desc.g, compliance_initial=0.0, lateral=lateral)
    return ElasticModel(payload=payload, compliance_initial=100.0, lateral=lateral)


def elastic_summary(problem, result) -> dict:
    """result.json's ``elastic``: compliances and mass parameters (value, std, unit, identifiable,
    why), those the data cannot determine (``not_identifiable``), those the plausibility gate
    (:func:`robocal.calib.sanity.elastic_reasons`) names as not identified (``not_identified``:
    negative, or sigma >= |value|) and its failure reasons (``gate_reasons``)."""
    ident = result.identifiability.by_block()
    dropped = {d["name"]: d["why"] for blk in ("compliance", "lateral", "gravity")
               for d in ident.get(blk, {}).get("dropped", [])}
    rows, masses = [], []
    for i, n in enumerate(result.names):
        if n.startswith(("compliance.", "lateral.", "gravity.")):
            row = {"name": n, "joint": n.split(".")[1], "value": float(result.values[i]), "unit": result.units[i],
                   "std": None if not np.isfinite(result.std[i]) else float(result.std[i]),
                   "identifiable": n not in dropped, "why": dropped.get(n)}
            (masses if n.startswith("gravity.") else rows).append(row)
    reasons, implausible = elastic_reasons(rows + masses)
    gate = {r["name"]: r["why"] for r in implausible}
    for row in rows + masses:
        if row["name"] in gate:
            row["identifiable"], row["why"] = False, gate[row["name"]]
    el = problem.elastic
    return {"model": "full" if el.lateral else "joint", "mass_model": not el.lumped,
            "payload": None if el.payload is None else {"mass_kg": float(np.mean(el.payload.mass)),
                                                        "com_mm": [float(v) for v in np.ravel(el.payload.com)[:3]]},
            "compliance": rows, "mass_parameters": masses,
            "not_identifiable": [{"name": k, "why": v} for k, v in dropped.items()],
            "not_identified": implausible, "gate_reasons": reasons,
            "note": "without a mass model only the products compliance x gravity torque are identifiable "
                    "(docs/elastic.md)" if el.lumped else "mass model from the robot file"}


def with_elastic(model, problem, result):
    """``model`` with the identified ``[elastic]`` section (compliances; mass model or lumped gravity)."""
    return model.replace(extra={**model.extra, "elastic": elastic_description(problem, result.state)})


def torque_plot(problem, res0, result) -> dict:
    """{section title: PNG}: per-pose errors against the gravity torque of the most loaded compliant
    joint, before (nominal geometry, best-fit base) and after."""
    d = problem.deflection
    tau = d.torques_at(problem.q).torques(d.gravity.theta(result.state.gravity))[:, d.compliance.joints]
    j = int(np.argmax(np.max(np.abs(tau), axis=0)))
    name = d.compliance.names[j].split(".", 1)[1]
    n_pose = len(problem.q)

    def per_pose(res):
        e = res.point_errors_after
        if e is None or e.size % n_pose:
            return None
        return np.sqrt(np.mean(e.reshape(n_pose, -1) ** 2, axis=1))

    before, after = per_pose(res0), per_pose(result)
    if before is None or after is None:
        return {}
    from ...report.elastic_plot import plot_residuals_vs_torque

    unit = "N m" if d.compliance.units[j] == "mrad/kNm" else "N"
    svg = plot_residuals_vs_torque(tau[:, j], before, after, joint=name, unit=unit)
    return {f"Residuals against the gravity torque of {name}": svg} if svg else {}
