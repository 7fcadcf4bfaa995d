"""Image points of a target seen by a camera: pixel residuals (issue 14; METHODS.md section 3,
"Hand-eye" and "Camera self-calibration").

For image i the target's points ``X`` (P, 3) [mm, target frame] are seen at::

    p_camera = C[c_i]^-1 . M_i . T[t_i] . X          u = project(p_camera; camera intrinsics)

with ``C`` a :class:`~robocal.calib.blocks.FramesBlock` of camera poses and ``T`` one of target
poses, both written in a common frame W, and ``M_i`` (N, 4, 4) a known transform per image
between them (default identity). The three set-ups of issue 14 are choices of these:

* camera calibration: ``C`` the identity (fixed), ``T[i] = T_camera_target`` per image;
* eye-in-hand: ``C = T_flange_camera``, ``M_i = T_base_flange_i^-1``, ``T = T_base_target``;
* eye-to-hand: ``C = T_base_camera``, ``M_i = T_base_flange_i``, ``T = T_flange_target``.

Derivatives: frames are left-perturbed, ``F <- [exp(w) | v] F``. With ``q = M_i T X`` (in C's
parent frame) and ``y = T X`` (in T's parent frame), a camera step moves ``p_camera`` by
``R_C^T ([q]x w - v)``, a target step by ``R_C^T R_M (-[y]x w + v)``.
"""

from __future__ import annotations

import numpy as np

from ...camera.projection import project_points
from ..blocks.camera import CameraIntrinsics
from ..errors import ProblemError
from .base import ResidualBlock

__all__ = ["ReprojectionResidual", "cross_rows"]


