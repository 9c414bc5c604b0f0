"""
Which candidate a greedy step selects, when the kind has a choice criterion (``choice``).

Among the candidates the gap finds comparable (``comparable``), the criterion chooses
(``choose_among``): each candidate refitted to it, the best first.

The gap judges every candidate in one common scatter (the baseline's, widened where the model
so far is more variable), so a process that adds variance gets no credit for the part of a
departure its own scatter holds. On a strong random walk, one realization's early trend is a
mean shape that a warm-up follows first; the walk, whose mean has no trend, then closes less
of what the warm-up leaves (the early-minus-late means) than the greedy bar, and the search
stopped with the walk's long-tau excess unexplained. So where no candidate closes the gap in
the common scatter, ``own_step`` looks for one that brings the record within its OWN widened
scatter (to the current model's 95 % level) and that the criterion prefers to the model so
far: its ``2 ln s`` term charges a candidate for every bit of spread it adds, so none wins by
spreading its twins, only by a better likelihood. The joint refit and the pruning then say
whether the earlier effect was only standing in for it.
"""
from typing import Dict, Sequence

from gyro_char.diagnosis.choice import INDISTINGUISHABLE, model_score, refit_score
from gyro_char.diagnosis.greedy import gap_in

# With a choice criterion, a candidate is compared with the best one by the gap when it
# removes at least this share of what the best removes.
COMPARABLE = 0.5


def comparable(order: Sequence[str], judged: Dict[str, float], gap_now: float,
               rivals: Sequence[str]) -> list:
    """
    Candidates (``order[1:]``) that close the gap comparably to the best (``order[0]``).

    The gap's rivals, and any candidate that removes at least ``COMPARABLE`` of what the
    best removes.
    """
    best = order[0]
    return [n for n in order[1:] if n in rivals
            or gap_now - judged[n] >= COMPARABLE * (gap_now - judged[best])]


def choose_among(objective, problem, selected: list, fits: dict, significant: Sequence[str]):
    """
    Best of the ``significant`` candidates by ``problem.choose``, each refitted to it.

    Returns the best and the others, best first, and the scores.
    """
    spaces = {s.name: s for s in problem.spaces}
    scores = {}
    for n in significant:
        params, nuis, _ = fits[n]
        scores[n] = refit_score(objective, problem.choose, list(selected), spaces[n], params,
                                nuis, problem.nuisance)[0]
    ranked = sorted(significant, key=lambda n: scores[n])
    return ranked[0], ranked[1:], {n: float(v) for n, v in scores.items()}


def own_step(objective, problem, selected: list, current, fits: dict, order: Sequence[str],
             scatters: list, gap_now: float, bar: float, needed: float):
    """
    Return a candidate that closes the gap in its own scatter only, if the criterion wants it.

    Only where the gap now stands clearly above the current model's own 95 % level (``bar``:
    by more than the greedy bar ``needed``; the criterion has no null level of its own, and
    at the edge a mode fitted to a chance excess in one band wins it). Candidates whose gap
    in the common scatter widened by their own is at most ``bar`` are then ranked by the
    criterion; the best is taken when it beats the model so far (``current``, its score
    ``before``, its nuisance refitted to the criterion as each candidate's is) by more than
    ``INDISTINGUISHABLE``.
    Returns (best, rivals within ``INDISTINGUISHABLE`` of it, scores, before) or None.
    """
    if gap_now - bar <= needed:
        return None
    own = [n for n in order
           if gap_in(objective, fits[n][2], list(scatters) + [fits[n][2]]) <= bar]
    if not own:
        return None
    before = float(model_score(objective, problem.choose, current.effects, problem.nuisance))
    best, others, scores = choose_among(objective, problem, selected, fits, own)
    if scores[best] >= before - INDISTINGUISHABLE:
        return None
    rivals = [n for n in others if scores[n] - scores[best] <= INDISTINGUISHABLE]
    return best, rivals, scores, before
