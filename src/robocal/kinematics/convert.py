"""Exact conversions between model kinds: DH (with or without beta) -> Craig MDH -> URDF chain.

The conversions regroup the same product of elementary transforms, so forward kinematics are
identical (tests check this to rounding). Parameter *names* change with the kind; which
parameters are held fixed moves with them.

DH -> MDH: ``Π_i Rz(θ_i) Tz(d_i) [Tx(a_i) Rx(α_i) Ry(β_i)]`` is regrouped so that link i's
trailing ``Tx Rx Ry`` becomes the leading ``Rx(α) Tx(a) Ry(β)`` of its children (``Tx`` and
``Rx`` commute), and of its end effectors' fixed transforms.

MDH -> URDF: ``Rx(α) Tx(a) Ry(β) Rz(θ + q) Tz(d)`` = origin ``Rx(α) Tx(a) Ry(β) Rz(θ) Tz(d)``
followed by a rotation ``q`` about z (``Rz`` and ``Tz`` commute); prismatic joints likewise.
"""

from __future__ import annotations
from ..errors import InputError

import numpy as np

from ..transforms import euler_from_matrix
from .links import OP_RX, OP_RY, OP_RZ, OP_TX, OP_TZ, Link, elementary_transforms
from .model import EndEffector, RobotModel

__all__ = ["dh_to_mdh", "dh_with_beta", "mdh_to_urdf", "to_urdf_kind", "ConversionError"]


class ConversionError(InputError):
    """The model cannot be converted exactly (the message says why)."""


def _trail(link: Link) -> np.ndarray:
    p = link.params
    return (elementary_transforms(OP_TX, p["a"]) @ elementary_transforms(OP_RX, p["alpha"])
            @ elementary_transforms(OP_RY, p.get("beta", 0.0)))


def dh_with_beta(model: RobotModel) -> RobotModel:
    """A ``dh`` model as ``dh_beta`` (Hayati's beta, METHODS.md (2-18)) with beta = 0 on every link
    that has none: identical kinematics, and the betas can then be set (``with_params(beta2=...)``)."""
    if model.kind not in ("dh", "dh_beta"):
        raise ConversionError(f"{model.name}: dh_with_beta needs a dh or dh_beta model, got {model.kind}")
    # every DH link becomes a dh_beta link (a link may already carry the beta the loader adds
    # between parallel axes while still named 'dh'; the file format needs one convention)
    links = [L if L.convention not in ("dh", "dh_beta") else
             Link(L.name, L.joint_type, "dh_beta", {**L.params, "beta": L.params.get("beta", 0.0)}, L.parent, L.axis,
                  L.fixed)
             for L in model.links]
    return model.replace(kind="dh_beta", links=links)


def dh_to_mdh(model: RobotModel) -> RobotModel:
    """Convert a ``dh`` / ``dh_beta`` model to Craig's modified DH (``mdh``, with beta)."""
    if model.kind not in ("dh", "dh_beta"):
        raise ConversionError(f"{model.name}: dh_to_mdh needs a dh or dh_beta model, got {model.kind}")
    links = []
    for L in model.links:
        if L.convention not in ("dh", "dh_beta"):
            raise ConversionError(f"{model.name}: link {L.name!r} is a {L.convention} frame; only DH links convert")
        if L.parent >= 0:
            P = model.links[L.parent]
            lead = {"alpha": P.params["alpha"], "a": P.params["a"], "beta": P.params.get("beta", 0.0)}
            lead_fixed = {n for n in ("alpha", "a", "beta") if n in P.fixed or n not in P.params}
        else:
            lead = {"alpha": 0.0, "a": 0.0, "beta": 0.0}
            lead_fixed = {"alpha", "a", "beta"}
        params = {"alpha": lead["alpha"], "a": lead["a"], "beta": lead["beta"],
                  "theta": L.params["theta"], "d": L.params["d"]}
        fixed = lead_fixed | {n for n in ("theta", "d") if n in L.fixed}
        links.append(Link(L.name, L.joint_type, "mdh", params, L.parent, L.axis, frozenset(fixed)))
    ees = []
    for e in model.end_effectors:
        T = e.T_link_ee if e.link < 0 else _trail(model.links[e.link]) @ e.T_link_ee
        ees.append(EndEffector(e.name, e.link, T))
    return model.replace(kind="mdh", links=links, end_effectors=ees)


def mdh_to_urdf(model: RobotModel) -> RobotModel:
    """Convert an ``mdh`` model to a URDF joint chain (``urdf``: origin xyz/rpy + z axis)."""
    if model.kind != "mdh":
        raise ConversionError(f"{model.name}: mdh_to_urdf needs an mdh model, got {model.kind}")
    links = []
    for L in model.links:
        p = L.params
        if L.convention == "mdh":
            T = (elementary_transforms(OP_RX, p["alpha"]) @ elementary_transforms(OP_TX, p["a"])
                 @ elementary_transforms(OP_RY, p.get("beta", 0.0)) @ elementary_transforms(OP_RZ, p["theta"])
                 @ elementary_transforms(OP_TZ, p["d"]))
            roll, pitch, yaw = euler_from_matrix(T[:3, :3], "rpy")
            params = {"x": T[0, 3], "y": T[1, 3], "z": T[2, 3], "roll": roll, "pitch": pitch, "yaw": yaw}
            if L.joint_type == "revolute":
                params["theta"] = 0.0
            elif L.joint_type == "prismatic":
                params["d"] = 0.0
            links.append(Link(L.name, L.joint_type, "urdf", {k: float(v) for k, v in params.items()},
                              L.parent, (0.0, 0.0, 1.0)))
        else:
            conv = "urdf" if L.joint_type == "fixed" else L.convention
            links.append(Link(L.name, L.joint_type, conv, dict(L.params), L.parent, L.axis, L.fixed))
    return model.replace(kind="urdf", links=links)


def to_urdf_kind(model: RobotModel) -> RobotModel:
    """Any model kind as a URDF joint chain with identical forward kinematics."""
    if model.kind == "urdf":
        return model
    if model.kind in ("dh", "dh_beta"):
        model = dh_to_mdh(model)
    return mdh_to_urdf(model)
