"""GA-RBF IK seed networks as ``.npz`` files (format ``robocal-ik-net/1``).

One file holds one :class:`~robocal.kinematics.ik_net.IKSeedNetwork`: the RBF arrays, and as
metadata the format, the robocal version that wrote it, the robot's name and model fingerprint
(:func:`~robocal.kinematics.fingerprint.model_fingerprint`), the configuration branch (closed-form
index, name, joint box, singularity margin), the pose encoding, the GA's structure, the domain-check
envelope and the validation statistics. Files are written atomically (temporary file and rename) and
read with ``allow_pickle=False``. By convention the file sits next to the robot file:
``<robot>.iknet.npz`` (:func:`default_network_path`).
"""

from __future__ import annotations

import io
import zipfile
from pathlib import Path

import numpy as np

from .. import __version__
from ..kinematics.ik_net import ENCODING, ConfigurationBranch, IKSeedNetwork, NetworkMismatchError, RBFNetwork, Structure
from .atomic import atomic_write_bytes
from .header import FileFormatError

__all__ = ["FORMAT", "save_ik_network", "load_ik_network", "default_network_path", "IKNetworkFileError"]

FORMAT = "robocal-ik-net/1"
_STATS = ("joint_deg", "position_mm", "rotation_deg")
_QUANTS = ("median", "p95", "max")
_ENVELOPE = ("centre_distance", "workspace_mm", "position_mm", "rotation_rad")


class IKNetworkFileError(FileFormatError):
    """A network file is unreadable, of another format or encoding, or for another robot."""


def default_network_path(robot_path) -> Path:
    """``<dir>/<stem>.iknet.npz`` next to a robot file ``<dir>/<stem>.toml``."""
    p = Path(robot_path)
    return p.with_name(p.stem + ".iknet.npz")


def save_ik_network(path, net: IKSeedNetwork, overwrite: bool = False) -> Path:
    """Write ``net`` to ``path`` (``.npz``); an existing file needs ``overwrite=True``."""
    s, st = net.structure, net.stats
    arrays = {
        "format": np.array(FORMAT), "robocal_version": np.array(__version__),
        "robot_name": np.array(net.robot_name), "robot_fingerprint": np.array(net.robot_fingerprint),
        "branch_index": np.array(net.branch.index), "branch_name": np.array(net.branch.name),
        "branch_box": net.branch.box, "branch_margin_rad": np.array(net.branch.margin_rad),
        "encoding": np.array(net.encoding), "length_scale_mm": np.array(net.length_scale_mm),
        "x_mean": net.rbf.x_mean, "x_std": net.rbf.x_std, "centres": net.rbf.centres,
        "sigma": np.array(net.rbf.sigma), "weights": net.rbf.weights, "y_mean": net.rbf.y_mean,
        "structure": np.array([s.n_centres, s.width_factor, s.reg, s.position_weight]),
        "envelope": np.array([net.envelope[k] for k in _ENVELOPE]), "workspace_points": net.workspace_points,
    }
    for key in _STATS:
        if key in st:
            arrays[f"stats_{key}"] = np.array([st[key][q] for q in _QUANTS])
    for key in ("n_samples", "n_validation", "seed", "train_seconds", "tuned"):
        if key in st:
            arrays[f"stats_{key}"] = np.array(st[key])
    hist = st.get("ga_history") or []
    arrays["stats_ga_history"] = np.array([[h["generation"], h["best_rms_rad"], h["mean_rms_rad"], h["evaluations"]]
                                           for h in hist], dtype=float).reshape(-1, 4)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return atomic_write_bytes(path, buf.getvalue(), overwrite=overwrite)


def load_ik_network(path, model=None) -> IKSeedNetwork:
    """Read a network file; with ``model``, also check that it was trained for that model
    (:class:`IKNetworkFileError` naming both robots otherwise)."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
    except FileNotFoundError:
        raise IKNetworkFileError(path, "no such file") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise IKNetworkFileError(path, f"not a robocal IK network file (.npz): {exc}") from None
    fmt = str(d.get("format", ""))
    if fmt != FORMAT:
        raise IKNetworkFileError(path, f"format {fmt or 'missing'!r}, expected {FORMAT!r}")
    missing = [k for k in ("robot_name", "robot_fingerprint", "branch_index", "branch_box", "branch_margin_rad",
                           "encoding", "length_scale_mm", "x_mean", "x_std", "centres", "sigma", "weights",
                           "y_mean", "structure", "envelope", "workspace_points") if k not in d]
    if missing:
        raise IKNetworkFileError(path, f"missing entries {missing}")
    if str(d["encoding"]) != ENCODING:
        raise IKNetworkFileError(path, f"pose encoding {str(d['encoding'])!r}; this robocal reads {ENCODING!r}")
    n_c, wf, reg, pw = d["structure"].tolist()
    stats = {}
    for key in _STATS:
        if f"stats_{key}" in d:
            stats[key] = dict(zip(_QUANTS, d[f"stats_{key}"].tolist()))
    for key in ("n_samples", "n_validation", "seed", "train_seconds", "tuned"):
        if f"stats_{key}" in d:
            stats[key] = d[f"stats_{key}"].item()
    stats["ga_history"] = [{"generation": int(g), "best_rms_rad": b, "mean_rms_rad": m, "evaluations": int(e)}
                           for g, b, m, e in d.get("stats_ga_history", np.zeros((0, 4))).tolist()]
    stats["robocal_version"] = str(d.get("robocal_version", ""))
    if d["envelope"].shape != (len(_ENVELOPE),):
        raise IKNetworkFileError(path, f"envelope has {d['envelope'].size} values, expected {len(_ENVELOPE)}")
    net = IKSeedNetwork(
        robot_name=str(d["robot_name"]), robot_fingerprint=str(d["robot_fingerprint"]),
        branch=ConfigurationBranch(int(d["branch_index"]), d["branch_box"], float(d["branch_margin_rad"])),
        length_scale_mm=float(d["length_scale_mm"]),
        rbf=RBFNetwork(d["x_mean"], d["x_std"], d["centres"], float(d["sigma"]), d["weights"], d["y_mean"]),
        structure=Structure(int(n_c), wf, reg, pw),
        envelope=dict(zip(_ENVELOPE, d["envelope"].tolist())), workspace_points=d["workspace_points"],
        stats=stats, encoding=str(d["encoding"]))
    if model is not None:
        try:
            net.check_model(model)
        except NetworkMismatchError as exc:
            raise IKNetworkFileError(path, str(exc)) from None
    return net
