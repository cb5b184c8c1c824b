"""The genetic algorithm of seed 000 (sec. 4.4, Table 4) on DEAP.

One population per DOF (each DOF is optimized individually), evolved in lock
step so that every generation's evaluations of all DOFs go through one map call
(one batched simulation per block, :mod:`uvsim.calibration.evaluation`).

Per generation and DOF (DEAP's ``eaSimple`` scheme, Table 4 settings):

1. selection: ``tools.selTournament`` (tournament size 5), as many as the population;
2. variation: ``algorithms.varAnd`` with two-point crossover (``tools.cxTwoPoint``,
   probability 0.5) and Gaussian mutation (``tools.mutGaussian``, probability
   0.25 per offspring, ``indpb`` per gene, ``sigma`` in units of the bound width);
   genes live in [0, 1] (scaled bounds) and are clipped back into them;
3. evaluation of the changed individuals; the offspring replace the population;
4. a hall of fame keeps the fittest individual found ("returned the fittest
   solution found", sec. 4.4 vi).

Initialization (sec. 4.4 i): ``seeded_fraction`` of the first generation is built
from the initial (experimental) values - one exact copy, the rest with a small
Gaussian spread ``seeded_sigma`` - the rest uniformly at random within the bounds.

Randomness: DEAP's operators draw from Python's :mod:`random`; it and numpy are
seeded explicitly from ``seed`` and their states are saved in each checkpoint
(:class:`uvsim.checkpoint.Checkpoint`: atomic, fingerprinted), so an interrupted run
resumed from its checkpoint continues exactly as if it had not been interrupted
(it logs ``resuming from PATH: the GA, generation N of G done``).  The DEAP classes are defined here (subclassing
``deap.base.Fitness`` directly), not through the global ``deap.creator``.
"""
from __future__ import annotations

import random
import time
from dataclasses import asdict, dataclass

import numpy as np
from deap import algorithms, base, tools

from uvsim.checkpoint import Checkpoint, fingerprint  # noqa: F401  (fingerprint: used by the calibrator)
from uvsim.errors import CalibrationError
from uvsim.progress import as_progress

#: What a resumed GA must share with the run that wrote the checkpoint.
RESUME_NEEDS = "--data, --vehicle, --dof, --seed, --population, --generations and GA settings"


class FitnessMin(base.Fitness):
    """Single-objective fitness to minimize (weighted absolute error)."""

    weights = (-1.0,)


class Individual(list):
    """Genes in [0, 1] (scaled parameter bounds) plus the DOF they belong to."""

    def __init__(self, genes=(), dof: str = ""):
        super().__init__(genes)
        self.dof = dof
        self.fitness = FitnessMin()

    def __reduce__(self):
        return (_rebuild_individual, (list(self), self.dof, self.fitness.values))


def _rebuild_individual(genes, dof, values):
    ind = Individual(genes, dof)
    if values:
        ind.fitness.values = values
    return ind


@dataclass
class GASettings:
    """seed 000 Table 4 (population 60, 30 generations, tournament 5, two-point
    crossover 0.5, Gaussian mutation 0.25) plus the details the paper does not give."""

    population: int = 60
    generations: int = 30
    tournament: int = 5
    crossover: float = 0.5
    mutation: float = 0.25
    mutation_indpb: float = 0.5    # per-gene probability inside a mutated individual (our choice)
    mutation_sigma: float = 0.1    # Gaussian sigma, fraction of the bound width (our choice)
    seeded_fraction: float = 0.1   # share of generation 0 built from the initial values (our choice)
    seeded_sigma: float = 0.02     # spread of the seeded individuals, fraction of bound width
    seed: int = 0

    def validate(self):
        if self.population < 2:
            raise CalibrationError(f"population must be >= 2, got {self.population}")
        if self.generations < 0:
            raise CalibrationError(f"generations must be >= 0, got {self.generations}")
        if not 1 <= self.tournament:
            raise CalibrationError(f"tournament size must be >= 1, got {self.tournament}")
        for k in ("crossover", "mutation", "mutation_indpb", "seeded_fraction"):
            v = getattr(self, k)
            if not 0 <= v <= 1:
                raise CalibrationError(f"{k} must be a probability in [0, 1], got {v}")
        if self.mutation_sigma <= 0 or self.seeded_sigma < 0:
            raise CalibrationError("mutation_sigma must be > 0 and seeded_sigma >= 0")


