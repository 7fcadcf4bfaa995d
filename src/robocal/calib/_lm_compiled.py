"""Levenberg-Marquardt of point-only calibrations run entirely in compiled code
(:mod:`robocal.calib._lm_kernels`): the driver that packs the problem once, calls the loop and
hands :func:`robocal.calib.solve` the same iteration record as the Python loop.

:func:`robocal.calib.solve` uses it for the problems :func:`robocal.calib._normal.supports` accepts
(one station, point measurements only, LM, linear loss, no prior), when
:func:`use_compiled` says so. The kernels take ~10 s of CPU to compile once (5x the calibration's
``target_points`` kernel), which a first ``robocal calibrate`` must not pay (issue 34 item 2), so by
default they run only when they are already compiled -- in this process or in numba's on-disk cache --
or when the problem has at least :data:`COMPILE_MIN_POINTS` measured points, or once the process has
solved :data:`COMPILE_AFTER_POINTS` points in the Python loop (a Monte Carlo study, a fleet worker).
``ROBOCAL_COMPILED_LM=always`` compiles them on first use, ``never`` keeps the Python loop, and
``python -c "from robocal.calib._lm_compiled import compile_kernels; compile_kernels()"`` compiles
them once ahead (:func:`compile_kernels`).

Same iteration, damping, line search and stop rules as :class:`~robocal.calib._iterate.DampedGaussNewton`
(the stop reasons are those strings); the normal equations are summed in another order than the
Python loop's block products, so the numbers agree to rounding (~1e-15 relative), not bit for bit
(docs/calibration.md "The compiled LM loop").
"""

from __future__ import annotations

import os
import sys

import numpy as np

from . import _iterate
from ._iterate import MAX_ITERATIONS_REASON, GTOL, STALL_RTOL
from ._normal import NormalEquations

__all__ = ["CompiledPointLM", "use_compiled", "compile_kernels", "COMPILE_MIN_POINTS", "COMPILE_AFTER_POINTS", "ENV"]

#: environment variable: ``auto`` (default), ``always`` or ``never``
ENV = "ROBOCAL_COMPILED_LM"
#: poses per block of Jacobian rows kept for the vectorized J^T J sums (n x 3 K x 64 floats)
POSE_BLOCK = 64
#: measured points from which ``auto`` compiles the loop when it is not compiled yet: there one
#: solve in the Python loop takes seconds, comparable with the loop's one-time compile (~10 s of CPU)
COMPILE_MIN_POINTS = 200_000
#: measured points summed over the point-only solves of one process from which ``auto`` compiles the
#: loop (the work pays for the compile): ~1.5 M points are ~10 s of the Python loop (a 100-pose solve
#: takes ~1 ms, a 5 000-pose one ~30 ms), the loop's one-time compile. Counted, not timed, so a study
#: takes the same path on any machine and load.
COMPILE_AFTER_POINTS = 1_500_000
_points_solved = 0


