"""
The greedy search's parts: a candidate fitted on a model, the widened yardstick, look-alikes.

``gyro_char.diagnosis.engine`` runs the search; these are its steps. ``objective`` is a gap
objective (``fit.GapObjective`` on twins or ``closed_form.ExpectedObjective``), ``problem``
an ``engine.Problem``.
"""
from typing import List, Optional, Sequence

from gyro_char.diagnosis import gap as diag_gap
from gyro_char.diagnosis.fit import EffectSpace, Evaluation, fit_effect
import numpy as np

Obs = dict

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
    frozenset({'temperature_drift', 'gauss_markov'}):
        'a repeat static record after a full warm-up (or with the temperature logged): a thermal '
        'transient recurs at switch-on, a slow Gauss-Markov excursion does not',
    frozenset({'time_delay', 'g_sensitivity'}):
        'repeat at a second swing period (e.g. half; a second amplitude alone scales both '
        'alike) and diagnose both runs together: the cos θ residual of a delay scales as A·ω, '
        'that of g-sensitivity as g·A/ω',
    frozenset({'scale_factor_asymmetry', 'scale_factor_nonlinearity'}):
        'repeat at a second amplitude or period (another peak rate A·ω) and diagnose both runs '
        'together: the 2f line of an asymmetry grows as the peak rate, that of a quadratic '
        'term as its square',
    frozenset({'vibration', 'resonance'}):
        'a longer record (finer frequency resolution): a tone stays one Welch bin wide however '
        'long the record, a resonance keeps its width f0 / q',
    frozenset({'resonance', 'gauss_markov'}):
        'a static record at another output rate or with the internal filter changed: the '
        'band keeps its centre frequency, a low-pass process has none',
    frozenset({'vibration', 'gauss_markov'}):
        'a longer record with finer frequency resolution: a tone keeps a constant width, a '
        'resonant process does not',
    frozenset({'stale_samples', 'internal_lowpass'}):
        'the raw record at a finer output step (or logged before the driver): a hold repeats '
        'a sample exactly, so equal neighbours far above the rounding’s own share are holds; '
        'a smoothing filter never repeats one',
    frozenset({'stale_samples', 'gauss_markov'}):
        'the raw record at a finer output step (or logged before the driver): equal neighbours '
        'far above the rounding’s own share are holds; a correlated process has none',
}
DEFAULT_SEPARATING_RUN = ('a record that differs in the one condition the two effects react to '
                          'differently (sample rate, length, temperature or excitation)')


def separating_run(a: str, b: str) -> str:
    """Name the run that would tell effects ``a`` and ``b`` apart."""
    return SEPARATING_RUNS.get(frozenset({a, b}), DEFAULT_SEPARATING_RUN)


# Rounds of (nuisance, effect) refits after the first fit of an effect: an effect that reshapes
# the white noise (holds, smoothing) is first fitted at the N the baseline alone pulled off
# its calibrated value, and one nuisance step (one grid cell) does not bring it back.
ALTERNATIONS = 2


def fit_on_top(objective, problem, selected: list, nuisance: Optional[tuple],
               space: EffectSpace, near: Optional[dict] = None):
    """
    Fit ``space`` on top of ``selected``, then re-tune the baseline's nuisance parameters.

    While the nuisance step improves the gap, the effect is refitted at the new nuisance (up
    to ``ALTERNATIONS`` rounds; over its whole space unless ``near`` is given, since effect and
    nuisance can trade against each other in a narrow valley); no step that worsens the gap
    is kept.
    """
    extra = [nuisance] if nuisance else []
    params, ev = fit_effect(objective, selected + extra, space, near=near)
    if problem.nuisance is None:
        return params, nuisance, ev
    for turn in range(ALTERNATIONS):
        # The first nuisance step searches its whole (narrow) range: the baseline alone may
        # have pulled it to a bound that is wrong once the effect is in.
        nparams, nev = fit_effect(objective, selected + [(space.name, params)],
                                  problem.nuisance, near=nuisance[1] if turn else None,
                                  refine=3)
        if nev.gap >= ev.gap:
            break
        nuisance, ev = (problem.nuisance.name, nparams), nev
        fitted, fev = fit_effect(objective, selected + [nuisance], space,
                                 near=params if near else None)
        if fev.gap >= ev.gap:
            break
        params, ev = fitted, fev
    return params, nuisance, ev


