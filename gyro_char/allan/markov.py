"""
IEEE 952 Annex C exponentially correlated (first-order Gauss-Markov) terms in the noise fit.

A Markov rate of correlation time T_c and driving density q (rate variance sigma^2 =
q^2 T_c / 2) looks like a random walk (q^2 tau / 3) well below T_c and like white noise
((q T_c)^2 / tau) well above: on the Allan curve, a bump near tau ~ 2 T_c. Consumer MEMS often
show one at 10-100 s, which formula (4) can only leave to N with every other term unresolved.

How the fit uses them (``gyro_char.allan.fit.fit_noise``, opt in: ``--markov 1`` or ``2``):
formula (4)'s terms are selected first, as without Markov terms. Then up to ``MARKOV_MAX``
correlation times are searched with all five terms of formula (4) free: each on a log grid
(``PER_DECADE`` a decade, from 3 x the shortest to a third of the longest fitted tau,
``SEPARATION`` apart), greedily, then refined between its grid neighbours. The Markov terms then
enter the same backward elimination as the others, with the same statistic and threshold
(``GAIN_MARKOV`` = ``GAIN_MIN``), and are dropped before any other weak term. The survivors
must then also beat formula (4)'s own selection (a comparison of non-nested models when they
displaced a term: a Markov bump can stand in for a flicker floor): the objective must drop by
``GAIN_MARKOV`` x the sum of their null scales. When no Markov term passes, the result is
formula (4)'s own selection, unchanged; when one does, formula (4)'s terms are those the joint
elimination kept.
"""
from typing import Callable, List, Sequence

from gyro_char.allan.selection import GAIN_MIN
import numpy as np
from scipy import optimize

MARKOV_MAX = 2
GAIN_MARKOV = GAIN_MIN
PER_DECADE = 6
SEPARATION = 3.0
MIN_SPAN = 30.0  # the fitted taus must span this factor for a Markov term to be searched


def tc_grid(tau: np.ndarray) -> np.ndarray:
    """Return the correlation times searched for the fitted taus ``tau`` (s)."""
    lo, hi = 3.0 * float(np.min(tau)), float(np.max(tau)) / 3.0
    if np.max(tau) < MIN_SPAN * np.min(tau):
        return np.zeros(0)
    step = np.log(10.0) / PER_DECADE
    return np.exp(np.arange(np.log(lo), np.log(hi) + 1e-9, step))


def search_tc(score: Callable[[Sequence[float]], float], tau: np.ndarray,
              count: int = MARKOV_MAX) -> List[float]:
    """
    Return up to ``count`` correlation times, each the best for ``score`` given the previous.

    ``score(tcs)`` is the fit objective with Markov terms at ``tcs`` (lower is better).
    """
    grid = tc_grid(tau)
    found: List[float] = []
    for _ in range(count):
        free = [t for t in grid if all(max(t / f, f / t) >= SEPARATION for f in found)]
        if not free:
            break
        vals = [score(found + [t]) for t in free]
        i = int(np.argmin(vals))
        lo = np.log(free[max(i - 1, 0)])
        hi = np.log(free[min(i + 1, len(free) - 1)])
        best = free[i]
        if hi > lo:
            sol = optimize.minimize_scalar(lambda v: score(found + [float(np.exp(v))]),
                                           bounds=(lo, hi), method='bounded',
                                           options={'xatol': 0.02, 'maxiter': 12})
            if sol.fun <= vals[i]:
                best = float(np.exp(sol.x))
        found.append(float(best))
    return found
