"""The controller's own model in and out: UR factory calibration import, driver-file export, tables.

See docs/controller.md. The numerics live in :mod:`robocal.kinematics.remodel` (the exact,
well-conditioned MDH + beta model) and the file formats in :mod:`robocal.io.ur_controller`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...calib.sanity import Verdict
from ...errors import InputError
from ...io.atomic import atomic_write_text
from ...io.ur_controller import (kinematics_yaml_text, parse_kinematics_yaml, read_calibration_conf,
                                read_kinematics_yaml, ur_driver_hash)
from ...kinematics.convert import dh_to_mdh, to_urdf_kind
from ...kinematics.links import frame_from_xyz_rpy
from ...kinematics.model import RobotModel
from ...kinematics.remodel import (EXTENDED_PRECISION, RemodelError, dh_table_axes, dh_table_fk, fk_longdouble,
                                  inverse_rigid, well_conditioned_mdh)
from ...robots import load_robot, save_robot
from ...transforms import euler_from_matrix

__all__ = ["UR_PI_2", "UR_NOMINAL_DH", "ControllerInputError", "ur_nominal_model", "load_nominal", "ur_controller_dh",
           "random_joints", "fk_agreement", "import_ur", "controller_comment", "ur_joint_origins", "origins_fk",
           "export_ur", "model_from_kinematics_yaml", "table_text", "export_table", "export_urdf", "save_model",
           "refuse_same_path"]

#: The value UR controllers store for pi/2 in their nominal DH alphas: 1.570796327 (10 digits).
#: Evidence: the UR driver's tests ("This is what the simulated robot reports as pi/2") and the real
#: UR10e table of ``ur_calibration/doc/algorithm.rst``, whose printed alphas (1.57014608044242,
#: -1.57038520649543) equal +-1.570796327 + the deltas of its test data to 15 digits, not +-pi/2 + deltas.
UR_PI_2 = 1.570796327


#: Nominal DH tables of the UR arm types (d1, a2, a3, d4, d5, d6 [m]; theta 0; alpha 90, 0, 0, 90, -90, 0 deg),
#: as ur_description's ``config/<type>/default_kinematics.yaml`` encodes them
#: (UniversalRobots/Universal_Robots_ROS2_Description); each reproduces that file's published driver
#: ``hash`` (tests/test_controller.py), so the six values are the controller's own to the hash's 6 digits.
UR_NOMINAL_DH = {
    "ur3": (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
    "ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
    "ur10": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922),
    "ur3e": (0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
    "ur5e": (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    "ur10e": (0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
    "ur16e": (0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
    "ur20": (0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
    "ur30": (0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543),
}


def ur_nominal_model(arm_type: str) -> RobotModel:
    """The nominal DH model (mm, deg file units) of a UR arm type from :data:`UR_NOMINAL_DH`."""
    from ...robots.loader import parse_robot

    d1, a2, a3, d4, d5, d6 = UR_NOMINAL_DH[arm_type]
    rows = [(d1, 0, 90), (0, a2, 0), (0, a3, 0), (d4, 0, 90), (d5, 0, -90), (d6, 0, 0)]
    joints = [{"name": f"J{i + 1}", "type": "revolute", "theta": 0.0, "d": round(d * 1000, 9), "a": round(a * 1000, 9),
               "alpha": float(al), "limits": [-360.0, 360.0]} for i, (d, a, al) in enumerate(rows)]
    data = {"format": "robocal-robot/1", "name": arm_type, "title": f"Universal Robots {arm_type.upper()} (nominal)",
            "model": "dh", "length_unit": "mm", "angle_unit": "deg",
            "source": f"UR nominal DH of the {arm_type.upper()} as ur_description's config/{arm_type}/"
                      "default_kinematics.yaml encodes it (robocal.workflows.controller.models.UR_NOMINAL_DH); limits +-360 deg",
            "controller_joints": [f"J{i + 1}" for i in range(6)], "joints": joints}
    return parse_robot(data, origin=f"<UR nominal {arm_type}>")


def load_nominal(name) -> RobotModel:
    """A robot by name or file (:func:`robocal.robots.load_robot`); a UR arm type that robocal does
    not ship as a file (``ur5e``, ``ur16e``, ...) comes from :data:`UR_NOMINAL_DH`."""
    from ...robots import RobotFileError

    try:
        return load_robot(name)
    except RobotFileError:
        if str(name).lower() in UR_NOMINAL_DH:
            return ur_nominal_model(str(name).lower())
        raise


class ControllerInputError(InputError):
    """Inputs of a ``robocal controller`` command do not fit together (the message says how)."""


def refuse_same_path(out, *inputs) -> None:
    """An output that resolves to one of the command's inputs is refused, even with --overwrite."""
    o = Path(out).resolve()
    for i in inputs:
        if i is not None and Path(str(i)).exists() and Path(str(i)).resolve() == o:
            raise ControllerInputError(f"{out}: the output would replace the input {i}; choose another --out")


