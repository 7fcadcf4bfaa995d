"""Screening of the thermal compensation parameters (thesis 3.2, figure 3-5, tables 5-1 / 5-2).

In the production gap only ~6 sphere poses (18 equations) can be measured, so only 6-9 of the 24
free DH + beta parameters can be re-identified. Screening picks them offline from a long heating
run in which the sphere is measured from many poses (thesis: 20) and monitored points on the
workpiece (thesis: 34 car-body points) are measured by a robot-held sensor in every cycle.

**Identification** (per cycle c, thesis (3-8)-(3-10)): ``Y_c = A dX_c`` with ``Y_c`` the stacked
sphere differences warm - cold (sensor frame) and ``A`` the stacked ``M(q_i)`` columns of the
chosen parameters (:func:`robocal.thermal.drift_coefficients`, computed once). Solved by the
truncated SVD (minimum-norm least squares) on unit-norm columns, singular values below
``rcond * s_max`` dropped -- exactly (3-10), so a subset that is not identifiable from the poses
(e.g. all four parameters of the last link from a single sphere centre) still gets a solution,
which is what makes large sets score badly. All cycles are solved at once (one pseudo-inverse,
many right-hand sides); the candidate sets of a screening step are solved as one stacked batch.

**Compensated residual** at monitored point k in cycle c. The robot-held sensor measures the
point at ``p_ck`` (sensor frame) from the recorded joints ``q_k``; with parameter deltas ``dX``
the model places it at ``X_ck(dX) = T_base_flange(q_k; X + dX) . T_flange_sensor . p_ck``. The
residual after compensation is::

    r_ck = X_ck(dX_c) - X_k(0)_cold = b_ck + J_k dX_c           (first order in dX_c: error < 1e-3 mm)
    b_ck = R_base_flange(q_k) R_flange_sensor (p_ck - p_k,cold)   (the drift seen without compensation)
    J_k  = d X / d X_params at the point F_k = T_flange_sensor . p_k,cold (identification Jacobian)

i.e. the thesis's "recompute the body points from the joints and the sensor measurement with the
identified parameters" (5.1.3), relative to the cold measurement of the same point. It equals the
drift the corrected program would leave at that point. "Before" is ``dX = 0`` (``r = b``).

**The metric lambda**: for each monitored direction (x, y, z of each point, base frame) the
residual over the run is summarised by a statistic over the cycles -- default ``"rms"`` (root
mean square over all cycles; ``"max"``: largest absolute value; ``"mean_abs"``) -- and
``lambda = 100 * (#directions with statistic < threshold) / (#directions)`` [%], threshold
0.1 mm by default. (The thesis does not say how a direction's residual over the 90 cycles is
summarised; RMS is the choice that tolerates single noisy cycles. With ``"max"`` a direction
passes only if it never left the band.)

**Stationarity** of an identified parameter series (thesis: "sample autocorrelation with an
interval test"): :func:`stationarity_test`. With ``n`` samples, sample autocorrelations
``r_k = sum_t (x_t - m)(x_{t+k} - m) / sum_t (x_t - m)^2`` for lags ``k = 1..K`` (``K =
min(15, n // 4)`` by default). Lags ``1..q`` (``small_lags``, default 1) may be correlated (short
memory is allowed in a stationary series); every lag ``k > q`` is tested against Bartlett's band
for an MA(q) process, ``|r_k| <= z sqrt((1 + 2 sum_{i<=q} r_i^2) / n)`` (``z`` = 1.96, 95 %). The
series is stationary when at least ``min_inside`` (default 80 %) of the tested lags lie inside
the band. White noise passes (each lag is outside with probability ~5 %); a trend or a random
walk has autocorrelations that decay slowly and stay far outside.

**Greedy backward elimination** (figure 3-5, :func:`screen_parameters`): start with all
candidates (default: the model's 24 free parameters); identify them over the run, compute lambda
and each parameter's series; the stationary ones form S (if S is empty, every current parameter
is a candidate). For each s in S identify the set without s and compute its lambda; remove the s
with the highest lambda (the thesis: take an improving one; if none improves, the best one --
both are the arg max). Ties in lambda (it moves in steps of 1/#directions) are broken by the
lower mean residual statistic, then by parameter order. Repeat until ``n_keep`` (default 8) remain.

:func:`traditional_parameters`: the traditional choice, only the non-zero length parameters
(d1, d4, d6, a1, a2, a3 on the KR150), derived from the model's nominal values.
:func:`select_online_poses`: the online pose subset (e.g. 6 of the 20) that minimises the
predicted noise at the monitored points for a given parameter set.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..kinematics.model import RobotModel
from .drift import drift_coefficients

__all__ = [
    "LAMBDA_THRESHOLD_MM", "STATISTICS", "ScreeningProblem", "SetEvaluation", "ScreeningStep", "ScreeningResult",
    "StationarityResult", "direction_residuals", "lambda_metric", "sample_autocorrelation", "stationarity_test",
    "screen_parameters", "traditional_parameters", "select_online_poses", "format_screening_table",
]

LAMBDA_THRESHOLD_MM = 0.1
STATISTICS = ("rms", "max", "mean_abs")


# ---------------------------------------------------------------------------------------------- lambda
def direction_residuals(residuals, statistic: str = "rms", axis: int = 0) -> np.ndarray:
    """Summarise residuals over the cycles (``axis``, default the first): ``"rms"``, ``"max"``
    (largest absolute value) or ``"mean_abs"``. (C, K, 3) -> (K, 3); (C, D) -> (D,)."""
    r = np.asarray(residuals, dtype=float)
    if statistic == "rms":
        return np.sqrt(np.mean(r * r, axis=axis))
    if statistic == "max":
        return np.max(np.abs(r), axis=axis)
    if statistic == "mean_abs":
        return np.mean(np.abs(r), axis=axis)
    raise ValueError(f"unknown statistic {statistic!r}; choose from {STATISTICS}")


def lambda_metric(residuals, threshold_mm: float = LAMBDA_THRESHOLD_MM, statistic: str = "rms") -> float:
    """The thesis's lambda [%]: share of monitored directions whose residual statistic over the
    cycles is below ``threshold_mm``. ``residuals`` (C, K, 3) (cycles, points, x/y/z) [mm] or (C, D)."""
    s = direction_residuals(residuals, statistic)
    return float(100.0 * np.mean(s < threshold_mm))


# ---------------------------------------------------------------------------------------------- stationarity
def sample_autocorrelation(x, max_lag: int) -> np.ndarray:
    """Sample autocorrelation ``r_0 .. r_max_lag`` of series ``x`` (n,) or of each row of (k, n)
    (biased estimator: sums over ``n - lag`` products divided by the total sum of squares)."""
    x = np.asarray(x, dtype=float)
    one = x.ndim == 1
    x = np.atleast_2d(x)
    n = x.shape[1]
    if not 0 <= max_lag < n:
        raise ValueError(f"max_lag must be in [0, {n - 1}] for a series of {n} samples, got {max_lag}")
    d = x - x.mean(axis=1, keepdims=True)
    c0 = np.sum(d * d, axis=1)
    r = np.empty((len(x), max_lag + 1))
    for k in range(max_lag + 1):
        r[:, k] = np.sum(d[:, : n - k] * d[:, k:], axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.where(c0[:, None] > 0, r / np.where(c0 > 0, c0, 1.0)[:, None], 0.0)
    r[:, 0] = 1.0
    return r[0] if one else r


@dataclass(frozen=True)
class StationarityResult:
    """acf (K+1,): r_0..r_K; band: the half width of the interval for lags > small_lags;
    tested (K - q,): the lags tested; inside_share: share of them inside; stationary: the verdict."""

    acf: np.ndarray
    band: float
    tested: np.ndarray
    inside_share: float
    stationary: bool


def _default_lag(n: int) -> int:
    return max(1, min(15, n // 4))


def stationarity_test(x, *, max_lag: int | None = None, small_lags: int = 1, z: float = 1.96,
                      min_inside: float = 0.8):
    """Interval test of the sample autocorrelation (see the module docstring).

    x: a series (n,) -> :class:`StationarityResult`; or (k, n), k series -> bool array (k,).
    max_lag: K (default ``min(15, n // 4)``); small_lags: q, lags not tested; z: band in standard
    errors; min_inside: share of lags ``q+1..K`` that must lie inside ``+- z sqrt((1 + 2 sum_{i<=q}
    r_i^2) / n)``. A constant series (no variation) counts as stationary.
    """
    x = np.asarray(x, dtype=float)
    one = x.ndim == 1
    X = np.atleast_2d(x)
    n = X.shape[1]
    K = _default_lag(n) if max_lag is None else int(max_lag)
    q = int(small_lags)
    if not 0 <= q < K:
        raise ValueError(f"small_lags must be in [0, max_lag), got {q} with max_lag {K}")
    r = sample_autocorrelation(X, K)
    band = z * np.sqrt((1.0 + 2.0 * np.sum(r[:, 1:q + 1] ** 2, axis=1)) / n)
    inside = np.abs(r[:, q + 1:]) <= band[:, None]
    share = inside.mean(axis=1)
    verdict = share >= min_inside
    if one:
        return StationarityResult(r[0], float(band[0]), np.arange(q + 1, K + 1), float(share[0]), bool(verdict[0]))
    return verdict


# ---------------------------------------------------------------------------------------------- problem
@dataclass
class SetEvaluation:
    """A parameter set evaluated over a run: names; lam [%]; score: mean residual statistic over
    the directions [mm] (the tie-breaker); deltas (C, k) identified per cycle [mm | rad];
    stats (K, 3): each direction's residual statistic [mm]; residuals (C, K, 3) [mm]."""

    names: tuple
    lam: float
    score: float
    deltas: np.ndarray
    stats: np.ndarray
    residuals: np.ndarray


@dataclass
class ScreeningProblem:
    """Everything screening needs, precomputed (see the module docstring for the definitions).

    names (F,): candidate parameter names; M (m, 3, F): sphere coefficients ``M(q_i)`` (sensor
    frame); Y (C, m, 3): sphere warm - cold per cycle [mm]; J (K, 3, F): monitored-point
    coefficients (base frame); before (C, K, 3): monitored residuals without compensation [mm];
    times_s (C,) optional; rcond: relative singular-value cut of the SVD solve.
    Build from measurements with :meth:`from_measurements`.
    """

    names: tuple
    M: np.ndarray
    Y: np.ndarray
    J: np.ndarray
    before: np.ndarray
    times_s: np.ndarray | None = None
    rcond: float = 1e-10

    def __post_init__(self):
        self.names = tuple(self.names)
        self.M = np.asarray(self.M, float)
        self.Y = np.asarray(self.Y, float)
        self.J = np.asarray(self.J, float)
        self.before = np.asarray(self.before, float)
        F = len(self.names)
        m, K = self.M.shape[0], self.J.shape[0]
        C = self.Y.shape[0]
        if self.M.shape != (m, 3, F) or self.Y.shape != (C, m, 3):
            raise ValueError(f"M {self.M.shape} / Y {self.Y.shape}: expected (m, 3, {F}) and (C, m, 3)")
        if self.J.shape != (K, 3, F) or self.before.shape != (C, K, 3):
            raise ValueError(f"J {self.J.shape} / before {self.before.shape}: expected (K, 3, {F}) and ({C}, K, 3)")
        A = self.M.reshape(3 * m, F)
        norms = np.linalg.norm(A, axis=0)
        self._norms = np.where(norms > 0, norms, 1.0)
        self._An = A / self._norms                                   # unit-norm columns
        self._Yt = self.Y.reshape(C, 3 * m).T                        # (3m, C)
        self._Jn = self.J.reshape(3 * K, F) / self._norms            # monitored rows in scaled units
        self._Bt = self.before.reshape(C, 3 * K).T                   # (3K, C)
        self._col = {n: i for i, n in enumerate(self.names)}

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_measurements(cls, model: RobotModel, T_sensor_base, P_e, q_sphere, sphere_cold, sphere, q_monitor,
                          monitor_cold, monitor, T_flange_sensor, *, candidates=None, times_s=None,
                          rcond: float = 1e-10) -> "ScreeningProblem":
        """Build the problem from measurements.

        model: the cold model (linearisation point). T_sensor_base (4, 4), P_e (3,): the system
        calibration. q_sphere (m, n); sphere_cold (m, 3); sphere (C, m, 3): sphere centres in the
        sensor frame [mm]. q_monitor (K, n); monitor_cold (K, 3); monitor (C, K, 3): monitored
        points in the robot-held sensor's frame [mm]; T_flange_sensor (4, 4): that sensor on the
        flange. candidates: parameter names (default the model's free parameters).
        """
        names = model.params.names
        cand = [n for n, f in zip(names, model.params.free) if f] if candidates is None else list(candidates)
        cols = np.array([model.params.index(n) for n in cand])
        q_sphere = np.atleast_2d(np.asarray(q_sphere, float))
        sphere = np.asarray(sphere, float)
        M = drift_coefficients(model, T_sensor_base, P_e, q_sphere)[:, :, cols]
        Y = sphere - np.asarray(sphere_cold, float)[None]
        qm = np.atleast_2d(np.asarray(q_monitor, float))
        mc = np.asarray(monitor_cold, float)
        Tfs = np.asarray(T_flange_sensor, float)
        T = model.fk(qm)                                               # (K, 4, 4) world
        R = T[:, :3, :3] @ Tfs[:3, :3]                                 # R_world_sensor per pose
        before = np.einsum("kij,ckj->cki", R, np.asarray(monitor, float) - mc[None])
        F_pts = mc @ Tfs[:3, :3].T + Tfs[:3, 3]                        # points in the flange frame
        Jall = model.identification_jacobian(qm, points=F_pts)         # (K, K, 3, P)
        k = np.arange(len(qm))
        J = Jall[k, k][:, :, cols]
        return cls(tuple(cand), M, Y, J, before, None if times_s is None else np.asarray(times_s, float), rcond)

    def with_poses(self, index) -> "ScreeningProblem":
        """The same problem with only the sphere poses ``index`` (e.g. the 6 online poses)."""
        idx = np.asarray(index)
        return ScreeningProblem(self.names, self.M[idx], self.Y[:, idx], self.J, self.before, self.times_s, self.rcond)

    def with_cycles(self, index) -> "ScreeningProblem":
        """The same problem with only the cycles ``index``."""
        idx = np.asarray(index)
        return ScreeningProblem(self.names, self.M, self.Y[idx], self.J, self.before[idx],
                                None if self.times_s is None else self.times_s[idx], self.rcond)

    @property
    def n_cycles(self) -> int:
        return self.Y.shape[0]

    @property
    def n_poses(self) -> int:
        return self.M.shape[0]

    @property
    def n_directions(self) -> int:
        return 3 * self.J.shape[0]

    def columns(self, names) -> np.ndarray:
        """Column indices of parameter ``names`` (unknown names: ``KeyError`` listing the candidates)."""
        names = [names] if isinstance(names, str) else list(names)
        try:
            return np.array([self._col[n] for n in names], dtype=np.int64)
        except KeyError as e:
            raise KeyError(f"{e.args[0]!r} is not a candidate parameter; candidates: {list(self.names)}") from None

    # ------------------------------------------------------------------ solve
    def _solve_batch(self, sets: np.ndarray) -> np.ndarray:
        """Scaled deltas (B, k, C) for B column sets (B, k) -- one stacked truncated-SVD solve."""
        A = np.moveaxis(self._An[:, sets], 1, 0)                       # (B, 3m, k)
        return np.linalg.pinv(A, rcond=self.rcond) @ self._Yt          # (B, k, C)

    def _residual_batch(self, sets: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Residuals (B, 3K, C) for scaled deltas x (B, k, C)."""
        Js = np.moveaxis(self._Jn[:, sets], 1, 0)                      # (B, 3K, k)
        return self._Bt[None] + Js @ x

    def identify(self, names) -> np.ndarray:
        """Identified deltas (C, k) [mm | rad] of parameter set ``names`` in every cycle."""
        cols = self.columns(names)
        if len(cols) == 0:
            return np.zeros((self.n_cycles, 0))
        x = self._solve_batch(cols[None])[0]
        return (x / self._norms[cols, None]).T

    def residuals(self, names) -> np.ndarray:
        """Compensated residuals (C, K, 3) [mm] at the monitored points with set ``names``
        (empty: no compensation, the "before" residuals)."""
        cols = self.columns(names)
        if len(cols) == 0:
            return self.before.copy()
        x = self._solve_batch(cols[None])
        return self._residual_batch(cols[None], x)[0].T.reshape(self.before.shape)

    def evaluate(self, names, threshold_mm: float = LAMBDA_THRESHOLD_MM, statistic: str = "rms") -> SetEvaluation:
        """lambda and the rest for one parameter set (empty = no compensation)."""
        names = tuple([names] if isinstance(names, str) else names)
        r = self.residuals(names)
        st = direction_residuals(r, statistic)
        return SetEvaluation(names, float(100.0 * np.mean(st < threshold_mm)), float(st.mean()), self.identify(names),
                             st, r)

    def _evaluate_sets(self, sets: np.ndarray, threshold_mm, statistic):
        """lambda (B,), score (B,), deltas (B, k, C) [mm | rad] of B column sets (B, k)."""
        x = self._solve_batch(sets)
        R = self._residual_batch(sets, x)                              # (B, 3K, C)
        st = direction_residuals(R, statistic, axis=2)                 # (B, 3K)
        lam = 100.0 * np.mean(st < threshold_mm, axis=1)
        return lam, st.mean(axis=1), x / self._norms[sets][:, :, None]


# ---------------------------------------------------------------------------------------------- screening
@dataclass(frozen=True)
class ScreeningStep:
    """One row of table 5-1: after removing ``removed`` (None in step 0) the set ``remaining``
    (its size ``n_params``) scores ``lam`` [%] (``score``: mean residual statistic [mm]);
    ``stationary``: the stationary parameters of that set (S, the next removal candidates);
    ``candidates``: ``{name: lambda}`` of every removal tried in this step; ``fallback``: S was
    empty, so every parameter was a candidate."""

    step: int
    n_params: int
    removed: str | None
    lam: float
    score: float
    remaining: tuple
    stationary: tuple
    candidates: dict = field(default_factory=dict)
    fallback: bool = False


@dataclass
class ScreeningResult:
    """The screening: ``steps`` (table 5-1), the ``selected`` set, and the settings used."""

    steps: list
    selected: tuple
    threshold_mm: float
    statistic: str
    n_cycles: int
    n_poses: int
    n_directions: int

    @property
    def lam(self) -> float:
        """lambda of the selected set on the screening run [%]."""
        return self.steps[-1].lam

    @property
    def removed(self) -> list:
        return [s.removed for s in self.steps[1:]]

    def table(self) -> list[dict]:
        """One dict per step: step, n_params, removed, lambda, stationary (S), remaining."""
        return [{"step": s.step, "n_params": s.n_params, "removed": s.removed or "-", "lambda": round(s.lam, 2),
                 "stationary": list(s.stationary), "remaining": list(s.remaining)} for s in self.steps]

    def format_table(self) -> str:
        return format_screening_table(self)


def format_screening_table(result: ScreeningResult, width: int = 110) -> str:
    """Text table like thesis table 5-1: card(dX0), removed parameter, lambda, stationary set S."""
    head = (f"parameter screening: {result.n_cycles} cycles x {result.n_poses} sphere poses, "
            f"{result.n_directions} monitored directions, lambda = share with {result.statistic} residual "
            f"< {result.threshold_mm:g} mm")
    lines = [head, f"{'n':>3}  {'removed':<8} {'lambda %':>8}  stationary set S (candidates for the next removal)"]
    for s in result.steps:
        S = ", ".join(s.stationary) if s.stationary else "(none: all are candidates)"
        text = f"{s.n_params:>3}  {s.removed or '-':<8} {s.lam:>8.2f}  "
        pad = " " * len(text)
        chunks, cur = [], ""
        for word in S.split(" "):
            if len(text) + len(cur) + len(word) + 1 > width and cur:
                chunks.append(cur.rstrip())
                cur = ""
            cur += word + " "
        chunks.append(cur.rstrip())
        lines.append(text + chunks[0])
        lines += [pad + c for c in chunks[1:]]
    lines.append(f"selected ({len(result.selected)}): {', '.join(result.selected)}")
    return "\n".join(lines)


def screen_parameters(problem: ScreeningProblem, n_keep: int = 8, *, start=None,
                      threshold_mm: float = LAMBDA_THRESHOLD_MM, statistic: str = "rms", max_lag: int | None = None,
                      small_lags: int = 1, z: float = 1.96, min_inside: float = 0.8) -> ScreeningResult:
    """Greedy backward elimination of figure 3-5 (see the module docstring).

    problem: the screening run (:class:`ScreeningProblem`, e.g. 90 cycles x 20 sphere poses).
    n_keep: parameters to keep (thesis 8). start: initial set (default all candidates of the problem).
    threshold_mm / statistic: the lambda metric. max_lag / small_lags / z / min_inside: the
    stationarity test (:func:`stationarity_test`).
    """
    if statistic not in STATISTICS:
        raise ValueError(f"unknown statistic {statistic!r}; choose from {STATISTICS}")
    current = list(problem.names if start is None else start)
    cols = list(problem.columns(current))
    if not 1 <= n_keep <= len(current):
        raise ValueError(f"n_keep must be in [1, {len(current)}], got {n_keep}")
    stat_kw = dict(max_lag=max_lag, small_lags=small_lags, z=z, min_inside=min_inside)

    def stationary_of(deltas):                                         # deltas (k, C)
        return stationarity_test(deltas, **stat_kw)

    lam, score, d = problem._evaluate_sets(np.array([cols]), threshold_mm, statistic)
    S = [n for n, s in zip(current, stationary_of(d[0])) if s]
    steps = [ScreeningStep(0, len(current), None, float(lam[0]), float(score[0]), tuple(current), tuple(S))]
    while len(current) > n_keep:
        fallback = not S
        cand = current if fallback else S
        pos = [current.index(c) for c in cand]
        sets = np.array([[c for j, c in enumerate(cols) if j != p] for p in pos])
        lams, scores, deltas = problem._evaluate_sets(sets, threshold_mm, statistic)
        order = sorted(range(len(cand)), key=lambda i: (-lams[i], scores[i], pos[i]))
        b = order[0]
        removed = cand[b]
        keep = [j for j in range(len(current)) if j != pos[b]]
        current = [current[j] for j in keep]
        cols = [cols[j] for j in keep]
        S = [n for n, s in zip(current, stationary_of(deltas[b])) if s]
        steps.append(ScreeningStep(len(steps), len(current), removed, float(lams[b]), float(scores[b]), tuple(current),
                                   tuple(S), {c: float(v) for c, v in zip(cand, lams)}, fallback))
    return ScreeningResult(steps, tuple(current), threshold_mm, statistic, problem.n_cycles, problem.n_poses,
                           problem.n_directions)


# ---------------------------------------------------------------------------------------------- helpers
def traditional_parameters(model: RobotModel, tol_mm: float = 1e-9) -> tuple:
    """The traditional compensation set: free length parameters (unit mm) with a non-zero nominal
    value, in model order (KR150 R3100: d1, a1, a2, a3, d4, d6)."""
    return tuple(n for n, v, f, u in zip(model.params.names, model.params.values, model.params.free,
                                         model.params.units) if f and u == "mm" and abs(v) > tol_mm)


from .online_poses import select_online_poses  # noqa: E402  (re-exported: the online pose design)
