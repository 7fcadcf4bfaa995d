"""Compiled (numba) Levenberg-Marquardt for point-only calibrations: normal equations accumulated
pose by pose from the kinematic program, and the whole damped Gauss-Newton loop, in machine code.

The driver is :mod:`robocal.calib._lm_compiled`; the iteration, its damping, line search and stop
rules are those of :class:`robocal.calib._iterate.DampedGaussNewton` (method ``"lm"``, linear loss,
no prior), written out here so that no Python runs between the first evaluation and the stop.

Per evaluation: the cosines and sines of the operations' parameter values once; then the poses in
blocks of 64, every step a loop over the block's poses (which vectorizes): the link frames by the
operation program (a joint's rotation by the angle-sum formula from the pose's joint cosines and
sines, computed once per solve, instead of a sine and cosine per operation and pose), the twist of
every free geometry parameter where it acts (as ``_op_twist`` of the kinematics kernels; an
axis-aligned operation's direction read off the frame), each measured point, its weighted residual
and its three Jacobian rows (geometry from the twists, the base frame's left perturbation
``w x p + v``, the target point's end-effector orientation) in a block buffer, added to ``J^T J``
(upper triangle) and ``J^T r`` by dot products over the block. J is never stored.

One type specialisation of each compiled function; scratch arrays come from the caller (no
allocation inside).
"""

from __future__ import annotations

import math

import numpy as np

from numba import njit

from ..kinematics.links import OP_RU, OP_RX, OP_TU, OP_TX, OP_TY, OP_TZ

_CACHE = True