# ------------------------------------------------------------------------------------------ nominal
def _controller_number(value: float) -> float:
    """A nominal value as the controller stores it: the short decimal (12 significant digits)."""
    return float(f"{value:.12g}")


def _check_nominal_dh(nominal: RobotModel) -> None:
    if nominal.kind not in ("dh", "dh_beta") or len(nominal.links) != 6 or not nominal.is_serial:
        raise ControllerInputError(f"{nominal.name}: a UR nominal model must be a serial DH table of 6 joints "
                                   f"(got kind {nominal.kind} with {len(nominal.links)} links)")
    if any(L.joint_type != "revolute" or abs(L.params.get("beta", 0.0)) > 0 for L in nominal.links):
        raise ControllerInputError(f"{nominal.name}: a UR nominal model has 6 revolute joints and no beta")
    if not np.array_equal(nominal.coupling, np.eye(6)):
        raise ControllerInputError(f"{nominal.name}: joint coupling or sign flips are not part of a UR DH table")
    if not np.allclose(nominal.T_world_base, np.eye(4)) or not np.allclose(nominal.end_effectors[0].T_link_ee, np.eye(4)):
        raise ControllerInputError(f"{nominal.name}: the nominal model must end at the DH flange with no base or tool "
                                   "frame (a UR controller's DH table runs from its base to its flange)")


def ur_controller_dh(nominal: RobotModel, cal) -> dict:
    """The DH table the UR controller runs: nominal + ``calibration.conf`` deltas, as doubles.

    ``nominal``: robocal DH model of the arm type (e.g. ``ur10``), read in the controller's units
    (metres, the 12-digit decimals of the published table; alphas of +-90 deg as +-1.570796327,
    :data:`UR_PI_2`). ``cal``: :class:`~robocal.io.ur_controller.UrCalibration` or None (nominal).
    Returns ``{"theta", "d", "a", "alpha"}`` (6,) float64 [rad | m] -- the values of the
    controller's ``KinematicsInfo`` -- and ``"nominal"`` the same for the nominal table.
    """
    _check_nominal_dh(nominal)
    nom = {k: np.zeros(6) for k in ("theta", "d", "a", "alpha")}
    for i, L in enumerate(nominal.links):
        p = L.params
        nom["theta"][i] = _controller_number(p["theta"])
        nom["d"][i] = _controller_number(p["d"] / 1000.0)
        nom["a"][i] = _controller_number(p["a"] / 1000.0)
        al = p["alpha"]
        nom["alpha"][i] = math.copysign(UR_PI_2, al) if abs(abs(al) - math.pi / 2) < 1e-9 else _controller_number(al)
    if cal is None:
        out = {k: v.copy() for k, v in nom.items()}
    else:
        out = {"theta": nom["theta"] + cal.delta_theta, "d": nom["d"] + cal.delta_d,
               "a": nom["a"] + cal.delta_a, "alpha": nom["alpha"] + cal.delta_alpha}
    out["nominal"] = nom
    return out