class _Packed:
    """The problem's fixed arrays for the kernels (joints, program, measurements, column map)."""

    def __init__(self, problem):
        res = problem.residual_blocks[0]
        ch = problem.chain
        model = ch.model
        n = problem.n_variables
        self.n = n
        self.K = K = ch.n_points
        self.P = P = len(model.params)
        self.m_rows = int(res.mask.sum()) * 3
        self.measured = _read_only(res.measured)
        mask = np.asarray(res.mask, dtype=bool)
        #: first residual row of each measured point (pose-major, then point), -1 where not measured
        self.row_of = np.where(mask, 3 * (np.cumsum(mask.ravel()) - 1).reshape(mask.shape), -1).astype(np.int64)
        self.w = float(res.weight)
        qm = np.ascontiguousarray((ch._q_kernel @ model.coupling.T).T, dtype=float)  # (n_model, N)
        self.qm, self.cq, self.sq = qm, np.cos(qm), np.sin(qm)
        ee = ch.ee_of_target
        n_links = len(model.links)
        tl = np.array([model.end_effectors[e].link for e in ee], dtype=np.int64)
        self.tT = np.ascontiguousarray(np.array([np.asarray(model.end_effectors[e].T_link_ee, float)[:3] for e in ee],
                                                dtype=float).reshape(K, 3, 4))
        anc = model._ee_ancestors[ee].reshape(K, n_links)
        # column maps: model parameter -> column, column -> model parameter, frame / target variable -> column
        free_col = np.full(P, -1, dtype=np.int64)
        gparam = np.full(n, -1, dtype=np.int64)
        fcol = np.full(6, -1, dtype=np.int64)
        tcol = np.full(3 * K, -1, dtype=np.int64)
        plan = problem._plan
        if ch.geometry in plan:
            c0, c1, loc = plan[ch.geometry]
            idx = ch.geometry.index if loc is None else ch.geometry.index[loc]
            free_col[idx] = np.arange(c0, c1)
            gparam[c0:c1] = idx
        if ch.frames in plan:
            c0, c1, loc = plan[ch.frames]
            fcol[np.arange(6) if loc is None else loc] = np.arange(c0, c1)
        if ch.targets in plan:
            c0, c1, loc = plan[ch.targets]
            tcol[np.arange(3 * K) if loc is None else loc] = np.arange(c0, c1)
        self.gparam = gparam
        n_ops = len(model._op_code)
        gcols = np.flatnonzero(gparam >= 0)
        # the link each geometry column's parameter acts on, and which points that link carries
        col_link = np.full(n, -1, dtype=np.int64)
        pcol = free_col[model._op_param]
        col_link[pcol[pcol >= 0]] = model._op_link[pcol >= 0]
        gmove = np.zeros((K, n), dtype=np.bool_)
        gmove[:, gcols] = anc[:, col_link[gcols]]
        self.gmove = np.ascontiguousarray(gmove)
        rows = [model._op_link, model._op_code, model._op_param, model._op_joint, model._link_parent, tl, free_col,
                fcol, tcol, np.array([n_links, len(gcols)]), gcols, pcol]
        width = max(len(x) for x in rows)
        ip = np.full((len(rows), width), -1, dtype=np.int64)
        for i, x in enumerate(rows):
            ip[i, :len(x)] = x
        self.ip = ip
        self.op_axis = np.ascontiguousarray(model._op_axis, dtype=float)
        B = max(1, min(POSE_BLOCK, qm.shape[1]))
        #: residual rows per block of Jb: 3 K rows per pose, B poses
        self.block_rows = 3 * K * B
        self.fw_size = 3 * n_ops + 12 * B * (n_links + 2) + 6 * B * n + 3 * K * B + 2 * B
        # the problem's fixed arrays, to tell whether this packing still describes it
        self.key = (res.measured, ch._q_kernel, problem._plan)


def _read_only(a) -> np.ndarray:
    """A read-only C-contiguous float view (or copy) of ``a``: one numba type whether the caller's
    array is writeable or not (a writeable one would need a second compiled specialisation)."""
    v = np.ascontiguousarray(a, dtype=float).view()
    v.flags.writeable = False
    return v


def _packed(problem) -> _Packed:
    p = getattr(problem, "_compiled_lm_packed", None)
    res, ch = problem.residual_blocks[0], problem.chain
    if p is None or p.key[0] is not res.measured or p.key[1] is not ch._q_kernel or p.key[2] is not problem._plan:
        p = _Packed(problem)
        problem._compiled_lm_packed = p
    return p


