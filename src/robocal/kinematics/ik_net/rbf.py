"""A Gaussian radial-basis-function network with a linear output layer solved by least squares.

``y(x) = W^T [phi(x); x; 1]`` with ``phi_k(x) = exp(-|x - c_k|^2 / (2 sigma^2))``: K Gaussian units
with one shared width sigma on the z-scored inputs, plus an affine tail (so the units only model
what a linear map cannot). The centres are K training inputs drawn at random (seeded); sigma is
``width_factor`` times the mean distance from a centre to its nearest neighbour among the centres;
``W`` solves the ridge problem ``min |A W - Y|^2 + lam * s * |W|^2`` with ``s`` the mean diagonal of
``A^T A`` (so ``lam`` is relative, as in the damped least squares of :mod:`..ik`). Structure
(K, width_factor, lam) is what the genetic algorithm of :mod:`.tuning` chooses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["RBFNetwork", "fit_rbf"]


@dataclass(frozen=True)
class RBFNetwork:
    """Input scaling ``x_mean, x_std`` (D,) (inputs are used as ``(x - x_mean) / x_std``), centres (K, D) in scaled inputs, width ``sigma``,
    output weights (K + D + 1, M) and output offset ``y_mean`` (M,)."""

    x_mean: np.ndarray
    x_std: np.ndarray
    centres: np.ndarray
    sigma: float
    weights: np.ndarray
    y_mean: np.ndarray

    @property
    def n_centres(self) -> int:
        return len(self.centres)

    def scaled(self, X) -> np.ndarray:
        return (np.asarray(X, dtype=float) - self.x_mean) / self.x_std

    def design(self, Xs) -> np.ndarray:
        """Design matrix (N, K + D + 1) of scaled inputs ``Xs`` (N, D)."""
        return _design(Xs, self.centres, self.sigma)

    def predict(self, X) -> np.ndarray:
        """Outputs (N, M) for inputs ``X`` (N, D)."""
        return self.design(self.scaled(X)) @ self.weights + self.y_mean

    def nearest_centre_distance(self, X) -> np.ndarray:
        """(N,) distance of each input to its nearest centre, in units of ``sigma``."""
        d2 = _sq_distances(self.scaled(X), self.centres)
        return np.sqrt(np.maximum(d2.min(axis=1), 0.0)) / self.sigma


def _sq_distances(Xs, C):
    return (np.einsum("ij,ij->i", Xs, Xs)[:, None] + np.einsum("ij,ij->i", C, C)[None, :]
            - 2.0 * (Xs @ C.T))


def _design(Xs, C, sigma):
    Phi = _sq_distances(Xs, C)
    Phi *= -0.5 / sigma ** 2
    np.exp(Phi, out=Phi)
    return np.hstack([Phi, Xs, np.ones((len(Xs), 1))])


def fit_rbf(X, Y, n_centres: int, width_factor: float, reg: float, rng, input_weights=None) -> RBFNetwork:
    """Fit the network to inputs ``X`` (N, D) and targets ``Y`` (N, M) (see the module docstring).

    ``rng``: a numpy Generator (choice of the centres). ``input_weights`` (D,): multiply the z-scored
    inputs (e.g. position against rotation features) before distances are taken; default all 1."""
    X = np.asarray(X, dtype=float)
    Y = np.asarray(Y, dtype=float)
    x_mean, x_std = X.mean(axis=0), X.std(axis=0)
    x_std = np.where(x_std > 1e-12, x_std, 1.0)
    if input_weights is not None:
        x_std = x_std / np.asarray(input_weights, dtype=float)
    Xs = (X - x_mean) / x_std
    K = int(min(max(n_centres, 2), len(X)))
    C = Xs[rng.choice(len(X), size=K, replace=False)]
    nn, _ = cKDTree(C).query(C, k=2)
    sigma = float(width_factor * np.mean(nn[:, 1]))
    A = _design(Xs, C, sigma)
    y_mean = Y.mean(axis=0)
    AtA = A.T @ A
    s = max(float(np.trace(AtA)) / len(AtA), 1e-300)
    AtA[np.diag_indices_from(AtA)] += reg * s
    W = _solve_spd(AtA, A.T @ (Y - y_mean))
    return RBFNetwork(x_mean, x_std, C, sigma, W, y_mean)


def _solve_spd(M, B):
    from scipy.linalg import LinAlgError, cho_factor, cho_solve

    try:
        return cho_solve(cho_factor(M, check_finite=False), B, check_finite=False)
    except LinAlgError:  # numerically indefinite at tiny lam: least squares instead
        return np.linalg.lstsq(M, B, rcond=None)[0]
