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
   when the problem has a ``choose`` criterion (``choice.Criterion``), the candidates that
   close the gap comparably are ranked by it instead of by the gap, and where none closes
   it in the common scatter, one that does in its own may be selected by it (``step_choice``);
6. refits the selected effects jointly (coordinate passes, each with the others fixed) and
   reports the final gap after that (``refined``); when the kind asks for it, then drops
   any selected effect the others have made redundant (``refined['dropped']``); when the
   kind has a check finer than the gap (``Problem.lines``: narrow lines), adds the effect
   that check finds missing, held where it put it, and refits the others around it;
7. reads the result in one line (``verdict``): consistent, explained, partly explained or
   unexplained, from the same levels.
"""
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

from gyro_char.diagnosis import gap as diag_gap, step_choice
from gyro_char.diagnosis.choice import INDISTINGUISHABLE
from gyro_char.diagnosis.closed_form import ExpectedObjective
from gyro_char.diagnosis.fit import EffectSpace, Evaluation, fit_effect, GapObjective
from gyro_char.diagnosis.greedy import (
    backfit, could_trail, fit_on_top, gap_in, levels, look_alikes, prune, separating_run)
from gyro_char.diagnosis.verdict import verdict
from gyro_char.progress import progress
import numpy as np

Obs = Dict[str, np.ndarray]


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
    # Kind-specific fitted baseline object (e.g. ``static.StaticBaseline``).
    context: object = None
    # Closed-form statistics of a model on record i, ``expect(i, effects)``, when the kind has
    # them (``closed_form``): candidates are then scored without simulation.
    expect: Optional[Callable[[int, list], object]] = None
    # What the simulated twins said about the closed forms (``static_expect``), if used.
    check: dict = field(default_factory=dict)
    # How to choose among the candidates the gap found significant, ``choose(ev) -> score``
    # (lower is better; ``choice.Criterion``), when the kind has one; else the smallest gap.
    choose: Optional[Callable[[Evaluation], float]] = None
    # The simulator's own twins, ``twin(i, effects, seed)``, when ``simulate`` approximates
    # them (the swing kind's pseudo-twins): the check of the selected model.
    twin: Optional[Callable[[int, list, int], Obs]] = None
    # Known look-alike pairs (``greedy.SEPARATING_RUNS``) that the records given cannot tell
    # apart (one swing period: a delay and g-sensitivity leave the same cos θ residual). A
    # rival from such a pair is flagged whenever it removes ``UNRESOLVED_SHARE`` of what the
    # best removes, however the two gaps compare: their difference is then the catalogue
    # shapes' fit to a real shape, not evidence.
    unresolved: frozenset = frozenset()
    # The search spaces re-seeded from where the baseline's gap lies, ``reseed(where)``, when
    # the kind has data-driven starts that only the gap can place (a weak mode's band).
    reseed: Optional[Callable[[List[dict]], List[EffectSpace]]] = None
    # Whether a selected effect that the later ones have made redundant is dropped after the
    # joint refit (``greedy.prune``): a warm-up standing in for a random walk's trend.
    prune: bool = False
    # A check finer than the gap, asked once the search is done (``narrow_lines``: steady
    # lines too narrow for the gap's tone bands): ``lines(model)`` returns the effect that
    # makes what the model lacks and the evidence, ``((name, params), evidence)``, or None.
    lines: Optional[Callable[[list], Optional[tuple]]] = None


def objective_for(problem: Problem, seeds: Sequence[int]):
    """Return the gap objective of ``problem``: closed forms when it has them, else twins."""
    if problem.expect is not None:
        return ExpectedObjective(problem.reals, problem.expect)
    return GapObjective(problem.reals, problem.simulate, seeds)


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
    # The one-line reading (``verdict.verdict``).
    verdict: dict = field(default_factory=dict)

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
            'verdict': self.verdict,
        }


# A rival of an unresolved look-alike pair (``Problem.unresolved``) is flagged when it removes
# at least this share of what the best removes.
UNRESOLVED_SHARE = 0.8
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


def run(problem: Problem, *, repeats: int = 8, seed: int = 1, max_steps: int = 3,
        quiet: bool = True) -> Diagnosis:
    seeds = [seed * 1000 + k for k in range(repeats)]
    objective = objective_for(problem, seeds)
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
    if problem.reseed is not None:
        problem.spaces = problem.reseed(where)

    fits = {}
    bar = progress(total=len(problem.spaces), desc='ranking effects', quiet=quiet)
    for space in problem.spaces:
        fits[space.name] = fit_on_top(objective, problem, [], nuisance, space)
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
        gap_now, shrink_needed, explained = levels(objective, base, current, base_needed,
                                                   base_explained)
        if gap_now <= explained:
            break  # within what the current model scores against itself
        if step > 0:
            fits = {}
            for space in problem.spaces:
                if space.name in [n for n, _ in selected]:
                    continue
                fits[space.name] = fit_on_top(objective, problem, selected, nuisance, space,
                                              near=first[space.name][0])
        if not fits:
            break
        judged = {n: gap_in(objective, f[2], scatters) for n, f in fits.items()}
        order = sorted(fits, key=lambda n: judged[n])
        best = order[0]
        before = None
        if gap_now - judged[best] > shrink_needed:
            best, rivals, scores = _rivals(objective, problem, selected, fits, judged, order,
                                           gap_now, shrink_needed, scatters)
        else:
            # None closes the gap in the common scatter; one may in its own (a random walk
            # beside the warm-up that took its trend): ``step_choice.own_step``.
            found = (step_choice.own_step(objective, problem, selected, current, fits, order,
                                          scatters, gap_now, explained, shrink_needed)
                     if problem.choose is not None else None)
            if found is None:
                break
            best, rivals, scores, before = found
        params, best_nuisance, ev = fits[best]
        if rivals:
            # Look-alikes (known pairs, see SEPARATING_RUNS): keep the best, say which run
            # would separate them. Unrelated effects shrinking the gap equally: none of them
            # is evidenced (they are fitting what is left of the noise), so stop without
            # selecting.
            named = [best] + rivals
            decided = bool(scores) and all(
                scores[n] - scores[best] > INDISTINGUISHABLE for n in rivals)
            chosen = len(rivals) == 1 or look_alikes(named)
            ambiguous.append({'step': step + 1, 'effects': named,
                              'gap_after': [fits[n][2].gap for n in named],
                              'selected': chosen,
                              **({'criterion': [scores[n] for n in named],
                                  'decided_by_criterion': decided} if scores else {}),
                              'separating_run': '; '.join(separating_run(best, r)
                                                          for r in rivals)})
            if not chosen:
                break
        selected.append((best, params))
        nuisance = best_nuisance
        steps.append({'effect': best, 'params': _jsonable(params), 'gap_after': ev.gap,
                      **({'criterion': scores} if scores else {}),
                      **({'own_scatter': {'criterion_before': before}}
                         if before is not None else {})})
        current = ev
    greedy_gap = current.gap
    dropped = []
    if selected:
        selected, nuisance, current = backfit(objective, problem, selected, nuisance, current)
        if problem.prune:
            selected, nuisance, current, dropped = prune(
                objective, problem, selected, nuisance, current, base, base_needed,
                base_explained)
    if problem.lines is not None and all(n != 'vibration' for n, _ in selected):
        found = problem.lines(selected + ([nuisance] if nuisance else []))
        if found is not None:
            (name, params), evidence = found
            selected.append((name, params))
            current = objective.evaluate(selected + ([nuisance] if nuisance else []))
            # The other effects may have stood in for the line (a mode fitted to it): they
            # are refitted around it, the line held where the finer check put it.
            selected, nuisance, current = backfit(objective, problem, selected, nuisance,
                                                  current, passes=1, hold=1)
            steps.append({'effect': name, 'params': _jsonable(params),
                          'gap_after': current.gap, 'evidence': evidence})
    evaluations['final'] = current
    model = selected + ([nuisance] if nuisance else [])
    names = [n for n, _ in selected]
    final_judged, final_q95 = base.gap, None
    if selected:
        final_judged, _, final_q95 = levels(objective, base, current, base_needed,
                                            base_explained)
    return Diagnosis(
        kind=problem.kind, baseline_gap=base.gap, where=where, steps=steps,
        selected_effects=names, final_gap=current.gap, ranking=ranking,
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
                 'params': {n: _jsonable(p) for n, p in selected}, 'dropped': dropped},
        evaluations=evaluations,
        reals=problem.reals, model=model,
        verdict=verdict(base.gap, base_explained, names, current.gap, final_judged, final_q95,
                        ranking, seen_finer=[s for s in steps if 'evidence' in s]))


def _rivals(objective, problem: Problem, selected: list, fits: dict, judged: dict,
            order: list, gap_now: float, shrink_needed: float, scatters: list):
    """
    Return the step's effect, its rivals and the criterion's scores, from the gaps.

    Rivals close the gap within ``shrink_needed`` of the best (or within what the true model
    could trail by), or form an unresolved look-alike pair with it. With a choice
    criterion, the candidates that close the gap comparably are ranked by it instead
    (``step_choice``), not by how well their mean curves follow this one realization.
    """
    best = order[0]
    rivals = [n for n in order[1:]
              if gap_now - judged[n] > shrink_needed
              and (judged[n] - judged[best] <= shrink_needed
                   or judged[n] - judged[best] <= could_trail(
                       objective, fits[n][2], fits[best][2], scatters))]
    rivals += [n for n in order[1:] if n not in rivals
               and frozenset({best, n}) in problem.unresolved
               and gap_now - judged[n] >= UNRESOLVED_SHARE * (gap_now - judged[best])]
    scores = {}
    if problem.choose is not None:
        close = step_choice.comparable(order, judged, gap_now, rivals)
        if close:
            best, others, scores = step_choice.choose_among(objective, problem, selected, fits,
                                                            [best] + close)
            rivals = [n for n in others if n in rivals
                      or scores[n] - scores[best] <= INDISTINGUISHABLE]
    return best, rivals, scores


def evaluate_model(problem: Problem, effects: Sequence, *, repeats: int = 10,
                   seed: int = 1) -> Optional[Evaluation]:
    """Gap of a fixed model (e.g. fitted on another record) on ``problem``'s records."""
    seeds = [seed * 1000 + k for k in range(repeats)]
    objective = objective_for(problem, seeds)
    objective.set_reference(objective.evaluate([]))
    return objective.evaluate(list(effects))
