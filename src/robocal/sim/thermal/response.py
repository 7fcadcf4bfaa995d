"""Temperatures of the realistic thermal simulator: nonlinear two-mode motor heating and the hall.

:func:`motor_temperatures` integrates, for every heat source j of a
:class:`~robocal.sim.thermal.heat.ThermalModel` and both modes m of a
:class:`~robocal.sim.thermal.effects.HeatResponse` (fast: share ``a``, ``fast_tau_s``; slow:
share ``1 - a``, the source's tau times ``slow_tau_scale``)::

    tau_m dh/dt = (1 + k) G_jm u^p - h - k h^2 / G_jm        G_jm = share_m G_j,  u = load (0..1)

(``p`` = ``load_exponent``, ``k`` = ``loss_nonlinearity``; at full load h settles at G_jm, as
in the linear model) by classical Runge-Kutta with steps <= ``max_step_s`` over the schedule's
piecewise-constant load; after the schedule the robot idles. The temperature rise of source j is
the sum of its two modes [K].

:func:`hall_temperature` is the hall temperature change since the cold start [K]: a daily sine
from a random phase plus an Ornstein-Uhlenbeck wander, sampled exactly at the given times.
"""

from __future__ import annotations

import math

import numpy as np

from ..robot import as_rng

__all__ = ["motor_temperatures", "hall_temperature"]


def _rate(h, target, gain, tau, k):
    """dh/dt (2, S) of both modes for the load's target input ``target`` (2, S) [K/s]."""
    return ((1.0 + k) * target - h - k * h * h / gain) / tau


def _rk4(h, target, gain, tau, k, dt: float, n: int):
    """``n`` classical Runge-Kutta steps of ``dt`` [s] from ``h`` (2, S)."""
    for _ in range(n):
        k1 = _rate(h, target, gain, tau, k)
        k2 = _rate(h + 0.5 * dt * k1, target, gain, tau, k)
        k3 = _rate(h + 0.5 * dt * k2, target, gain, tau, k)
        k4 = _rate(h + dt * k3, target, gain, tau, k)
        h = h + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return h


def motor_temperatures(model, schedule, times_s, heat, *, max_step_s: float = 20.0) -> np.ndarray:
    """Temperature rise (T, S) [K] of every heat source of ``model`` at ``times_s`` (T,) [s, >= 0,
    any order], starting cold, for the :class:`HeatResponse` ``heat`` (module docstring)."""
    t = np.asarray(times_s, float)
    t0, dur, loads = schedule.segments()
    joint = np.array([s.joint - 1 for s in model.sources])
    share = np.array([heat.fast_share, 1.0 - heat.fast_share])[:, None]
    gain = np.maximum(share * model.gains[None], 1e-12)                           # (2, S)
    tau = np.stack([np.full(len(model.sources), heat.fast_tau_s), model.taus * heat.slow_tau_scale])
    inputs = gain[None] * (loads[:, joint][:, None, :] ** heat.load_exponent)      # (Seg, 2, S)
    end = t0[-1] + dur[-1]
    grid = np.unique(np.concatenate([t0, [end], t[t >= 0]]))
    seg = np.clip(np.searchsorted(t0, grid, side="right") - 1, 0, len(t0) - 1)
    h = np.zeros_like(gain)
    at = {float(grid[0]): h.sum(axis=0)}
    k = float(heat.loss_nonlinearity)
    for i in range(len(grid) - 1):
        span = grid[i + 1] - grid[i]
        target = inputs[seg[i]] if grid[i] < end else np.zeros_like(gain)
        n = max(1, math.ceil(span / max_step_s))
        h = _rk4(h, target, gain, tau, k, span / n, n)
        at[float(grid[i + 1])] = h.sum(axis=0)
    return np.array([at[float(x)] for x in t])


def hall_temperature(times_s, hall, rng) -> np.ndarray:
    """Hall temperature change since t = 0 (T,) [K] at ``times_s`` (T,) [s, any order] for the
    :class:`HallTemperature` ``hall``: ``A (sin(w (t + t_0)) - sin(w t_0))`` with the start of
    the run ``t_0`` uniform over the day, plus an Ornstein-Uhlenbeck process (stationary rms
    ``wander_K``, time constant ``wander_tau_s``) minus its value at t = 0. ``rng``: seed or
    Generator (draws the phase, then the wander at the sorted distinct times)."""
    rng = as_rng(rng)
    t = np.asarray(times_s, float)
    w = 2.0 * math.pi / hall.period_s
    t_start = rng.uniform(0.0, hall.period_s)
    daily = hall.amplitude_K * (np.sin(w * (t + t_start)) - math.sin(w * t_start))
    grid, inv = np.unique(np.concatenate([[0.0], t]), return_inverse=True)
    x = np.empty(len(grid))
    x[0] = rng.normal(0.0, hall.wander_K)
    a = np.exp(-np.diff(grid) / hall.wander_tau_s)
    e = rng.standard_normal(len(grid) - 1)
    for i in range(1, len(grid)):
        x[i] = a[i - 1] * x[i - 1] + hall.wander_K * math.sqrt(1.0 - a[i - 1] ** 2) * e[i - 1]
    wander = x[inv[1:]] - x[inv[0]]
    return daily + wander