def _kernel_args(pk: _Packed, state, active, ctl):
    """The arguments of :func:`robocal.calib._lm_kernels.lm_points` (fresh output buffers)."""
    n, M = pk.n, pk.m_rows
    act = np.flatnonzero(active).astype(np.int64)
    na = len(act)
    params = np.array(state.params, dtype=float)
    base = np.array(state.bases[0, :3], dtype=float, order="C")  # a copy: the kernel updates it in place
    pts = np.array(state.targets, dtype=float).reshape(pk.K, 3)
    return (pk.ip, pk.op_axis, pk.qm, pk.cq, pk.sq, pk.tT, pk.gmove, pk.measured, pk.row_of, pk.w, pk.gparam, act, ctl,
            params, base, pts, np.empty_like(params), np.empty_like(base), np.empty_like(pts),
            np.empty(M), np.empty(M), np.empty(M), np.empty((n, n)), np.empty(n), np.empty((n, n)), np.empty(n),
            np.empty(n), np.empty(pk.fw_size), np.empty((n, pk.block_rows)),
            np.empty(2 * na * na + 2 * na + n), np.empty((na, na)), np.empty(5), np.full(max(int(ctl[6]), 1), np.nan))


def _ready(dispatcher, args) -> bool:
    """True when ``dispatcher`` has machine code for ``args``' types: compiled in this process, or
    loaded now from numba's on-disk cache (what a call would do first). Never compiles."""
    from numba import typeof
    from numba.core.compiler_lock import global_compiler_lock

    try:
        sig = tuple(typeof(a) for a in args)
        with global_compiler_lock:
            if dispatcher.overloads.get(sig) is not None:
                return True
            cres = dispatcher._cache.load_overload(sig, dispatcher.targetctx)
            if cres is None:
                return False
            dispatcher.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
            dispatcher.add_overload(cres)
            return True
    except Exception:  # pragma: no cover - a numba without these internals: decide by size only
        return False


def use_compiled(problem, n_points: int) -> bool:
    """Whether :func:`robocal.calib.solve` runs this problem's LM in compiled code (see the module
    docstring): ``ROBOCAL_COMPILED_LM`` = ``always`` / ``never``, else (``auto``) when the kernel is
    compiled already (and numba is loaded in this process anyway), ``n_points`` >=
    :data:`COMPILE_MIN_POINTS`, or this process has solved
    :data:`COMPILE_AFTER_POINTS` measured points in the Python loop (a study, a fleet worker)."""
    global _points_solved
    mode = os.environ.get(ENV, "auto").strip().lower()
    if mode == "never":
        return False
    _points_solved += int(n_points)
    if mode == "always" or n_points >= COMPILE_MIN_POINTS or _points_solved >= COMPILE_AFTER_POINTS:
        return True
    if "numba" not in sys.modules:
        # a process that has not loaded numba (a small calibration: robocal.kinematics._backend runs its
        # kernels in numpy) does not load it (0.1-0.4 s, ~100 MiB) to save ~1 ms of a small solve
        return False
    from . import _lm_kernels

    if _lm_kernels.lm_points.signatures:  # compiled or loaded in this process
        return True
    global _cache_checked
    if _cache_checked:  # not in the cache at the first look: it is not compiled by looking again
        return False
    _cache_checked = True
    pk = _packed(problem)
    active = np.ones(pk.n, dtype=bool)
    return _ready(_lm_kernels.lm_points, _kernel_args(pk, problem.initial_state(), active, np.zeros(7)))


_cache_checked = False


def compile_kernels() -> None:
    """Compile the loop now (~10 s of CPU once; numba caches the machine code on disk, and every later
    process uses the compiled loop by default)."""
    from . import _lm_kernels

    pk = _Packed.__new__(_Packed)  # an empty problem of the right array types: nothing is computed
    pk.n, pk.K, pk.m_rows, pk.w = 1, 1, 0, 1.0
    pk.ip = np.full((12, 2), -1, dtype=np.int64)
    pk.ip[9] = 0
    pk.op_axis = np.zeros((0, 3))
    pk.qm = pk.cq = pk.sq = np.zeros((1, 0))
    pk.tT, pk.gmove = np.zeros((1, 3, 4)), np.zeros((1, 1), dtype=np.bool_)
    pk.measured, pk.row_of = _read_only(np.zeros((0, 1, 3))), np.zeros((0, 1), dtype=np.int64)
    pk.gparam = np.full(1, -1, dtype=np.int64)
    pk.fw_size, pk.block_rows = 64, 3

    class _State:
        params, bases, targets = np.zeros(1), np.eye(4)[None], np.zeros((1, 3))

    _lm_kernels.lm_points(*_kernel_args(pk, _State, np.ones(1, dtype=bool), np.zeros(7)))