def _clip(ind):
    for i, g in enumerate(ind):
        ind[i] = min(1.0, max(0.0, g))
    return ind


def make_toolbox(settings: GASettings, hook) -> base.Toolbox:
    tb = base.Toolbox()
    tb.register("mate", tools.cxTwoPoint)
    tb.register("mutate", tools.mutGaussian, mu=0.0, sigma=settings.mutation_sigma, indpb=settings.mutation_indpb)
    tb.register("select", tools.selTournament, tournsize=settings.tournament)
    tb.register("map", hook)
    return tb


def initial_population(dof: str, p: int, initial_genes: np.ndarray, settings: GASettings) -> list:
    """Generation 0 of one DOF (module doc)."""
    n_seed = max(1, int(round(settings.seeded_fraction * settings.population))) if settings.seeded_fraction > 0 else 0
    pop = []
    for i in range(settings.population):
        if i == 0 and n_seed:
            genes = list(map(float, initial_genes))
        elif i < n_seed:
            genes = [min(1.0, max(0.0, g + random.gauss(0.0, settings.seeded_sigma))) for g in initial_genes]
        else:
            genes = [random.random() for _ in range(p)]
        pop.append(Individual(genes, dof))
    return pop


def _stats():
    s = tools.Statistics(lambda ind: ind.fitness.values[0])
    s.register("min", np.min)
    s.register("avg", np.mean)
    s.register("max", np.max)
    s.register("std", np.std)
    return s


def _record(logbook, gen, pop, nevals, wall):
    fits = np.array([ind.fitness.values[0] for ind in pop])
    finite = fits[np.isfinite(fits)]
    logbook.record(gen=gen, nevals=nevals, min=float(fits.min()),
                   avg=float(finite.mean()) if finite.size else float("inf"),
                   max=float(fits.max()), std=float(finite.std()) if finite.size else float("nan"),
                   wall_s=round(wall, 3))


def _checkpoint(path, key: str) -> Checkpoint:
    return Checkpoint(path, kind="ga", key=key, what="the GA", must_match=RESUME_NEEDS)


def _save_checkpoint(checkpoint: Checkpoint, state: dict) -> None:
    """Write the GA state after a generation (atomic)."""
    done = state["generation"]
    total = state["settings"]["generations"]
    checkpoint.save(state, progress=f"generation {done} of {total} done")


def load_checkpoint(path) -> dict:
    """The GA state stored in ``path`` (no problem check; :func:`run_ga` checks it)."""
    env = _checkpoint(path, "").read()
    if env["kind"] != "ga":
        raise CalibrationError(f"checkpoint {path} holds a {env['kind']!r} state, not a GA state")
    return env["state"]


