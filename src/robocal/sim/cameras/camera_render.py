"""Rendering images of a calibration board seen by a camera (pure numpy; issue 14).

For every pixel (``supersample`` x ``supersample`` sub-pixel samples) the ray is back-projected
through the camera model (undistortion of :mod:`robocal.camera`, so lens distortion is exact),
intersected with the board plane z = 0 and the printed board (:func:`robocal.io.boards.board_image`)
is sampled bilinearly; the samples of a pixel are averaged (anti-aliasing). Then the optics blur
(Gaussian, ``blur_px``), a lighting gradient and vignetting, and sensor noise (Gaussian, grey
levels) are applied and the result is quantised to 8 bits.

The rays depend only on the camera, so :class:`BoardRenderer` computes them once and renders any
number of board poses with a few vectorised operations per image.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter

from ...camera import Camera

__all__ = ["RenderSettings", "BoardRenderer"]


@dataclass(frozen=True)
class RenderSettings:
    """Image effects. supersample: samples per pixel side; blur_px: Gaussian sigma of the optics
    [px]; noise_grey: sensor noise sigma [grey levels of 255]; gradient: relative brightness change
    across the image (a linear ramp in a random direction); vignetting: relative darkening in the
    corners; background_grey: brightness of what is not the board; black_grey, white_grey: the
    board's printed black and white as seen."""

    supersample: int = 2
    blur_px: float = 0.6
    noise_grey: float = 2.0
    gradient: float = 0.25
    vignetting: float = 0.2
    background_grey: float = 70.0
    black_grey: float = 30.0
    white_grey: float = 220.0


