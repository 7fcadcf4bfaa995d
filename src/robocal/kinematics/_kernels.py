"""Compiled (numba) kernels for forward kinematics and Jacobians, looping over poses.

Two program forms, both built by :mod:`robocal.kinematics.model` from the link operations (the
fused one packed by :func:`robocal.kinematics._packing.pack_fused`):

* the *fused* program for forward kinematics: per moving joint ``m`` a constant affine ``K[m]``
  (3x4) from its parent joint's frame, then the joint motion ``Rz(q)`` or ``Tz(q)``; end effectors
  hang off a joint by a constant ``E[e]``. This is the fast path (one 3x4 product per joint).
* the *operation* program for Jacobians: every elementary operation of every link, so that each
  parameter's spatial twist is read off where it acts.

Twists are spatial, in the world frame: ``(omega, v)`` with the velocity of a world point ``p``
equal to ``omega x p + v``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .links import OP_RU, OP_RX, OP_RY, OP_RZ, OP_TU, OP_TX, OP_TY, OP_TZ

_CACHE = True


@njit(cache=_CACHE, inline="always")
def _mul_affine(A, B, out):
    """out = A @ B for affine 3x4 matrices (implicit last row 0 0 0 1)."""
    for i in range(3):
        a0, a1, a2 = A[i, 0], A[i, 1], A[i, 2]
        out[i, 0] = a0 * B[0, 0] + a1 * B[1, 0] + a2 * B[2, 0]
        out[i, 1] = a0 * B[0, 1] + a1 * B[1, 1] + a2 * B[2, 1]
        out[i, 2] = a0 * B[0, 2] + a1 * B[1, 2] + a2 * B[2, 2]
        out[i, 3] = a0 * B[0, 3] + a1 * B[1, 3] + a2 * B[2, 3] + A[i, 3]


@njit(cache=_CACHE)
def _copy34(src, dst):
    """dst[:, :] = src for (3, 4) blocks, as a loop: numba compiles an array-to-slice assignment
    with its shape-mismatch message (f-strings, str.join: ~4 s of the first compile)."""
    for i in range(3):
        for j in range(4):
            dst[i, j] = src[i, j]


@njit(cache=_CACHE, inline="always")
def _model_joint(q_row, m, cpl_ptr, cpl_idx, cpl_coef):
    acc = 0.0
    for t in range(cpl_ptr[m], cpl_ptr[m + 1]):
        acc += cpl_coef[t] * q_row[cpl_idx[t]]
    return acc


# sin and cos of a joint angle without libm, so that loops over poses vectorize (numba has no SVML
# here: math.sin in a loop is one scalar libm call per value). Cody & Waite's range reduction
# (Software Manual for the Elementary Functions, 1980): x = k pi/2 + r, |r| <= pi/4, with pi/2
# split into three parts: the first two carry 33 significant bits, so k * part is exact for
# |k| < 2**20, the third the next 53 bits (1e-37 rad left over); computed from pi with exact
# rational arithmetic. Then the Taylor series of sin and cos on [-pi/4, pi/4] (terms to r**17 and
# r**18: truncation below 1e-19), summed so that the leading term is added last (cos: 1 - z/2
# with its rounding error carried), and the quadrant chosen by selects, not branches.
# Within 2 ulp of numpy's sin/cos for |x| <= _SINCOS_MAX (tests/test_kinematics.py).
_PIO2_1 = 1.5707963267341256
_PIO2_2 = 6.077100506303966e-11
_PIO2_3 = 2.0222662487959506e-21
_TWO_OVER_PI = 0.6366197723675814
#: |x| [rad] up to which :func:`_sincos` is used; beyond it libm (``math.sin``/``math.cos``).
_SINCOS_MAX = 1e5


@njit(cache=_CACHE, fastmath={"contract"}, inline="always")
def _sincos(x):
    """sin(x), cos(x) within 2 ulp for |x| <= _SINCOS_MAX rad; branch-free so loops over it vectorize."""
    k = np.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
    z = r * r
    ps = -1.6666666666666666e-01 + z * (8.3333333333333332e-03 + z * (-1.9841269841269841e-04 + z * (
        2.7557319223985893e-06 + z * (-2.5052108385441720e-08 + z * (1.6059043836821613e-10 + z * (
            -7.6471637318198164e-13 + z * 2.8114572543455206e-15))))))
    pc = 4.1666666666666664e-02 + z * (-1.3888888888888889e-03 + z * (2.4801587301587302e-05 + z * (
        -2.7557319223985888e-07 + z * (2.0876756987868100e-09 + z * (-1.1470745597729725e-11 + z * (
            4.7794773323873853e-14 + z * -1.5619206968586225e-16))))))
    sp = r + r * z * ps
    hz = 0.5 * z
    w = 1.0 - hz
    cp = w + (((1.0 - w) - hz) + z * z * pc)
    k4 = k - 4.0 * np.floor(k * 0.25)  # quadrant 0..3 as a float (keeps the loop vectorizable)
    swap = (k4 == 1.0) | (k4 == 3.0)
    s = cp if swap else sp
    c = sp if swap else cp
    s = -s if k4 >= 2.0 else s
    c = -c if (k4 == 1.0) | (k4 == 2.0) else c
    return s, c


@njit(cache=_CACHE, fastmath={"contract"}, inline="always")
def _sincos_any(x):
    """sin(x), cos(x) for any x: :func:`_sincos`, libm beyond _SINCOS_MAX (a branch: scalar code)."""
    if abs(x) > _SINCOS_MAX:
        return math.sin(x), math.cos(x)
    return _sincos(x)


@njit(cache=_CACHE, fastmath={"contract"}, inline="always")
def _sincos_into(x, s, c, n):
    """s[:n], c[:n] = sin, cos of x[:n] (1-D arrays): one vectorized pass, libm for huge values."""
    big = False
    for i in range(n):
        s[i], c[i] = _sincos(x[i])
        big |= abs(x[i]) > _SINCOS_MAX
    if big:
        for i in range(n):
            if abs(x[i]) > _SINCOS_MAX:
                s[i] = math.sin(x[i])
                c[i] = math.cos(x[i])


@njit(cache=_CACHE)
def sincos_array(x):
    """Element-wise (sin, cos) of a contiguous float array (vectorized polynomial, libm for |x| > 1e5)."""
    flat = x.ravel()
    s = np.empty_like(flat)
    c = np.empty_like(flat)
    _sincos_into(flat, s, c, flat.size)
    return s.reshape(x.shape), c.reshape(x.shape)


@njit(cache=_CACHE, inline="always")
def _unpack(ints, floats):
    n_m, n_e, nnz = ints[0], ints[1], ints[2]
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


@njit(cache=_CACHE, inline="always")
def _chain(n_m, qm, c, s, K, mparent, mtype, G, tmp):
    """Fill G (n_m, 3, 4) with each joint's frame after its motion, for one configuration."""
    for m in range(n_m):
        p = mparent[m]
        if p < 0:
            for i in range(3):
                for j in range(4):
                    tmp[i, j] = K[m, i, j]
        else:
            _mul_affine(G[p], K[m], tmp)
        g = G[m]
        if mtype[m] == 0:
            cm = c[m]
            sm = s[m]
            for i in range(3):
                x0 = tmp[i, 0]
                x1 = tmp[i, 1]
                g[i, 0] = cm * x0 + sm * x1
                g[i, 1] = cm * x1 - sm * x0
                g[i, 2] = tmp[i, 2]
                g[i, 3] = tmp[i, 3]
        else:
            d = qm[m]
            for i in range(3):
                g[i, 0] = tmp[i, 0]
                g[i, 1] = tmp[i, 1]
                g[i, 2] = tmp[i, 2]
                g[i, 3] = tmp[i, 3] + d * tmp[i, 2]


