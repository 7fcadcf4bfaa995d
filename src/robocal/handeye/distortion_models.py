"""Which lens-distortion terms the images determine (issue 30 item 3, issue 25 item 6).

* :data:`DISTORTION_MODELS`: the standard OpenCV sets by name, as a coefficient count and the
  terms held at zero: ``k1-k2``, ``k1-k3``, ``k1-k2-p1-p2``, ``k1-k3-p1-p2`` (OpenCV's default 5)
  and ``rational`` (8: k1-k6 with p1, p2).
* :func:`held_out_rms_px`: K-fold cross-validation over images (image ``i`` in fold ``i mod K``):
  the camera calibrated on the other folds, each held-out image's board pose found by PnP with that
  camera, the held-out corners' RMS [px]. A term that only fits the noise of the training images
  raises it.
* :func:`select_distortion_model`: the model with the lowest held-out RMS; a richer model is kept
  only if it lowers it by more than 1 % (otherwise the simpler one).
* :func:`undetermined_terms`: the distortion terms whose 1-sigma exceeds their magnitude: the
  images do not determine them (they are reported by name, not as if known).
"""

from __future__ import annotations

import numpy as np

from .pnp import solve_pnp

__all__ = ["DISTORTION_MODELS", "held_out_rms_px", "select_distortion_model", "undetermined_terms",
           "DISTORTION_TERMS"]

#: OpenCV's Brown-Conrady coefficients in order
DISTORTION_TERMS = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")

#: name -> (coefficient count, terms held at 0), simplest first
DISTORTION_MODELS = {
    "k1-k2": (5, ("p1", "p2", "k3")),
    "k1-k2-p1-p2": (4, ()),
    "k1-k3": (5, ("p1", "p2")),
    "k1-k3-p1-p2": (5, ()),
    "rational": (8, ()),
}

#: a richer model must lower the held-out RMS by more than this (relative)
SELECTION_MARGIN = 0.01


def held_out_rms_px(calibrate, uv, X, folds: int = 5, min_points: int = 6) -> float:
    """Held-out RMS per corner [px] of ``calibrate(uv_train) -> CameraCalibration`` (module
    docstring). uv (N, P, 2) [px] NaN where not detected; X (P, 3) [mm]. NaN with fewer than 4
    images."""
    N = len(uv)
    if N < 4:
        return float("nan")
    K = min(folds, N)
    fold = np.arange(N) % K
    sse, n = 0.0, 0
    for k in range(K):
        cal = calibrate(uv[fold != k])
        test = uv[fold == k]
        T, _, _ = solve_pnp(cal.camera, X, test, min_points=min_points)
        p = np.einsum("nij,pj->npi", T[:, :3, :3], X) + T[:, None, :3, 3]
        r = test - cal.camera.project(p.reshape(-1, 3)).pixels.reshape(test.shape)
        ok = np.all(np.isfinite(r), axis=2)
        sse, n = sse + float(np.sum(r[ok] ** 2)), n + int(ok.sum())
    return float(np.sqrt(sse / max(n, 1)))


def select_distortion_model(calibrate_model, uv, X, *, models=None, folds: int = 5, min_points: int = 6) -> tuple:
    """``(name, {name: held-out RMS [px]})``: the distortion model of :data:`DISTORTION_MODELS`
    (or ``models``, simplest first) with the lowest held-out RMS, a richer one kept only when it
    is more than 1 % lower. ``calibrate_model(name, uv_train)`` calibrates with that model."""
    names = list(models or DISTORTION_MODELS)
    scores = {m: held_out_rms_px(lambda u, m=m: calibrate_model(m, u), uv, X, folds, min_points) for m in names}
    best = names[0]
    for m in names[1:]:
        if np.isfinite(scores[m]) and scores[m] < (1.0 - SELECTION_MARGIN) * scores[best]:
            best = m
    return best, scores


def undetermined_terms(values: dict, sigma: dict) -> dict:
    """{term: (value, sigma)} of the distortion terms (k1...k6, p1, p2, kappa) whose 1-sigma
    exceeds their magnitude; terms without a sigma (held) are not listed."""
    out = {}
    for name, v in values.items():
        if name not in DISTORTION_TERMS and name != "kappa":
            continue
        s = sigma.get(name)
        if s is not None and np.isfinite(s) and s > 0 and s > abs(v):
            out[name] = (float(v), float(s))
    return out
