"""
Which of the candidates that close the gap is the effect: a likelihood in each one's own spread.

The gap (``gap``) detects: it scores every model in the baseline's scatter, so a model cannot
close it by making its twins noisier. That yardstick is wrong for telling apart effects that
all add variance (flicker, a rate random walk, a Gauss-Markov process): in the baseline's
scatter each is judged by how well its *mean* curve follows this one realization, which a
Gauss-Markov process with a free correlation time does best. Among the candidates the gap has
found significant, the choice is made here on the observables' Gaussian deviance under each
candidate's OWN expectation and spread (closed forms: the chi-square EDF of the Allan variance,
the Welch bins' chi-square, the acf's delta method, the exact variance of the drift forms),

    D = sum_j ((r_j - m_j) / s_j)^2 + 2 ln s_j   (+ ln(n_elements) per free parameter, BIC),

where the 2 ln s_j term charges a model for every bit of variance it adds: a random walk
cannot "explain" a warm-up's early-minus-late means by widening their spread for free. Elements
are treated as independent (neighbouring octaves and Welch bins are not quite), which is why
this only ranks candidates the gap has already found and never detects.
"""
from typing import Callable, Dict, Optional, Sequence

from gyro_char.diagnosis.fit import EffectSpace, Evaluation, fit_effect
import numpy as np

# Deviance differences up to this are "not worth more than a bare mention" (Kass & Raftery's
# BIC scale): two candidates closer than this are reported as indistinguishable.
INDISTINGUISHABLE = 2.0


def deviance(reals: Sequence[dict], ev: Evaluation) -> float:
    """Return the Gaussian deviance of the real observables in ``ev``'s own mean and spread."""
    total = 0.0
    for real, stats in zip(reals, ev.stats):
        mean, std = stats.mean, stats.std
        for b in mean:
            s = np.asarray(std[b], dtype=float)
            z = (np.asarray(real[b], dtype=float) - mean[b]) / s
            total += float(np.sum(z * z + 2.0 * np.log(s)))
    return total


def element_count(reals: Sequence[dict]) -> int:
    """Return the number of observable elements over all records (the BIC sample size)."""
    return int(sum(np.size(v) for r in reals for v in r.values()))


class Criterion:
    """BIC-like score of a fitted model: own-spread deviance plus ln(n) per free parameter."""

    def __init__(self, reals: Sequence[dict], spaces: Sequence[EffectSpace]):
        self.reals = list(reals)
        self.params = {s.name: list(s.params) for s in spaces}
        # What only an alternative search has (a warm-up's onset, a comb's width), and the
        # values a search estimates from the record instead (a comb's spacing).
        self.extra, self.estimated = {}, {}
        for space in spaces:
            own = {p.name for p in space.params}
            for sp in (space,) + tuple(space.alternatives):
                self.extra.setdefault(space.name, {}).update(
                    {p.name: p for p in sp.params if p.name not in own})
                self.estimated.setdefault(space.name, set()).update(sp.estimated)
        self.log_n = float(np.log(max(element_count(self.reals), 2)))

    def free(self, name: str, params: dict) -> int:
        """Return the free parameters of one effect (an optional part that is off is not)."""
        own = sum(1 for p in self.params.get(name, ()) if not p.is_off(params.get(p.name, 1.0)))
        extra = sum(1 for key, p in self.extra.get(name, {}).items()
                    if key in params and not p.is_off(params[key]))
        return own + extra + sum(1 for key in self.estimated.get(name, ()) if key in params)

    def __call__(self, ev: Evaluation) -> float:
        k = sum(self.free(name, params) for name, params in ev.effects)
        return deviance(self.reals, ev) + k * self.log_n


class _ScoredObjective:
    """An objective whose ``gap`` is the criterion: ``fit_effect`` then minimises it."""

    def __init__(self, objective, score: Callable[[Evaluation], float]):
        self.objective = objective
        self.score = score

    def evaluate(self, effects) -> Evaluation:
        ev = self.objective.evaluate(effects)
        return Evaluation(effects=ev.effects, gap=self.score(ev), stats=ev.stats)


def refit_score(objective, score: Callable[[Evaluation], float], others: list,
                space: EffectSpace, params: Dict, nuisance=None,
                nuisance_space: Optional[EffectSpace] = None):
    """
    Return the best score of ``space`` on top of ``others``, searched near its gap fit.

    The gap fit puts a variance-adding process where its mean curve follows the record; its
    own likelihood may peak elsewhere (e.g. a random walk a little weaker, with the white
    noise a little stronger), so each candidate is compared at its own best: its parameters,
    then the baseline's nuisance parameters (``nuisance``, within ``nuisance_space``), then
    its parameters again. Returns the score, the parameters and the nuisance entry there.
    """
    scored = _ScoredObjective(objective, score)
    extra = [nuisance] if nuisance else []
    params = dict(params)
    best = score(objective.evaluate(list(others) + [(space.name, params)] + extra))
    for turn in range(3 if nuisance and nuisance_space is not None else 1):
        if turn % 2:
            p, ev = fit_effect(scored, list(others) + [(space.name, params)], nuisance_space,
                               near=nuisance[1], refine=3)
            if ev.gap < best:
                extra = [(nuisance_space.name, p)]
        else:
            near = {k: v for k, v in params.items() if k not in space.fixed}
            p, ev = fit_effect(scored, list(others) + extra, space, near=near, at=len(others),
                               refine=3)
            if ev.gap < best:
                params = p
        best = min(best, ev.gap)
    return best, params, (extra[0] if extra else None)


def model_score(objective, score: Callable[[Evaluation], float], effects: list,
                nuisance_space: Optional[EffectSpace] = None) -> float:
    """
    Return the score of a fixed model, its nuisance entry (if any) refitted to the score.

    What a candidate scored by ``refit_score`` is compared with: the model so far at its own
    best, so that a candidate does not win by the nuisance refit alone.
    """
    best = score(objective.evaluate(list(effects)))
    if nuisance_space is None:
        return best
    nuis = [e for e in effects if e[0] == nuisance_space.name]
    if not nuis:
        return best
    others = [e for e in effects if e[0] != nuisance_space.name]
    _, ev = fit_effect(_ScoredObjective(objective, score), others, nuisance_space,
                       near=nuis[0][1], refine=3)
    return min(best, ev.gap)