def _dh_mm(dh):
    """The controller table in longdouble millimetres (exact scaling of the doubles in metres)."""
    LD = np.longdouble
    return (np.asarray(dh["theta"], LD), np.asarray(dh["d"], LD) * 1000, np.asarray(dh["a"], LD) * 1000,
            np.asarray(dh["alpha"], LD))


def random_joints(model: RobotModel, n: int, seed: int) -> np.ndarray:
    """(n, n_joints) uniform joint values within the model's limits (infinite limits: +-2 pi) [rad]."""
    lo = np.where(np.isfinite(model.limits[:, 0]), model.limits[:, 0], -2 * np.pi)
    hi = np.where(np.isfinite(model.limits[:, 1]), model.limits[:, 1], 2 * np.pi)
    return np.random.default_rng(seed).uniform(lo, hi, size=(n, model.n_joints))


def _pose_errors(T_ref, T):
    """Position error [mm] and rotation angle [rad] per pose between two (N, 4, 4) stacks."""
    T_ref = np.asarray(T_ref, dtype=np.longdouble)
    T = np.asarray(T, dtype=np.longdouble)
    dp = np.sqrt(((T_ref[:, :3, 3] - T[:, :3, 3]) ** 2).sum(axis=1))
    R = np.swapaxes(T_ref[:, :3, :3], 1, 2) @ T[:, :3, :3]
    c = np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1)
    s = np.sqrt(((R - np.swapaxes(R, 1, 2)) ** 2).sum(axis=(1, 2)) / 8)  # |sin| -- accurate for small angles
    ang = np.arctan2(s, c)
    return np.asarray(dp, dtype=float), np.asarray(ang, dtype=float)


def fk_agreement(model: RobotModel, reference_fk, q) -> dict:
    """Max position [mm] and rotation [rad] difference between ``model.fk`` (float64, the path every
    robocal command uses; base frame) and ``reference_fk(q)`` (longdouble (N, 4, 4) [mm])."""
    T = model.fk(q)
    T = np.linalg.inv(model.T_world_base)[None] @ T
    dp, ang = _pose_errors(reference_fk(q), T)
    return {"n": int(len(q)), "max_mm": float(dp.max()), "max_rad": float(ang.max())}


# ------------------------------------------------------------------------------------------ import
def _nominal_difference(model: RobotModel, nominal: RobotModel) -> dict:
    """Parameter-by-parameter difference of a well-conditioned model from the nominal's MDH form."""
    ref = dh_to_mdh(nominal)
    out = {}
    for k, (L, R) in enumerate(zip(model.links, ref.links)):
        for p in ("alpha", "a", "beta", "theta", "d"):
            v = L.params[p] - R.params.get(p, 0.0)
            if p in ("alpha", "beta", "theta"):
                v = (v + math.pi) % (2 * math.pi) - math.pi
            out[f"{p}{k + 1}"] = v
    return out


