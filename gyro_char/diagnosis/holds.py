"""
Stale samples in closed form: how holds map an output spectrum (``stale_samples``).

A held output is x'_k = x_(k-D_k), D_k the run of holds ending at sample k. Independent holds
(probability p each) have geometric runs, g(d) = (1 - p) p^d; two samples m apart share their
source with probability p^|m| (every sample between them held) and otherwise draw their lags
independently, hence exactly

    R'(m) = (g * g~ * R)(m) + p^|m| (R(0) - R_G(0)),
    S'(f) = |G|^2 S(f) + (integral of S (1 - |G|^2)) AR1_p(f),   G(z) = (1 - p) / (1 - p z^-1).

Isolated holds (never two in a row: a read loop slightly faster than the sensor) follow the
chain P(hold | none before) = p / (1 - p), P(hold | hold) = 0; D_k = h_k in {0, 1}, whose
lag-m covariance is p (1 - p) l^|m|, l = -p / (1 - p). Hence, exactly,

    R'(m) = (g * g~ * R)(m) - p (1 - p) l^|m| (R(m+1) - 2 R(m) + R(m-1)),   G(z) = 1 - p + p z^-1,

the second term a few lags long (|l|^m below 1e-7 beyond ``lags``).

Both keep the variance; on white noise of variance s^2 they give R'(m) = s^2 p^|m| and
R'(+-1) = s^2 p only. The integrals are trapezoids on ``GRID`` points; every integrand carries a
factor sin^2(pi f dt), so a random walk's or flicker's low end stays finite.
"""
from dataclasses import dataclass
from typing import Sequence, Tuple

import numpy as np

GRID = 1 << 14      # points of the integrals behind the holds' broadband share


@dataclass(frozen=True)
class Holds:
    """Stale samples of one output: probability ``p``, independent or ``isolated``."""

    p: float
    isolated: bool = False

    def gain(self) -> float:
        """Return the long-τ gain of the holds on white noise (in N): sqrt of S'(0) / S(0)."""
        p = self.p
        return float(np.sqrt(1.0 + 2.0 * p if self.isolated else (1.0 + p) / (1.0 - p)))

    def g2(self, f, dt: float) -> np.ndarray:
        """Return |G|^2 at output frequencies ``f`` (the holds' averaging of a slow part)."""
        p, s2 = self.p, _s2(f, dt)
        if self.isolated:
            return 1.0 - 4.0 * p * (1.0 - p) * s2
        return (1.0 - p) ** 2 / ((1.0 - p) ** 2 + 4.0 * p * s2)

    def terms(self, f: np.ndarray, s: np.ndarray, lines: Sequence[Tuple[float, float]],
              dt: float) -> np.ndarray:
        """
        Return the broadband share's coefficients from the unheld one-sided PSD ``s`` on ``f``.

        ``f`` spans (0, fs / 2]; ``lines`` are (frequency, mean square) of the unheld lines.
        Independent holds: [lost variance]; isolated: the correction's lag terms, m = 0, 1, ..
        """
        f0 = np.array([a for a, _ in lines], dtype=np.float64)
        power = np.array([b for _, b in lines], dtype=np.float64)
        p = self.p
        if not self.isolated:
            def lost(freq):
                s2 = _s2(freq, dt)
                return 4.0 * p * s2 / ((1.0 - p) ** 2 + 4.0 * p * s2)
            return np.array([_integral(f, s, lost, f0, power)])
        m = np.arange(self.lags())

        def second_difference(freq):           # R(m+1) - 2 R(m) + R(m-1) kernels, lags m
            freq = np.asarray(freq, dtype=np.float64)
            return (-4.0 * _s2(freq, dt))[:, None] * np.cos(2 * np.pi * freq[:, None] * dt * m)
        lam = -p / (1.0 - p)
        return -p * (1.0 - p) * lam ** m * _integral(f, s, second_difference, f0, power)

    def lags(self) -> int:
        """Return how many lags of an isolated hold's correction are kept (|l|^m > 1e-7)."""
        lam = self.p / (1.0 - self.p)
        return 1 if lam <= 0.0 else int(np.ceil(np.log(1e-7) / np.log(lam))) + 1

    def apply(self, f, s: np.ndarray, terms: np.ndarray, dt: float) -> np.ndarray:
        """Return the held one-sided PSD at ``f`` from the unheld one ``s`` and ``terms``."""
        p = self.p
        f = np.asarray(f, dtype=np.float64)
        if self.isolated:
            w = 2 * np.pi * f * dt
            extra = terms[0] + 2.0 * sum(c * np.cos(k * w) for k, c in enumerate(terms) if k)
            return self.g2(f, dt) * s + 2.0 * dt * extra
        ar1 = 2.0 * (1.0 - p * p) * dt / ((1.0 - p) ** 2 + 4.0 * p * _s2(f, dt))
        return self.g2(f, dt) * s + terms[0] * ar1


def _s2(f, dt: float) -> np.ndarray:
    s = np.sin(np.pi * np.asarray(f, dtype=np.float64) * dt)
    return s * s


def _integral(f, s, kernel, f0, power):
    """Return the integral of s * kernel over ``f`` plus the lines' power times the kernel."""
    k = kernel(f)
    out = np.trapezoid(s.reshape((-1,) + (1,) * (k.ndim - 1)) * k, f, axis=0)
    if f0.size:
        k0 = kernel(f0)
        out = out + np.sum(power.reshape((-1,) + (1,) * (k0.ndim - 1)) * k0, axis=0)
    return out


# The held share is searched only where exact repeats exceed the rounding's own by this many
# of their standard errors: a hold repeats a sample exactly, so a record without such an
# excess has no holds, whatever its spectrum says (the ADIS16405's smoothing filter gives the
# same lag-1 correlation as 17 % isolated holds, and its records have no excess: z 1.2).
REPEAT_Z = 4.0


def repeat_excess(x: np.ndarray, lsb: float) -> Tuple[float, float]:
    """
    Return the share of exact repeats beyond the output rounding's, and its standard error.

    Unrounded records (``lsb`` 0): every exact repeat is a hold. Rounded ones: the rounded
    differences of a smooth process fall on the integers (in steps) with a density that is
    flat near 0, so the share at 0 expected without holds is that at +-1 times exp(1 / (2 v)),
    v their variance; holds add their share at 0 alone. Returns (nan, nan) where the step is
    too coarse to tell (differences spread over less than about one step).
    """
    d = np.diff(np.asarray(x, dtype=np.float64))
    n = d.size
    if n < 2:
        return float('nan'), float('nan')
    if lsb <= 0.0:
        share = float(np.count_nonzero(d == 0.0)) / n
        return share, float(np.sqrt(max(share, 1.0 / n) / n))
    k = np.round(d / lsb)
    v = float(np.var(k))
    if v < 1.0:
        return float('nan'), float('nan')
    p0 = float(np.count_nonzero(k == 0)) / n
    p1 = 0.5 * float(np.count_nonzero(np.abs(k) == 1)) / n
    expected = p1 * float(np.exp(0.5 / v))
    return p0 - expected, float(np.sqrt((p0 + 0.5 * p1) / n))
