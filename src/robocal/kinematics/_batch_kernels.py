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