def _import_gates(cal, agreement, diff, tol_mm, tol_rad) -> Verdict:
    checks, reasons = {}, []

    def gate(name, value, limit, unit, reason):
        passed = bool(math.isfinite(value) and value <= limit)
        checks[name] = {"value": float(value), "limit": float(limit), "unit": unit, "passed": passed}
        if not passed:
            reasons.append(reason)

    gate("conversion_position", agreement["max_mm"], tol_mm, "mm",
         f"the converted model's FK differs from the controller's DH + deltas by {agreement['max_mm']:.3g} mm "
         f"(limit {tol_mm:g} mm): the conversion is not exact"
         + ("" if EXTENDED_PRECISION else " (numpy.longdouble is plain float64 on this platform)"))
    gate("conversion_rotation", agreement["max_rad"], tol_rad, "rad",
         f"the converted model's orientation differs by {agreement['max_rad']:.3g} rad (limit {tol_rad:g})")
    lengths = max(abs(v) for k, v in diff.items() if k[:1] in ("a", "d") and not k.startswith("alpha"))
    angles = max(abs(v) for k, v in diff.items() if k.startswith(("alpha", "beta", "theta")))
    gate("nominal_lengths", lengths, 10.0, "mm",
         f"a link length differs from the nominal robot's by {lengths:.3f} mm (a factory calibration moves them by "
         "well under 10 mm): is ROBOT the arm's type (UR10 vs UR10e ...)?")
    gate("nominal_angles", math.degrees(angles), 2.0, "deg",
         f"a link angle differs from the nominal robot's by {math.degrees(angles):.3f} deg (limit 2 deg): is ROBOT "
         "the arm's type?")
    if cal is not None and cal.calibration_status is not None:
        ok = cal.calibration_status == 2
        checks["calibration_status"] = {"value": cal.calibration_status, "limit": 2, "unit": "", "passed": ok}
        if not ok:
            reasons.append(f"calibration_status = {cal.calibration_status} ({cal.status_text}), not 2 (Linearised): "
                           "the controller may not be running these deltas")
    return Verdict(tuple(reasons), checks)


def import_ur(conf_path, nominal_name, *, n_check: int = 1000, seed: int = 0, tol_mm: float = 1e-9,
              tol_rad: float = 1e-12) -> dict:
    """Read a UR ``calibration.conf`` and build the exact, well-conditioned model of the controller.

    Returns a dict with ``model`` (:class:`RobotModel`, kind ``mdh`` with beta, mm/deg file units),
    ``dh`` (the controller's table, see :func:`ur_controller_dh`), ``hash`` (the driver's),
    ``calibration`` (the parsed file), ``agreement`` (FK check at ``n_check`` random joint sets
    within the limits: max mm, max rad), ``difference`` (per parameter from the nominal MDH) and
    ``verdict`` (sanity gates).
    """
    cal = read_calibration_conf(conf_path)
    nominal = load_nominal(nominal_name)
    dh = ur_controller_dh(nominal, cal)
    th, d, a, al = _dh_mm(dh)
    P, U, T_last = dh_table_axes(th, d, a, al)
    status = cal.status_text
    checksum = "[" + ", ".join(f"0x{c:x}" for c in cal.joint_checksum) + "]" if cal.joint_checksum else "not given"
    h = ur_driver_hash(dh["theta"], dh["d"], dh["a"], dh["alpha"])
    source = (f"UR controller factory calibration {Path(str(conf_path)).name} ([mounting] deltas on the nominal "
              f"{nominal.name} DH table; calibration_status {cal.calibration_status} = {status}; joint_checksum "
              f"{checksum}; UR driver hash {h}); converted exactly to MDH + beta by robocal controller import ur")
    try:
        model = well_conditioned_mdh(P, U, T_last, nominal, name=f"{nominal.name}_controller",
                                     title=f"{nominal.title or nominal.name} (controller factory calibration)",
                                     source=source)
    except RemodelError as exc:
        raise ControllerInputError(f"{conf_path}: {exc}") from None
    q = random_joints(model, n_check, seed)
    agreement = fk_agreement(model, lambda qq: dh_table_fk(th, d, a, al, qq), q)
    diff = _nominal_difference(model, nominal)
    verdict = _import_gates(cal, agreement, diff, tol_mm, tol_rad)
    return {"model": model, "nominal": nominal, "dh": dh, "hash": h, "calibration": cal, "agreement": agreement,
            "difference": diff, "verdict": verdict}


