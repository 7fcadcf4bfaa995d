"""The configuration branch a learned IK seed is trained on, and sampling joints on it.

Inverse kinematics of a 6R arm is multi-valued (up to 8 closed-form branches, plus 2 pi copies of
wide joints), and a regressor trained across branches averages between solutions: its output is no
solution at all. So the network learns ONE branch, defined by the closed-form solver's branch flags
(:data:`~robocal.kinematics.ik_analytic.BRANCHES`) and a joint box:

- default branch 0, ``front/up/noflip``: wrist centre in front of axis 1, elbow up, OPW theta5 > 0
  -- the configuration industrial arms work in most of the time;
- every revolute joint restricted to its limits and to ``[-max_abs, +max_abs]`` (150 deg by
  default), so that no joint wraps around +-180 deg inside the branch (J1 behind the robot, J4 and J6
  of wide-range wrists would otherwise jump by 2 pi between neighbouring poses);
- ``margin`` (10 deg) away from the wrist singularity (theta5 = 0, where only theta4 + theta6 is
  determined) and from the stretched / folded elbow, where the map from pose to joints is not smooth.

The flags come from the closed-form solver of a *reference* model: the model itself when it is of the
OPW class, or its nominal shape with every Hayati beta set to zero (a calibrated model with small beta
tilts has no closed form, but its branches are those of its nominal shape). Samples are drawn
uniformly in the box and kept when the reference solver labels them with the wanted branch.

Robots with no closed-form reference at all (offset wrists such as the UR arms, trees) get a branch
defined by the joint box alone (:func:`joint_box_branch`, ``index = -1``): the user restricts the joints
that select a configuration (e.g. the UR elbow J3 and wrist J5 to one sign). Whether such a box holds one
solution per pose is then the user's responsibility; the validation error shows it when it does not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..ik_analytic import BRANCHES, NotAnalyticError, ik_analytic, opw_from_model
from .._opw_model import wrap
from ..model import RobotModel

__all__ = ["ConfigurationBranch", "default_branch", "joint_box_branch", "reference_model", "sample_branch",
           "on_branch"]


@dataclass(frozen=True)
class ConfigurationBranch:
    """A configuration branch: closed-form branch ``index`` (name ``shoulder/elbow/wrist``; -1: the
    joint box alone, name ``joint box``), the joint ``box`` (n_joints, 2) [rad | mm] sampled, and
    ``margin_rad`` from the wrist and elbow singularities."""

    index: int
    box: np.ndarray
    margin_rad: float

    @property
    def name(self) -> str:
        return "joint box" if self.index < 0 else "/".join(BRANCHES[self.index])

    def contains(self, q, tol: float = 0.0) -> np.ndarray:
        """(N,) bool: joints ``q`` (N, n) inside the box (widened by ``tol``)."""
        q = np.atleast_2d(q)
        return np.all((q >= self.box[:, 0] - tol) & (q <= self.box[:, 1] + tol), axis=-1)


def reference_model(model: RobotModel) -> RobotModel:
    """The model whose closed-form solver labels branches: ``model`` itself if it is of the OPW class,
    else ``model`` with every beta parameter set to zero. Raises :class:`NotAnalyticError` (naming the
    reason) when neither has a closed form."""
    try:
        opw_from_model(model)
        return model
    except NotAnalyticError as exc:
        first = exc
    betas = {n: 0.0 for n in model.params.names if n.startswith("beta")}
    if betas:
        nominal = model.with_params(**betas)
        try:
            opw_from_model(nominal)
            return nominal
        except NotAnalyticError:
            pass
    raise NotAnalyticError(
        f"{model.name}: cannot label configuration branches: the model has no closed form ({first}), "
        "not even with its beta tilts set to zero; pass an explicit reference model, or define the branch "
        "by joint ranges (joint_box_branch)") from None


def default_branch(model: RobotModel, index: int = 0, max_abs_deg: float = 150.0,
                   margin_deg: float = 10.0) -> ConfigurationBranch:
    """Branch ``index`` of :data:`BRANCHES` with the joint box of the module docstring."""
    if not 0 <= index < len(BRANCHES):
        raise ValueError(f"branch index must be 0..{len(BRANCHES) - 1}, got {index}")
    return ConfigurationBranch(index, _capped_box(model, max_abs_deg), float(np.radians(margin_deg)))


def joint_box_branch(model: RobotModel, ranges: dict, max_abs_deg: float = 150.0) -> ConfigurationBranch:
    """A branch defined by the joint box alone (``index = -1``): ``ranges`` maps controller joint names
    to ``(low, high)`` [rad | mm], intersected with the limits and +-``max_abs_deg``."""
    box = _capped_box(model, max_abs_deg)
    for name, (lo, hi) in ranges.items():
        if name not in model.controller_joints:
            raise ValueError(f"{model.name}: no joint {name!r} (joints: {', '.join(model.controller_joints)})")
        j = model.controller_joints.index(name)
        box[j] = max(box[j, 0], float(lo)), min(box[j, 1], float(hi))
        if box[j, 1] <= box[j, 0]:
            raise ValueError(f"{model.name}: joint {name} range {lo:.4g}..{hi:.4g} is empty within its limits")
    return ConfigurationBranch(-1, box, 0.0)


def _capped_box(model: RobotModel, max_abs_deg: float) -> np.ndarray:
    box = np.array(model.limits, dtype=float, copy=True)
    rev = ~model.prismatic_joints
    cap = np.radians(max_abs_deg)
    box[rev, 0] = np.maximum(box[rev, 0], -cap)
    box[rev, 1] = np.minimum(box[rev, 1], cap)
    if np.any(~np.isfinite(box)) or np.any(box[:, 1] <= box[:, 0]):
        raise ValueError(f"{model.name}: joint box {np.degrees(box).round(1).tolist()} is empty or unbounded")
    return box


def on_branch(reference: RobotModel | None, q, branch: ConfigurationBranch) -> np.ndarray:
    """(N,) bool: joints ``q`` (N, 6) lie on ``branch`` of the ``reference`` model (its closed-form
    solver reproduces them in that branch, within the singularity margins and the box). A joint-box
    branch (``index = -1``, ``reference`` may be None) checks the box only."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if branch.index < 0:
        return branch.contains(q)
    if reference is None:
        raise ValueError(f"branch {branch.name} needs a closed-form reference model")
    q_all, valid = ik_analytic(reference, reference.fk(q))
    d = np.abs(wrap(q_all - q[:, None, :])).max(axis=-1)          # (N, 8)
    d = np.where(valid & np.isfinite(d), d, np.inf)
    ok = (np.argmin(d, axis=1) == branch.index) & (d.min(axis=1) < 1e-6)
    P = opw_from_model(reference)
    theta = P.opw_angles(q)
    s = np.sin(branch.margin_rad)
    gamma = wrap(theta[:, 2] + np.arctan2(P.a2, P.c3))           # 0: stretched elbow, +-pi: folded
    ok &= np.abs(np.sin(theta[:, 4])) >= s
    ok &= (np.abs(gamma) >= branch.margin_rad) & (np.abs(gamma) <= np.pi - branch.margin_rad)
    return ok & branch.contains(q)


def sample_branch(reference: RobotModel | None, branch: ConfigurationBranch, n: int, rng) -> np.ndarray:
    """``n`` joint vectors (n, 6), uniform in the branch's box, kept if :func:`on_branch`."""
    lo, hi = branch.box[:, 0], branch.box[:, 1]
    chunks, got = [], 0
    for _ in range(50):
        if got >= n:
            break
        q = rng.uniform(lo, hi, size=(max(4 * (n - got), 2000), len(lo)))
        q = q[on_branch(reference, q, branch)]
        chunks.append(q)
        got += len(q)
    if got < n:
        raise ValueError(f"branch {branch.name} is (nearly) empty inside the joint box "
                         f"{np.degrees(branch.box).round(1).tolist()} deg: found {got} of {n} samples")
    return np.concatenate(chunks)[:n]
