"""The kinematics kernels in plain numpy, vectorised over poses: no compilation, no numba import.

Same arguments and results as their compiled counterparts in :mod:`robocal.kinematics._kernels`
(the same operation and fused programs, the same arithmetic up to rounding, ~1e-15 relative). A
process runs them unless compiled code pays for its load (:mod:`robocal.kinematics._backend`
decides): loading numba costs ~0.4 s and ~105 MiB, a compile 1-2 s of CPU per kernel, while a numpy
evaluation of 100 poses takes well under a millisecond and a big batch (thousands of poses, in blocks
of :data:`BLOCK` with working arrays reused from block to block inside :func:`reused_work`) runs
within 1.1-2x of the compiled kernels (the forward kinematics ~7x).
"""

from __future__ import annotations

import threading
from contextlib import contextmanager

import numpy as np

from .links import OP_RU, OP_RX, OP_RY, OP_RZ, OP_TU, OP_TX, OP_TZ

_ROTATIONS = (OP_RX, OP_RY, OP_RZ, OP_RU)
#: Poses per block of the batched kernels (working arrays of a few MB).
BLOCK = 4096
_scratch = threading.local()


@contextmanager
def reused_work():
    """Within this context the numpy kernels called from this thread keep their working arrays
    between calls (a loop over blocks of a big batch: a fresh multi-MB array costs its page faults,
    ~0.3 ms per MB, on every call); they are freed when the outermost context exits."""
    state = _scratch.__dict__
    outer = "bufs" not in state
    if outer:
        state["bufs"] = {}
    try:
        yield
    finally:
        if outer:
            del state["bufs"]


def _work(name, shape):
    """A float working array of ``shape`` (uninitialised): the one kept under ``name`` inside
    :func:`reused_work`, else a fresh one. A kernel returns copies of it, never it."""
    bufs = _scratch.__dict__.get("bufs")
    if bufs is None:
        return np.empty(shape)
    size = int(np.prod(shape))
    flat = bufs.get(name)
    if flat is None or flat.size < size:
        flat = bufs[name] = np.empty(size)
    return flat[:size].reshape(shape)


def _model_joints(q, n_model, cpl_ptr, cpl_idx, cpl_coef):
    """(N, n_model) model joints from controller joints q (N, n_ctrl) and the sparse coupling rows."""
    qm = np.zeros((q.shape[0], n_model))
    for m in range(n_model):
        for t in range(cpl_ptr[m], cpl_ptr[m + 1]):
            qm[:, m] += cpl_coef[t] * q[:, cpl_idx[t]]
    return qm


def _apply_op(M, code, value, ax):
    """Right-multiply the affine frames M (3, 4, N) (component-major: ``M[i, j]`` is a contiguous
    (N,) row) in place by one elementary operation; ``value`` a scalar or (N,) [mm | rad]."""
    if OP_TX <= code <= OP_TZ:
        M[:, 3] += value * M[:, code - OP_TX]
    elif code == OP_TU:
        M[:, 3] += value * (ax[0] * M[:, 0] + ax[1] * M[:, 1] + ax[2] * M[:, 2])
    elif code == OP_RU:
        c, s = np.cos(value), np.sin(value)
        v = 1.0 - c
        x, y, z = ax[0], ax[1], ax[2]
        R = ((c + x * x * v, x * y * v - z * s, x * z * v + y * s),
             (y * x * v + z * s, c + y * y * v, y * z * v - x * s),
             (z * x * v - y * s, z * y * v + x * s, c + z * z * v))
        m0, m1, m2 = M[:, 0].copy(), M[:, 1].copy(), M[:, 2].copy()
        for col in range(3):
            M[:, col] = m0 * R[0][col] + m1 * R[1][col] + m2 * R[2][col]
    else:  # rotation about a coordinate axis: columns j, k mix
        a = code - OP_RX
        j, k = (a + 1) % 3, (a + 2) % 3
        c, s = np.cos(value), np.sin(value)
        mj = M[:, j].copy()
        M[:, j] *= c
        M[:, j] += s * M[:, k]
        M[:, k] *= c
        M[:, k] -= s * mj