def controller_comment(result) -> str:
    """Comment lines for the robot file of an imported controller model (the raw table kept for reference)."""
    dh, cal = result["dh"], result["calibration"]

    def row(v):
        return "[" + ", ".join(repr(float(x)) for x in v) + "]"

    return ("The UR controller's own kinematics, from " + str(cal.origin) + ".\n"
            "Controller DH table (nominal + deltas; metres, radians; link i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) "
            "Rx(alpha_i)):\n"
            f"  theta = {row(dh['theta'])}\n  d     = {row(dh['d'])}\n  a     = {row(dh['a'])}\n"
            f"  alpha = {row(dh['alpha'])}\n"
            f"This file is the same kinematics as a well-conditioned MDH + beta model (FK equal to "
            f"{result['agreement']['max_mm']:.1e} mm at {result['agreement']['n']} random joint sets).\n"
            f"UR ROS driver hash of the controller table: {result['hash']}")


# ------------------------------------------------------------------------------------------ export
def _fold_tool(T_ee, tol_mm=1e-9, tol_rad=1e-12):
    """A flange transform folded into the last joint's origin: it must be a turn about and a shift
    along the joint axis (those commute with the joint). Returns the residual (mm, rad) if not."""
    T = np.asarray(T_ee, dtype=float)
    off = float(np.hypot(T[0, 3], T[1, 3]))
    tilt = float(math.atan2(math.hypot(T[0, 2], T[1, 2]), T[2, 2]))
    return off <= tol_mm and abs(tilt) <= tol_rad, off, tilt


def ur_joint_origins(model: RobotModel, end_effector=0):
    """Joint origins of a 6-joint serial revolute model with each joint turning about its own z.

    Returns a list of 6 (4, 4) transforms [mm], ``FK = prod_i origin_i Rz(q_i)`` in the robot base
    frame (the model's ``T_world_base`` is left out) -- the chain of ur_description's kinematics
    YAML and URDF. The end effector must be the flange or differ from the last joint frame only by
    a turn about and a shift along joint 6's axis; otherwise :class:`ControllerInputError`.
    """
    if len(model.links) != 6 or not model.is_serial or any(L.joint_type != "revolute" for L in model.links):
        raise ControllerInputError(f"{model.name}: the UR kinematics file needs a serial chain of 6 revolute joints")
    if not np.array_equal(model.coupling, np.eye(6)):
        raise ControllerInputError(f"{model.name}: joint coupling or sign flips cannot be written to a UR kinematics "
                                   "file")
    m = to_urdf_kind(model)
    origins = []
    for L in m.links:
        if np.abs(np.asarray(L.axis) - (0.0, 0.0, 1.0)).max() > 0:
            raise ControllerInputError(f"{model.name}: joint {L.name!r} turns about {L.axis}, not its own z axis")
        p = L.params
        T = frame_from_xyz_rpy([p["x"], p["y"], p["z"]], [p["roll"], p["pitch"], p["yaw"]])
        c, s = math.cos(p["theta"]), math.sin(p["theta"])
        Rz = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        origins.append(T @ Rz)
    ee = m.end_effectors[m.end_effector_index(end_effector)]
    if ee.link != 5:
        raise ControllerInputError(f"{model.name}: end effector {ee.name!r} is not carried by joint 6")
    ok, off, tilt = _fold_tool(ee.T_link_ee)
    if not ok:
        raise ControllerInputError(
            f"{model.name}: end effector {ee.name!r} is {off:.6g} mm off and {math.degrees(tilt):.6g} deg tilted from "
            "joint 6's axis; the UR kinematics file ends at the flange (tool0) -- export the model's flange (a robot "
            "file without [tool]) and set the tool on the controller")
    origins[5] = origins[5] @ np.asarray(ee.T_link_ee, dtype=float)
    return origins


def origins_fk(origins, q) -> np.ndarray:
    """FK (N, 4, 4) [mm] of a chain of joint origins turning about z, in longdouble."""
    LD = np.longdouble
    q = np.atleast_2d(np.asarray(q, LD))
    T = np.broadcast_to(np.eye(4, dtype=LD), (len(q), 4, 4)).copy()
    for i, O in enumerate(origins):
        c, s = np.cos(q[:, i]), np.sin(q[:, i])
        Rz = np.zeros((len(q), 4, 4), LD)
        Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1] = c, -s, s, c
        Rz[:, 2, 2] = Rz[:, 3, 3] = 1
        T = T @ np.asarray(O, LD) @ Rz
    return T


