"""Packing of the fused forward-kinematics program into flat arrays (plain numpy, no numba).

The compiled kernels (:mod:`robocal.kinematics._kernels`) unpack the same layout; keeping the
packer here lets a model be built, checked and written without importing numba.
"""

from __future__ import annotations

import numpy as np


def pack_fused(K, mparent, mtype, cpl_ptr, cpl_idx, cpl_coef, ee_anchor, E, post):
    """Pack the fused FK program into one int and one float array (cheap kernel dispatch)."""
    n_m, n_e = len(K), len(E)
    ints = np.concatenate([[n_m, n_e, len(cpl_idx)], mparent, mtype, cpl_ptr, cpl_idx, ee_anchor]).astype(np.int64)
    floats = np.concatenate([np.ravel(K), np.ravel(E), np.ravel(post), cpl_coef]).astype(float)
    return ints, floats