def _op_twist(M, code, ax, w_out, v_out):
    """Spatial twist (omega into ``w_out``, v into ``v_out``, each (3, N)) of an elementary
    operation acting at frames M (3, 4, N)."""
    np.multiply(M[:, 0], ax[0], out=w_out)
    w_out += ax[1] * M[:, 1]
    w_out += ax[2] * M[:, 2]
    if code in _ROTATIONS:
        o = M[:, 3]
        v_out[0] = o[1] * w_out[2] - o[2] * w_out[1]
        v_out[1] = o[2] * w_out[0] - o[0] * w_out[2]
        v_out[2] = o[0] * w_out[1] - o[1] * w_out[0]
    else:
        v_out[...] = w_out
        w_out[...] = 0.0


def _run_operations(q, op_link, op_code, op_axis, op_value, op_joint, link_parent, root,
                    cpl_ptr, cpl_idx, cpl_coef, on_op, reuse=False):
    """Walk the operation program for all poses at once; ``on_op(t, M)`` is called before operation
    ``t`` acts on its link's frames M (3, 4, N). Returns the link frames (n_links, 3, 4, N) (a
    reused working array when ``reuse``)."""
    N = q.shape[0]
    n_links = link_parent.shape[0]
    qm = _model_joints(q, len(cpl_ptr) - 1, cpl_ptr, cpl_idx, cpl_coef).T.copy()  # (n_model, N)
    frames = _work("frames", (n_links, 3, 4, N)) if reuse else np.empty((n_links, 3, 4, N))
    root_cols = np.asarray(root, dtype=float)[:, :, None]
    M = None
    cur = -1
    for t in range(op_code.shape[0]):
        L = int(op_link[t])
        if L != cur:
            cur = L
            p = link_parent[L]
            M = frames[L]
            M[...] = root_cols if p < 0 else frames[p]
        value = op_value[t]
        jm = op_joint[t]
        if jm >= 0:
            value = value + qm[jm]
        on_op(t, M)
        _apply_op(M, int(op_code[t]), value, op_axis[t])
    return frames


def _affine_cols(F, T):
    """F (3, 4, N) composed with the constant affine T (3, 4): rotation (3, 3, N), origin (3, N)."""
    R = np.einsum("irn,rc->icn", F[:, :3], T[:, :3])
    o = np.einsum("irn,r->in", F[:, :3], T[:, 3]) + F[:, 3]
    return R, o


def target_points(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                  cpl_ptr, cpl_idx, cpl_coef, target_link, target_T, target_p, target_anc, free_col, n_free, want_jac):
    """:func:`robocal.kinematics._kernels.target_points` in numpy (same arguments and results):
    p (N, K, 3), R (N, K, 3, 3), J (N, K, 3, n_free) (size 0 unless ``want_jac``). Runs in blocks of
    :data:`BLOCK` poses (the working arrays stay small on a big campaign)."""
    N = q.shape[0]
    args = (op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root, cpl_ptr, cpl_idx, cpl_coef,
            target_link, target_T, target_p, target_anc, free_col, n_free, want_jac)
    if N <= BLOCK:
        return _target_points_block(q, *args)
    K = target_link.shape[0]
    pts = np.empty((N, K, 3))
    rot = np.empty((N, K, 3, 3))
    J = np.empty((N if want_jac else 0, K, 3, n_free))
    with reused_work():
        for first in range(0, N, BLOCK):
            last = min(first + BLOCK, N)
            p, R, Jb = _target_points_block(q[first:last], *args)
            pts[first:last], rot[first:last] = p, R
            if want_jac:
                J[first:last] = Jb
    return pts, rot, J


def _axis_into(M, ax, out):
    """out (3, N) = M[:, :3] @ ax: the direction of the unit axis ``ax`` (3,) of frames M (3, 4, N);
    a coordinate axis is one column (copied), any other the sum of its components."""
    nz = [i for i in range(3) if ax[i] != 0.0]
    if len(nz) == 1 and ax[nz[0]] == 1.0:
        out[...] = M[:, nz[0]]
        return
    np.multiply(M[:, 0], ax[0], out=out)
    out += ax[1] * M[:, 1]
    out += ax[2] * M[:, 2]


