"""
Sim-to-real gap diagnosis: locate the gap, rank candidate effects, add them greedily.

Kind-independent engine. A ``Problem`` supplies the real records' observables, a simulator of
twins of those records under a list of effects, and the candidate effects' search spaces
(``gyro_char.diag_static`` builds one for static records). The engine:

1. simulates the fitted baseline ``repeats`` times per record and scores the real records
   against that scatter (``gyro_char.diag_gap``); the leave-one-out null distribution of the
   gap says what "within the sim's own scatter" means for this record;
2. locates the gap (``where``);
3. fits every candidate effect alone (``ranking``);
4. adds effects greedily while the best one shrinks the gap by more than ``2 σ_null`` and the
   gap is still above the null's 95th percentile (``steps``, ``selected_effects``);
5. flags a step as ambiguous when other candidates shrink the gap as much within ``2 σ_null``,
   naming the run that would separate them instead of pretending to know; with three or more
   such candidates none is selected and the search stops.
"""
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

from gyro_char import diag_gap
from gyro_char.diag_fit import EffectSpace, Evaluation, fit_effect, GapObjective
from gyro_char.progress import progress
import numpy as np

Obs = Dict[str, np.ndarray]

# Which extra run tells two look-alike effects apart (unordered pairs).
SEPARATING_RUNS = {
    frozenset({'internal_lowpass', 'gauss_markov'}):
        'a static record at a higher output rate (or with the internal filter setting changed): '
        'a fixed smoothing filter scales with the sample rate, a physical correlation time does '
        'not',
    frozenset({'bias_instability', 'rate_random_walk'}):
        'a static record several times longer: the Allan slope beyond the present longest τ is '
        '0 for flicker and +1/2 for a rate random walk',
    frozenset({'bias_instability', 'gauss_markov'}):
        'a longer static record: a Gauss-Markov process flattens to τ^-1/2 beyond a few '
        'correlation times, flicker stays flat',
    frozenset({'rate_random_walk', 'gauss_markov'}):
        'a longer static record: a Gauss-Markov process turns over beyond its correlation time',
    frozenset({'temperature_drift', 'rate_random_walk'}):
        'a repeat static record after a full warm-up (or with the temperature logged): a thermal '
        'transient recurs at switch-on, a random walk does not',
    frozenset({'temperature_drift', 'bias_instability'}):
        'a repeat static record after a full warm-up (or with the temperature logged)',
    frozenset({'time_delay', 'g_sensitivity'}):
        'repeat at a second swing period (e.g. half; a second amplitude alone scales both '
        'alike) and diagnose both runs together: the cos θ residual of a delay scales as A·ω, '
        'that of g-sensitivity as g·A/ω',
    frozenset({'scale_factor_asymmetry', 'scale_factor_nonlinearity'}):
        'repeat at a second amplitude or period (another peak rate A·ω) and diagnose both runs '
        'together: the 2f line of an asymmetry grows as the peak rate, that of a quadratic '
        'term as its square',
    frozenset({'vibration', 'gauss_markov'}):
        'a longer record with finer frequency resolution: a tone keeps a constant width, a '
        'resonant process does not',
}
DEFAULT_SEPARATING_RUN = ('a record that differs in the one condition the two effects react to '
                          'differently (sample rate, length, temperature or excitation)')


@dataclass
class Problem:
    """What the engine needs for one kind of record."""

    kind: str
    reals: List[Obs]
    simulate: Callable[[int, list, int], Obs]
    spaces: List[EffectSpace]
    ranges: List[Dict[str, np.ndarray]]
    units: Dict[str, str]
    baseline: dict = field(default_factory=dict)
    # Baseline parameters re-tuned with every candidate (e.g. a scale on the white noise N),
    # so that a small error in the baseline fit is not mistaken for an effect.
    nuisance: Optional[EffectSpace] = None
    # Kind-specific fitted baseline object (e.g. ``diag_static.StaticBaseline``).
    context: object = None


