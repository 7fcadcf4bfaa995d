"""Compiled kernel: one end effector's frames for many parameter vectors at once.

A particle swarm (:mod:`robocal.calib.swarm`) evaluates P candidate parameter vectors at the
same N configurations every generation. :func:`ee_frames_batch` runs the model's *operation*
program (every elementary operation of every link, :mod:`robocal.kinematics._kernels`) for all
P x N combinations in one call: no Python loop over particles or poses.

Per particle, each link's operations before its joint motion and after it are multiplied out
once (``pre``, ``post``: constant affines); per configuration a link then costs two affine
products and one joint motion, instead of one trigonometric evaluation per rotation parameter.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels import _apply_op, _mul_affine

_CACHE = True


@njit(cache=_CACHE, inline="always")
def _set_identity(M):
    for i in range(3):
        for j in range(4):
            M[i, j] = 1.0 if i == j else 0.0


@njit(cache=_CACHE)
def _split_links(vals, op_link, op_code, op_axis, op_moves, n_links, pre, post, joint_op):
    """Per link: ``pre`` (3, 4) the operations before its joint motion, ``post`` those after,
    ``joint_op`` the index of the motion's operation (-1 for a link without one)."""
    for L in range(n_links):
        _set_identity(pre[L])
        _set_identity(post[L])
        joint_op[L] = -1
    for t in range(op_code.shape[0]):
        L = op_link[t]
        if op_moves[t]:
            joint_op[L] = t
        elif joint_op[L] < 0:
            _apply_op(pre[L], op_code[t], vals[t], op_axis[t])
        else:
            _apply_op(post[L], op_code[t], vals[t], op_axis[t])


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def ee_frames_batch(op_values, joint_values, op_link, op_code, op_axis, op_moves, link_parent, ee_link, ee_T, out):
    """Write ``out[p, n]`` (3, 4): the end effector's frame in the robot base frame for parameter
    vector ``p`` at configuration ``n``.

    op_values (P, n_ops): each operation's parameter value per particle [mm | rad];
    joint_values (N, n_ops): the joint value added to each operation at each configuration;
    op_moves (n_ops,) bool: the operation is a joint motion; op_link, op_code, op_axis,
    link_parent: the model's operation program (links in topological order); ee_link: the link
    carrying the end effector (-1: the base); ee_T (3, 4): the end effector in that link's frame;
    out (P, N, 3, 4).
    """
    P = op_values.shape[0]
    N = joint_values.shape[0]
    n_links = link_parent.shape[0]
    frames = np.empty((n_links, 3, 4))
    pre = np.empty((n_links, 3, 4))
    post = np.empty((n_links, 3, 4))
    joint_op = np.empty(n_links, dtype=np.int64)
    M = np.empty((3, 4))
    root = np.empty((3, 4))
    _set_identity(root)
    for p in range(P):
        vals = op_values[p]
        _split_links(vals, op_link, op_code, op_axis, op_moves, n_links, pre, post, joint_op)
        for n in range(N):
            jv = joint_values[n]
            for L in range(n_links):
                parent = link_parent[L]
                _mul_affine(root if parent < 0 else frames[parent], pre[L], M)
                t = joint_op[L]
                if t >= 0:
                    _apply_op(M, op_code[t], vals[t] + jv[t], op_axis[t])
                _mul_affine(M, post[L], frames[L])
            _mul_affine(root if ee_link < 0 else frames[ee_link], ee_T, out[p, n])


@njit(cache=_CACHE, fastmath={"contract"}, nogil=True)
def ee_objective_batch(op_values, joint_values, op_link, op_code, op_axis, op_moves, link_parent, ee_link, ee_T,
                       base, targets, p_meas, p_mask, p_w2, r_right, r_meas, r_w2, out):
    """Add to ``out[p]`` the squared weighted residuals of one end effector's frames for parameter
    vector ``p`` over all configurations (objective (7) of the swarm, before its 1/N scale), without
    storing any frame.

    The frame at configuration n is ``W = base[n] F(p, n)`` (F: :func:`ee_frames_batch`'s frame).
    Points: targets (P, K, 3) in the end effector's frame; p_meas (N, K, 3) measured [mm]; p_mask
    (N, K) bool: measured; p_w2 (K,) squared weights; term ``p_w2[k] |p_meas[n, k] - W t_k|^2``.
    Rotations: r_right (P, M, 3, 3) right factors (a tool's rotation); r_meas (N, M, 3, 3);
    r_w2 (M,); term ``r_w2[m] theta^2`` with ``theta = 2 asin(min(||r_meas - W_R r_right||_F / sqrt 8, 1))``.
    """
    P = op_values.shape[0]
    N = joint_values.shape[0]
    K = targets.shape[1]
    Mr = r_right.shape[1]
    n_links = link_parent.shape[0]
    frames = np.empty((n_links, 3, 4))
    pre = np.empty((n_links, 3, 4))
    post = np.empty((n_links, 3, 4))
    joint_op = np.empty(n_links, dtype=np.int64)
    M = np.empty((3, 4))
    F = np.empty((3, 4))
    W = np.empty((3, 4))
    root = np.empty((3, 4))
    _set_identity(root)
    for p in range(P):
        vals = op_values[p]
        _split_links(vals, op_link, op_code, op_axis, op_moves, n_links, pre, post, joint_op)
        pos_acc = 0.0
        rot_acc = 0.0
        for n in range(N):
            jv = joint_values[n]
            for L in range(n_links):
                parent = link_parent[L]
                _mul_affine(root if parent < 0 else frames[parent], pre[L], M)
                t = joint_op[L]
                if t >= 0:
                    _apply_op(M, op_code[t], vals[t] + jv[t], op_axis[t])
                _mul_affine(M, post[L], frames[L])
            _mul_affine(root if ee_link < 0 else frames[ee_link], ee_T, F)
            _mul_affine(base[n], F, W)
            for k in range(K):
                if not p_mask[n, k]:
                    continue
                tk = targets[p, k]
                s = 0.0
                for i in range(3):
                    d = p_meas[n, k, i] - (W[i, 0] * tk[0] + W[i, 1] * tk[1] + W[i, 2] * tk[2] + W[i, 3])
                    s += d * d
                pos_acc += p_w2[k] * s
            for m in range(Mr):
                Rr = r_right[p, m]
                d2 = 0.0
                for i in range(3):
                    for j in range(3):
                        d = r_meas[n, m, i, j] - (W[i, 0] * Rr[0, j] + W[i, 1] * Rr[1, j] + W[i, 2] * Rr[2, j])
                        d2 += d * d
                th = 2.0 * np.arcsin(min(np.sqrt(d2 / 8.0), 1.0))
                rot_acc += r_w2[m] * th * th
        out[p] += pos_acc + rot_acc