def _target_points_block(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                         cpl_ptr, cpl_idx, cpl_coef, target_link, target_T, target_p, target_anc, free_col, n_free,
                         want_jac):
    N = q.shape[0]
    K = target_link.shape[0]
    # per free column, recorded where its operation acts: the axis direction w (3, N) and, for a
    # rotation, a point o on the axis (3, N); a point p then moves by w x (p - o) per rad (rotation)
    # or by w per mm (translation), the same derivative as the twist form w x p + o x w
    axes = _work("axes", (3, n_free, N)) if want_jac else None
    origins = _work("origins", (3, n_free, N)) if want_jac else None
    tw_link = np.full(n_free, -1, dtype=np.int64)
    rotation = np.zeros(n_free, dtype=np.bool_)

    def on_op(t, M):
        col = free_col[op_param[t]]
        if want_jac and col >= 0:
            tw_link[col] = op_link[t]
            _axis_into(M, op_axis[t], axes[:, col])
            if int(op_code[t]) in _ROTATIONS:
                rotation[col] = True
                origins[:, col] = M[:, 3]

    frames = _run_operations(q, op_link, op_code, op_axis, op_value, op_joint, link_parent, root,
                             cpl_ptr, cpl_idx, cpl_coef, on_op, reuse=True)
    pts = np.empty((N, K, 3))
    rot = np.empty((N, K, 3, 3))
    J = np.empty((N if want_jac else 0, K, 3, n_free))
    root_cols = np.broadcast_to(np.asarray(root, dtype=float)[:, :, None], (3, 4, N))
    Jt = _work("jac", (3, n_free, N)) if want_jac else None  # one target's Jacobian, pose index last
    for k in range(K):
        L = target_link[k]
        R, o = _affine_cols(root_cols if L < 0 else frames[L], target_T[k])
        p = np.einsum("icn,c->in", R, target_p[k]) + o
        pts[:, k] = p.T
        rot[:, k] = R.transpose(2, 0, 1)
        if not want_jac:
            continue
        moves = (tw_link >= 0) & target_anc[k, np.maximum(tw_link, 0)]
        if not moves.all():
            Jt[:] = 0.0
        rc = np.flatnonzero(moves & rotation)
        tc = np.flatnonzero(moves & ~rotation)
        if len(tc):
            Jt[:, tc] = axes[:, tc]
        if len(rc):
            every = len(rc) == n_free
            w = axes if every else axes[:, rc]
            # p - o, in place when no other target needs the origins
            d = np.subtract(p[:, None, :], origins if every else origins[:, rc],
                            out=origins if every and K == 1 else _work("arm", (3, len(rc), N)))
            tmp = _work("cross", (len(rc), N))
            for i in range(3):
                j, m = (i + 1) % 3, (i + 2) % 3
                dst = Jt[i] if every else tmp
                np.multiply(w[j], d[m], out=dst)
                dst -= w[m] * d[j]
                if not every:
                    Jt[i, rc] = dst
        J[:, k] = Jt.transpose(2, 0, 1)
    return pts, rot, J


def op_twists(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
              cpl_ptr, cpl_idx, cpl_coef, n_params, n_model_joints):
    """:func:`robocal.kinematics._kernels.op_twists` in numpy (same arguments and results):
    ``param_twists`` (N, 6, n_params), ``joint_twists`` (N, 6, n_model_joints), ``frames``
    (N, n_links, 3, 4)."""
    N = q.shape[0]
    ptw = np.zeros((n_params, 2, 3, N))
    jtw = np.zeros((n_model_joints, 2, 3, N))

    def on_op(t, M):
        pi, jm = op_param[t], op_joint[t]
        if pi >= 0 or jm >= 0:
            tw = ptw[pi] if pi >= 0 else jtw[jm]
            _op_twist(M, int(op_code[t]), op_axis[t], tw[0], tw[1])
            if pi >= 0 and jm >= 0:
                jtw[jm] = tw

    frames = _run_operations(q, op_link, op_code, op_axis, op_value, op_joint, link_parent, root,
                             cpl_ptr, cpl_idx, cpl_coef, on_op)
    return (np.ascontiguousarray(ptw.reshape(n_params, 6, N).transpose(2, 1, 0)),
            np.ascontiguousarray(jtw.reshape(n_model_joints, 6, N).transpose(2, 1, 0)),
            np.ascontiguousarray(frames.transpose(3, 0, 1, 2)))


