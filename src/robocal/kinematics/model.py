"""The robot model: named kinematic parameters, joint coupling, batched FK and Jacobians.

A :class:`RobotModel` is immutable (like a Pinocchio ``Model``): algorithms never change it;
identification returns a new model via :meth:`RobotModel.with_params`. Internally lengths are
millimetres and angles radians.

Joints: the *controller* joints ``q`` (what the robot controller reports, shape ``(N, n_ctrl)``)
map linearly to the *model* joints ``q_model = q @ coupling.T`` (``(N, n_model)``), which covers
direction signs (Kawasaki BX200L joint 1), FANUC's J2/J3 coupling and passive joints driven by
others (DLR Justin's torso). A revolute link's angle is ``theta = q_model + theta_0``; a prismatic
link's offset is ``d = q_model + d_0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..transforms import invert_transforms
from ._backend import kernel as _kernel
from ._kernel_loader import kernels as _kernels
from ._packing import pack_fused
from ._result_pool import empty as _pooled_empty
from ._threads import PARALLEL_MIN, run_ranges
from .links import (
    ANGLE_PARAMS,
    OP_RU,
    OP_RZ,
    OP_TU,
    OP_TZ,
    Link,
    elementary_transforms,
    link_operations,
    op_axis,
)

__all__ = ["RobotModel", "EndEffector", "ParameterTable"]

_empty44 = np.empty  # module-level aliases: fewer lookups on the single-call path
_F64 = np.dtype(np.float64)


def _fk_checked_range(kernel, q, ints, floats, e, out, links, bad, start, stop):
    """``kernel`` on ``q[start:stop]`` once those joints are checked finite; else ``start`` goes to
    ``bad`` and nothing is computed (a thread's share of :meth:`RobotModel.fk`; numpy's sum and the
    kernel both release the GIL)."""
    part = q[start:stop]
    with np.errstate(over="ignore", invalid="ignore"):  # a sum of huge finite values may overflow: look closer
        total = float(np.add.reduce(part, axis=None))
    if not math.isfinite(total) and not np.isfinite(part).all():
        bad.append(start)
        return
    kernel(q, ints, floats, e, out, links, start, stop)


@dataclass(frozen=True)
class EndEffector:
    """A frame carried by link ``link`` (index; ``-1`` = the base) at ``T_link_ee`` (4x4, mm)."""

    name: str
    link: int
    T_link_ee: np.ndarray


@dataclass(frozen=True)
class ParameterTable:
    """Named kinematic parameters: ``values`` (P,) in mm / rad, ``units``, ``free`` mask (P,)."""

    names: tuple
    values: np.ndarray
    units: tuple
    free: np.ndarray
    link_of: np.ndarray  # (P,) index of the link each parameter belongs to

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            import difflib

            close = difflib.get_close_matches(name, self.names, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise KeyError(f"unknown parameter {name!r}{hint}") from None

    def as_dict(self) -> dict:
        return dict(zip(self.names, self.values.tolist()))

    def __len__(self) -> int:
        return len(self.names)


def _rz_to(axis) -> np.ndarray:
    """A rotation (3, 3) whose z column is the unit ``axis``."""
    z = np.asarray(axis, dtype=float)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def _sparse_rows(coupling):
    """Compressed rows ``(ptr, idx, coef)`` of the coupling matrix (n_model, n_joints)."""
    ptr, idx, coef = [0], [], []
    for row in coupling:
        nz = np.flatnonzero(row)
        idx.extend(nz.tolist())
        coef.extend(row[nz].tolist())
        ptr.append(len(idx))
    return np.array(ptr, dtype=np.int64), np.array(idx, dtype=np.int64), np.array(coef, dtype=float)


def _link_pre_post(link):
    """A link's operations as ``(pre, post, motion)``: the fixed 4x4 transforms before and after
    its motion, with the motion canonicalized to Rz(q) or Tz(q) (``motion`` = the op code of the
    motion, None for a fixed link): ``motion(q + offset) = [Ru] Rz|Tz(q) . Rz|Tz(offset) [Ru^T]``."""
    pre, post, motion = np.eye(4), np.eye(4), None
    for code, pname, moves in link_operations(link):
        value = link.params[pname]
        if moves:
            motion = code
            canon = OP_RZ if code in (OP_RZ, OP_RU) else OP_TZ
            post = elementary_transforms(canon, value)
            if code in (OP_RU, OP_TU):
                Ru = np.eye(4)
                Ru[:3, :3] = _rz_to(link.axis)
                pre = pre @ Ru
                post = post @ invert_transforms(Ru)
            continue
        E = elementary_transforms(code, value, op_axis(code, link.axis))
        if motion is None:
            pre = pre @ E
        else:
            post = post @ E
    return pre, post, motion


#: Attributes of :class:`RobotModel` that :meth:`RobotModel._build_programs` sets (built on first use).
_PROGRAM_ATTRIBUTES = frozenset({
    "_op_code", "_op_axis", "_op_value", "_op_param", "_op_joint", "_op_link", "_link_parent", "_cpl", "_fused",
    "_fused_ints", "_fused_floats", "_one_q", "_no_links", "_ee_ancestors", "_root_affine", "_identity_root",
    "_target_cache",
})


class RobotModel:
    """Kinematic model of a serial or tree-shaped robot.

    Parameters
    ----------
    name, title, source: identification and provenance strings.
    kind: the model kind of its links (``dh``, ``dh_beta``, ``mdh``, ``urdf``).
    links: sequence of :class:`Link` in topological order (parents before children).
    controller_joints: names of the controller joints, length ``n_ctrl``.
    coupling: (n_model, n_ctrl) matrix, ``q_model = coupling @ q``; n_model = moving links.
    limits: (n_ctrl, 2) controller joint limits [rad | mm].
    T_world_base: (4, 4) robot base in the world (instrument) frame [mm].
    end_effectors: sequence of :class:`EndEffector`.
    """

    def __init__(self, *, name, kind, links, controller_joints, coupling, limits, T_world_base,
                 end_effectors, title="", source="", extra=None):
        self.name = name
        self.kind = kind
        self.title = title
        self.source = source
        self.extra = dict(extra or {})
        self.links = tuple(links)
        for k, link in enumerate(self.links):
            if not -1 <= link.parent < k:
                raise ValueError(f"link {link.name!r}: parent index {link.parent} must refer to an earlier link")
        self.moving = np.array([k for k, L in enumerate(self.links) if L.moves], dtype=np.int64)
        self.controller_joints = tuple(controller_joints)
        self.coupling = np.array(coupling, dtype=float, copy=True)
        n_m, n_c = len(self.moving), len(self.controller_joints)
        if self.coupling.shape != (n_m, n_c):
            raise ValueError(f"coupling: expected shape ({n_m}, {n_c}) (model x controller joints), got {self.coupling.shape}")
        self.limits = np.array(limits, dtype=float, copy=True).reshape(n_c, 2)
        self.T_world_base = np.array(T_world_base, dtype=float, copy=True)
        self.end_effectors = tuple(end_effectors)
        if not self.end_effectors:
            raise ValueError("a robot needs at least one end effector")
        for arr in (self.coupling, self.limits, self.T_world_base):
            arr.setflags(write=False)

        names, values, units, free, link_of = [], [], [], [], []
        for k, link in enumerate(self.links):
            for p, v in link.params.items():
                names.append(f"{p}{k + 1}")
                values.append(float(v))
                units.append("rad" if p in ANGLE_PARAMS else "mm")
                free.append(p not in link.fixed)
                link_of.append(k)
        vals = np.array(values)
        vals.setflags(write=False)
        fr = np.array(free, dtype=bool)
        fr.setflags(write=False)
        self.params = ParameterTable(tuple(names), vals, tuple(units), fr, np.array(link_of, dtype=np.int64))
        # the kernels' programs are built on first use (__getattr__): a model made only to be
        # converted or written (a calibrated robot's URDF takes three) never needs them

    def __getattr__(self, name):
        # called only for an attribute the instance lacks: the programs, until they are built
        if name in _PROGRAM_ATTRIBUTES and "params" in self.__dict__:
            self._build_programs()
            return self.__dict__[name]
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    # ------------------------------------------------------------------ construction helpers
    @property
    def n_joints(self) -> int:
        """Number of controller joints (columns of ``q``)."""
        return len(self.controller_joints)

    @property
    def prismatic_joints(self) -> np.ndarray:
        """(n_ctrl,) bool: the controller joint drives a prismatic model joint (its unit is mm)."""
        pris = np.array([self.links[k].joint_type == "prismatic" for k in self.moving], dtype=bool)
        return np.any((self.coupling != 0.0) & pris[:, None], axis=0)

    @property
    def n_model_joints(self) -> int:
        return len(self.moving)

    @property
    def is_serial(self) -> bool:
        return all(L.parent == k - 1 for k, L in enumerate(self.links))

    def end_effector_index(self, end_effector) -> int:
        if end_effector is None:
            return 0
        if isinstance(end_effector, (int, np.integer)):
            if not 0 <= end_effector < len(self.end_effectors):
                raise IndexError(f"end effector index {end_effector} out of range 0..{len(self.end_effectors) - 1}")
            return int(end_effector)
        for i, e in enumerate(self.end_effectors):
            if e.name == end_effector:
                return i
        raise KeyError(f"{self.name}: unknown end effector {end_effector!r}; have {[e.name for e in self.end_effectors]}")

    def replace(self, **changes) -> "RobotModel":
        """A copy with constructor arguments replaced (the model itself never changes)."""
        args = dict(name=self.name, kind=self.kind, links=self.links, controller_joints=self.controller_joints,
                    coupling=self.coupling, limits=self.limits, T_world_base=self.T_world_base,
                    end_effectors=self.end_effectors, title=self.title, source=self.source, extra=self.extra)
        args.update(changes)
        return RobotModel(**args)

    def with_params(self, values=None, **named) -> "RobotModel":
        """A new model with parameter values replaced: a full vector (P,) and/or ``name=value``."""
        new = self.params.values.copy() if values is None else np.array(values, dtype=float, copy=True)
        if new.shape != self.params.values.shape:
            raise ValueError(f"parameter vector: expected shape {self.params.values.shape}, got {new.shape}")
        for k, v in named.items():
            new[self.params.index(k)] = v
        links = []
        for k, link in enumerate(self.links):
            p = {name: float(new[self.params.index(f"{name}{k + 1}")]) for name in link.params}
            links.append(Link(link.name, link.joint_type, link.convention, p, link.parent, link.axis, link.fixed))
        return self.replace(links=links)

    def with_free(self, free) -> "RobotModel":
        """A new model whose link parameters' fixed sets follow the boolean mask ``free`` (P,)."""
        free = np.asarray(free, dtype=bool)
        links = []
        for k, link in enumerate(self.links):
            fixed = frozenset(n for n in link.params if not free[self.params.index(f"{n}{k + 1}")])
            links.append(Link(link.name, link.joint_type, link.convention, dict(link.params), link.parent,
                              link.axis, fixed))
        return self.replace(links=links)

    def _build_programs(self) -> None:
        """Compile the link tables into the arrays the numba kernels run on."""
        model_index = {int(k): m for m, k in enumerate(self.moving)}
        self._build_operation_program(model_index)
        self._cpl = _sparse_rows(self.coupling)
        self._build_fused_program(model_index)
        self._ee_ancestors = self._end_effector_ancestors()
        self._root_affine = self.T_world_base[:3].copy()
        self._identity_root = np.eye(4)[:3].copy()
        self._target_cache = {}

    def _build_operation_program(self, model_index: dict) -> None:
        """Operation program (Jacobians, reference FK): one row per elementary operation."""
        codes, axes, vals, pidx, joint, owner = [], [], [], [], [], []
        for k, link in enumerate(self.links):
            for code, pname, moves in link_operations(link):
                codes.append(code)
                axes.append(op_axis(code, link.axis))
                vals.append(link.params[pname])
                pidx.append(self.params.index(f"{pname}{k + 1}"))
                joint.append(model_index[k] if moves else -1)
                owner.append(k)
        self._op_code = np.array(codes, dtype=np.int64)
        self._op_axis = np.array(axes, dtype=float).reshape(-1, 3)
        self._op_value = np.array(vals, dtype=float)
        self._op_param = np.array(pidx, dtype=np.int64)
        self._op_joint = np.array(joint, dtype=np.int64)
        self._op_link = np.array(owner, dtype=np.int64)
        self._link_parent = np.array([L.parent for L in self.links], dtype=np.int64)

    def _build_fused_program(self, model_index: dict) -> None:
        """Fused program (FK fast path): per moving link the fixed transform ``K`` (3, 4) from the
        frame it hangs from to its motion, the motion canonicalized to Rz(q) or Tz(q), and the
        transform after it; per end effector its anchor and fixed transform."""
        n_m = len(self.moving)
        K = np.zeros((n_m, 3, 4))
        post_m = np.zeros((n_m, 3, 4))
        mparent = np.full(n_m, -1, dtype=np.int64)
        mtype = np.zeros(n_m, dtype=np.int64)
        ref = []  # per link: (moving index of the frame it hangs from or -1, 4x4 from that frame to the link frame)
        for k, link in enumerate(self.links):
            pre, post, motion = _link_pre_post(link)
            if link.parent < 0:
                anchor, T_from = -1, self.T_world_base
            else:
                anchor, T_from = ref[link.parent]
            if link.moves:
                m = model_index[k]
                K[m] = (T_from @ pre)[:3]
                mparent[m] = anchor
                mtype[m] = 0 if motion in (OP_RZ, OP_RU) else 1
                post_m[m] = post[:3]
                ref.append((m, post))
            else:
                ref.append((anchor, T_from @ pre @ post))
        E_ee = np.zeros((len(self.end_effectors), 3, 4))
        anchor_ee = np.zeros(len(self.end_effectors), dtype=np.int64)
        for e, ee in enumerate(self.end_effectors):
            if ee.link < 0:
                anchor, T_from = -1, self.T_world_base
            else:
                anchor, T_from = ref[ee.link]
            anchor_ee[e] = anchor
            E_ee[e] = (T_from @ np.asarray(ee.T_link_ee, dtype=float))[:3]
        # T_from already contains T_world_base for root-level links.
        self._fused = pack_fused(K, mparent, mtype, *self._cpl, anchor_ee, E_ee, post_m)
        self._fused_ints, self._fused_floats = self._fused
        self._one_q = (self.n_joints,)  # shape of one configuration (the single-pose fast path of fk)
        self._no_links = np.empty((0, n_m, 4, 4))  # fk_fused_into's "no link frames" argument

    def _end_effector_ancestors(self) -> np.ndarray:
        """(n_ee, n_links) bool: the links each end effector depends on, for Jacobian masking."""
        anc = np.zeros((len(self.end_effectors), len(self.links)), dtype=bool)
        for e, ee in enumerate(self.end_effectors):
            k = ee.link
            while k >= 0:
                anc[e, k] = True
                k = self.links[k].parent
        return anc

    # ------------------------------------------------------------------ joints
    def _as_joints(self, q) -> tuple[np.ndarray, bool]:
        q = np.asarray(q, dtype=float)
        single = q.ndim == 1
        q2 = q[None] if single else q
        if q2.ndim != 2 or q2.shape[1] != self.n_joints:
            raise ValueError(f"{self.name}: joints must have shape (N, {self.n_joints}) or ({self.n_joints},), got {q.shape}")
        if not math.isfinite(float(np.add.reduce(q2, axis=None))):  # one pass; NaN/inf make the sum non-finite
            if np.isfinite(q2).all():  # finite values whose sum overflows: fine
                return np.ascontiguousarray(q2), single
            r, c = np.argwhere(~np.isfinite(q2))[0]
            raise ValueError(f"{self.name}: pose {r}, joint {self.controller_joints[c]} is {q2[r, c]} (not a finite number)")
        return np.ascontiguousarray(q2), single

    def checked_joints(self, q) -> np.ndarray:
        """``q`` as a C-contiguous float64 (N, n_ctrl) array, checked for shape and finite values
        (ValueError naming the pose and joint otherwise): what ``q_checked=True`` promises."""
        return self._as_joints(q)[0]

    def model_joints(self, q) -> np.ndarray:
        """Model joint values (..., n_model) from controller joints (..., n_ctrl)."""
        return np.asarray(q, dtype=float) @ self.coupling.T

    def within_limits(self, q, tol: float = 1e-9) -> np.ndarray:
        """Boolean (N,) or scalar: every joint within its limits."""
        q = np.asarray(q, dtype=float)
        return np.all((q >= self.limits[:, 0] - tol) & (q <= self.limits[:, 1] + tol), axis=-1)

    # ------------------------------------------------------------------ forward kinematics
    def fk(self, q, end_effector=None, out=None) -> np.ndarray:
        """End-effector poses ``T_world_ee``.

        q: (N, n_ctrl) or (n_ctrl,) controller joints [rad | mm].
        Returns (N, 4, 4) [mm] (or (4, 4) for a single configuration) for the named end effector
        (default: the first, the flange of a single-chain robot). out: optional float64
        C-contiguous array of that shape to write into (returned); saves the allocation of a
        large batch. Without it, a result from 32 MiB up (262,144 poses) reuses the memory of the
        last such result dropped (:mod:`~robocal.kinematics._result_pool`; never memory a live
        array uses), so a loop of ``T = fk(q)`` runs near the speed of ``out=``. Batches of :data:`~robocal.kinematics._threads.PARALLEL_MIN` poses or more
        are shared between the cores.
        """
        if (out is None and end_effector is None and type(q) is np.ndarray and q.shape == self._one_q
                and q.dtype == _F64):
            pose = _empty44((4, 4))
            if _kernel("fk_fused_single_checked")(q, self._fused_ints, self._fused_floats, pose):
                return pose
        q_arr = np.asarray(q, dtype=float)
        big = q_arr.ndim == 2 and len(q_arr) >= PARALLEL_MIN and q_arr.shape[1] == self.n_joints
        # a large batch: its finite-value check runs in the threads, range by range (a serial pass
        # over q was ~12 % of a 2-thread batch); the error raised is the same
        q2, single = (np.ascontiguousarray(q_arr), False) if big else self._as_joints(q_arr)
        e = self.end_effector_index(end_effector)
        shape = (4, 4) if single else (len(q2), 4, 4)
        if out is None:
            # a large result reuses the memory of the last one dropped (no page faults), never shared
            out = _pooled_empty(shape) if big else np.empty(shape)
        elif (not isinstance(out, np.ndarray) or out.shape != shape or out.dtype != _F64
              or not out.flags.c_contiguous or not out.flags.writeable):
            raise ValueError(f"{self.name}: out must be a writeable C-contiguous float64 array of shape {shape}")
        fk_kernel = _kernel("fk_fused_into", len(q2))
        if not big:
            run_ranges(fk_kernel, len(q2), q2, self._fused_ints, self._fused_floats, e,
                       out.reshape(len(q2), 4, 4), self._no_links)
            return out
        bad = []
        run_ranges(_fk_checked_range, len(q2), fk_kernel, q2, self._fused_ints, self._fused_floats,
                   e, out, self._no_links, bad)
        if bad:
            self._as_joints(q2)  # raises, naming the first pose and joint that is not finite
        return out

    def fk_all(self, q) -> np.ndarray:
        """Poses of every end effector: (N, n_ee, 4, 4) [mm]."""
        q2, single = self._as_joints(q)
        if len(self.end_effectors) == 1:  # fk()'s kernel: one FK kernel compiled, not two
            out = self.fk(q2)[:, None]
        else:
            out, _ = _kernels.fk_fused(q2, *self._fused, False)
        return out[0] if single else out

    def link_frames(self, q) -> np.ndarray:
        """World poses of every moving link's frame, (N, n_model, 4, 4) [mm]."""
        q2, single = self._as_joints(q)
        links = np.empty((len(q2), len(self.moving), 4, 4))
        # fk()'s kernel, writing the link frames too: one FK kernel to compile, not two
        run_ranges(_kernel("fk_fused_into", 2 * len(q2)), len(q2), q2, self._fused_ints, self._fused_floats, 0,
                   np.empty((len(q2), 4, 4)), links)
        return links[0] if single else links

    def fk_single(self, q, out=None) -> np.ndarray:
        """Low-latency FK of one configuration: ``q`` float64 (n_ctrl,) -> (4, 4) pose [mm].

        First end effector only; no input checking beyond numba's typing (use :meth:`fk` for
        checked calls). Pass ``out`` (4, 4) float64 to reuse a buffer.
        """
        if out is None:
            out = _empty44((4, 4))
        _kernels.fk_fused_single(q, self._fused_ints, self._fused_floats, out)
        return out

    def fk_reference(self, q, end_effector=None) -> np.ndarray:
        """Forward kinematics by plain numpy products of the elementary operations.

        Slow and independent of the compiled kernels; used to check them.
        """
        q2, single = self._as_joints(q)
        qm = self.model_joints(q2)
        N = len(q2)
        frames = []
        for k, link in enumerate(self.links):
            T = np.broadcast_to(self.T_world_base, (N, 4, 4)) if link.parent < 0 else frames[link.parent]
            m = np.searchsorted(self.moving, k)
            for code, pname, moves in link_operations(link):
                value = np.full(N, link.params[pname]) + (qm[:, m] if moves else 0.0)
                T = T @ elementary_transforms(code, value, op_axis(code, link.axis))
            frames.append(T)
        ee = self.end_effectors[self.end_effector_index(end_effector)]
        base = np.broadcast_to(self.T_world_base, (N, 4, 4)) if ee.link < 0 else frames[ee.link]
        out = base @ ee.T_link_ee
        return out[0] if single else out

    # ------------------------------------------------------------------ Jacobians
    def twists(self, q):
        """Spatial twists (world frame, rows omega then v) of every parameter and model joint.

        Returns ``param_twists`` (N, 6, P), ``joint_twists`` (N, 6, n_model) and the link frames
        (N, n_links, 3, 4). The velocity of a world point p is ``omega x p + v``.
        """
        q2, _ = self._as_joints(q)
        return _kernel("op_twists", len(q2))(q2, self._op_link, self._op_code, self._op_axis, self._op_value,
                                  self._op_param, self._op_joint, self._link_parent, self._root_affine,
                                  *self._cpl, len(self.params), self.n_model_joints)

    def kinematics_with(self, q, params=None, T_world_base=None, end_effectors=None):
        """Forward kinematics and spatial twists with a parameter vector, without building a model.

        The hot path of calibration: ``params`` (P,) [mm | rad] replaces the model's values (the
        model itself is untouched); ``T_world_base`` (4, 4) replaces its base.
        Returns ``T`` (N, n_e, 4, 4) end-effector poses, ``param_twists`` (N, 6, P) and
        ``joint_twists`` (N, 6, n_model) in the world frame (rows omega, v), and ``masks`` (n_e, P)
        bool: which parameters move each end effector.
        """
        q2, _ = self._as_joints(q)
        values = self._op_value if params is None else np.asarray(params, dtype=float)[self._op_param]
        root = self._root_affine if T_world_base is None else np.ascontiguousarray(np.asarray(T_world_base, float)[:3])
        ptw, jtw, frames = _kernel("op_twists", len(q2))(q2, self._op_link, self._op_code, self._op_axis, values,
                                              self._op_param, self._op_joint, self._link_parent, root,
                                              *self._cpl, len(self.params), self.n_model_joints)
        ees = range(len(self.end_effectors)) if end_effectors is None else end_effectors
        N = len(q2)
        T = np.empty((N, len(ees), 4, 4))
        for i, e in enumerate(ees):
            ee = self.end_effectors[e]
            F = np.zeros((N, 4, 4))
            F[:, 3, 3] = 1.0
            F[:, :3] = root if ee.link < 0 else frames[:, ee.link]
            T[:, i] = F @ ee.T_link_ee
        masks = self._ee_ancestors[list(ees)][:, self.params.link_of]
        return T, ptw, jtw, masks

    def target_points(self, q, params, points_in_ee, ee_of_point, free_index, want_jacobian=True, root=None, *,
                      q_checked: bool = False):
        """Points carried by end effectors, in the base frame (no ``T_world_base``) or in the frame
        where the base sits at ``root`` (4, 4), with their derivatives w.r.t. the parameters
        ``free_index`` -- the calibration hot path, one kernel call.

        params (P,) [mm | rad]; points_in_ee (K, 3) [mm]; ee_of_point (K,) end-effector indices.
        Returns p (N, K, 3), R_base_ee (N, K, 3, 3), J (N, K, 3, len(free_index)). ``q_checked``:
        ``q`` is already a C-contiguous float64 (N, n_ctrl) array of finite values (a solver's
        fixed joints, checked once; skips ~10 us of checks per call).
        """
        q2 = q if q_checked else self._as_joints(q)[0]
        params = np.asarray(params, dtype=float)
        # the key as bytes: building tuples of Python ints cost ~15 us a call on the solver's hot path
        key = (np.asarray(ee_of_point, dtype=np.int64).tobytes(), np.asarray(free_index, dtype=np.int64).tobytes())
        cached = self._target_cache.get(key)
        if cached is None:
            K = len(ee_of_point)
            tl = np.empty(K, dtype=np.int64)
            tT = np.empty((K, 3, 4))
            anc = np.zeros((K, len(self.links)), dtype=np.bool_)
            for k, e in enumerate(ee_of_point):
                ee = self.end_effectors[e]
                tl[k] = ee.link
                tT[k] = ee.T_link_ee[:3]
                anc[k] = self._ee_ancestors[e]
            free_col = np.full(len(self.params), -1, dtype=np.int64)
            free_col[np.asarray(free_index, dtype=np.int64)] = np.arange(len(free_index))
            cached = self._target_cache[key] = (tl, tT, anc, free_col, len(free_index))
        tl, tT, anc, free_col, n_free = cached
        root3 = self._identity_root if root is None else np.ascontiguousarray(np.asarray(root, dtype=float)[:3])
        return _kernel("target_points", len(q2) * len(tl))(q2, self._op_link, self._op_code, self._op_axis, params[self._op_param],
                                      self._op_param, self._op_joint, self._link_parent, root3,
                                      *self._cpl, tl, tT, np.ascontiguousarray(points_in_ee, dtype=float).reshape(-1, 3),
                                      anc, free_col, n_free, bool(want_jacobian))

    def _ee_masks(self, e):
        anc = self._ee_ancestors[e]
        pmask = anc[self.params.link_of]
        jmask = anc[self.moving]
        return pmask, jmask

    def jacobian(self, q, end_effector=None) -> np.ndarray:
        """Geometric Jacobian w.r.t. controller joints, in the world frame.

        Returns (N, 6, n_ctrl) (or (6, n_ctrl)): rows 0-2 the velocity of the end-effector origin
        [mm per rad | mm per mm], rows 3-5 its angular velocity [rad per rad | rad per mm].
        """
        q2, single = self._as_joints(q)
        e = self.end_effector_index(end_effector)
        _, jtw, _ = self.twists(q2)
        T = self.fk(q2, e)
        J6 = _twists_to_pose_rows(jtw * self._ee_masks(e)[1], T[:, :3, 3])
        J = J6 @ self.coupling
        return J[0] if single else J

    def identification_jacobian(self, q, points=None, end_effector=None) -> np.ndarray:
        """Derivatives of measurements w.r.t. every kinematic parameter ((3-6) of METHODS.md).

        Without ``points``: pose Jacobian (N, 6, P): rows 0-2 the end-effector origin [mm per unit],
        rows 3-5 the small rotation of the end-effector frame (world frame) [rad per unit].
        With ``points`` (3,) or (k, 3) [mm] given in the end-effector frame: (N, 3, P) or
        (N, k, 3, P), the derivatives of those points' world coordinates.
        Units per column follow ``params.units`` (mm or rad).
        """
        q2, single = self._as_joints(q)
        e = self.end_effector_index(end_effector)
        ptw, _, _ = self.twists(q2)
        ptw = ptw * self._ee_masks(e)[0]
        T = self.fk(q2, e)
        if points is None:
            J = _twists_to_pose_rows(ptw, T[:, :3, 3])
        else:
            pts = np.asarray(points, dtype=float)
            world = (T[:, None, :3, :3] @ np.atleast_2d(pts)[None, :, :, None])[..., 0] + T[:, None, :3, 3]
            J = _twists_to_point_rows(ptw[:, None], world)
            if pts.ndim == 1:
                J = J[:, 0]
        return J[0] if single else J


def _twists_to_point_rows(tw, p):
    """Point derivatives omega x p + v; tw (..., 6, C), p (..., 3) -> (..., 3, C)."""
    w, v = tw[..., :3, :], tw[..., 3:, :]
    cross = np.stack([
        w[..., 1, :] * p[..., 2, None] - w[..., 2, :] * p[..., 1, None],
        w[..., 2, :] * p[..., 0, None] - w[..., 0, :] * p[..., 2, None],
        w[..., 0, :] * p[..., 1, None] - w[..., 1, :] * p[..., 0, None],
    ], axis=-2)
    return cross + v


def _twists_to_pose_rows(tw, p):
    """Rows (dp of origin p, omega): (..., 6, C)."""
    return np.concatenate([_twists_to_point_rows(tw, p), tw[..., :3, :]], axis=-2)