@dataclass
class Diagnosis:
    """Everything ``diagnosis.json`` and the plots need."""

    kind: str
    baseline_gap: float
    where: List[dict]
    steps: List[dict]
    selected_effects: List[str]
    final_gap: float
    ranking: List[dict]
    null_gap: dict
    ambiguous: List[dict]
    baseline: dict
    # Gaps above the level a record drawn from the model itself scores (see ``excess_gap``).
    baseline_excess: float = 0.0
    final_excess: float = 0.0
    evaluations: Dict[str, Evaluation] = field(default_factory=dict)
    reals: List[Obs] = field(default_factory=list)
    # The final model as simulator effects (selected effects plus the tuned nuisance entry).
    model: list = field(default_factory=list)

    def to_json(self) -> dict:
        return {
            'kind': self.kind,
            'gap_metric': diag_gap.GAP_METRIC,
            'baseline_gap': self.baseline_gap,
            'where': self.where,
            'steps': self.steps,
            'selected_effects': self.selected_effects,
            'final_gap': self.final_gap,
            'ranking': self.ranking,
            # Extra fields (the contract's fields above are exact):
            'null_gap': self.null_gap,
            'excess_gap': {'metric': EXCESS_METRIC, 'baseline': self.baseline_excess,
                           'final': self.final_excess},
            'ambiguous': self.ambiguous,
            'baseline': self.baseline,
            'model': [{'name': n, 'params': _jsonable(p)} for n, p in self.model],
        }


EXCESS_METRIC = 'sqrt(gap^2 - mean null gap^2), 0 when below'


def excess_gap(gap: float, null: np.ndarray) -> float:
    """
    Return the part of ``gap`` above what the baseline's own twins score against each other.

    The rms z of a record drawn from the model itself is about 1, not 0 (its own noise), so
    1 - final/baseline understates how much of a gap an effect removes, the more so the
    nearer the effect is to detectability. The squared gap is a mean of z^2, whose null
    expectation is the mean squared leave-one-out gap; what is above it is the departure.
    """
    return float(np.sqrt(max(gap * gap - float(np.mean(np.square(null))), 0.0)))


def _jsonable(params: dict) -> dict:
    return {k: (float(v) if isinstance(v, (float, np.floating, int, np.integer))
                and not isinstance(v, bool) else v) for k, v in params.items()}


def separating_run(a: str, b: str) -> str:
    return SEPARATING_RUNS.get(frozenset({a, b}), DEFAULT_SEPARATING_RUN)


def _fit(objective: GapObjective, problem: Problem, selected: list, nuisance: Optional[tuple],
         space: EffectSpace, near: Optional[dict] = None):
    """Fit ``space`` on top of ``selected``, then re-tune the baseline's nuisance parameters."""
    extra = [nuisance] if nuisance else []
    params, ev = fit_effect(objective, selected + extra, space, near=near)
    if problem.nuisance is not None:
        nparams, nev = fit_effect(objective, selected + [(space.name, params)],
                                  problem.nuisance, near=nuisance[1], refine=3)
        if nev.gap < ev.gap:
            return params, (problem.nuisance.name, nparams), nev
    return params, nuisance, ev