def _unpack(ints, floats):
    # the same layout as robocal.kinematics._kernels._unpack (robocal.kinematics._packing writes it);
    # kept here so that this module runs without importing numba (the point of the numpy kernels)
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


def _compose(G, A, name):
    """Frames G (4, 3, N) (column-major: ``G[c, i]`` is row i of column c, a contiguous (N,) row)
    composed with the constant affine A (3, 4): (4, 3, N), a working array ``name``. One matrix
    product [A; 0 0 0 1]^T (4, 4) @ G (4, 3N)."""
    A4 = np.zeros((4, 4))
    A4[:3] = A
    A4[3, 3] = 1.0
    out = _work(name, G.shape)
    np.matmul(A4.T, G.reshape(4, -1), out=out.reshape(4, -1))
    return out


def _write_poses(dst, G):
    """dst (N, 4, 4) = the column-major frames G (4, 3, N) as homogeneous poses."""
    dst[:, :3] = G.transpose(2, 1, 0)
    dst[:, 3, :3] = 0.0
    dst[:, 3, 3] = 1.0


def fk_fused_into(q, ints, floats, e, out, links, start, stop):
    """:func:`robocal.kinematics._kernels.fk_fused_into` in numpy: poses of end effector ``e`` for
    ``q[start:stop]`` into ``out[start:stop]`` (N, 4, 4) [mm], and the moving links' frames into
    ``links[start:stop]`` unless ``links`` has no rows."""
    if stop - start > BLOCK:  # in blocks: the working arrays stay small on a big batch (and are reused)
        with reused_work():
            for first in range(start, stop, BLOCK):
                fk_fused_into(q, ints, floats, e, out, links, first, min(first + BLOCK, stop))
        return
    n_m, n_e, mparent, mtype, cpl_ptr, cpl_idx, ee_anchor, K, E, post, cpl_coef = _unpack(ints, floats)
    qs = q[start:stop]
    N = len(qs)
    qm = _model_joints(qs, n_m, cpl_ptr, cpl_idx, cpl_coef).T.copy()  # (n_m, N)
    G = []  # each moving link's frames, column-major (4, 3, N): a column's rows are contiguous
    for m in range(n_m):
        p = mparent[m]
        if p < 0:
            tmp = _work(f"link{m}", (4, 3, N))
            tmp[...] = K[m].T[:, :, None]
        else:
            tmp = _compose(G[p], K[m], f"link{m}")
        if mtype[m] == 0:
            c, s = np.cos(qm[m]), np.sin(qm[m])
            x0 = tmp[0].copy()
            tmp[0] *= c
            tmp[0] += s * tmp[1]
            tmp[1] *= c
            tmp[1] -= s * x0
        else:
            tmp[3] += qm[m] * tmp[2]
        G.append(tmp)
    a = ee_anchor[e]
    _write_poses(out[start:stop], np.broadcast_to(E[e].T[:, :, None], (4, 3, N)) if a < 0 else _compose(G[a], E[e], "pose"))
    if links.shape[0] > 0:
        for m in range(n_m):
            _write_poses(links[start:stop, m], _compose(G[m], post[m], "pose"))


def fk_fused_single_checked(q, ints, floats, out):
    """:func:`robocal.kinematics._kernels.fk_fused_single_checked` in numpy: False (nothing
    written) unless every value of ``q`` (n_ctrl,) is finite, else the first end effector's pose
    written into ``out`` (4, 4)."""
    if not np.all(np.isfinite(q)):
        return False
    fk_fused_into(q[None], ints, floats, 0, out[None], np.empty((0, 1, 4, 4)), 0, 1)
    return True