class CompiledPointLM:
    """The record :func:`robocal.calib.solve` reads from an LM run (``state``, ``r``, ``J`` as
    :class:`~robocal.calib._normal.NormalEquations`, ``col_scale``, ``it``, ``converged``,
    ``reason``, ``weights``, ``rejected``, ``pose_of_row``, ``robust``), the loop run by
    :func:`robocal.calib._lm_kernels.lm_points` from ``state``; ``r0`` the start's residuals.
    ``progress(iteration, cost)`` is called for every accepted step as the Python loop does, but
    when the compiled loop has returned."""

    robust = False

    def __init__(self, problem, state, labels, active, *, ftol, xtol, chi2_tol, progress=None):
        self.problem, self.state0, self.active = problem, state, np.asarray(active, dtype=bool)
        self.progress = progress
        self.tol = (ftol, xtol, chi2_tol)
        self.n_poses = problem.n_poses
        self.pose_of_row = np.where(labels[:, 0] < 0, self.n_poses, labels[:, 0])
        self.n_slots = self.n_poses + 1
        self.weights = np.ones(self.n_slots)
        self.rejected = np.zeros(self.n_slots, dtype=bool)
        self.robust_weights = None
        self.it, self.converged, self.reason = 0, False, MAX_ITERATIONS_REASON

    def run_phase(self, first_iteration: int, max_iterations: int) -> None:
        from . import _lm_kernels as lk

        pk = _packed(self.problem)
        ctl = np.array([*self.tol, GTOL, STALL_RTOL, first_iteration, max_iterations], dtype=float)
        args = _kernel_args(pk, self.state0, self.active, ctl)
        it, code = lk.lm_points(*args)
        params, base, pts = args[13], args[14], args[15]
        self.r0, self.r = args[19], args[20]
        self.J = NormalEquations(args[22], args[23])
        self.col_scale = args[26]
        cost, optimality, rel, self.lam, pd = args[31]
        self.cost = float(cost)
        na = len(args[11])
        #: the final scaled normal matrix of the active columns and its inverse (None if not positive definite)
        self.G = args[29][:na * na].reshape(na, na)
        self.G_inv = args[30] if pd else None
        bases = np.array(self.state0.bases, dtype=float)
        bases[0, :3] = base
        self.state = self.state0._replace(params=params, bases=bases, targets=pts.reshape(np.shape(self.state0.targets)))
        self.it = int(it)
        self.reason, self.converged = _reason(int(code), float(optimality), float(rel), self.tol[2])
        if self.progress is not None:  # the Python loop's calls, after the fact (the loop takes milliseconds)
            for i, c in enumerate(args[32]):
                if np.isfinite(c):
                    self.progress(first_iteration + i, float(c))


def _reason(code, optimality, rel, chi2_tol):
    """(reason, converged) of a stop code: the Python loop's strings (robocal.calib._iterate)."""
    from . import _lm_kernels as lk

    if code == lk.MAX_ITERATIONS:
        return MAX_ITERATIONS_REASON, False
    if code == lk.GRADIENT_ZERO:
        return "gradient is zero", True
    if code in (lk.STATIONARY, lk.NOT_AT_MINIMUM):
        return _iterate.no_step_reason(optimality, rel)
    if code == lk.FTOL:
        return "relative cost reduction below ftol", True
    if code == lk.CHI2:
        return _iterate.chi2_reason(chi2_tol), True
    return "step below xtol", True

