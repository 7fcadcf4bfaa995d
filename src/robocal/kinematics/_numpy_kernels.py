"""The kinematics kernels in plain numpy, vectorised over poses: no compilation, no numba import.

Same arguments and results as their compiled counterparts in :mod:`robocal.kinematics._kernels`
(the same operation and fused programs, the same arithmetic up to rounding, ~1e-15 relative). A
small problem runs them instead of compiling or loading a kernel (:mod:`robocal.kinematics._backend`
decides): a compile costs ~1-2 s of CPU per kernel and loading numba ~0.1-0.4 s, while a numpy
evaluation of 100 poses takes well under a millisecond.
"""

from __future__ import annotations

import numpy as np

from .links import OP_RU, OP_RX, OP_RY, OP_RZ, OP_TU, OP_TX, OP_TZ

_ROTATIONS = (OP_RX, OP_RY, OP_RZ, OP_RU)


def _model_joints(q, n_model, cpl_ptr, cpl_idx, cpl_coef):
    """(N, n_model) model joints from controller joints q (N, n_ctrl) and the sparse coupling rows."""
    qm = np.zeros((q.shape[0], n_model))
    for m in range(n_model):
        for t in range(cpl_ptr[m], cpl_ptr[m + 1]):
            qm[:, m] += cpl_coef[t] * q[:, cpl_idx[t]]
    return qm


def _apply_op(M, code, value, ax):
    """Right-multiply the affine frames M (N, 3, 4) in place by one elementary operation;
    ``value`` a scalar or (N,) [mm | rad]."""
    if OP_TX <= code <= OP_TZ:
        M[:, :, 3] += (value[:, None] if np.ndim(value) else value) * M[:, :, code - OP_TX]
    elif code == OP_TU:
        d = M[:, :, :3] @ np.asarray(ax, dtype=float)
        M[:, :, 3] += (value[:, None] if np.ndim(value) else value) * d
    elif code == OP_RU:
        c, s = np.cos(value), np.sin(value)
        v = 1.0 - c
        x, y, z = ax[0], ax[1], ax[2]
        R = np.empty(np.shape(value) + (3, 3))
        R[..., 0, 0] = c + x * x * v
        R[..., 0, 1] = x * y * v - z * s
        R[..., 0, 2] = x * z * v + y * s
        R[..., 1, 0] = y * x * v + z * s
        R[..., 1, 1] = c + y * y * v
        R[..., 1, 2] = y * z * v - x * s
        R[..., 2, 0] = z * x * v - y * s
        R[..., 2, 1] = z * y * v + x * s
        R[..., 2, 2] = c + z * z * v
        M[:, :, :3] = M[:, :, :3] @ R
    else:  # rotation about a coordinate axis: columns j, k mix
        a = code - OP_RX
        j, k = (a + 1) % 3, (a + 2) % 3
        c, s = np.cos(value), np.sin(value)
        if np.ndim(value):
            c, s = c[:, None], s[:, None]
        mj = M[:, :, j].copy()
        mk = M[:, :, k]
        M[:, :, j] = c * mj + s * mk
        M[:, :, k] = c * mk - s * mj


def _op_twist(M, code, ax):
    """Spatial twists (N, 6) (omega, v) of an elementary operation acting at frames M (N, 3, 4)."""
    w = M[:, :, :3] @ np.asarray(ax, dtype=float)
    if code in _ROTATIONS:
        return np.concatenate([w, np.cross(M[:, :, 3], w)], axis=1)
    return np.concatenate([np.zeros_like(w), w], axis=1)


def _run_operations(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                    cpl_ptr, cpl_idx, cpl_coef, on_op):
    """Walk the operation program for all poses at once; ``on_op(t, M)`` is called before operation
    ``t`` acts on its link's frames M (N, 3, 4). Returns the link frames (n_links, N, 3, 4)."""
    N = q.shape[0]
    n_links = link_parent.shape[0]
    n_model = len(cpl_ptr) - 1
    qm = _model_joints(q, n_model, cpl_ptr, cpl_idx, cpl_coef)
    frames = np.empty((n_links, N, 3, 4))
    M = None
    cur = -1
    for t in range(op_code.shape[0]):
        L = int(op_link[t])
        if L != cur:
            if cur >= 0:
                frames[cur] = M
            cur = L
            p = link_parent[L]
            M = np.empty((N, 3, 4))
            M[:] = root if p < 0 else frames[p]
        value = op_value[t]
        jm = op_joint[t]
        if jm >= 0:
            value = value + qm[:, jm]
        on_op(t, M)
        _apply_op(M, int(op_code[t]), value, op_axis[t])
    if cur >= 0:
        frames[cur] = M
    return frames