@njit(cache=_CACHE, inline="always")
def _write_pose(G, a, E, out, tmp):
    if a < 0:
        for i in range(3):
            for j in range(4):
                tmp[i, j] = E[i, j]
    else:
        _mul_affine(G[a], E, tmp)
    for i in range(3):
        for j in range(4):
            out[i, j] = tmp[i, j]
    out[3, 0] = 0.0
    out[3, 1] = 0.0
    out[3, 2] = 0.0
    out[3, 3] = 1.0


@njit(cache=_CACHE, fastmath={"contract"})
def fk_fused(q, ints, floats, want_links):
    """Batched forward kinematics of a packed fused program (see :func:`pack_fused`).

    q (N, n_ctrl) controller joints [rad | mm]. Returns (N, n_e, 4, 4) end-effector poses and
    (N, n_m, 4, 4) link frames (size 0 unless ``want_links``).
    """
    n_m, n_e, mparent, mtype, cpl_ptr, cpl_idx, ee_anchor, K, E, post, cpl_coef = _unpack(ints, floats)
    N = q.shape[0]
    out = np.empty((N, n_e, 4, 4))
    links = np.empty((N if want_links else 0, n_m, 4, 4))
    G = np.empty((n_m, 3, 4))
    tmp = np.empty((3, 4))
    # Work in cache-sized chunks: model joints, then their sines/cosines (a vectorized loop),
    # then the chain products pose by pose.
    B = 512
    qm = np.empty((B, n_m))
    s = np.empty((B, n_m))
    c = np.empty((B, n_m))
    for start in range(0, N, B):
        stop = min(start + B, N)
        nb = stop - start
        for n in range(nb):
            for m in range(n_m):
                qm[n, m] = _model_joint(q[start + n], m, cpl_ptr, cpl_idx, cpl_coef)
        qf = qm.ravel()
        sf = s.ravel()
        cf = c.ravel()
        _sincos_into(qf, sf, cf, nb * n_m)
        for n in range(nb):
            _chain(n_m, qm[n], c[n], s[n], K, mparent, mtype, G, tmp)
            for e in range(n_e):
                _write_pose(G, ee_anchor[e], E[e], out[start + n, e], tmp)
            if want_links:
                for m in range(n_m):
                    _write_pose(G, m, post[m], links[start + n, m], tmp)
    return out, links


