"""Genetic algorithm for periodic sequence analysis (thesis 004, 6.3, Algs 4–7, eqs 6.31–6.33).

An individual is a (N,) bool mask over the members of the sample (True = kept): every
individual is a subsequence of the sample, and crossover cuts both parents at the same sample
position (the thesis's strings are cut "in the middle", its example 6.34–6.37). Fitness is a
penalty: lower is fitter.

Departures from the printed pseudo-code, each fixing what cannot run as printed:

- Alg 4 loops ``while N + 1 < N_g`` from N = 1 (N_g − 2 generations); we run ``generations``.
- Alg 6 takes the i-th best of a tournament with probability BC_p(1 − BC_p)^(i−1) (the prose;
  the printed loop starts at the second term). Selection is with replacement: removing each
  winner from the pool, as printed, would make |P| draws a mere permutation of the population.
- Alg 7: ``child(i)`` is ``child(j)`` (SPEC erratum); as printed both children get the same
  genes, we swap the tails as example 6.34–6.37 does; ``while |S| > 2`` would drop the last
  pair every generation, we pair everyone (an odd one out passes unchanged).
- MutatePrior (6.33) removes a member of largest positive CFitness(·, 1, r_e), ties at random
  (the prose: "a random sequence cycle member among those whose fitness is not null").

Our additions, all off in :data:`PAPER_GA` / :data:`PAPER_GA_K` (docs/sections/eval_periodic.md):
``cost="alignment"`` (the fitness of ``periodic_cost``), ``elitism``, ``crossover="random"``,
and ``seeded``: the first individuals start from NaivePSA and from :func:`prior_descent`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from analysis.periodic.cost import member_scores, new_cache, population_cost
from analysis.periodic.fitness import INVERSION_RULES, Tables, member_cfitness, population_fitness


@dataclass(frozen=True)
class GAOptions:
    """Parameters of the GA (Alg 4), its operators and its fitness.

    generations: N_g. population: |P|. mutation_p: M_p. bc_p: best-candidate probability of
    the tournament (Alg 6). tournament: k, candidates per tournament. mutation: "random"
    (MutateRandom, GA) or "prior" (MutatePrior, GA^K). crossover: "middle" (Alg 7) or "random".
    cost: "thesis" (eq 6.31 with f_e, r_e, inversion; the thesis gives no values for f_e, r_e)
    or "alignment" (``periodic_cost`` with f_e, c_m, r_e, c_h and c_d per removed member).
    elitism: best individuals carried over. seeded: start from NaivePSA and prior_descent.
    """

    generations: int = 40
    population: int = 10
    mutation_p: float = 0.3
    bc_p: float = 0.65
    tournament: int = 3
    mutation: str = "prior"
    crossover: str = "random"
    cost: str = "alignment"
    f_e: float = 1.0
    r_e: float = 0.6
    inversion: str = "prose"
    c_m: float = 0.5
    c_h: float = 2.0
    c_d: float = 0.9
    elitism: int = 1
    seeded: bool = True

    def __post_init__(self) -> None:
        choices = {
            "mutation": ("random", "prior"),
            "crossover": ("middle", "random"),
            "cost": ("thesis", "alignment"),
            "inversion": tuple(INVERSION_RULES),
        }
        for name, allowed in choices.items():
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {allowed}, not {getattr(self, name)!r}")
        if self.population < 2 or self.generations < 0 or self.tournament < 1:
            raise ValueError("need population >= 2, generations >= 0 and tournament >= 1")


# The thesis's operators and fitness, with Table 6.1's 40 generations and M_p 0.3 (its text says
# 20 individuals, its caption 10); f_e = 1 as in MutatePrior, r_e = 0.5 (not given).
PAPER_GA = GAOptions(
    mutation="random",
    population=20,
    cost="thesis",
    crossover="middle",
    elitism=0,
    seeded=False,
    r_e=0.5,
    c_d=0.0,
)
PAPER_GA_K = replace(PAPER_GA, mutation="prior")


class Problem:
    """One coded sample and its patterns: evaluates, scores and mutates masks."""

    def __init__(
        self, symbols: np.ndarray, tables: Tables, options: GAOptions, rng: np.random.Generator
    ) -> None:
        self.symbols, self.tables, self.opt, self.rng = symbols, tables, options, rng
        self.rule = INVERSION_RULES[options.inversion]
        o = options
        self.weights = np.array([o.f_e, o.c_m, o.r_e, o.c_h, o.c_d], dtype=np.float64)
        self.params = np.array([o.f_e, o.r_e, self.rule], dtype=np.float64)
        self.prior_params = np.array([1.0, o.r_e, self.rule], dtype=np.float64)
        self.cache = new_cache()

    def fitness(self, masks: np.ndarray) -> np.ndarray:
        """(P, N) bool → (P,) penalties."""
        o = self.opt
        if o.cost == "alignment":
            cost = population_cost(self.symbols, masks, self.tables, self.weights, self.cache)
            return np.asarray(cost)
        fit = population_fitness(self.symbols, masks, self.tables, self.params)
        return np.asarray(fit + o.c_d * (masks.shape[1] - masks.sum(axis=1)))

    def prior_scores(self, mask: np.ndarray) -> np.ndarray:
        """Per kept member: CFitness(·, 1, r_e) (6.33) or its share of the alignment cost."""
        kept = self.symbols[mask]
        if self.opt.cost == "alignment":
            return np.asarray(member_scores(kept, self.tables, self.weights, self.cache))
        return np.asarray(member_cfitness(kept, self.tables, self.prior_params))

    def mutate(self, mask: np.ndarray) -> None:
        """MutateRandom (6.32) or MutatePrior (6.33) on ``mask``, in place."""
        kept = np.flatnonzero(mask)
        if kept.size == 0:
            return
        if self.opt.mutation == "random":
            mask[kept[self.rng.integers(kept.size)]] = False
            return
        scores = self.prior_scores(mask)
        if scores.max() > 0:
            ties = np.flatnonzero(scores == scores.max())
            mask[kept[ties[self.rng.integers(ties.size)]]] = False


def prior_descent(problem: Problem, mask: np.ndarray, tries: int = 3) -> np.ndarray:
    """Greedy MutatePrior: remove a worst-scored member while that lowers the fitness.

    First removes, at once, every flagged member whose symbol heads no pattern (removing those
    cannot change the periods), then tries the ``tries`` worst members one at a time.
    """
    mask = mask.copy()
    best = float(problem.fitness(mask[None])[0])
    heads = problem.tables[3] > 0
    while True:
        kept = np.flatnonzero(mask)
        scores = problem.prior_scores(mask)
        trial = mask.copy()
        trial[kept[(scores >= problem.opt.f_e) & ~heads[problem.symbols[kept]]]] = False
        candidates = [trial] if trial.sum() < mask.sum() else []
        for o in np.argsort(-scores, kind="stable")[:tries]:
            if scores[o] > 0:
                candidates.append(mask.copy())
                candidates[-1][kept[o]] = False
        fits = problem.fitness(np.array(candidates)) if candidates else np.zeros(0)
        if fits.size == 0 or fits.min() >= best:
            return mask
        mask, best = candidates[int(np.argmin(fits))], float(fits.min())


def tournament_selection(
    fitness: np.ndarray, n: int, options: GAOptions, rng: np.random.Generator
) -> np.ndarray:
    """Probabilistic tournament selection (Alg 6): ``n`` indices into the population.

    Each draw takes ``k`` distinct individuals, ranks them by fitness (stable) and takes the
    i-th best with probability BC_p(1 − BC_p)^(i−1); the worst gets the remaining mass.
    """
    k = min(options.tournament, fitness.shape[0])
    candidates = np.argsort(rng.random((n, fitness.shape[0])), axis=1)[:, :k]
    order = np.argsort(fitness[candidates], axis=1, kind="stable")
    ranked = np.take_along_axis(candidates, order, axis=1)
    place = np.minimum(rng.geometric(options.bc_p, size=n) - 1, k - 1)
    return np.asarray(ranked[np.arange(n), place])


def single_point_crossover(
    parents: np.ndarray, options: GAOptions, rng: np.random.Generator
) -> np.ndarray:
    """Single-point crossover (Alg 7, erratum fixed): (P, N) masks → (P, N) children.

    Parents are paired at random; each pair swaps its genes from the cut on (the middle, or a
    random point with ``crossover="random"``); an odd one out passes unchanged.
    """
    children = parents[rng.permutation(parents.shape[0])]
    pairs, n = children.shape[0] // 2, children.shape[1]
    if options.crossover == "middle":
        cuts = np.full(pairs, n // 2)
    else:
        cuts = rng.integers(0, n + 1, size=pairs)
    tail = np.arange(n)[None, :] >= cuts[:, None]
    first, second = children[0 : 2 * pairs : 2].copy(), children[1 : 2 * pairs : 2].copy()
    children[0 : 2 * pairs : 2] = np.where(tail, second, first)
    children[1 : 2 * pairs : 2] = np.where(tail, first, second)
    return children


def initial_population(problem: Problem, starts: list[np.ndarray]) -> np.ndarray:
    """|P| masks: the ``starts`` (when seeded) then copies of the whole sample."""
    pop = np.ones((problem.opt.population, problem.symbols.shape[0]), dtype=bool)
    if problem.opt.seeded:
        for row, start in enumerate(starts[: problem.opt.population]):
            pop[row] = start
    return pop


def run_ga(
    symbols: np.ndarray,
    tables: Tables,
    options: GAOptions,
    rng: np.random.Generator,
    starts: list[np.ndarray] | None = None,
) -> np.ndarray:
    """Alg 4 on the coded sample ``symbols`` (N,): the fittest (N,) bool mask of the last
    generation. With ``options.seeded`` the population starts from :func:`prior_descent` of the
    whole sample (GA^K only: it uses MutatePrior's scores) and the given ``starts``."""
    problem = Problem(symbols, tables, options, rng)
    seeds = list(starts or [])
    if options.seeded and options.mutation == "prior":
        seeds.insert(0, prior_descent(problem, np.ones(symbols.shape[0], dtype=bool)))
    pop = initial_population(problem, seeds)
    fit = problem.fitness(pop)
    for _ in range(options.generations):
        elite = np.argsort(fit, kind="stable")[: options.elitism]
        elite_pop, elite_fit = pop[elite].copy(), fit[elite].copy()
        pop = pop[tournament_selection(fit, pop.shape[0], options, rng)]
        pop = single_point_crossover(pop, options, rng)
        for row in np.flatnonzero(rng.random(pop.shape[0]) < options.mutation_p):
            problem.mutate(pop[row])
        fit = problem.fitness(pop)
        if elite.size:  # the elite replace the worst children
            worst = np.argsort(-fit, kind="stable")[: elite.size]
            pop[worst], fit[worst] = elite_pop, elite_fit
    return np.asarray(pop[np.argmin(fit)])