def run_ga(problems: dict, evaluator, hook, settings: GASettings, *, checkpoint=None, resume=None,
           progress=False, problem_key: str = "", stop_after: int | None = None) -> dict:
    """Evolve one population per DOF in lock step.

    Parameters
    ----------
    problems : dof -> :class:`uvsim.calibration.evaluation.DofProblem`.
    evaluator : the fitness callable (a :class:`BatchEvaluator`).
    hook : DEAP map hook (SerialMap / ProcessMap / DaskMap).
    checkpoint : path written after every generation (None: no checkpoints).
    resume : path of a checkpoint to continue from (must match settings and problem).
    progress : the generations as a stage (:func:`uvsim.progress.as_progress`: True a tqdm bar).
    problem_key : fingerprint of the dataset/vehicle/problem, checked on resume.
    stop_after : stop after this generation (for tests of resume); None = run all.

    Returns
    -------
    dict with ``best`` (dof -> genes), ``best_fitness`` (dof -> float),
    ``logbooks`` (dof -> deap.tools.Logbook), ``evaluations`` (int),
    ``generations_run`` (int), ``wall_s`` (float, including time before a resume).
    """
    settings.validate()
    dofs = list(problems)
    key = fingerprint({"settings": asdict(settings), "problem": problem_key, "dofs": dofs})
    tb = make_toolbox(settings, hook)
    tb.register("evaluate", evaluator)
    t_start = time.perf_counter()
    if resume is not None:
        st = _checkpoint(resume, key).load()
        pops = st["populations"]
        hofs = st["halls"]
        logbooks = st["logbooks"]
        evaluations = st["evaluations"]
        gen0 = st["generation"] + 1
        prior_wall = st["wall_s"]
        random.setstate(st["random_state"])
        np.random.set_state(st["numpy_state"])
    else:
        random.seed(settings.seed)
        np.random.seed(settings.seed % (2 ** 32))
        pops = {d: initial_population(d, len(problems[d].names), problems[d].encode(problems[d].initial), settings)
                for d in dofs}
        hofs = {d: tools.HallOfFame(1) for d in dofs}
        logbooks = {}
        for d in dofs:
            lb = tools.Logbook()
            lb.header = ["gen", "nevals", "min", "avg", "max", "std", "wall_s"]
            logbooks[d] = lb
        evaluations = 0
        gen0 = 0
        prior_wall = 0.0

    name = (f"GA of {', '.join(dofs)}: {settings.population} individuals x {settings.generations} generations"
            + (f", from generation {gen0}" if gen0 else ""))
    stage = as_progress(progress).stage(name, total=settings.generations + 1, unit="gen", short="GA")

    def wall():
        return prior_wall + time.perf_counter() - t_start

    last = gen0 - 1
    with stage:
        stage.set(gen0)
        for gen in range(gen0, settings.generations + 1):
            last = gen
            t_gen = time.perf_counter()
            if gen == 0:
                offspring = pops
            else:
                offspring = {}
                for d in dofs:
                    off = tb.select(pops[d], len(pops[d]))
                    off = algorithms.varAnd(off, tb, settings.crossover, settings.mutation)
                    offspring[d] = [_clip(ind) for ind in off]
            invalid = [ind for d in dofs for ind in offspring[d] if not ind.fitness.valid]
            fits = tb.map(tb.evaluate, invalid)
            for ind, fit in zip(invalid, fits):
                ind.fitness.values = fit
            evaluations += len(invalid)
            for d in dofs:
                pops[d] = offspring[d]
                hofs[d].update(pops[d])
                _record(logbooks[d], gen, pops[d], sum(1 for i in invalid if i.dof == d), wall())
            if checkpoint is not None:
                _save_checkpoint(_checkpoint(checkpoint, key), {
                    "generation": gen, "populations": pops,
                    "halls": hofs, "logbooks": logbooks, "evaluations": evaluations, "wall_s": wall(),
                    "random_state": random.getstate(), "numpy_state": np.random.get_state(),
                    "settings": asdict(settings), "dofs": dofs,
                })
            dt = time.perf_counter() - t_gen
            best = sum(h[0].fitness.values[0] for h in hofs.values())
            stage.update(1, best=f"{best:.4g}", evals_per_s=f"{len(invalid) / dt if dt > 0 else 0:.0f}")
            if stop_after is not None and gen >= stop_after:
                break
        stage.summary = f"{evaluations} evaluations"
    return {
        "best": {d: list(hofs[d][0]) for d in dofs},
        "best_fitness": {d: float(hofs[d][0].fitness.values[0]) for d in dofs},
        "logbooks": logbooks,
        "evaluations": evaluations,
        "generations_run": last,
        "wall_s": wall(),
    }
