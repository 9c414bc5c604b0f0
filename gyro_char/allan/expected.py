"""
Exact Allan variances of stationary sequences: from an autocovariance, through an FIR + decimation.

A stationary sequence y_n with autocovariance r(k) = Cov(y_n, y_(n+k)) has, for m-sample
averages (tau = m dt), the Allan variance

    sigma^2(m) = Var(mean of m) - Cov(two adjacent means of m)
               = [m r(0) + sum_k>=1 (2 max(m - k, 0) - max(m - |k - m|, 0)) r(k)] / m^2

a finite sum when r has finite support (an FIR's output). For m at or beyond the support K,
sigma^2(m) = S / m - 3 M / m^2 with S = r(0) + 2 sum r(k) and M = sum k r(k): a white term with
the long-tau density S plus an exact 1/m^2 (quantization-like) correction.

White noise of variance s^2 per internal sample through an FIR h and kept every D-th sample
has the output autocovariance r(k) = s^2 sum_j h_j h_(j + kD) (aliasing included: it is the
decimated sequence's own autocovariance). Normalised to unit long-tau density, its Allan
variance is 1 / tau at long tau, so the white term's coefficient N keeps its IEEE meaning (the
long-tau angle random walk) whatever the filter.

Also the Allan variance of IEEE 952 Annex C's exponentially correlated (first-order Markov)
rate, ``markov_avar``. Pure numpy, no other project imports: for the noise fit
(``gyro_char.allan.design``), the simulator's ``internal_lowpass`` kernel and any other
closed-form expectation (e.g. the diagnosis's).

API: ``moving_average_kernel`` (boxcar / Bartlett impulse response), ``decimated_autocov``
(r(k) of white noise through h and decimation D), ``avar_from_autocov`` (sigma^2(m) from any
finite autocovariance), ``long_tau_density`` (S), ``white_avar_unit`` (tau sigma^2 / N^2 of
filtered white noise), ``autocorrelation`` (rho(k)), ``markov_avar``.
"""
from typing import Sequence

import numpy as np


def moving_average_kernel(taps: int, stages: int = 1) -> np.ndarray:
    """
    Return the impulse response of ``stages`` cascaded ``taps``-point moving averages.

    Unit DC gain. ``stages`` 1 is a boxcar, 2 a Bartlett (triangular) window of
    2 ``taps`` - 1 points.
    """
    taps, stages = int(taps), int(stages)
    if taps < 1 or stages < 1:
        raise ValueError(f'taps and stages must be >= 1, got {taps}, {stages}')
    h = np.ones(1)
    for _ in range(stages):
        h = np.convolve(h, np.full(taps, 1.0 / taps))
    return h


def decimated_autocov(h: Sequence[float], decimation: int = 1) -> np.ndarray:
    """
    Return r(k), k = 0..K-1, of unit white noise through FIR ``h``, then every D-th sample kept.

    r(k) = sum_j h_j h_(j + k D); K = ceil(len(h) / D) (r is zero beyond, and symmetric).
    """
    h = np.asarray(h, dtype=np.float64)
    d = int(decimation)
    if h.ndim != 1 or h.size == 0:
        raise ValueError('h must be a non-empty 1-D kernel')
    if d < 1:
        raise ValueError(f'decimation must be >= 1, got {decimation}')
    full = np.correlate(h, h, mode='full')[h.size - 1:]  # lag 0..len(h)-1 at the internal rate
    return full[::d].copy()


def avar_from_autocov(acov: Sequence[float], m) -> np.ndarray:
    """
    Return the exact Allan variance of a stationary sequence with autocovariance ``acov``.

    ``acov[k]`` = r(k) for k = 0..K-1 (zero beyond), ``m`` the averaging factors (integers
    >= 1). Units: those of r (per sample); sigma^2 at tau = m dt, whatever dt.
    """
    r = np.asarray(acov, dtype=np.float64)
    m = np.atleast_1d(np.asarray(m, dtype=np.float64))
    k = np.arange(1, r.size, dtype=np.float64)
    mm = m[:, None]
    w = 2.0 * np.maximum(mm - k, 0.0) - np.maximum(mm - np.abs(k - mm), 0.0)
    return (m * r[0] + w @ r[1:]) / m ** 2


def long_tau_density(acov: Sequence[float]) -> float:
    """Return S = r(0) + 2 sum_k>=1 r(k): sigma^2(m) -> S / m at long tau (spectrum at DC)."""
    r = np.asarray(acov, dtype=np.float64)
    return float(r[0] + 2.0 * np.sum(r[1:]))


def white_avar_unit(h: Sequence[float], decimation: int, m) -> np.ndarray:
    """
    Return tau x sigma^2(tau) / N^2 of white noise N through ``h`` and decimation ``D``.

    1 for an identity filter and at long tau for any filter (N is the long-tau density), so
    sigma^2(tau) = N^2 g(m) / tau with g the returned array: the filter's exact replacement of
    formula (4)'s N^2 / tau.
    """
    r = decimated_autocov(h, decimation)
    m = np.atleast_1d(np.asarray(m, dtype=np.float64))
    return m * avar_from_autocov(r / long_tau_density(r), m)


def autocorrelation(h: Sequence[float], decimation: int, lags: int) -> np.ndarray:
    """Return rho(k), k = 0..lags, of unit white noise through ``h`` and decimation."""
    r = decimated_autocov(h, decimation)
    out = np.zeros(int(lags) + 1)
    n = min(out.size, r.size)
    out[:n] = r[:n] / r[0]
    return out


def markov_avar(tau, tc: float) -> np.ndarray:
    """
    Return sigma^2(tau) / q^2 of a first-order Gauss-Markov rate (IEEE 952 Annex C).

    Rate autocovariance q^2 tc / 2 exp(-|t| / tc) (q the density of its driving white noise):
    sigma^2 = (q tc)^2 / tau [1 - tc / (2 tau) (3 - 4 exp(-tau / tc) + exp(-2 tau / tc))];
    ~ q^2 tau / 3 for tau << tc (a random walk), ~ (q tc)^2 / tau for tau >> tc (white).
    """
    tau = np.asarray(tau, dtype=np.float64)
    x = tau / float(tc)
    out = np.empty_like(x)
    small = x < 1e-3  # series: the closed form cancels catastrophically there
    xs = x[small]
    out[small] = tc * (xs / 3.0 - xs ** 2 / 4.0 + 7.0 * xs ** 3 / 60.0)
    xl = x[~small]
    out[~small] = tc ** 2 / tau[~small] * (
        1.0 - (3.0 - 4.0 * np.exp(-xl) + np.exp(-2.0 * xl)) / (2.0 * xl))
    return out
