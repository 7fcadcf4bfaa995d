"""The swarm's convergence curve (best objective per generation) for the report, as SVG text."""

from __future__ import annotations

from ._figures import plot_convergence

__all__ = ["plot_convergence"]