def yardstick(scatters: Sequence[Evaluation], k: Optional[int] = None) -> List[Obs]:
    """
    Per record, the widest scatter of the ``scatters``' twins per element (without twin ``k``).

    Later greedy steps are judged in the baseline's scatter widened wherever the current model
    is more variable (a random walk at long τ), never narrowed: a model that only reshapes the
    noise (a smoothing filter) keeps the baseline's yardstick and its better-known scatter.
    """
    def std(s):
        return s.std if k is None else diag_gap.leave_out(s, k).std
    out = []
    for per_record in zip(*(e.stats for e in scatters)):
        stds = [std(s) for s in per_record]
        out.append({b: np.max([d[b] for d in stds], axis=0) for b in stds[0]})
    return out


def gap_in(objective, ev: Evaluation, scatters: Sequence[Evaluation]) -> float:
    """Gap of ``ev``'s twins to the real records in the ``scatters``' widest yardstick."""
    return diag_gap.multi_gap(objective.reals, ev.stats, yardstick(scatters))


def levels(objective, base: Evaluation, current: Evaluation, base_needed: float,
           base_explained: float):
    """
    Return the gap now, the shrink a step must exceed and the gap the model explains.

    All in the baseline's scatter widened where ``current`` is more variable (``yardstick``),
    from what ``current``'s twins score against each other; never below the baseline's
    levels (a 95th percentile of a few repeats is noisy).
    """
    scatters = [base, current]
    null_now = diag_gap.null_gaps(current.stats, yardstick=lambda k: yardstick(scatters, k))
    needed = max(base_needed, 2.0 * float(np.std(null_now, ddof=1)))
    explained = max(base_explained, float(np.quantile(null_now, 0.95)))
    return gap_in(objective, current, scatters), needed, explained


def look_alikes(names: Sequence[str]) -> bool:
    """Tell whether every pair of ``names`` is a known look-alike pair (``SEPARATING_RUNS``)."""
    return all(frozenset({a, b}) in SEPARATING_RUNS
               for k, a in enumerate(names) for b in names[k + 1:])


def could_trail(objective, truth: Evaluation, other: Evaluation,
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
            return [diag_gap.leave_out(s, k) for s in ev.stats]
        refs = yardstick(scatters, k)
        trail.append(diag_gap.multi_gap(reals, without(truth), refs)
                     - diag_gap.multi_gap(reals, without(other), refs))
    return float(np.max(trail))


def backfit(objective, problem, selected: list, nuisance: Optional[tuple],
            current: Evaluation, passes: int = 3, refine: int = 8, hold: int = 0):
    """
    Refit every selected effect with the others fixed, in place, then the nuisance.

    The last ``hold`` effects are kept as they are (an effect a finer check than the gap
    placed, which the gap cannot refine).

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
        for k, (name, params) in enumerate(selected[:len(selected) - hold]):
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


def prune(objective, problem, selected: list, nuisance: Optional[tuple], current: Evaluation,
          base: Evaluation, base_needed: float, base_explained: float):
    """
    Drop each selected effect that the others have made redundant (backward elimination).

    A greedy step adds the effect that shrinks the gap most given the earlier ones; a later
    effect may explain what an earlier one was only standing in for (a warm-up fitted to the
    trend of a random walk's one realization, before the walk itself). An effect is dropped
    when the model without it, the others refitted, scores within the greedy bar (``levels``)
    of the model with it, judged in the yardstick of the model with it. Cheapest removal
    first, one at a time, never the last effect.
    """
    dropped = []
    while len(selected) > 1:
        scatters = [base, current]
        gap_now, needed, _ = levels(objective, base, current, base_needed, base_explained)
        trials = []
        for k, (name, params) in enumerate(selected):
            rest = selected[:k] + selected[k + 1:]
            ev = objective.evaluate(rest + ([nuisance] if nuisance else []))
            rest, nuis, ev = backfit(objective, problem, list(rest), nuisance, ev, passes=1,
                                     refine=3)
            trials.append((gap_in(objective, ev, scatters) - gap_now, k, rest, nuis, ev))
        cost, k, rest, nuis, ev = min(trials, key=lambda t: t[0])
        if cost > needed:
            break
        dropped.append({'effect': selected[k][0], 'params': dict(selected[k][1]),
                        'gap_without': ev.gap, 'cost': float(cost), 'needed': needed})
        selected, nuisance, current = rest, nuis, ev
    return selected, nuisance, current, dropped
