"""
Sim-to-real gap diagnosis: locate the gap, rank candidate effects, add them greedily.

Kind-independent engine. A ``Problem`` supplies the real records' observables, a simulator of
twins of those records under a list of effects, and the candidate effects' search spaces
(``gyro_char.diagnosis.static`` builds one for static records). The engine:

1. simulates the fitted baseline ``repeats`` times per record and scores the real records
   against that scatter (``gyro_char.diagnosis.gap``); the leave-one-out null distribution of the
   gap says what "within the sim's own scatter" means for this record;
2. locates the gap (``where``);
3. fits every candidate effect alone (``ranking``);
4. adds effects greedily while the best one shrinks the gap by more than ``2 σ_null`` and the
   gap is still above the null's 95th percentile (``steps``, ``selected_effects``); every step
   is judged in the baseline's scatter widened where the current model's twins scatter more
   (a noise process), while the reported gaps stay in the baseline's scatter;
5. flags a step as ambiguous when other candidates shrink the gap as much within ``2 σ_null``
   (or within the spread of the candidates' own gaps, for effects that add variance), naming
   the run that would separate them instead of pretending to know; with three or more such
   candidates that are not all known look-alikes, none is selected and the search stops;
6. refits the selected effects jointly (coordinate passes, each with the others fixed) and
   reports the final gap after that (``refined``).
"""
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

from gyro_char.diagnosis import gap as diag_gap
from gyro_char.diagnosis.fit import EffectSpace, Evaluation, fit_effect, GapObjective
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
    # The joint refit of the selected effects after the greedy steps (``_backfit``): the gap
    # before and after it, and the refitted parameters (``final_gap`` is the gap after it).
    refined: dict = field(default_factory=dict)
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
            'refined': self.refined,
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


def _yardstick(scatters: Sequence[Evaluation], k: Optional[int] = None) -> List[Obs]:
    """
    Per record, the widest scatter of the ``scatters``' twins per element (without twin ``k``).

    Later greedy steps are judged in the baseline's scatter widened wherever the current model
    is more variable (a random walk at long τ), never narrowed: a model that only reshapes the
    noise (a smoothing filter) keeps the baseline's yardstick and its better-known scatter.
    """
    def std(s):
        return s.std if k is None else diag_gap.sim_stats(s.repeats[:k] + s.repeats[k + 1:]).std
    out = []
    for per_record in zip(*(e.stats for e in scatters)):
        stds = [std(s) for s in per_record]
        out.append({b: np.max([d[b] for d in stds], axis=0) for b in stds[0]})
    return out


def _gap_in(objective: GapObjective, ev: Evaluation, scatters: Sequence[Evaluation]) -> float:
    """Gap of ``ev``'s twins to the real records in the ``scatters``' widest yardstick."""
    return diag_gap.multi_gap(objective.reals, ev.stats, _yardstick(scatters))


def _look_alikes(names: Sequence[str]) -> bool:
    """Tell whether every pair of ``names`` is a known look-alike pair (``SEPARATING_RUNS``)."""
    return all(frozenset({a, b}) in SEPARATING_RUNS
               for k, a in enumerate(names) for b in names[k + 1:])


def _could_trail(objective: GapObjective, truth: Evaluation, other: Evaluation,
                 scatters: Sequence[Evaluation]) -> float:
    """
    Return how far the true model can trail ``other`` on a record drawn from it (its largest).

    Each twin k of ``truth`` plays the real record: its gap to ``truth``'s other twins, and to
    ``other``'s twins without twin k (same random numbers), both in the ``scatters``'
    yardstick without twin k. A candidate whose gap exceeds the best one's by less than this
    could be the true effect all the same: two noise processes that both add variance
    trade places from one record to the next by far more than the baseline's null spread, a
    tone and a random walk do not.
    """
    k_max = min(len(s.repeats) for s in truth.stats)
    trail = []
    for k in range(k_max):
        reals = [s.repeats[k] for s in truth.stats]

        def without(ev, k=k):
            return [diag_gap.sim_stats(s.repeats[:k] + s.repeats[k + 1:]) for s in ev.stats]
        refs = _yardstick(scatters, k)
        trail.append(diag_gap.multi_gap(reals, without(truth), refs)
                     - diag_gap.multi_gap(reals, without(other), refs))
    return float(np.max(trail))