# Structure-of-arrays blocks for fk_fused_into: the poses of a block run along a row, so every
# loop over them is one vectorizable stream (the pose-by-pose chain of ``_chain`` vectorizes not).
# A joint's *record* is _REC rows of one scratch array: its frame (12 rows, row-major 3x4), then
# cos, sin and the prismatic offset of its motion. Each helper addresses rows at constant distances
# from one view's start, so LLVM proves the loop free of aliasing and vectorizes it without
# run-time overlap checks (rows of separate arrays defeated it: the chain stayed scalar).
_BLOCK = 64  # poses per block: a 6-joint robot's records (~70 KB) stay in L1/L2
_ROW = _BLOCK + 8  # row length: rows not a multiple of 4 KiB apart (no 4K aliasing)
_REC = 15
_C, _S, _D = 12, 13, 14


@njit(cache=_CACHE, fastmath={"contract"}, inline="always")
def _soa_chain(V, Km, nb):
    """Record 1 of ``V`` (frame rows) = record 0's frame @ ``Km`` @ the motion of record 1."""
    k00, k01, k02, k03 = Km[0, 0], Km[0, 1], Km[0, 2], Km[0, 3]
    k10, k11, k12, k13 = Km[1, 0], Km[1, 1], Km[1, 2], Km[1, 3]
    k20, k21, k22, k23 = Km[2, 0], Km[2, 1], Km[2, 2], Km[2, 3]
    for i in range(3):
        r = 4 * i
        for n in range(nb):
            a0 = V[r, n]
            a1 = V[r + 1, n]
            a2 = V[r + 2, n]
            t0 = a0 * k00 + a1 * k10 + a2 * k20
            t1 = a0 * k01 + a1 * k11 + a2 * k21
            t2 = a0 * k02 + a1 * k12 + a2 * k22
            t3 = a0 * k03 + a1 * k13 + a2 * k23 + V[r + 3, n]
            cn = V[_REC + _C, n]
            sn = V[_REC + _S, n]
            V[_REC + r, n] = cn * t0 + sn * t1
            V[_REC + r + 1, n] = cn * t1 - sn * t0
            V[_REC + r + 2, n] = t2
            V[_REC + r + 3, n] = t3 + V[_REC + _D, n] * t2