def _interpolation_matrix(grid: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(len(at), len(grid)) weights of linear interpolation from the regular ``grid`` to ``at``."""
    step = grid[1] - grid[0]
    k = np.clip(np.floor((at - grid[0]) / step).astype(int), 0, len(grid) - 2)
    f = (at - grid[k]) / step
    M = np.zeros((len(at), len(grid)))
    M[np.arange(len(at)), k] = 1.0 - f
    M[np.arange(len(at)), k + 1] = f
    return M


def _texture_outline(shape, affine: np.ndarray) -> np.ndarray:
    """(K, 3) board points [mm] along the border of the texture (to find where it appears)."""
    Ht, Wt = shape
    A = np.vstack([affine, [0.0, 0.0, 1.0]])
    t = np.linspace(0.0, 1.0, 33)
    cols = np.concatenate([t * (Wt - 1), np.full_like(t, Wt - 1), (1 - t) * (Wt - 1), np.zeros_like(t)])
    rows = np.concatenate([np.zeros_like(t), t * (Ht - 1), np.full_like(t, Ht - 1), (1 - t) * (Ht - 1)])
    xy = np.linalg.solve(A, np.stack([cols, rows, np.ones_like(cols)]))[:2].T
    return np.column_stack([xy, np.zeros(len(xy))])


class BoardRenderer:
    """Renders a board texture for one camera.

    camera: the true camera (its ``image_size`` is required); texture: (Ht, Wt) uint8 printed
    board; affine: (2, 3) board [mm] -> texel (column, row) (:func:`robocal.io.boards.board_image`);
    surface: optional ``surface(x, y) -> z`` [mm, board frame] of a slightly bent board (default flat).
    """

    def __init__(self, camera: Camera, texture: np.ndarray, affine: np.ndarray, settings: RenderSettings | None = None,
                 ray_grid_px: float = 8.0, surface=None):
        if camera.image_size is None:
            raise ValueError("camera.image_size (width, height) is needed to render images")
        self.camera = camera
        # optional board surface z = surface(x, y) [mm, board frame] (a slightly bent board); the
        # ray is moved from the plane to that height once (error second order in the slope)
        self._surface = surface
        self.settings = settings or RenderSettings()
        self.texture = np.asarray(texture, dtype=np.float32) / 255.0
        self.affine = np.asarray(affine, dtype=float).reshape(2, 3)
        w, h = (int(v) for v in camera.image_size)
        self.width, self.height = w, h
        n = int(self.settings.supersample)
        offsets = (np.arange(n) + 0.5) / n - 0.5
        v = (np.arange(h)[:, None] + offsets[None, :]).ravel()
        u = (np.arange(w)[:, None] + offsets[None, :]).ravel()
        # the rays are smooth in the pixel position: undistort exactly on a coarse grid and
        # interpolate bilinearly (error below 0.002 px for ordinary lenses, checked in the tests)
        step = float(ray_grid_px)
        gu = np.arange(-1.0, w + step, step)
        gv = np.arange(-1.0, h + step, step)
        guu, gvv = np.meshgrid(gu, gv)
        coarse = camera.rays(np.stack([guu.ravel(), gvv.ravel()], axis=1)).reshape(len(gv), len(gu), 2)
        Wv, Wu = _interpolation_matrix(gv, v), _interpolation_matrix(gu, u)
        # (H n, W n) in the order (row, sub-row, column, sub-column)
        self._x = (Wv @ coarse[..., 0] @ Wu.T).astype(np.float32).reshape(h, n, w, n)
        self._y = (Wv @ coarse[..., 1] @ Wu.T).astype(np.float32).reshape(h, n, w, n)
        self._outline = _texture_outline(self.texture.shape, self.affine)

    def _region(self, T: np.ndarray):
        """Pixel rows and columns (slices) that can show the texture, or None for the full image."""
        p = self.camera.project((T[:3, :3] @ self._outline.T).T + T[:3, 3]).pixels
        if not np.all(np.isfinite(p)):
            return slice(0, self.height), slice(0, self.width)
        pad = 4
        c0, c1 = int(np.floor(p[:, 0].min())) - pad, int(np.ceil(p[:, 0].max())) + pad + 1
        r0, r1 = int(np.floor(p[:, 1].min())) - pad, int(np.ceil(p[:, 1].max())) + pad + 1
        return slice(max(r0, 0), min(max(r1, 0), self.height)), slice(max(c0, 0), min(max(c1, 0), self.width))

    def board_intensity(self, T_camera_target: np.ndarray):
        """Printed brightness in [0, 1] seen by the sub-pixel samples of the pixels that can show
        the board: ``(rows, cols, values (h, n, w, n))``, NaN where a ray misses the texture."""
        T = np.asarray(T_camera_target, dtype=float).reshape(4, 4)
        rows, cols = self._region(T)
        R, t = T[:3, :3], T[:3, 3]
        r1, r2, r3 = (R[:, k].astype(np.float32) for k in range(3))
        x = np.ascontiguousarray(self._x[rows, :, cols, :])
        y = np.ascontiguousarray(self._y[rows, :, cols, :])
        # ray parameter s of the plane z = 0: s = (r3 . t) / (r3 . d), d = (x, y, 1)
        s = r3[0] * x
        s += r3[1] * y
        s += r3[2]
        with np.errstate(divide="ignore", invalid="ignore"):
            np.divide(np.float32(r3 @ t), s, out=s)
        s[~(s > 0)] = np.nan
        # the ray point s (x, y, 1) in the board frame: R^T (s d - t); then texel coordinates
        X = r1[0] * x
        X += r1[1] * y
        X += r1[2]
        X *= s
        X -= np.float32(r1 @ t)
        Y = r2[0] * x
        Y += r2[1] * y
        Y += r2[2]
        Y *= s
        Y -= np.float32(r2 @ t)
        if self._surface is not None:
            # the ray at board height h: s' = s (1 + h / (r3 . t)), so (X + r1.t) scales by the same factor
            f = 1.0 + np.asarray(self._surface(X, Y), dtype=np.float32) / np.float32(r3 @ t)
            X = (X + np.float32(r1 @ t)) * f - np.float32(r1 @ t)
            Y = (Y + np.float32(r2 @ t)) * f - np.float32(r2 @ t)
        A = self.affine.astype(np.float32)
        col = A[0, 0] * X
        col += A[0, 1] * Y
        col += A[0, 2]
        row = A[1, 0] * X
        row += A[1, 1] * Y
        row += A[1, 2]
        Ht, Wt = self.texture.shape
        inside = (col >= 0) & (col < Wt - 1) & (row >= 0) & (row < Ht - 1)
        col[~inside] = 0
        row[~inside] = 0
        c0 = np.floor(col)
        r0 = np.floor(row)
        col -= c0  # fractions
        row -= r0
        k = (r0 * Wt + c0).astype(np.int32)
        flat = self.texture.ravel()
        top = flat[k]
        top += col * (flat[k + 1] - top)
        k += Wt
        bottom = flat[k]
        bottom += col * (flat[k + 1] - bottom)
        bottom -= top
        bottom *= row
        val = top + bottom
        val[~inside] = np.nan
        return rows, cols, val

    def render(self, T_camera_target: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """One 8-bit grey image (H, W) of the board at ``T_camera_target`` (4, 4) [mm]."""
        st = self.settings
        grey = np.full((self.height, self.width), np.float32(st.background_grey), dtype=np.float32)
        rows, cols, samples = self.board_intensity(T_camera_target)
        g = st.black_grey + (st.white_grey - st.black_grey) * samples
        g[np.isnan(g)] = st.background_grey
        grey[rows, cols] = g.mean(axis=(1, 3))
        if st.blur_px > 0:
            grey = gaussian_filter(grey, st.blur_px, mode="nearest")
        h, w = grey.shape
        xn = (np.arange(w, dtype=np.float32) - w / 2) / (w / 2)
        yn = (np.arange(h, dtype=np.float32) - h / 2) / (h / 2)
        angle = rng.uniform(0, 2 * np.pi)
        light = 1.0 + 0.5 * st.gradient * (np.float32(np.cos(angle)) * xn[None, :] + np.float32(np.sin(angle)) * yn[:, None])
        light *= 1.0 - st.vignetting * (xn[None, :] ** 2 + yn[:, None] ** 2) / 2
        grey = grey * light + rng.normal(0.0, st.noise_grey, size=grey.shape).astype(np.float32)
        return np.clip(np.rint(grey), 0, 255).astype(np.uint8)
