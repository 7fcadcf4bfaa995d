"""Genetic-algorithm tuning of the RBF network's structure on a validation split (DEAP).

Genes (each in [0, 1], mapped log-uniformly): the number of centres K in ``[k_min, k_max]``, the width
factor in [0.5, 4], the ridge regularisation lam in [1e-10, 1e-3] and the weight of the position
features against the rotation features in [0.5, 6]. Fitness: RMS joint error [rad] of the network
fitted on the training split, evaluated on the validation split (lower is better).

The GA is DEAP's (``deap>=1.4``, the ``ik-net`` extra): tournament selection, blend crossover,
Gaussian mutation and a (mu + lambda) generation step (``deap.algorithms.varOr``). DEAP draws from
Python's global ``random`` module; it is seeded here and its state restored afterwards, so runs are
reproducible and the caller's random state is untouched.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

import numpy as np

from .rbf import fit_rbf

__all__ = ["Structure", "tune_structure", "DEFAULT_STRUCTURE"]

_WIDTH = (0.5, 4.0)
_REG = (1e-10, 1e-3)
_POSW = (0.5, 6.0)


@dataclass(frozen=True)
class Structure:
    """Network structure: centres K, width factor, ridge lam, position-feature weight."""

    n_centres: int
    width_factor: float
    reg: float
    position_weight: float

    def input_weights(self, n_features: int = 9) -> np.ndarray:
        w = np.ones(n_features)
        w[:3] = self.position_weight
        return w


DEFAULT_STRUCTURE = Structure(500, 2.0, 1e-8, 3.0)
"""The untuned structure (``tune=False``): a sensible middle of the GA's ranges."""


def _log_map(u, lo, hi):
    return float(np.exp(np.log(lo) + float(np.clip(u, 0.0, 1.0)) * (np.log(hi) - np.log(lo))))


def decode(genes, k_min: int, k_max: int) -> Structure:
    """The :class:`Structure` of genes (4,) in [0, 1]."""
    return Structure(int(round(_log_map(genes[0], k_min, k_max))), _log_map(genes[1], *_WIDTH),
                     _log_map(genes[2], *_REG), _log_map(genes[3], *_POSW))


def validation_rms(structure: Structure, X_train, Y_train, X_val, Y_val, seed: int) -> float:
    """RMS joint error [rad] on the validation split of the network fitted with ``structure``."""
    net = fit_rbf(X_train, Y_train, structure.n_centres, structure.width_factor, structure.reg,
                  np.random.default_rng(seed), input_weights=structure.input_weights(X_train.shape[1]))
    err = net.predict(X_val) - Y_val
    return float(np.sqrt(np.mean(err ** 2)))


def tune_structure(X_train, Y_train, X_val, Y_val, *, seed: int, population: int = 10, generations: int = 5,
                   k_min: int = 50, k_max: int = 1200, progress=None):
    """Best :class:`Structure` found by the GA, and its history.

    Returns ``(structure, history)``: ``history`` is a list with one dict per generation
    (``generation``, ``best_rms_rad``, ``mean_rms_rad``, ``evaluations``). ``progress(generation,
    generations, best_rms_rad, structure)`` is called after every generation (generation 0: the initial
    population). Raises ``ImportError`` with the install hint when DEAP is missing.
    """
    try:
        from deap import algorithms, base, tools
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError("the genetic algorithm needs DEAP: pip install 'robocal[ik-net]' (deap>=1.4), "
                          "or train with tune=False (fixed structure)") from None

    class Fitness(base.Fitness):
        weights = (-1.0,)

    class Individual(list):
        def __init__(self, genes):
            super().__init__(genes)
            self.fitness = Fitness()

    k_max = int(max(k_min + 1, min(k_max, len(X_train) // 2)))
    cache: dict = {}

    def evaluate(ind):
        s = decode(ind, k_min, k_max)
        key = (s.n_centres, round(s.width_factor, 3), round(np.log10(s.reg), 2), round(s.position_weight, 3))
        if key not in cache:
            cache[key] = validation_rms(s, X_train, Y_train, X_val, Y_val, seed)
        return (cache[key],)

    def clip(ind):
        ind[:] = [min(max(g, 0.0), 1.0) for g in ind]
        return ind

    def mate(a, b):
        tools.cxBlend(a, b, alpha=0.3)
        return clip(a), clip(b)

    def mutate(ind):
        tools.mutGaussian(ind, mu=0.0, sigma=0.15, indpb=0.5)
        return (clip(ind),)

    toolbox = base.Toolbox()
    toolbox.register("evaluate", evaluate)
    toolbox.register("mate", mate)
    toolbox.register("mutate", mutate)
    toolbox.register("select", tools.selTournament, tournsize=3)

    saved = random.getstate()
    random.seed(seed)
    try:
        pop = [Individual([random.random() for _ in range(4)]) for _ in range(population - 1)]
        pop.append(Individual([0.72, 0.67, 0.29, 0.72]))   # near DEFAULT_STRUCTURE, so the GA never does worse
        history = []
        for gen in range(generations + 1):
            if gen > 0:
                offspring = algorithms.varOr(pop, toolbox, lambda_=population, cxpb=0.5, mutpb=0.4)
                for ind in offspring:
                    ind.fitness.values = toolbox.evaluate(ind)
                pop = tools.selBest(pop + offspring, population - 2) + toolbox.select(pop + offspring, 2)
            else:
                for ind in pop:
                    ind.fitness.values = toolbox.evaluate(ind)
            fits = [ind.fitness.values[0] for ind in pop]
            best = min(pop, key=lambda i: i.fitness.values[0])
            history.append({"generation": gen, "best_rms_rad": float(min(fits)), "mean_rms_rad": float(np.mean(fits)),
                            "evaluations": len(cache)})
            if progress is not None:
                progress(gen, generations, float(min(fits)), decode(best, k_min, k_max))
    finally:
        random.setstate(saved)
    return decode(best, k_min, k_max), history