@njit(cache=_CACHE, fastmath={"contract"}, inline="always")
def _soa_root(V, Km, nb):
    """Record 1 of ``V`` = ``Km`` @ the motion of record 1 (a joint hanging from the base)."""
    for i in range(3):
        r = 4 * i
        t0, t1, t2, t3 = Km[i, 0], Km[i, 1], Km[i, 2], Km[i, 3]
        for n in range(nb):
            cn = V[_REC + _C, n]
            sn = V[_REC + _S, n]
            V[_REC + r, n] = cn * t0 + sn * t1
            V[_REC + r + 1, n] = cn * t1 - sn * t0
            V[_REC + r + 2, n] = t2
            V[_REC + r + 3, n] = t3 + V[_REC + _D, n] * t2


@njit(cache=_CACHE, fastmath={"contract"}, inline="always")
def _soa_store(V, P, out, j, first, nb):
    """``out[first + n, j]`` (4x4) = the frame in ``V``'s first 12 rows @ ``P`` (3x4), pose by pose."""
    for n in range(nb):
        o = out[first + n, j]
        for i in range(3):
            r = 4 * i
            a0 = V[r, n]
            a1 = V[r + 1, n]
            a2 = V[r + 2, n]
            o[i, 0] = a0 * P[0, 0] + a1 * P[1, 0] + a2 * P[2, 0]
            o[i, 1] = a0 * P[0, 1] + a1 * P[1, 1] + a2 * P[2, 1]
            o[i, 2] = a0 * P[0, 2] + a1 * P[1, 2] + a2 * P[2, 2]
            o[i, 3] = a0 * P[0, 3] + a1 * P[1, 3] + a2 * P[2, 3] + V[r + 3, n]
        o[3, 0] = 0.0
        o[3, 1] = 0.0
        o[3, 2] = 0.0
        o[3, 3] = 1.0