#: stop codes of :func:`lm_points` (the driver turns them into the Python loop's reasons)
MAX_ITERATIONS, GRADIENT_ZERO, STATIONARY, NOT_AT_MINIMUM, FTOL, CHI2, XTOL = 0, 1, 2, 3, 4, 5, 6
#: trial steps per iteration before "no step reduces the cost" (robocal.calib._iterate's line search)
_LINE_SEARCH_TRIES = 30


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def _evaluate(ip, op_axis, qm, cq, sq, tT, gmove, measured, row_of, w, params, base, pts_ee, want_jac,
              r, JtJ, Jtr, fw, Jb):
    """Cost 0.5 r.r of the weighted residuals r (M,) = w (measured - predicted), written into r, and
    with ``want_jac`` J^T J (n, n) and J^T r (n,) of the weighted prediction Jacobian J.

    Blocks of B poses (B = Jb.shape[1] // (3 K)) at a time, every step a loop over the block's poses
    (which vectorizes): the frames (12 components x B), the twists, the points, their residuals and
    Jacobian rows. ip: the int program, rows ``op_link, op_code, op_param, op_joint`` (n_ops,) padded
    to one width, then ``link_parent``, ``target_link`` (K,), ``free_col`` (P,), ``fcol`` (6,: column
    of each base-frame variable or -1), ``tcol`` (3K,: column of each target coordinate or -1),
    ``[n_links, n_geometry_columns]``, the geometry columns, the column of each operation's parameter
    (n_ops,) or -1 -- see :class:`robocal.calib._lm_compiled._Packed`; qm, cq, sq (n_model, N): the
    model joints, their cosines and sines; gmove (K, n): geometry column c moves point k; row_of
    (N, K): the first residual row of each measured point, -1 where not measured; fw: float scratch;
    Jb (n, 3 K B): the buffer of a block's unweighted Jacobian rows, viewed as (n, 3 K nb) for a
    block of nb poses, a column per row (segment 3 k + i of nb columns: coordinate i of point k),
    added to J^T J and J^T r by :func:`_accumulate`.
    """
    n_ops = op_axis.shape[0]
    op_link, op_code, op_joint = ip[0], ip[1], ip[3]
    link_parent, target_link, fcol, tcol = ip[4], ip[5], ip[7], ip[8]
    n_links, ng = int(ip[9, 0]), int(ip[9, 1])
    gcols, op_col = ip[10], ip[11]
    op_param = ip[2]
    N, K = measured.shape[0], measured.shape[1]
    n = Jtr.shape[0]
    B = Jb.shape[1] // (3 * K)
    o = 0
    val = fw[o:o + n_ops]
    o += n_ops
    cv = fw[o:o + n_ops]
    o += n_ops
    sv = fw[o:o + n_ops]
    o += n_ops
    frames = fw[o:o + 12 * B * n_links].reshape((n_links, 12, B))
    o += 12 * B * n_links
    M = fw[o:o + 12 * B].reshape((12, B))
    o += 12 * B
    T = fw[o:o + 12 * B].reshape((12, B))
    o += 12 * B
    tw = fw[o:o + 6 * B * n].reshape((n, 6, B))
    o += 6 * B * n
    rb = fw[o:o + 3 * K * B]
    o += 3 * K * B
    cb = fw[o:o + B]
    o += B
    sb = fw[o:o + B]
    for t in range(n_ops):
        v = params[op_param[t]]
        val[t] = v
        cv[t] = math.cos(v)
        sv[t] = math.sin(v)
    if want_jac:
        for i in range(n):
            Jtr[i] = 0.0
            for j in range(n):
                JtJ[i, j] = 0.0
    cost2 = 0.0
    Jflat = Jb.ravel()
    for p0 in range(0, N, B):
        nb = min(B, N - p0)
        W = 3 * K * nb  # the block's rows: segment 3 k + i of nb columns (a last block may be short)
        Jbv = Jflat[:n * W].reshape((n, W))
        cur = -1
        for t in range(n_ops):
            L = op_link[t]
            if L != cur:
                if cur >= 0:
                    for e in range(12):
                        for p in range(nb):
                            frames[cur, e, p] = M[e, p]
                cur = L
                par = link_parent[L]
                for e in range(12):
                    if par < 0:
                        b0 = base[e // 4, e % 4]
                        for p in range(nb):
                            M[e, p] = b0
                    else:
                        for p in range(nb):
                            M[e, p] = frames[par, e, p]
            code = op_code[t]
            jm = op_joint[t]
            ax = op_axis[t]
            col = op_col[t]
            if want_jac and col >= 0:  # the operation's spatial twist (omega, v) at M
                for p in range(nb):
                    if code < OP_RU:  # about / along a coordinate axis: its direction is a column of M
                        ia = code % 3
                        w0, w1, w2 = M[ia, p], M[4 + ia, p], M[8 + ia, p]
                    else:
                        w0 = M[0, p] * ax[0] + M[1, p] * ax[1] + M[2, p] * ax[2]
                        w1 = M[4, p] * ax[0] + M[5, p] * ax[1] + M[6, p] * ax[2]
                        w2 = M[8, p] * ax[0] + M[9, p] * ax[1] + M[10, p] * ax[2]
                    if code < OP_TX or code == OP_RU:  # a rotation: v = o x omega
                        ox, oy, oz = M[3, p], M[7, p], M[11, p]
                        tw[col, 0, p] = w0
                        tw[col, 1, p] = w1
                        tw[col, 2, p] = w2
                        tw[col, 3, p] = oy * w2 - oz * w1
                        tw[col, 4, p] = oz * w0 - ox * w2
                        tw[col, 5, p] = ox * w1 - oy * w0
                    else:
                        tw[col, 0, p] = 0.0
                        tw[col, 1, p] = 0.0
                        tw[col, 2, p] = 0.0
                        tw[col, 3, p] = w0
                        tw[col, 4, p] = w1
                        tw[col, 5, p] = w2
            if code == OP_TX or code == OP_TY or code == OP_TZ or code == OP_TU:
                for p in range(nb):  # the length, with a prismatic joint's travel
                    cb[p] = val[t] + (qm[jm, p0 + p] if jm >= 0 else 0.0)
                if code == OP_TU:
                    for i in range(3):
                        for p in range(nb):
                            M[4 * i + 3, p] += cb[p] * (M[4 * i, p] * ax[0] + M[4 * i + 1, p] * ax[1]
                                                        + M[4 * i + 2, p] * ax[2])
                else:
                    k = code - OP_TX
                    for i in range(3):
                        for p in range(nb):
                            M[4 * i + 3, p] += cb[p] * M[4 * i + k, p]
                continue
            c, s = cv[t], sv[t]
            if jm >= 0:  # the joint's angle added: cos(a + q), sin(a + q) from the pose's cos q, sin q
                for p in range(nb):
                    cj = cq[jm, p0 + p]
                    sj = sq[jm, p0 + p]
                    cb[p] = c * cj - s * sj
                    sb[p] = s * cj + c * sj
            else:
                for p in range(nb):
                    cb[p] = c
                    sb[p] = s
            if code == OP_RU:
                x, y, z = ax[0], ax[1], ax[2]
                for i in range(3):
                    for p in range(nb):
                        cc = cb[p]
                        ss = sb[p]
                        vv = 1.0 - cc
                        m0, m1, m2 = M[4 * i, p], M[4 * i + 1, p], M[4 * i + 2, p]
                        M[4 * i, p] = (m0 * (cc + x * x * vv) + m1 * (y * x * vv + z * ss)
                                       + m2 * (z * x * vv - y * ss))
                        M[4 * i + 1, p] = (m0 * (x * y * vv - z * ss) + m1 * (cc + y * y * vv)
                                           + m2 * (z * y * vv + x * ss))
                        M[4 * i + 2, p] = (m0 * (x * z * vv + y * ss) + m1 * (y * z * vv - x * ss)
                                           + m2 * (cc + z * z * vv))
            else:  # about a coordinate axis: columns j, k mix
                a = code - OP_RX
                j = (a + 1) % 3
                k = (a + 2) % 3
                for i in range(3):
                    for p in range(nb):
                        mj = M[4 * i + j, p]
                        mk = M[4 * i + k, p]
                        M[4 * i + j, p] = cb[p] * mj + sb[p] * mk
                        M[4 * i + k, p] = cb[p] * mk - sb[p] * mj
        if cur >= 0:
            for e in range(12):
                for p in range(nb):
                    frames[cur, e, p] = M[e, p]
        for k in range(K):
            Lk = target_link[k]
            # T = F tT[k], F the carrying link's frame (or the base), per pose
            for i in range(3):
                for jj in range(4):
                    t0, t1, t2 = tT[k, 0, jj], tT[k, 1, jj], tT[k, 2, jj]
                    extra = 1.0 if jj == 3 else 0.0
                    if Lk < 0:
                        v = base[i, 0] * t0 + base[i, 1] * t1 + base[i, 2] * t2 + base[i, 3] * extra
                        for p in range(nb):
                            T[4 * i + jj, p] = v
                    else:
                        for p in range(nb):
                            T[4 * i + jj, p] = (frames[Lk, 4 * i, p] * t0 + frames[Lk, 4 * i + 1, p] * t1
                                                + frames[Lk, 4 * i + 2, p] * t2 + frames[Lk, 4 * i + 3, p] * extra)
            a, b, cc = pts_ee[k, 0], pts_ee[k, 1], pts_ee[k, 2]
            sx, sy, sz = 3 * k * nb, (3 * k + 1) * nb, (3 * k + 2) * nb
            for p in range(nb):
                px = T[0, p] * a + T[1, p] * b + T[2, p] * cc + T[3, p]
                py = T[4, p] * a + T[5, p] * b + T[6, p] * cc + T[7, p]
                pz = T[8, p] * a + T[9, p] * b + T[10, p] * cc + T[11, p]
                row = row_of[p0 + p, k]
                if row < 0:  # not measured: a zero row adds nothing
                    rb[sx + p] = 0.0
                    rb[sy + p] = 0.0
                    rb[sz + p] = 0.0
                else:
                    rx = w * (measured[p0 + p, k, 0] - px)
                    ry = w * (measured[p0 + p, k, 1] - py)
                    rz = w * (measured[p0 + p, k, 2] - pz)
                    r[row] = rx
                    r[row + 1] = ry
                    r[row + 2] = rz
                    rb[sx + p] = rx
                    rb[sy + p] = ry
                    rb[sz + p] = rz
                    cost2 += rx * rx + ry * ry + rz * rz
                # the point itself, kept in T's last column for the Jacobian rows below
                T[3, p] = px
                T[7, p] = py
                T[11, p] = pz
            if want_jac:
                _point_rows(Jbv, k, nb, p0, T, tw, gcols, ng, gmove, fcol, tcol, row_of)
        if want_jac:
            _accumulate(Jbv, rb, 0, W, JtJ, Jtr)
    if want_jac:  # the rows above are unweighted: J = w Jb, and r already carries w
        w2 = w * w
        for i in range(n):
            Jtr[i] *= w
            for j in range(i, n):
                JtJ[i, j] *= w2
                JtJ[j, i] = JtJ[i, j]
    return 0.5 * cost2


@njit(cache=_CACHE, inline="always")
def _point_rows(Jb, k, nb, p0, T, tw, gcols, ng, gmove, fcol, tcol, row_of):
    """The unweighted prediction Jacobian rows of point k over a block of nb poses, into Jb's
    segments 3k, 3k + 1, 3k + 2; T (12, B): the point's end-effector frame per pose, its translation
    column replaced by the point (instrument frame). Every column of the problem is written: a
    geometry, base-frame or target column; zero where a point is not measured."""
    sx, sy, sz = 3 * k * nb, (3 * k + 1) * nb, (3 * k + 2) * nb
    for gi in range(ng):  # geometry: the twist's velocity of the point, where it moves the point
        c = gcols[gi]
        if not gmove[k, c]:
            for p in range(nb):
                Jb[c, sx + p] = 0.0
                Jb[c, sy + p] = 0.0
                Jb[c, sz + p] = 0.0
            continue
        for p in range(nb):
            px, py, pz = T[3, p], T[7, p], T[11, p]
            w0, w1, w2 = tw[c, 0, p], tw[c, 1, p], tw[c, 2, p]
            Jb[c, sx + p] = w1 * pz - w2 * py + tw[c, 3, p]
            Jb[c, sy + p] = w2 * px - w0 * pz + tw[c, 4, p]
            Jb[c, sz + p] = w0 * py - w1 * px + tw[c, 5, p]
    # base frame, left perturbation (w, v): dp = w x p + v
    for p in range(nb):
        px, py, pz = T[3, p], T[7, p], T[11, p]
        c = fcol[0]
        if c >= 0:
            Jb[c, sx + p] = 0.0
            Jb[c, sy + p] = -pz
            Jb[c, sz + p] = py
        c = fcol[1]
        if c >= 0:
            Jb[c, sx + p] = pz
            Jb[c, sy + p] = 0.0
            Jb[c, sz + p] = -px
        c = fcol[2]
        if c >= 0:
            Jb[c, sx + p] = -py
            Jb[c, sy + p] = px
            Jb[c, sz + p] = 0.0
        for i in range(3):
            c = fcol[3 + i]
            if c >= 0:
                Jb[c, sx + p] = 1.0 if i == 0 else 0.0
                Jb[c, sy + p] = 1.0 if i == 1 else 0.0
                Jb[c, sz + p] = 1.0 if i == 2 else 0.0
    for kk in range(tcol.shape[0] // 3):  # a target point moves with its end-effector frame's orientation
        for j in range(3):
            ct = tcol[3 * kk + j]
            if ct < 0:
                continue
            if kk == k:
                for p in range(nb):
                    Jb[ct, sx + p] = T[j, p]
                    Jb[ct, sy + p] = T[4 + j, p]
                    Jb[ct, sz + p] = T[8 + j, p]
            else:
                for p in range(nb):
                    Jb[ct, sx + p] = 0.0
                    Jb[ct, sy + p] = 0.0
                    Jb[ct, sz + p] = 0.0
    for p in range(nb):  # a point not measured at this pose: no rows
        if row_of[p0 + p, k] < 0:
            for c in range(Jb.shape[0]):
                Jb[c, sx + p] = 0.0
                Jb[c, sy + p] = 0.0
                Jb[c, sz + p] = 0.0


@njit(cache=_CACHE, fastmath={"contract", "reassoc"}, nogil=True)
def _accumulate(Jb, r, row0, row1, JtJ, Jtr):
    """Add a block's rows: JtJ (upper triangle) += Jb Jb^T and Jtr += Jb r[row0:row1], with Jb
    (n, m_b) holding rows row0..row1 of the unweighted Jacobian as columns 0..row1-row0: dot products
    of contiguous rows, whose summation order is free (``reassoc``) so that they vectorize. The
    indices are unsigned: a signed one makes numba guard against negative indices, and the guarded
    loads are compiled as gathers (~2x slower)."""
    n = Jb.shape[0]
    m = np.uint64(row1 - row0)
    rb = r[row0:row1]
    one = np.uint64(1)
    for i in range(n):
        a = Jb[i]
        acc = 0.0
        t = np.uint64(0)
        while t < m:
            acc += a[t] * rb[t]
            t += one
        Jtr[i] += acc
        for j in range(i, n):
            b = Jb[j]
            acc = 0.0
            t = np.uint64(0)
            while t < m:
                acc += a[t] * b[t]
                t += one
            JtJ[i, j] += acc


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def _cholesky(G, shift, L):
    """Lower Cholesky factor L (n_a, n_a) of G + shift I; False when that matrix is not positive
    definite, where LAPACK's ``dpotrf`` fails too (a pivot <= 0 or NaN)."""
    na = G.shape[0]
    for j in range(na):
        d = G[j, j] + shift
        for k in range(j):
            d -= L[j, k] * L[j, k]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        L[j, j] = d
        for i in range(j + 1, na):
            e = G[i, j]
            for k in range(j):
                e -= L[i, k] * L[j, k]
            L[i, j] = e / d
    return True


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def _cho_solve(L, g, x):
    """x = (L L^T)^-1 g (n_a,) from the factor of :func:`_cholesky`."""
    na = g.shape[0]
    for i in range(na):  # L y = g
        e = g[i]
        for k in range(i):
            e -= L[i, k] * x[k]
        x[i] = e / L[i, i]
    for i in range(na - 1, -1, -1):  # L^T x = y
        e = x[i]
        for k in range(i + 1, na):
            e -= L[k, i] * x[k]
        x[i] = e / L[i, i]


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def _retract(ip, gparam, params, base, pts, step, params_t, base_t, pts_t):
    """The trial state (params_t, base_t, pts_t) = the state moved by ``step`` (n,): geometry
    additive, the base frame by the left perturbation exp(w) (w, v), target points additive."""
    fcol, tcol = ip[7], ip[8]
    for i in range(params.shape[0]):
        params_t[i] = params[i]
    for c in range(step.shape[0]):
        if gparam[c] >= 0:
            params_t[gparam[c]] += step[c]
    x = step[fcol[0]] if fcol[0] >= 0 else 0.0
    y = step[fcol[1]] if fcol[1] >= 0 else 0.0
    z = step[fcol[2]] if fcol[2] >= 0 else 0.0
    th2 = x * x + y * y + z * z
    th = math.sqrt(th2)
    if th < 1e-6:  # robocal.transforms.rodrigues_coefficients
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        a, b = math.sin(th) / th, (1.0 - math.cos(th)) / th2
    R00, R01, R02 = 1.0 - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y
    R10, R11, R12 = b * x * y + a * z, 1.0 - b * (x * x + z * z), b * y * z - a * x
    R20, R21, R22 = b * x * z - a * y, b * y * z + a * x, 1.0 - b * (x * x + y * y)
    for j in range(4):
        b0, b1, b2 = base[0, j], base[1, j], base[2, j]
        base_t[0, j] = R00 * b0 + R01 * b1 + R02 * b2
        base_t[1, j] = R10 * b0 + R11 * b1 + R12 * b2
        base_t[2, j] = R20 * b0 + R21 * b1 + R22 * b2
    for i in range(3):
        if fcol[3 + i] >= 0:
            base_t[i, 3] += step[fcol[3 + i]]
    for k in range(pts.shape[0]):
        for j in range(3):
            ct = tcol[3 * k + j]
            pts_t[k, j] = pts[k, j] + (step[ct] if ct >= 0 else 0.0)


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def lm_points(ip, op_axis, qm, cq, sq, tT, gmove, measured, row_of, w, gparam, act, ctl,
              params, base, pts, params_t, base_t, pts_t, r0, r, rt, JtJ, Jtr, JtJt, Jtrt, col_scale,
              fw, Jb, la, Gi, out, hist):
    """The damped Gauss-Newton (Levenberg-Marquardt) loop of ``DampedGaussNewton`` on the normal
    equations of :func:`_evaluate`, from the state (params, base, pts), which ends as the last
    accepted one; r0 the start's residuals, r and JtJ, Jtr the final ones; col_scale (n,) the
    column norms of the start's Jacobian (zeros -> 1). Returns ``(last iteration, stop code)``;
    ``out`` = [cost, optimality, relative predicted reduction (both set when no step reduces the
    cost), lam, 1 if the final G is positive definite]; la starts with the final scaled normal
    matrix G (n_a, n_a) of the active columns, Gi its inverse (when positive definite); hist
    (max iterations,): the cost after each accepted step (untouched for the others).

    ctl: [ftol, xtol, chi2_tol, gtol, stall_rtol, first iteration, max iterations]; act (n_a,): the
    active columns; the *_t arrays, rt, JtJt, Jtrt: trial buffers; la: linear-algebra scratch.
    """
    ftol, xtol, chi2_tol, gtol, stall_rtol = ctl[0], ctl[1], ctl[2], ctl[3], ctl[4]
    first, max_it = int(ctl[5]), int(ctl[6])
    n = Jtr.shape[0]
    na = act.shape[0]
    M = r.shape[0]
    G = la[:na * na].reshape((na, na))
    L = la[na * na:2 * na * na].reshape((na, na))
    o = 2 * na * na
    g = la[o:o + na]
    o += na
    step_s = la[o:o + na]
    o += na
    step = la[o:o + n]
    # a runtime bool, not the literal True: numba would compile a second _evaluate for a literal
    with_jac = first >= 0
    cost = _evaluate(ip, op_axis, qm, cq, sq, tT, gmove, measured, row_of, w, params, base, pts, with_jac, r, JtJ, Jtr,
                     fw, Jb)
    for i in range(M):
        r0[i] = r[i]
    for i in range(n):
        d = math.sqrt(max(JtJ[i, i], 0.0))
        col_scale[i] = d if d != 0.0 else 1.0
    lam = 1e-3
    refused_last = False
    # the cost decreases of the two previous accepted steps (NaN: none yet), for the chi-square stop's
    # estimated remainder (robocal.calib._iterate.remaining_decrease_bound)
    d_prev = math.nan
    d_prev2 = math.nan
    code = MAX_ITERATIONS
    it = first + max_it - 1
    out[1] = math.nan
    out[2] = math.nan
    for itn in range(first, first + max_it):
        it = itn
        g_max, g_inf = _scaled_system(JtJ, Jtr, act, col_scale, G, g)
        s_max = math.sqrt(g_max)
        if g_inf <= 1e-14 * max(1.0, s_max * math.sqrt(2.0 * cost)):
            code = GRADIENT_ZERO
            break
        found = False
        c_t = cost
        for attempt in range(_LINE_SEARCH_TRIES):
            if not _cholesky(G, lam * g_max, L):
                lam *= 10.0
                continue
            _cho_solve(L, g, step_s)
            for i in range(n):
                step[i] = 0.0
            for a in range(na):
                step[act[a]] = step_s[a] / col_scale[act[a]]
            _retract(ip, gparam, params, base, pts, step, params_t, base_t, pts_t)
            # with the Jacobian unless steps are being refused; a lazy trial that lowers the cost is
            # evaluated again with it (one call site: each one is compiled again inside this loop)
            jac = not (refused_last or attempt > 0)
            while True:
                c_t = _evaluate(ip, op_axis, qm, cq, sq, tT, gmove, measured, row_of, w, params_t, base_t, pts_t, jac,
                                rt, JtJt, Jtrt, fw, Jb)
                if c_t < cost and not jac:
                    jac = with_jac
                    continue
                break
            if c_t < cost:
                refused_last = attempt > 0
                found = True
                break
            lam *= 10.0
        if not found:
            predicted = math.inf
            if _cholesky(G, 1e-12 * g_max, L):
                _cho_solve(L, g, step_s)
                predicted = 0.0
                for a in range(na):
                    predicted += g[a] * step_s[a]
                predicted *= 0.5
            optimality = g_inf / max(s_max * math.sqrt(2.0 * cost), 1e-300)
            rel = predicted / max(cost, 1e-300)
            out[1] = optimality
            out[2] = rel
            code = STATIONARY if (optimality <= gtol or rel <= stall_rtol) else NOT_AT_MINIMUM
            break
        for i in range(params.shape[0]):
            params[i] = params_t[i]
        for i in range(3):
            for j in range(4):
                base[i, j] = base_t[i, j]
        for k in range(pts.shape[0]):
            for j in range(3):
                pts[k, j] = pts_t[k, j]
        for i in range(M):
            r[i] = rt[i]
        for i in range(n):
            Jtr[i] = Jtrt[i]
            for j in range(n):
                JtJ[i, j] = JtJt[i, j]
        lam = max(lam / 10.0, 1e-12)
        hist[itn - first] = c_t
        dcost = cost - c_t
        cost = c_t
        dp, dp2 = d_prev, d_prev2
        d_prev2 = d_prev
        d_prev = dcost
        if lam >= 1.0:  # a heavily damped step is short wherever it is: no convergence test
            continue
        if abs(dcost) <= ftol * max(cost, 1e-300):
            code = FTOL
            break
        s2 = 2.0 * cost / max(M - na, 1)
        remainder = math.inf  # the geometric tail at the slower of the last two contraction ratios
        if dp > 0.0 and dp2 > 0.0:  # False for NaN (fewer than three steps in this phase)
            q = max(dcost / dp, dp / dp2)
            if q < 1.0:
                remainder = dcost * q / (1.0 - q)
        if lam <= 1e-3 and 2.0 * max(abs(dcost), remainder) <= chi2_tol * max(s2, 1e-300):
            code = CHI2
            break
        ss = 0.0
        for a in range(na):
            ss += step_s[a] * step_s[a]
        if math.sqrt(ss) <= xtol * (1.0 + math.sqrt(2.0 * cost)):
            code = XTOL
            break
    out[0] = cost
    out[3] = lam
    # the final scaled normal matrix G and, when positive definite, its inverse (the covariance's core)
    _scaled_system(JtJ, Jtr, act, col_scale, G, g)
    out[4] = 0.0
    if _cholesky(G, 0.0, L):
        out[4] = 1.0
        for j in range(na):
            for i in range(na):
                g[i] = 0.0
            g[j] = 1.0
            _cho_solve(L, g, step_s)
            for i in range(na):
                Gi[i, j] = step_s[i]
    return it, code


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def _scaled_system(JtJ, Jtr, act, col_scale, G, g):
    """G (n_a, n_a) = the active block of JtJ / (s s^T), g (n_a,) = Jtr / s; returns (max diag G,
    max |g|)."""
    na = act.shape[0]
    g_max = -math.inf
    g_inf = 0.0
    for a in range(na):
        ia = act[a]
        ca = col_scale[ia]
        g[a] = Jtr[ia] / ca
        g_inf = max(g_inf, abs(g[a]))
        for b in range(na):
            G[a, b] = JtJ[ia, act[b]] / (ca * col_scale[act[b]])
        g_max = max(g_max, G[a, a])
    return g_max, g_inf
