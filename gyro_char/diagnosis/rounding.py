"""
Rounding a Gaussian rate to the output step, exactly: what the step adds to its variance.

Samples x ~ N(mu, sigma^2) rounded to a grid of step q are independent when the x are, so a
white rate stays white; but the rounding error is the uniform, uncorrelated q^2 / 12 of the
usual model only while sigma exceeds about half a step (its corrections fall as
exp(-2 pi^2 sigma^2 / q^2): 7e-3 at sigma = q / 2, 5e-13 at 1.2 q). Below that the output's
variance depends on where the mean sits on the grid: a coarse step can hide the noise (mean on
a level) or make it a coin flip between two levels (mean half-way). ``excess`` is the exact
Var(round(x)) - sigma^2, ``sigma_for`` its inverse: the white noise a record of the given
output variance came from.
"""
import numpy as np
from scipy.special import ndtr

# sigma / q above which rounding is the white q^2 / 12 to double precision, and used as such.
EXACT_BELOW = 1.2


def rounded_variance(sigma: float, mu: float, q: float) -> float:
    """Return Var(q round(x / q)) for x ~ N(mu, sigma^2), summed over the levels within 9 sd."""
    if sigma <= 0.0:
        return 0.0
    k = np.arange(np.floor((mu - 9 * sigma) / q) - 1, np.ceil((mu + 9 * sigma) / q) + 2)
    edges = (np.r_[k - 0.5, k[-1] + 0.5] * q - mu) / sigma
    p = np.diff(ndtr(edges))
    level = k * q
    m = float(np.dot(p, level))
    return float(np.dot(p, (level - m) ** 2))


def excess(sigma2: float, mu: float, q: float) -> float:
    """Return what rounding to ``q`` adds to the variance ``sigma2`` of a rate of mean ``mu``."""
    if q <= 0.0:
        return 0.0
    sigma = float(np.sqrt(max(sigma2, 0.0)))
    if sigma >= EXACT_BELOW * q:
        return q * q / 12.0
    return rounded_variance(sigma, mu, q) - sigma2


def sigma_for(variance: float, mu: float, q: float, points: int = 400) -> float:
    """
    Return the sigma whose rounded variance is ``variance`` (mean ``mu``, step ``q``).

    Searched on a log grid from q / 100 to 10 q: the rounded variance can be flat in sigma
    (a mean half-way between levels reads q^2 / 4 for any sigma below ~q / 3), and then the
    largest sigma that gives it is taken.
    """
    grid = q * np.geomspace(0.01, 10.0, points)
    v = np.array([rounded_variance(s, mu, q) for s in grid])
    err = np.abs(np.log(np.maximum(v, 1e-300) / variance))
    near = np.flatnonzero(err <= err.min() + 5e-3)
    return float(grid[near[-1]])