@njit(cache=_CACHE)
def _copy_frame_rows(src, dst, nb):
    """dst[:12, :nb] = src[:12, :nb]: a tree's frames in and out of the records (one compiled
    function for the two call sites: inlined, such loops add to fk_fused_into's compile time)."""
    for r in range(12):
        for n in range(nb):
            dst[r, n] = src[r, n]


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def fk_fused_into(q, ints, floats, e, out, links, start, stop):
    """Poses of end effector ``e`` for the configurations ``q[start:stop]``, into ``out[start:stop]``.

    q (N, n_ctrl) controller joints [rad | mm]; out (N, 4, 4) [mm], written in place; links
    (N, n_m, 4, 4) [mm]: the moving links' frames written too, or (0, n_m, 4, 4) for none (one
    compiled kernel serves ``fk`` and ``link_frames``). The arithmetic of :func:`fk_fused` (the
    same products in the same order), organised for SIMD: blocks of 64 poses held as structure of
    arrays, joint by joint (joint value, its sine and cosine, the frame), each step one loop over
    the block's poses that LLVM vectorizes. Releases the GIL so that threads can share a batch
    (disjoint ranges).
    """
    n_m, n_e, mparent, mtype, cpl_ptr, cpl_idx, ee_anchor, K, E, post, cpl_coef = _unpack(ints, floats)
    # Records: m + 1 holds joint m; record m also serves as joint m's parent frame, so a joint whose
    # parent is not the previous joint (a tree) gets its parent's frame copied there from G (and
    # the previous joint's frame, if a later branch needs it, goes to G first).
    F = np.empty(((n_m + 2) * _REC, _ROW))
    anchor = ee_anchor[e]
    Ee = E[e]
    want_links = links.shape[0] > 0
    keep = np.zeros(n_m, dtype=np.bool_)  # frames needed after a branch overwrote their record
    for m in range(n_m):
        p = mparent[m]
        if p >= 0 and p != m - 1:
            keep[p] = True
    G = np.empty((n_m, 12, _ROW))
    out4 = out.reshape((out.shape[0], 1, 4, 4))  # one inlined store for out and links: same type
    for first in range(start, stop, _BLOCK):
        nb = min(first + _BLOCK, stop) - first
        for m in range(n_m):
            R = F[_REC * (m + 1):]
            for n in range(nb):
                R[_D, n] = 0.0
            for t in range(cpl_ptr[m], cpl_ptr[m + 1]):
                col = cpl_idx[t]
                w = cpl_coef[t]
                for n in range(nb):
                    R[_D, n] += w * q[first + n, col]
            if mtype[m] == 0:
                big = False
                for n in range(nb):
                    x = R[_D, n]
                    R[_S, n], R[_C, n] = _sincos(x)
                    big |= abs(x) > _SINCOS_MAX
                if big:  # huge angles: libm
                    for n in range(nb):
                        x = R[_D, n]
                        if abs(x) > _SINCOS_MAX:
                            R[_S, n] = math.sin(x)
                            R[_C, n] = math.cos(x)
                for n in range(nb):
                    R[_D, n] = 0.0
            else:
                for n in range(nb):
                    R[_S, n] = 0.0
                    R[_C, n] = 1.0
            p = mparent[m]
            V = F[_REC * m:]
            if m > 0 and keep[m - 1]:  # before a branch overwrites it
                _copy_frame_rows(V, G[m - 1], nb)
            if p >= 0 and p != m - 1:
                _copy_frame_rows(G[p], V, nb)
            if p < 0:
                _soa_root(V, K[m], nb)
            else:
                _soa_chain(V, K[m], nb)
            for j in range(2):  # its link frame and the end effector, while its record is intact
                if (want_links if j == 0 else m == anchor):
                    _soa_store(R, post[m] if j == 0 else Ee, links if j == 0 else out4, m if j == 0 else 0,
                               first, nb)
        if anchor < 0:
            for n in range(nb):
                o = out[first + n]
                for i in range(3):
                    for j in range(4):
                        o[i, j] = Ee[i, j]
                o[3, 0] = 0.0
                o[3, 1] = 0.0
                o[3, 2] = 0.0
                o[3, 3] = 1.0


@njit(cache=_CACHE, fastmath={"contract"})
def fk_fused_single_checked(q, ints, floats, out):
    """:func:`fk_fused_single` that first checks ``q`` is finite; False (nothing written) if not."""
    for i in range(q.shape[0]):
        if not math.isfinite(q[i]):
            return False
    fk_fused_single(q, ints, floats, out)
    return True


@njit(cache=_CACHE, fastmath={"contract"})
def fk_fused_single(q, ints, floats, out):
    """One configuration ``q`` (n_ctrl,), first end effector, written into ``out`` (4, 4).

    Writes in place and returns nothing: boxing a returned array costs more than the kinematics.
    """
    n_m, n_e, mparent, mtype, cpl_ptr, cpl_idx, ee_anchor, K, E, post, cpl_coef = _unpack(ints, floats)
    scratch = np.empty(15 * n_m + 12)  # one allocation: qm, c, s, G, tmp
    qm = scratch[:n_m]
    c = scratch[n_m:2 * n_m]
    s = scratch[2 * n_m:3 * n_m]
    G = scratch[3 * n_m:15 * n_m].reshape((n_m, 3, 4))
    tmp = scratch[15 * n_m:].reshape((3, 4))
    for m in range(n_m):
        qm[m] = _model_joint(q, m, cpl_ptr, cpl_idx, cpl_coef)
        s[m], c[m] = _sincos_any(qm[m])
    _chain(n_m, qm, c, s, K, mparent, mtype, G, tmp)
    _write_pose(G, ee_anchor[0], E[0], out, tmp)


