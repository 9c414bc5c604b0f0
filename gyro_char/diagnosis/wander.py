"""
Closed-form spectrum of a tone whose frequency wanders: a machine whose speed is not held.

The tone A sin(phi(t)) has instantaneous frequency f0 + w u(t), u a unit Gauss-Markov process
of correlation time tau (``vibration``'s ``wander_hz``, ``wander_s``). Its phase increment over
a lag u is Gaussian with variance D(u) = 2 beta (x - 1 + e^-x), x = u / tau, beta =
(2 pi w tau)^2, so the autocovariance is (A^2 / 2) cos(2 pi f0 u) e(u), e = exp(-D / 2), and
the two-sided PSD (A^2 / 4) (E(f - f0) + E(f + f0)), E the envelope's spectrum (unit area).
Slow wander (beta >> 1) spreads the power as the frequency's own Gaussian law (sd w); fast
wander (beta << 1) leaves a Lorentzian line of half width beta / (2 pi tau). Either way the
envelope stays constant: band-passed, the tone has excess kurtosis -3/2, where a mode's
Gaussian noise has 0 (``band_kurtosis``).

E is taken by one DCT-I of e on 2^15 lags up to where D / 2 reaches 40 (the trapezoid rule,
exact cosine transform of the sampled e); beyond that lag e < 4e-18.
"""
from functools import lru_cache
from typing import Tuple

import numpy as np
from scipy import fft, optimize

LAGS = 2 ** 15
DECAY = 40.0          # D / 2 where the lag grid ends


def phase_structure(x: np.ndarray, beta: float) -> np.ndarray:
    """Return D(u) / 2 = beta (x - 1 + e^-x) at x = u / tau, without cancellation at small x."""
    x = np.asarray(x, dtype=np.float64)
    small = x < 1e-3
    series = x * x * (0.5 - x * (1.0 / 6.0 - x / 24.0))
    return beta * np.where(small, series, x + np.expm1(-np.where(small, 1.0, x)))


@lru_cache(maxsize=64)
def envelope_spectrum(wander_hz: float, wander_s: float) -> Tuple[np.ndarray, np.ndarray]:
    """Return (nu, E): the envelope's two-sided spectrum (unit area) at nu >= 0 Hz (E even)."""
    beta = (2.0 * np.pi * wander_hz * wander_s) ** 2
    hi = np.sqrt(2.0 * DECAY / beta) + DECAY / beta + 2.0
    x_end = optimize.brentq(lambda x: float(phase_structure(x, beta)) - DECAY, 0.0, hi)
    h = x_end * wander_s / LAGS
    e = np.exp(-phase_structure(np.arange(LAGS + 1) * h / wander_s, beta))
    spec = h * fft.dct(e, type=1)
    nu = np.arange(LAGS + 1) / (2.0 * LAGS * h)
    return nu, np.maximum(spec, 0.0)


def tone_psd(f: np.ndarray, power: float, f0: float, wander_hz: float,
             wander_s: float) -> np.ndarray:
    """
    Two-sided PSD (per Hz) at ``f`` of a wandering tone of mean square ``power``.

    Periodic images are the caller's: ``f`` and ``f0`` are taken as given (both >= 0).
    """
    nu, e = envelope_spectrum(float(wander_hz), float(wander_s))
    f = np.abs(np.asarray(f, dtype=np.float64))
    return 0.5 * power * (np.interp(np.abs(f - f0), nu, e, right=0.0)
                          + np.interp(f + f0, nu, e, right=0.0))


def spread_hz(wander_hz: float, wander_s: float) -> float:
    """Return the tone's spectral width: the frequency's sd or the Lorentzian's half width."""
    beta = (2.0 * np.pi * wander_hz * wander_s) ** 2
    return float(max(min(wander_hz, beta / (2.0 * np.pi * wander_s)), 1e-6))


@lru_cache(maxsize=64)
def _envelope_cumulative(wander_hz: float, wander_s: float) -> Tuple[np.ndarray, np.ndarray]:
    """Return (nu, C): C(nu) the integral of E from 0 to nu (trapezoid on E's grid)."""
    nu, e = envelope_spectrum(wander_hz, wander_s)
    return nu, np.concatenate([[0.0], np.cumsum(0.5 * (e[1:] + e[:-1]) * np.diff(nu))])


def band_share(lo: float, hi: float, f0: float, wander_hz: float, wander_s: float) -> float:
    """Return the share of the tone's power in [lo, hi] Hz (one-sided, both images of E)."""
    nu, c = _envelope_cumulative(float(wander_hz), float(wander_s))

    def cum(x):                      # integral of E from 0 to x (E even)
        return float(np.sign(x) * np.interp(abs(x), nu, c))
    return (cum(hi - f0) - cum(lo - f0)) + (cum(hi + f0) - cum(lo + f0))