def run(problem: Problem, *, repeats: int = 8, seed: int = 1, max_steps: int = 3,
        quiet: bool = True) -> Diagnosis:
    seeds = [seed * 1000 + k for k in range(repeats)]
    objective = GapObjective(problem.reals, problem.simulate, seeds)
    nuisance = None
    if problem.nuisance is not None:
        nparams, base = fit_effect(objective, [], problem.nuisance)
        nuisance = (problem.nuisance.name, nparams)
    else:
        base = objective.evaluate([])
    objective.set_reference(base)
    null = diag_gap.null_gaps(base.stats)
    shrink_needed = 2.0 * float(np.std(null, ddof=1))
    explained = float(np.quantile(null, 0.95))
    where = []
    for i, (real, stats) in enumerate(zip(problem.reals, base.stats)):
        for w in diag_gap.locate(diag_gap.zscores(real, stats), problem.ranges[i],
                                 problem.units):
            if len(problem.reals) > 1:
                w['record'] = i
            where.append(w)
    where.sort(key=lambda w: -abs(w['excess']))

    fits = {}
    bar = progress(total=len(problem.spaces), desc='ranking effects', quiet=quiet)
    for space in problem.spaces:
        fits[space.name] = _fit(objective, problem, [], nuisance, space)
        bar.update()
    bar.close()
    first = dict(fits)
    ranking = sorted(({'effect': n, 'gap_after': f[2].gap, 'params': _jsonable(f[0])}
                      for n, f in fits.items()), key=lambda r: r['gap_after'])

    selected, steps, ambiguous = [], [], []
    current = base
    evaluations = {'baseline': base}
    for step in range(max_steps):
        if current.gap <= explained:
            break  # within what the current model scores against itself
        if step > 0:
            fits = {}
            for space in problem.spaces:
                if space.name in [n for n, _ in selected]:
                    continue
                fits[space.name] = _fit(objective, problem, selected, nuisance, space,
                                        near=first[space.name][0])
        if not fits:
            break
        order = sorted(fits, key=lambda n: fits[n][2].gap)
        best = order[0]
        params, best_nuisance, ev = fits[best]
        if current.gap - ev.gap <= shrink_needed:
            break
        rivals = [n for n in order[1:]
                  if fits[n][2].gap - ev.gap <= shrink_needed
                  and current.gap - fits[n][2].gap > shrink_needed]
        if rivals:
            # Two look-alikes: keep the best, say which run would separate them. Three or more
            # unrelated effects shrinking the gap equally: none of them is evidenced (they are
            # fitting what is left of the noise), so stop without selecting.
            chosen = len(rivals) == 1
            ambiguous.append({'step': step + 1, 'effects': [best] + rivals,
                              'gap_after': [fits[n][2].gap for n in [best] + rivals],
                              'selected': chosen,
                              'separating_run': '; '.join(separating_run(best, r)
                                                          for r in rivals)})
            if not chosen:
                break
        selected.append((best, params))
        nuisance = best_nuisance
        steps.append({'effect': best, 'params': _jsonable(params), 'gap_after': ev.gap})
        current = ev
        # The model now has its own scatter: re-derive what "within it" means.
        null_now = diag_gap.null_gaps(ev.stats, base.stats)
        # Never below the baseline's own spread (a 95th percentile of few repeats is noisy).
        explained = max(explained, float(np.quantile(null_now, 0.95)))
        shrink_needed = max(shrink_needed, 2.0 * float(np.std(null_now, ddof=1)))
    evaluations['final'] = current
    model = selected + ([nuisance] if nuisance else [])
    return Diagnosis(
        kind=problem.kind, baseline_gap=base.gap, where=where, steps=steps,
        selected_effects=[n for n, _ in selected], final_gap=current.gap, ranking=ranking,
        null_gap={'mean': float(np.mean(null)), 'std': float(np.std(null, ddof=1)),
                  'q95': float(np.quantile(null, 0.95)), 'repeats': repeats,
                  'final_model_q95': explained, 'shrink_needed': shrink_needed},
        ambiguous=ambiguous, baseline=problem.baseline,
        baseline_excess=excess_gap(base.gap, null), final_excess=excess_gap(current.gap, null),
        evaluations=evaluations,
        reals=problem.reals, model=model)


def evaluate_model(problem: Problem, effects: Sequence, *, repeats: int = 10,
                   seed: int = 1) -> Optional[Evaluation]:
    """Gap of a fixed model (e.g. fitted on another record) on ``problem``'s records."""
    seeds = [seed * 1000 + k for k in range(repeats)]
    objective = GapObjective(problem.reals, problem.simulate, seeds)
    objective.set_reference(objective.evaluate([]))
    return objective.evaluate(list(effects))