@njit(cache=_CACHE, inline="always")
def _apply_op(M, code, value, ax):
    """Right-multiply the affine frame M (3x4) in place by one elementary operation."""
    if code == OP_TX or code == OP_TY or code == OP_TZ:
        k = code - OP_TX
        for i in range(3):
            M[i, 3] += value * M[i, k]
    elif code == OP_TU:
        for i in range(3):
            M[i, 3] += value * (M[i, 0] * ax[0] + M[i, 1] * ax[1] + M[i, 2] * ax[2])
    elif code == OP_RU:
        c = math.cos(value)
        s = math.sin(value)
        v = 1.0 - c
        x, y, z = ax[0], ax[1], ax[2]
        R00 = c + x * x * v
        R01 = x * y * v - z * s
        R02 = x * z * v + y * s
        R10 = y * x * v + z * s
        R11 = c + y * y * v
        R12 = y * z * v - x * s
        R20 = z * x * v - y * s
        R21 = z * y * v + x * s
        R22 = c + z * z * v
        for i in range(3):
            m0, m1, m2 = M[i, 0], M[i, 1], M[i, 2]
            M[i, 0] = m0 * R00 + m1 * R10 + m2 * R20
            M[i, 1] = m0 * R01 + m1 * R11 + m2 * R21
            M[i, 2] = m0 * R02 + m1 * R12 + m2 * R22
    else:
        # Rotation about a coordinate axis: columns j, k mix.
        a = code - OP_RX
        j = (a + 1) % 3
        k = (a + 2) % 3
        c = math.cos(value)
        s = math.sin(value)
        for i in range(3):
            mj = M[i, j]
            mk = M[i, k]
            M[i, j] = c * mj + s * mk
            M[i, k] = c * mk - s * mj


@njit(cache=_CACHE, inline="always")
def _op_twist(M, code, ax):
    """Spatial twist (omega, v) of an elementary operation acting at frame M (3x4)."""
    w0 = M[0, 0] * ax[0] + M[0, 1] * ax[1] + M[0, 2] * ax[2]
    w1 = M[1, 0] * ax[0] + M[1, 1] * ax[1] + M[1, 2] * ax[2]
    w2 = M[2, 0] * ax[0] + M[2, 1] * ax[1] + M[2, 2] * ax[2]
    if code == OP_RX or code == OP_RY or code == OP_RZ or code == OP_RU:
        ox, oy, oz = M[0, 3], M[1, 3], M[2, 3]
        return w0, w1, w2, oy * w2 - oz * w1, oz * w0 - ox * w2, ox * w1 - oy * w0
    return 0.0, 0.0, 0.0, w0, w1, w2


@njit(cache=_CACHE)
def op_twists(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
              cpl_ptr, cpl_idx, cpl_coef, n_params, n_model_joints):
    """Spatial twists of every parameter and every model joint, and every link frame.

    Returns ``param_twists`` (N, 6, n_params), ``joint_twists`` (N, 6, n_model_joints) as
    (omega, v) in the world frame, and ``frames`` (N, n_links, 3, 4): each link's frame.
    Parameters whose operation is absent get zero columns.
    """
    N = q.shape[0]
    n_ops = op_code.shape[0]
    n_links = link_parent.shape[0]
    ptw = np.zeros((N, 6, n_params))
    jtw = np.zeros((N, 6, n_model_joints))
    frames = np.empty((N, n_links, 3, 4))
    M = np.empty((3, 4))
    for n in range(N):
        qn = q[n]
        cur = -1
        for t in range(n_ops):
            L = op_link[t]
            if L != cur:
                if cur >= 0:
                    _copy34(M, frames[n, cur])
                cur = L
                p = link_parent[L]
                if p < 0:
                    _copy34(root, M)
                else:
                    _copy34(frames[n, p], M)
            code = op_code[t]
            value = op_value[t]
            jm = op_joint[t]
            if jm >= 0:
                value += _model_joint(qn, jm, cpl_ptr, cpl_idx, cpl_coef)
            pi = op_param[t]
            if pi >= 0 or jm >= 0:
                tw = _op_twist(M, code, op_axis[t])
                if pi >= 0:
                    for r in range(6):
                        ptw[n, r, pi] = tw[r]
                if jm >= 0:
                    for r in range(6):
                        jtw[n, r, jm] = tw[r]
            _apply_op(M, code, value, op_axis[t])
        if cur >= 0:
            _copy34(M, frames[n, cur])
    return ptw, jtw, frames