class ReprojectionResidual(ResidualBlock):
    """Detected image points of a target: 2 rows (u, v) per detected point [px / sigma].

    camera: :class:`CameraIntrinsics`; camera_poses, target_poses: FramesBlocks (see the module
    docstring); image_points (N, P, 2) [px], NaN where a point was not detected; target_points
    (P, 3) [mm] in the target frame (z = 0 for a planar target); camera_index, target_index (N,)
    the frame of each image in its block (default 0 for a single frame, else the image index);
    links (N, 4, 4) the known ``M_i`` (default identity); sigma [px]; compact_targets: return the
    target poses' Jacobian as (M, 6), each row's derivative by its own target frame
    (``target_frame_of_row`` (M,) says which), instead of (M, 6 n_frames) mostly zeros -- for the
    structured solver (:mod:`robocal.calib.schur`), not for :meth:`Problem.evaluate`.
    """

    kind = "reprojection"

    def __init__(self, camera: CameraIntrinsics, camera_poses, target_poses, image_points, target_points, *,
                 camera_index=None, target_index=None, links=None, sigma: float | None = None, compact_targets: bool = False):
        uv = np.asarray(image_points, dtype=float)
        X = np.asarray(target_points, dtype=float)
        if uv.ndim != 3 or uv.shape[2] != 2 or X.shape != (uv.shape[1], 3):
            raise ProblemError(f"reprojection: image points (N, P, 2) and target points (P, 3) expected, got "
                               f"{uv.shape} and {X.shape}")
        N = len(uv)
        self.camera, self.camera_poses, self.target_poses = camera, camera_poses, target_poses
        self.image_points, self.target_points = uv, X
        self.camera_index = self._index(camera_index, camera_poses, N)
        self.target_index = self._index(target_index, target_poses, N)
        self.links = np.tile(np.eye(4), (N, 1, 1)) if links is None else np.asarray(links, dtype=float)
        if self.links.shape != (N, 4, 4):
            raise ProblemError(f"reprojection: links must be ({N}, 4, 4), got {self.links.shape}")
        self.mask = np.all(np.isfinite(uv), axis=2)  # (N, P)
        self._detected = uv[self.mask]  # (n, 2) the detected points, in row order
        self.image_of_row = np.nonzero(self.mask)[0]
        self.compact_targets = bool(compact_targets)
        self.target_frame_of_row = np.repeat(self.target_index[self.image_of_row], 2)
        super().__init__((camera, camera_poses, target_poses), np.repeat(self.image_of_row, 2), sigma)

    @staticmethod
    def _index(index, frames, N):
        if index is None:
            index = np.zeros(N, int) if frames.n_frames == 1 else np.arange(N)
        index = np.asarray(index, dtype=int)
        if index.shape != (N,) or index.min() < 0 or index.max() >= frames.n_frames:
            raise ProblemError(f"reprojection: {frames.name} index must be ({N},) in [0, {frames.n_frames})")
        return index

    def _links(self, ev):
        """The per-image links ``M_i`` (N, 4, 4) at this evaluation (fixed here; a subclass may
        compute them from parameters)."""
        return self.links

    def _points(self, ev):
        """(y, q, p_camera, R_C, R_M, image of each point), each (n, 3) or (n, 3, 3) for the n
        detected points."""
        img = self.image_of_row
        # per image (N, P, 3) by matrix products, then the detected points
        T = ev[self.target_poses][self.target_index]
        C = ev[self.camera_poses][self.camera_index]
        M = self._links(ev)
        m = self.mask
        # one matrix product for every image: Y[p, 3n + i] = sum_j X[p, j] R_n[i, j]
        N, P = m.shape
        Y = self.target_points @ T[:, :3, :3].transpose(2, 0, 1).reshape(3, 3 * N)
        y = (Y.reshape(P, N, 3).transpose(1, 0, 2) + T[:, None, :3, 3])[m]
        # identity links / camera frames (camera calibration) are skipped, not multiplied
        q = y if _all_identity(M, 4) else np.einsum("nij,nj->ni", M[img, :3, :3], y) + M[img, :3, 3]
        p = q if _all_identity(C, 4) else np.einsum("nji,nj->ni", C[img, :3, :3], q - C[img, :3, 3])
        return y, q, p, C[img, :3, :3], M[img, :3, :3], img

    def evaluate(self, ev, jacobian):
        return self._evaluate(ev, jacobian)[:2]

    def _evaluate(self, ev, jacobian):
        """``(r, jac, (y, q, p, R_C, R_M, img, d_point))``: the residuals, the Jacobians and the
        intermediate points for subclasses (``d_point`` (n, 2, 3) None without ``jacobian``)."""
        y, q, p, RC, RM, img = self._points(ev)
        intr, dist = CameraIntrinsics.split(ev[self.camera])
        proj = project_points(p, intr, dist, self.camera.model, jacobian)
        w = self.weight
        r = (self._detected - proj.pixels).ravel()
        if w != 1.0:
            r *= w
        if not jacobian:
            return r, None, (y, q, p, RC, RM, img, None)
        jac = {}
        if ev.wants(self.camera):
            jac[self.camera] = np.concatenate([proj.d_intrinsics, proj.d_distortion], axis=2).reshape(len(r), -1)
            if w != 1.0:
                jac[self.camera] *= w
        # a row a of d_point times [y]x is (a x y): the pose derivatives as cross products
        # (camera step: e_C = d_point R_C^T, [-(q x e_C), -e_C]; target step: e_T = e_C R_M, [y x e_T, e_T])
        e_C = proj.d_point if _all_identity(RC) else proj.d_point @ np.swapaxes(RC, 1, 2)
        for frames, index in ((self.camera_poses, self.camera_index), (self.target_poses, self.target_index)):
            if not ev.wants(frames):
                continue
            if frames is self.camera_poses:
                dpose = cross_rows(q, e_C, -1.0)
            else:
                dpose = cross_rows(y, e_C if _all_identity(RM) else e_C @ RM, 1.0)
            if self.compact_targets and frames is self.target_poses:
                jac[frames] = dpose.reshape(len(r), 6) if w == 1.0 else dpose.reshape(len(r), 6) * w
            else:
                J = np.zeros((len(p), 2, frames.n_frames, 6))
                J[np.arange(len(p)), :, index[img], :] = dpose
                jac[frames] = J.reshape(len(r), -1) * w
        return r, jac, (y, q, p, RC, RM, img, proj.d_point)

    def errors(self, r):
        """Pixel distances between detected and predicted points."""
        return np.linalg.norm((np.asarray(r) * (self.sigma or 1.0)).reshape(-1, 2), axis=1)

    @classmethod
    def example(cls, rng):
        """Two small set-ups: a Brown camera with per-image target poses and a fixed camera, and a
        division-model camera on a robot flange (links) with one target pose."""
        from ..blocks.manifolds import FramesBlock
        from .examples import example_frames

        grid = np.stack(np.meshgrid(np.arange(4.0), np.arange(3.0)), -1).reshape(-1, 2) * 30.0
        X = np.column_stack([grid - 45.0, np.zeros(len(grid))])
        out = []
        for model, dist, shared in (("brown", rng.normal(0, [0.1, 0.05, 0.002, 0.002, 0.02]), False),
                                    ("division", [rng.uniform(-0.3, 0.1)], True)):
            N = 4
            cam = CameraIntrinsics(rng.uniform([900, 900, 600, 450], [1100, 1100, 700, 550]), dist, model=model)
            T_ct = example_frames(rng, N)
            T_ct[:, :3, 3] = np.column_stack([rng.normal(0, 40, (N, 2)), rng.uniform(400, 700, N)])
            C = example_frames(rng, 1)
            links = example_frames(rng, N) if shared else np.tile(np.eye(4), (N, 1, 1))
            # target frames so that C^-1 M_i T_i = T_ct_i; with one shared target, per-image links absorb it
            T = np.linalg.inv(links) @ C @ T_ct
            if shared:
                links = C @ T_ct @ np.linalg.inv(T[:1])
                T = T[:1]
            uv = project_points((T_ct[:, None, :3, :3] @ X[None, :, :, None])[..., 0] + T_ct[:, None, :3, 3],
                                cam.initial[:4], cam.initial[4:], model).pixels
            uv = uv.reshape(N, len(X), 2) + rng.normal(0, 0.5, (N, len(X), 2))
            uv[1, 2] = np.nan
            out.append(cls(cam, FramesBlock("camera", C, free=shared), FramesBlock("target", T), uv, X,
                           links=None if not shared else links, sigma=0.3))
        return out


def cross_rows(a, e, sign):
    """``[sign * (a x e_k), sign * e_k]`` (n, 2, 6) for a (n, 3) and the two rows e (n, 2, 3): the
    derivative of two image coordinates by a left step ``(w, v)`` of a frame moving the point ``a``
    [mm], from their derivative ``e`` by the point (``e_k^T [a]x = (e_k x a)^T``)."""
    out = np.empty((len(a), 2, 6))
    a0, a1, a2 = (a[:, None, k] for k in range(3))
    e0, e1, e2 = e[..., 0], e[..., 1], e[..., 2]
    out[..., 0] = a1 * e2 - a2 * e1
    out[..., 1] = a2 * e0 - a0 * e2
    out[..., 2] = a0 * e1 - a1 * e0
    out[..., 3:] = e
    if sign != 1.0:
        out *= sign
    return out


def _all_identity(R, k: int = 3) -> bool:
    """Every matrix of R (n, k, k) exactly the identity (a fixed camera frame, no links)."""
    return bool(np.all(R == np.eye(k)))