def _yaml_origins(origins):
    """(xyz [m], URDF rpy [rad]) of each origin (4, 4) [mm]."""
    return [(np.asarray(O[:3, 3], float) / 1000.0, euler_from_matrix(np.asarray(O[:3, :3], float), "rpy"))
            for O in origins]


def export_ur(model_path, out, *, hash_value=None, overwrite=False, force=False, n_check=1000, seed=0,
              tol_mm=1e-9, tol_rad=1e-12) -> dict:
    """Write a robot file's kinematics as ur_description's ``kinematics`` YAML, checked first.

    ``hash_value``: the driver hash to write (``robocal controller import ur`` prints the
    controller's); default ``robocal_<fingerprint>``, which never matches a controller (the driver
    then logs that the file is not the controller's calibration, which is true of a model calibrated
    with an instrument). The YAML text is parsed back and its FK compared with the model's at
    ``n_check`` random joint sets; the file is written only when that check passes (or ``force``).
    Returns a dict with ``file`` (None when not written), ``hash``, ``agreement``, ``verdict``,
    ``base_left_out``.
    """
    refuse_same_path(out, model_path)
    if Path(out).exists() and not overwrite:
        raise FileExistsError(f"{out}: output file exists; pass --overwrite to replace it")
    model = load_nominal(model_path)
    origins = ur_joint_origins(model)
    if hash_value is None:
        from ...kinematics.fingerprint import model_fingerprint

        hash_value = f"robocal_{model_fingerprint(model)[:16]}"
    comment = (f"ur_description kinematics parameters written by robocal controller export ur from {model_path}\n"
               f"({model.title or model.name}). Joint origins: x, y, z [m]; roll, pitch, yaw [rad], URDF rpy\n"
               "(R = Rz(yaw) Ry(pitch) Rx(roll)); each joint turns about its own z. hash: the UR driver's\n"
               "calib_<std::hash of the controller DH table> when this is the controller's own calibration,\n"
               "else a robocal fingerprint (the driver then warns that it is not the controller's model).")
    text = kinematics_yaml_text(_yaml_origins(origins), hash_value, comment)
    back, _ = parse_kinematics_yaml(text, str(out))
    back_origins = [_origin_from_yaml(xyz, rpy) for xyz, rpy in back]
    q = random_joints(model, n_check, seed)
    if model.kind != "urdf":
        ref = fk_longdouble(model, q)
    else:
        ref = inverse_rigid(np.asarray(model.T_world_base, np.longdouble))[None] @ np.asarray(model.fk(q), np.longdouble)
    dp, ang = _pose_errors(ref, origins_fk(back_origins, q))
    agreement = {"n": n_check, "max_mm": float(dp.max()), "max_rad": float(ang.max())}
    ok = agreement["max_mm"] <= tol_mm and agreement["max_rad"] <= tol_rad
    verdict = Verdict(() if ok else (f"the kinematics file's FK differs from the model's by {agreement['max_mm']:.3g} mm"
                                     f" / {agreement['max_rad']:.3g} rad (limit {tol_mm:g} mm, {tol_rad:g} rad)",),
                      {"fk_position": {"value": agreement["max_mm"], "limit": tol_mm, "unit": "mm", "passed": ok}})
    path = atomic_write_text(out, text, overwrite=overwrite) if ok or force else None
    return {"file": path, "hash": hash_value, "agreement": agreement, "verdict": verdict,
            "base_left_out": not np.allclose(model.T_world_base, np.eye(4)), "model": model}