def target_points(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                  cpl_ptr, cpl_idx, cpl_coef, target_link, target_T, target_p, target_anc, free_col, n_free, want_jac):
    """:func:`robocal.kinematics._kernels.target_points` in numpy (same arguments and results):
    p (N, K, 3), R (N, K, 3, 3), J (N, K, 3, n_free) (size 0 unless ``want_jac``)."""
    N = q.shape[0]
    K = target_link.shape[0]
    tw = np.zeros((n_free, N, 6))
    tw_link = np.full(n_free, -1, dtype=np.int64)

    def on_op(t, M):
        col = free_col[op_param[t]]
        if want_jac and col >= 0:
            tw_link[col] = op_link[t]
            tw[col] = _op_twist(M, int(op_code[t]), op_axis[t])

    frames = _run_operations(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                             cpl_ptr, cpl_idx, cpl_coef, on_op)
    pts = np.empty((N, K, 3))
    rot = np.empty((N, K, 3, 3))
    J = np.zeros((N if want_jac else 0, K, 3, n_free))
    w = np.ascontiguousarray(tw[:, :, :3].transpose(1, 2, 0))  # (N, 3, n_free)
    v = np.ascontiguousarray(tw[:, :, 3:].transpose(1, 2, 0))
    for k in range(K):
        L = target_link[k]
        F = np.broadcast_to(root, (N, 3, 4)) if L < 0 else frames[L]
        T = target_T[k]
        R = F[:, :, :3] @ T[:, :3]
        o = F[:, :, :3] @ T[:, 3] + F[:, :, 3]
        p = R @ target_p[k] + o
        pts[:, k] = p
        rot[:, k] = R
        if want_jac:
            cols = (tw_link >= 0) & target_anc[k, np.maximum(tw_link, 0)]
            if not cols.any():
                continue
            px, py, pz = p[:, 0:1], p[:, 1:2], p[:, 2:3]
            Jk = J[:, k]
            Jk[:, 0] = w[:, 1] * pz - w[:, 2] * py + v[:, 0]
            Jk[:, 1] = w[:, 2] * px - w[:, 0] * pz + v[:, 1]
            Jk[:, 2] = w[:, 0] * py - w[:, 1] * px + v[:, 2]
            Jk[:, :, ~cols] = 0.0
    return pts, rot, J


def op_twists(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
              cpl_ptr, cpl_idx, cpl_coef, n_params, n_model_joints):
    """:func:`robocal.kinematics._kernels.op_twists` in numpy (same arguments and results):
    ``param_twists`` (N, 6, n_params), ``joint_twists`` (N, 6, n_model_joints), ``frames``
    (N, n_links, 3, 4)."""
    N = q.shape[0]
    ptw = np.zeros((N, 6, n_params))
    jtw = np.zeros((N, 6, n_model_joints))

    def on_op(t, M):
        pi, jm = op_param[t], op_joint[t]
        if pi >= 0 or jm >= 0:
            tw = _op_twist(M, int(op_code[t]), op_axis[t])
            if pi >= 0:
                ptw[:, :, pi] = tw
            if jm >= 0:
                jtw[:, :, jm] = tw

    frames = _run_operations(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                             cpl_ptr, cpl_idx, cpl_coef, on_op)
    return ptw, jtw, np.ascontiguousarray(frames.transpose(1, 0, 2, 3))


def _unpack(ints, floats):
    n_m, n_e, nnz = int(ints[0]), int(ints[1]), int(ints[2])
    o = 3
    mparent = ints[o:o + n_m]
    o += n_m
    mtype = ints[o:o + n_m]
    o += n_m
    cpl_ptr = ints[o:o + n_m + 1]
    o += n_m + 1
    cpl_idx = ints[o:o + nnz]
    o += nnz
    ee_anchor = ints[o:o + n_e]
    f = 0
    K = floats[f:f + 12 * n_m].reshape((n_m, 3, 4))
    f += 12 * n_m
    E = floats[f:f + 12 * n_e].reshape((n_e, 3, 4))
    f += 12 * n_e
    post = floats[f:f + 12 * n_m].reshape((n_m, 3, 4))
    f += 12 * n_m
    cpl_coef = floats[f:f + nnz]
    return n_m, n_e, mparent, mtype, cpl_ptr, cpl_idx, ee_anchor, K, E, post, cpl_coef


def _compose(G, A):
    """G (N, 3, 4) composed with the constant affine A (3, 4): (N, 3, 4)."""
    out = G[:, :, :3] @ A
    out[:, :, 3] += G[:, :, 3]
    return out


def _write_poses(dst, G):
    dst[:, :3] = G
    dst[:, 3, :3] = 0.0
    dst[:, 3, 3] = 1.0


def fk_fused_into(q, ints, floats, e, out, links, start, stop):
    """:func:`robocal.kinematics._kernels.fk_fused_into` in numpy: poses of end effector ``e`` for
    ``q[start:stop]`` into ``out[start:stop]`` (N, 4, 4) [mm], and the moving links' frames into
    ``links[start:stop]`` unless ``links`` has no rows."""
    n_m, n_e, mparent, mtype, cpl_ptr, cpl_idx, ee_anchor, K, E, post, cpl_coef = _unpack(ints, floats)
    qs = q[start:stop]
    qm = _model_joints(qs, n_m, cpl_ptr, cpl_idx, cpl_coef)
    G = []
    for m in range(n_m):
        p = mparent[m]
        tmp = np.broadcast_to(K[m], (len(qs), 3, 4)).copy() if p < 0 else _compose(G[p], K[m])
        if mtype[m] == 0:
            c, s = np.cos(qm[:, m])[:, None], np.sin(qm[:, m])[:, None]
            x0 = tmp[:, :, 0].copy()
            x1 = tmp[:, :, 1]
            tmp[:, :, 0] = c * x0 + s * x1
            tmp[:, :, 1] = c * x1 - s * x0
        else:
            tmp[:, :, 3] += qm[:, m, None] * tmp[:, :, 2]
        G.append(tmp)
    a = ee_anchor[e]
    _write_poses(out[start:stop], np.broadcast_to(E[e], (len(qs), 3, 4)) if a < 0 else _compose(G[a], E[e]))
    if links.shape[0] > 0:
        for m in range(n_m):
            _write_poses(links[start:stop, m], _compose(G[m], post[m]))


def fk_fused_single_checked(q, ints, floats, out):
    """:func:`robocal.kinematics._kernels.fk_fused_single_checked` in numpy: False (nothing
    written) unless every value of ``q`` (n_ctrl,) is finite, else the first end effector's pose
    written into ``out`` (4, 4)."""
    if not np.all(np.isfinite(q)):
        return False
    fk_fused_into(q[None], ints, floats, 0, out[None], np.empty((0, 1, 4, 4)), 0, 1)
    return True
