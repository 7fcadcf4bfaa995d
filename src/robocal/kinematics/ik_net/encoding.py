"""Pose encoding of the learned IK seed: position plus a continuous 6-D rotation representation.

A pose ``T`` (4, 4) [mm] becomes the 9-vector ``(p / L, r1, r2)``: the position divided by a length
scale ``L`` [mm] (the largest sampled reach, so positions are O(1) like the rotation entries) and
the first two columns ``r1, r2`` of its rotation matrix. The 6-D rotation representation is
continuous (Zhou, Barnes, Lu, Yang, Li, "On the continuity of rotation representations in neural
networks", CVPR 2019): unlike Euler angles or quaternions (double cover) it has no jumps, which a
smooth regressor such as an RBF network needs. The third column is their cross product, so nothing
is lost.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ENCODING", "encode_poses"]

ENCODING = "position/L + rot6d (first two rotation columns), z-scored"
"""The name stored in network files; a file with another encoding is refused."""


def encode_poses(T, length_scale_mm: float) -> np.ndarray:
    """Features (N, 9) of poses ``T`` (N, 4, 4) [mm]: ``p / length_scale_mm`` then columns 0, 1 of R."""
    T = np.asarray(T, dtype=float).reshape(-1, 4, 4)
    return np.concatenate([T[:, :3, 3] / length_scale_mm, T[:, :3, 0], T[:, :3, 1]], axis=1)