def _origin_from_yaml(xyz_m, rpy):
    """(4, 4) [mm] of a YAML joint origin, built in longdouble."""
    LD = np.longdouble
    r, p, y = (LD(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    R = np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                  [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                  [-sp, cp * sr, cp * cr]], dtype=LD)
    T = np.eye(4, dtype=LD)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(xyz_m, LD) * 1000
    return T


def model_from_kinematics_yaml(path, nominal_name) -> dict:
    """A robocal model (well-conditioned MDH + beta) from ur_description's kinematics YAML.

    ``nominal_name``: the arm type's nominal robot (names, limits, branch choices). Returns
    ``{"model", "hash", "origins"}`` (origins (4, 4) longdouble [mm]).
    """
    nominal = load_nominal(nominal_name)
    raw, h = read_kinematics_yaml(path)
    origins = [_origin_from_yaml(xyz, rpy) for xyz, rpy in raw]
    LD = np.longdouble
    T = np.eye(4, dtype=LD)
    P, U = [], []
    for O in origins:
        T = T @ O
        P.append(T[:3, 3].copy())
        U.append(T[:3, 2].copy())
    try:
        model = well_conditioned_mdh(np.array(P), np.array(U), T, nominal, name=f"{nominal.name}_from_yaml",
                                     title=f"{nominal.title or nominal.name} (from {Path(str(path)).name})",
                                     source=f"ur_description kinematics YAML {path} (hash {h}) read by robocal")
    except RemodelError as exc:
        raise ControllerInputError(f"{path}: {exc}") from None
    return {"model": model, "hash": h, "origins": origins}


# ------------------------------------------------------------------------------------------ tables
_TABLE_COLUMNS = {
    "dh": (("theta", "deg"), ("d", "mm"), ("a", "mm"), ("alpha", "deg"), ("beta", "deg")),
    "dh_beta": (("theta", "deg"), ("d", "mm"), ("a", "mm"), ("alpha", "deg"), ("beta", "deg")),
    "mdh": (("alpha", "deg"), ("a", "mm"), ("beta", "deg"), ("theta", "deg"), ("d", "mm")),
    "urdf": (("x", "mm"), ("y", "mm"), ("z", "mm"), ("roll", "deg"), ("pitch", "deg"), ("yaw", "deg"),
             ("theta", "deg"), ("d", "mm")),
}
_FORMULAS = {
    "dh": "link i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)  (standard DH; Hayati's beta)",
    "dh_beta": "link i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)  (standard DH; Hayati's beta)",
    "mdh": "link i = Rx(alpha_i) Tx(a_i) Ry(beta_i) Rz(theta_i) Tz(d_i)  (Craig's modified DH with beta)",
    "urdf": "link i = Txyz(x_i, y_i, z_i) Rz(yaw_i) Ry(pitch_i) Rx(roll_i) R_axis(theta_i) T_axis(d_i)  (URDF origin, "
            "then the motion about / along the unit axis)",
}


def table_text(model: RobotModel) -> str:
    """A controller-neutral CSV table of the model's kinematic parameters with units.

    ``#`` lines give the link formula, the joint coupling, the base and the end-effector transforms;
    the header names each column with its unit (``theta_deg``, ``d_mm`` ...); one row per link.
    DH-family models whose links all share the model's convention are written in it; any other
    model as URDF origins with ``axis_x, axis_y, axis_z`` columns. A ``parent`` column appears for trees.
    """
    kind = model.kind
    if kind not in ("dh", "dh_beta", "mdh") or any(L.convention != kind for L in model.links):
        kind = "urdf"
        model = to_urdf_kind(model)
    cols = _TABLE_COLUMNS[kind]
    lines = [f"# robocal kinematic table of {model.title or model.name} ({model.name}), model kind {kind}",
             f"# {_FORMULAS[kind]}",
             "# a moving joint adds its model joint value q_i to theta_i (revolute) or d_i (prismatic); "
             "q_model = C q_controller",
             "# FK = T_base * link_1 * ... * link_n * T_end_effector; lengths in mm, angles in degrees"]
    if not (model.coupling.shape[0] == model.coupling.shape[1] and np.array_equal(model.coupling,
                                                                                   np.eye(len(model.coupling)))):
        lines.append(f"# coupling C (model joints x controller joints {list(model.controller_joints)}) = "
                     f"{model.coupling.tolist()}")
    names = [L.name for L in model.links]
    frames = [("T_base", "", model.T_world_base)] + [
        (f"T_end_effector {e.name}", f" on {names[e.link] if e.link >= 0 else 'the base'}", e.T_link_ee)
        for e in model.end_effectors]
    for label, where, T in frames:
        rpy = np.degrees(euler_from_matrix(np.asarray(T)[:3, :3], "rpy"))
        lines.append(f"# {label}{where}: xyz_mm = [{', '.join(repr(float(v)) for v in np.asarray(T)[:3, 3])}], "
                     f"rpy_deg = [{', '.join(repr(float(v)) for v in rpy)}] (R = Rz(yaw) Ry(pitch) Rx(roll))")
    tree = not model.is_serial
    header = ["joint"] + [f"{n}_{u}" for n, u in cols] + (["axis_x", "axis_y", "axis_z"] if kind == "urdf" else [])
    header += ["type"] + (["parent"] if tree else [])
    lines.append(",".join(header))
    for L in model.links:
        vals = []
        for n, u in cols:
            v = L.params.get(n, 0.0)
            vals.append(repr(float(math.degrees(v) if u == "deg" else v)))
        if kind == "urdf":
            vals += [repr(float(a)) for a in L.axis]
        row = [L.name] + vals + [L.joint_type] + ([names[L.parent] if L.parent >= 0 else "base"] if tree else [])
        lines.append(",".join(row))
    return "\n".join(lines) + "\n"


def export_table(model_path, out, *, overwrite=False) -> dict:
    refuse_same_path(out, model_path)
    model = load_nominal(model_path)
    path = atomic_write_text(out, table_text(model), overwrite=overwrite)
    return {"file": path, "kind": model.kind if model.kind != "urdf" else "urdf", "model": model}


def export_urdf(model_path, out, *, overwrite=False, force=False, n_check=1000, seed=0, tol_mm=1e-6,
                tol_rad=1e-9) -> dict:
    """Write the model as URDF, checked first: the URDF text is written to a scratch folder, read
    back and its FK compared with the model's; the output is written only when that passes (or
    ``force``)."""
    from ...io.urdf import read_urdf, write_urdf

    import tempfile

    refuse_same_path(out, model_path)
    if Path(out).exists() and not overwrite:
        raise FileExistsError(f"{out}: output file exists; pass --overwrite to replace it")
    model = load_nominal(model_path)
    with tempfile.TemporaryDirectory() as tmp:  # written and read back before the real output exists
        trial = write_urdf(model, Path(tmp) / Path(out).name)
        text = Path(trial).read_text(encoding="utf-8")
        back = read_urdf(trial)
    q = random_joints(model, n_check, seed)
    dp, ang = _pose_errors(model.fk(q), back.fk(q))
    agreement = {"n": n_check, "max_mm": float(dp.max()), "max_rad": float(ang.max())}
    ok = agreement["max_mm"] <= tol_mm and agreement["max_rad"] <= tol_rad
    verdict = Verdict(() if ok else (f"the URDF's FK differs from the model's by {agreement['max_mm']:.3g} mm / "
                                     f"{agreement['max_rad']:.3g} rad (limit {tol_mm:g} mm, {tol_rad:g} rad)",),
                      {"fk_position": {"value": agreement["max_mm"], "limit": tol_mm, "unit": "mm", "passed": ok}})
    path = atomic_write_text(out, text, overwrite=overwrite) if ok or force else None
    return {"file": path, "agreement": agreement, "verdict": verdict, "model": model}


def save_model(model: RobotModel, out, *, overwrite=False, comment=None) -> Path:
    return save_robot(model, out, overwrite=overwrite, comment=comment)
