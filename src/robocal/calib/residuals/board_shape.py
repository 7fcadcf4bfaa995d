"""Image points of a slightly bent board (issue 30 item 4): :class:`ReprojectionResidual` with the
board's out-of-plane shape as two more unknowns, as mrcal's two-parameter board sag.

The target's points are ``X(s) = X0 + (0, 0, s_x b_x + s_y b_y)`` in the target frame, with the
bases ``b_x = 1 - u^2``, ``b_y = 1 - v^2`` and ``u, v`` the point's x, y relative to the middle of
the points' extent, over its half-width (so ``u, v`` run from -1 to 1 across the outermost points).
``s_x``, ``s_y`` [mm] are the sag of the middle against the outermost points along x and y
(positive towards +z, the target frame's normal); a constant offset is the target pose's.
Derivative: a shape step ``ds`` moves the point by ``R_T e_z (b . ds)`` in T's parent frame, so
``p_camera`` by ``R_C^T R_M R_T e_z (b . ds)``.
"""

from __future__ import annotations

import numpy as np

from ..blocks.manifolds import VectorBlock
from .reprojection import ReprojectionResidual

__all__ = ["BoardShapeReprojectionResidual", "board_shape_block", "sag_bases"]


def sag_bases(target_points) -> np.ndarray:
    """(P, 2) the bases ``(1 - u^2, 1 - v^2)`` of the points (P, 3) [mm] (module docstring)."""
    X = np.asarray(target_points, dtype=float)
    lo, hi = X[:, :2].min(0), X[:, :2].max(0)
    half = np.where(hi > lo, 0.5 * (hi - lo), 1.0)
    uv = (X[:, :2] - 0.5 * (lo + hi)) / half
    return 1.0 - uv**2


def board_shape_block(initial=(0.0, 0.0), *, name: str = "board", free=True) -> VectorBlock:
    """The board's sag ``(<name>.sag_x, <name>.sag_y)`` [mm] as a parameter block."""
    return VectorBlock(name, [f"{name}.sag_x", f"{name}.sag_y"], ["mm", "mm"], np.asarray(initial, dtype=float),
                       free=free)


class BoardShapeReprojectionResidual(ReprojectionResidual):
    """:class:`ReprojectionResidual` of a board whose sag ``shape`` (a 2-vector block, see
    :func:`board_shape_block`) is estimated with the rest (module docstring)."""

    kind = "reprojection"

    def __init__(self, camera, camera_poses, target_poses, image_points, target_points, shape, **kw):
        super().__init__(camera, camera_poses, target_poses, image_points, target_points, **kw)
        self.shape = shape
        self.parameter_blocks = (*self.parameter_blocks, shape)
        self.bases = sag_bases(self.target_points)

    def _points(self, ev):
        img, pt = np.nonzero(self.mask)
        T = ev[self.target_poses][self.target_index[img]]
        C = ev[self.camera_poses][self.camera_index[img]]
        M = self._links(ev)[img]
        X = self.target_points[pt].copy()
        X[:, 2] += self.bases[pt] @ np.ravel(ev[self.shape])
        y = np.einsum("nij,nj->ni", T[:, :3, :3], X) + T[:, :3, 3]
        q = np.einsum("nij,nj->ni", M[:, :3, :3], y) + M[:, :3, 3]
        p = np.einsum("nji,nj->ni", C[:, :3, :3], q - C[:, :3, 3])
        return y, q, p, C[:, :3, :3], M[:, :3, :3], img

    def evaluate(self, ev, jacobian):
        r, jac, (y, q, p, RC, RM, img, d_point) = self._evaluate(ev, jacobian)
        if jacobian and ev.wants(self.shape):
            _, pt = np.nonzero(self.mask)
            RT = ev[self.target_poses][self.target_index[img]][:, :3, :3]
            normal = np.einsum("nji,njk,nk->ni", RC, RM, RT[:, :, 2])  # R_C^T R_M R_T e_z
            dp = normal[:, :, None] * self.bases[pt][:, None, :]  # (n, 3, 2)
            jac[self.shape] = (d_point @ dp).reshape(len(r), 2) * self.weight
        return r, jac

    @classmethod
    def example(cls, rng):
        """The first :meth:`ReprojectionResidual.example` set-up with a sag of a few tenths of a mm."""
        base = ReprojectionResidual.example(rng)[0]
        shape = board_shape_block(rng.normal(0.0, 0.3, 2))
        return cls(base.camera, base.camera_poses, base.target_poses, base.image_points, base.target_points, shape,
                   sigma=0.3)
