"""Heat sources of the thermal simulator and the kinematic-parameter drift they cause (METHODS.md 4).

:class:`ThermalModel`: one first-order heat source per joint motor,
``tau_j dh_j/dt = G_j u_j(t) - h_j`` (``h_j`` temperature rise [K], ``u_j`` motor load 0..1),
integrated exactly over the piecewise-constant load of a :class:`ProductionSchedule`; the
parameter drift is linear in the thermal state, ``dX(t) = sum_j h_j(t) D_j`` (P,) [mm | rad].
The realistic preset replaces the single time constant by :mod:`robocal.sim.thermal.response`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...kinematics.model import RobotModel
from ..robot import as_rng, parameter_kinds
from .schedule import ProductionSchedule

__all__ = ["HeatSource", "ThermalModel"]


@dataclass(frozen=True)
class HeatSource:
    """A heat source (joint motor): steady-state temperature rise ``gain_K`` at full load,
    time constant ``tau_s`` and the parameter drift per kelvin ``direction`` (P,) [mm/K | rad/K]."""

    name: str
    joint: int
    gain_K: float
    tau_s: float
    direction: np.ndarray


@dataclass
class ThermalModel:
    """Joint heat sources and the parameter drift they cause (see the module docstring).

    sources: one :class:`HeatSource` per joint motor, ``sources[j].joint == j + 1``.
    names: the robot's parameter names (P,), matching the directions.
    """

    sources: tuple
    names: tuple

    @property
    def directions(self) -> np.ndarray:
        """(S, P) drift per kelvin of every source."""
        return np.stack([s.direction for s in self.sources])

    @property
    def gains(self) -> np.ndarray:
        return np.array([s.gain_K for s in self.sources])

    @property
    def taus(self) -> np.ndarray:
        return np.array([s.tau_s for s in self.sources])

    def states(self, schedule: ProductionSchedule, times_s, h0=None) -> np.ndarray:
        """Thermal state (T, S) [K] at ``times_s`` (any order, >= 0), starting at ``h0`` (default cold, 0).

        Exact solution of the first-order equations over the schedule's piecewise-constant load;
        after the end of the schedule the robot stays idle (cools)."""
        t = np.asarray(times_s, float)
        t0, dur, loads = schedule.segments()
        G, tau = self.gains, self.taus
        joint = np.array([s.joint - 1 for s in self.sources])
        target = loads[:, joint] * G                                      # (Seg, S) equilibrium per segment
        # state at each segment start
        h = np.zeros((len(t0) + 1, len(G)))
        h[0] = 0.0 if h0 is None else np.asarray(h0, float)
        decay = np.exp(-dur[:, None] / tau)
        for i in range(len(t0)):
            h[i + 1] = target[i] + (h[i] - target[i]) * decay[i]
        seg = np.clip(np.searchsorted(t0, t, side="right") - 1, 0, len(t0) - 1)
        end = t0[-1] + dur[-1]
        after = t >= end
        dt = np.where(after, t - end, t - t0[seg])[:, None]
        hs = np.where(after[:, None], h[-1], h[seg])
        tg = np.where(after[:, None], 0.0, target[seg])
        return tg + (hs - tg) * np.exp(-dt / tau)

    def drift(self, states) -> np.ndarray:
        """Parameter drifts (T, P) [mm | rad] for thermal states (T, S)."""
        return np.asarray(states, float) @ self.directions

    @classmethod
    def kr150_default(cls, model: RobotModel, rng, *, scale: float = 1.0, leak: float = 1.0) -> "ThermalModel":
        """Heat sources of a KUKA KR150-like robot (DH + beta parameter names).

        Dominant drifts per kelvin (cast aluminium arms: 23e-6 / K): joint 2 (shoulder motor, 25 K, 0.9 h)
        stretches ``a1``, part of the upper arm ``a2`` and the column ``d1`` and tilts the
        shoulder axis (``beta2``); joint 3 (elbow motor, 22 K, 1.0 h) stretches ``a2``, ``a3`` and
        ``d4`` and shifts the elbow offset (``theta3``); joint 4 (wrist motors on the forearm,
        16 K, 0.8 h) stretches the forearm ``d4`` and twists ``alpha4``; joints 1, 5, 6 (9, 7, 5 K)
        add column height, turn of the base and flange length ``d6``. On top, every source gets
        small seeded contributions on every free parameter (``leak`` times 1.5e-4 mm/K or
        1.5e-7 rad/K standard deviation). ``scale`` multiplies all drifts.
        """
        rng = as_rng(rng)
        names = model.params.names
        idx = {n: i for i, n in enumerate(names)}
        P = len(names)
        al = 23e-6                       # cast aluminium arm housings, 1/K
        L = {n: abs(float(v)) for n, v in zip(names, model.params.values)}
        main = {
            1: (9.0, 1.2, {"d1": 0.3 * al * L.get("d1", 675.0), "theta1": 2.0e-6}),
            2: (25.0, 0.9, {"a1": 0.8 * al * L.get("a1", 350.0), "a2": 0.25 * al * L.get("a2", 1350.0),
                            "beta2": 1.2e-5}),
            3: (22.0, 1.0, {"a2": 0.35 * al * L.get("a2", 1350.0), "a3": 0.004, "theta3": 1.0e-5,
                            "d4": 0.2 * al * L.get("d4", 1400.0)}),
            4: (16.0, 0.8, {"d4": 0.4 * al * L.get("d4", 1400.0), "alpha4": 2.0e-5, "a3": 0.002}),
            5: (7.0, 0.7, {"d6": 1.5 * al * L.get("d6", 215.0)}),
            6: (5.0, 0.7, {"d6": 0.8 * al * L.get("d6", 215.0)}),
        }
        kinds = parameter_kinds(model)
        free = model.params.free
        sources = []
        for j in range(1, 7):
            gain, tau_h, dom = main[j]
            d = np.zeros(P)
            for n, v in dom.items():
                if n in idx:
                    d[idx[n]] += v
            noise = rng.standard_normal(P) * np.where(kinds == "length", 1.5e-4, 1.5e-7)
            d += leak * np.where(free, noise, 0.0)
            d *= scale
            d.setflags(write=False)
            sources.append(HeatSource(f"A{j} motor", j, gain, tau_h * 3600.0, d))
        return cls(tuple(sources), tuple(names))