def _backfit(objective: GapObjective, problem: Problem, selected: list,
             nuisance: Optional[tuple], current: Evaluation, passes: int = 3,
             refine: int = 8):
    """
    Refit every selected effect with the others fixed, in place, then the nuisance.

    A greedy step fits one effect with the earlier ones frozen at values they took while they
    had to explain the whole gap alone (e.g. a smoothing filter made a little too wide to
    mimic a warm-up it could not model); coordinate passes over the selected effects let each
    settle once the others are there. A refit is kept only if it lowers the gap; an effect
    stays at its position in the list, so its random numbers (and the comparison) are the same.
    The Brent refinement gets more iterations than in the greedy steps (``refine``): the basin
    is known by now, what is left is precision.
    """
    spaces = {s.name: s for s in problem.spaces}
    extra = [nuisance] if nuisance else []
    for _ in range(passes):
        before = current.gap
        for k, (name, params) in enumerate(selected):
            others = selected[:k] + selected[k + 1:]
            p, ev = fit_effect(objective, others + extra, spaces[name], near=params, at=k,
                               refine=refine)
            if ev.gap < current.gap:
                selected[k] = (name, p)
                current = ev
        if problem.nuisance is not None:
            p, ev = fit_effect(objective, list(selected), problem.nuisance, near=nuisance[1],
                               refine=3)
            if ev.gap < current.gap:
                nuisance = (problem.nuisance.name, p)
                extra = [nuisance]
                current = ev
        if before - current.gap < 1e-3 * before:
            break
    return selected, nuisance, current


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
    base_needed = 2.0 * float(np.std(null, ddof=1))
    base_explained = float(np.quantile(null, 0.95))
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
    shrink_needed, explained = base_needed, base_explained
    for step in range(max_steps):
        # Each step is judged as the first one is, against what the current model's twins
        # score against each other, in the baseline's scatter widened where the current model
        # is more variable (``_yardstick``): in the baseline's scatter alone, a model that
        # adds variance - a random walk - hides a later, sharper effect such as a tone behind
        # its own spread. Never below the baseline's levels: a 95th percentile of a few
        # repeats is noisy.
        scatters = [base, current]
        null_now = diag_gap.null_gaps(
            current.stats, yardstick=lambda k: _yardstick(scatters, k))
        explained = max(base_explained, float(np.quantile(null_now, 0.95)))
        shrink_needed = max(base_needed, 2.0 * float(np.std(null_now, ddof=1)))
        gap_now = _gap_in(objective, current, scatters)
        if gap_now <= explained:
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
        judged = {n: _gap_in(objective, f[2], scatters) for n, f in fits.items()}
        order = sorted(fits, key=lambda n: judged[n])
        best = order[0]
        params, best_nuisance, ev = fits[best]
        if gap_now - judged[best] <= shrink_needed:
            break

        rivals = [n for n in order[1:]
                  if gap_now - judged[n] > shrink_needed
                  and (judged[n] - judged[best] <= shrink_needed
                       or judged[n] - judged[best] <= _could_trail(
                           objective, fits[n][2], ev, scatters))]
        if rivals:
            # Look-alikes (known pairs, see SEPARATING_RUNS): keep the best, say which run
            # would separate them. Unrelated effects shrinking the gap equally: none of them
            # is evidenced (they are fitting what is left of the noise), so stop without
            # selecting.
            chosen = len(rivals) == 1 or _look_alikes([best] + rivals)
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
    greedy_gap = current.gap
    if selected:
        selected, nuisance, current = _backfit(objective, problem, selected, nuisance, current)
    evaluations['final'] = current
    model = selected + ([nuisance] if nuisance else [])
    return Diagnosis(
        kind=problem.kind, baseline_gap=base.gap, where=where, steps=steps,
        selected_effects=[n for n, _ in selected], final_gap=current.gap, ranking=ranking,
        null_gap={'mean': float(np.mean(null)), 'std': float(np.std(null, ddof=1)),
                  'q95': float(np.quantile(null, 0.95)), 'repeats': repeats,
                  'final_model_q95': explained, 'shrink_needed': shrink_needed,
                  # What the final model's own twins score in the baseline's scatter: the
                  # floor of final_gap for a model that adds variance (a noise process).
                  'final_model_mean': float(np.mean(diag_gap.null_gaps(current.stats,
                                                                       base.stats)))},
        ambiguous=ambiguous, baseline=problem.baseline,
        baseline_excess=excess_gap(base.gap, null), final_excess=excess_gap(current.gap, null),
        refined={'gap_before': greedy_gap, 'gap_after': current.gap,
                 'params': {n: _jsonable(p) for n, p in selected}},
        evaluations=evaluations,
        reals=problem.reals, model=model)


def evaluate_model(problem: Problem, effects: Sequence, *, repeats: int = 10,
                   seed: int = 1) -> Optional[Evaluation]:
    """Gap of a fixed model (e.g. fitted on another record) on ``problem``'s records."""
    seeds = [seed * 1000 + k for k in range(repeats)]
    objective = GapObjective(problem.reals, problem.simulate, seeds)
    objective.set_reference(objective.evaluate([]))
    return objective.evaluate(list(effects))