@njit(cache=_CACHE)
def target_points(q, op_link, op_code, op_axis, op_value, op_param, op_joint, link_parent, root,
                  cpl_ptr, cpl_idx, cpl_coef, target_link, target_T, target_p, target_anc, free_col, n_free, want_jac):
    """Positions of points carried by links, and their derivatives w.r.t. selected parameters.

    target_link (K,) link index carrying each point (-1: the root); target_T (K, 3, 4) the point's
    end-effector frame in that link's frame; target_p (K, 3) the point in that end-effector frame;
    target_anc (K, n_links) bool:
    the link moves the point; free_col (P,) column of each parameter in the output or -1.
    Returns p (N, K, 3) in the root frame, R (N, K, 3, 3) the end-effector orientations, and
    J (N, K, 3, n_free) (size 0 unless ``want_jac``).
    """
    N = q.shape[0]
    n_ops = op_code.shape[0]
    n_links = link_parent.shape[0]
    K = target_link.shape[0]
    pts = np.empty((N, K, 3))
    rot = np.empty((N, K, 3, 3))
    J = np.zeros((N if want_jac else 0, K, 3, n_free))
    frames = np.empty((n_links, 3, 4))
    tw = np.zeros((n_free, 6))
    tw_link = np.full(n_free, -1, dtype=np.int64)
    M = np.empty((3, 4))
    tmp = np.empty((3, 4))
    for n in range(N):
        qn = q[n]
        cur = -1
        for t in range(n_ops):
            L = op_link[t]
            if L != cur:
                if cur >= 0:
                    _copy34(M, frames[cur])
                cur = L
                p = link_parent[L]
                if p < 0:
                    _copy34(root, M)
                else:
                    _copy34(frames[p], M)
            code = op_code[t]
            value = op_value[t]
            jm = op_joint[t]
            if jm >= 0:
                value += _model_joint(qn, jm, cpl_ptr, cpl_idx, cpl_coef)
            col = free_col[op_param[t]]
            if want_jac and col >= 0:
                tw_link[col] = L
                tw0, tw1, tw2, tw3, tw4, tw5 = _op_twist(M, code, op_axis[t])
                tw[col, 0] = tw0
                tw[col, 1] = tw1
                tw[col, 2] = tw2
                tw[col, 3] = tw3
                tw[col, 4] = tw4
                tw[col, 5] = tw5
            _apply_op(M, code, value, op_axis[t])
        if cur >= 0:
            _copy34(M, frames[cur])
        for k in range(K):
            L = target_link[k]
            if L < 0:
                _mul_affine(root, target_T[k], tmp)
            else:
                _mul_affine(frames[L], target_T[k], tmp)
            a, b, c = target_p[k, 0], target_p[k, 1], target_p[k, 2]
            px = tmp[0, 0] * a + tmp[0, 1] * b + tmp[0, 2] * c + tmp[0, 3]
            py = tmp[1, 0] * a + tmp[1, 1] * b + tmp[1, 2] * c + tmp[1, 3]
            pz = tmp[2, 0] * a + tmp[2, 1] * b + tmp[2, 2] * c + tmp[2, 3]
            pts[n, k, 0] = px
            pts[n, k, 1] = py
            pts[n, k, 2] = pz
            for i in range(3):
                for j in range(3):
                    rot[n, k, i, j] = tmp[i, j]
            if want_jac:
                for c in range(n_free):
                    Lc = tw_link[c]
                    if Lc < 0 or not target_anc[k, Lc]:
                        continue
                    w0, w1, w2 = tw[c, 0], tw[c, 1], tw[c, 2]
                    J[n, k, 0, c] = w1 * pz - w2 * py + tw[c, 3]
                    J[n, k, 1, c] = w2 * px - w0 * pz + tw[c, 4]
                    J[n, k, 2, c] = w0 * py - w1 * px + tw[c, 5]
    return pts, rot, J
