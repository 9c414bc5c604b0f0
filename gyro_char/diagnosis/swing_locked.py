"""
The swing residual split into its part locked to the swing phase and the rest.

Whatever the motion drives - a scale factor that depends on the rate, a bias that depends on
the tilt, a lag, an encoder error along the angle - repeats every swing period: it is a
waveform of the phase θ, the same on every pass. The gyro's and the encoder's noise do not
repeat. The diagnosis scores the two apart:

- ``high_harmonics``: the angle residual's sin kθ and cos kθ for k = 4..``HIGH`` (the first
  three are the quadrature and harmonic blocks). Which of the four families a waveform's
  harmonics fall in says what it depends on: a rate error odd in the rate leaves sin kθ of
  odd k, one even in the rate sin kθ of even k, a bias odd in the tilt and a lag cos kθ of
  odd k, a direction memory cos kθ of even k;
- ``wave``: those harmonics evaluated at any phases. The noise blocks score the residual
  less them (before, a locked waveform's 5th-16th harmonics sat in the lowest PSD bins as if
  they were noise, where a stamp jitter or an encoder error took them). Only the harmonics
  the blocks score come out: sharper locked content (an encoder's lines, a dead band's
  turning points) stays where it was scored before, since a phase mean cannot hold it - the
  samples' phases spread across a bin over the periods, and the share of it left over would
  grow with the record (3 % of a 1000-line cyclic error's power on 300 s, 0.1 % on 60 s);
- ``phase_mean`` / ``locked_bands``: the mean square of the residual rate's phase mean
  beyond harmonic ``HIGH`` up to ``LOCKED_TOP`` of the sample rate, where a bin still holds
  it (sharp turning points, staircases, a dead band).
"""
from typing import Optional, Tuple

import numpy as np
from scipy import signal

HIGH = 16          # highest harmonic scored one by one
LOCKED_BANDS = 4   # bands of locked power beyond HIGH, log-spaced up to LOCKED_TOP
LOCKED_TOP = 0.02  # of the sample rate: a one-sample phase bin holds 99.9 % of a line there


def harmonic_basis(th: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """
    Return e^iθ and, per k = 4..``HIGH``, Σ sin² kθ, Σ cos² kθ and Σ sin kθ cos kθ (rows).

    sin² = (1 - cos 2kθ) / 2, cos² = (1 + cos 2kθ) / 2, sin cos = sin 2kθ / 2.
    """
    z1 = np.exp(1j * th)
    z2 = z1 * z1
    zk = z2 ** 3
    sums = np.empty((HIGH - 3, 3))
    for j in range(HIGH - 3):
        zk = zk * z2
        c2, s2 = float(np.sum(zk.real)), float(np.sum(zk.imag))
        sums[j] = 0.5 * (th.size - c2), 0.5 * (th.size + c2), 0.5 * s2
    return z1, sums


def high_harmonics(th: np.ndarray, r: np.ndarray,
                   basis: Optional[Tuple[np.ndarray, np.ndarray]] = None) -> np.ndarray:
    """
    Return the sin kθ and cos kθ coefficients of ``r`` for k = 4..``HIGH`` (sin, cos, ...).

    Least squares on each pair alone (its own 2 x 2 normal equations; ``basis``: the
    ``harmonic_basis`` of ``th``, when several ``r`` share it): over a record of many
    periods the pairs are orthogonal to each other and to the lower harmonics and trends to
    about one over the number of periods, and whatever leaks is the same linear map on
    record and twins. The powers of e^iθ are built by repeated products (no trigonometry).
    """
    z1, sums = harmonic_basis(th) if basis is None else basis
    zk = z1 ** 3
    out = np.empty(2 * (HIGH - 3))
    for j in range(HIGH - 3):
        zk = zk * z1
        ss, cc, sc = sums[j]
        ys, yc = (float(np.einsum('i,i->', zk.imag, r)),
                  float(np.einsum('i,i->', zk.real, r)))
        det = ss * cc - sc * sc
        out[2 * j] = (cc * ys - sc * yc) / det if det > 0 else 0.0
        out[2 * j + 1] = (ss * yc - sc * ys) / det if det > 0 else 0.0
    return out


def wave(th: np.ndarray, low: np.ndarray, high: np.ndarray,
         z1: Optional[np.ndarray] = None) -> np.ndarray:
    """
    Return the harmonics 1..``HIGH`` evaluated at the phases ``th``.

    ``low``: the sin and cos coefficients of θ, 2θ and 3θ; ``high``: those of 4θ..16θ
    (``high_harmonics``). Clenshaw's recurrence b_k = a_k + 2 cos θ b_(k+1) - b_(k+2) on the
    sine and cosine series (three real passes a harmonic, no complex powers); ``z1``: e^iθ,
    when known.
    """
    coef = np.r_[low, high].reshape(-1, 2)             # (sin, cos) of k = 1..HIGH
    z1 = np.exp(1j * th) if z1 is None else z1
    x = 2.0 * z1.real
    bs, bs2, bc, bc2 = (np.zeros(th.size) for _ in range(4))
    tmp = np.empty(th.size)
    for s_k, c_k in coef[::-1]:
        np.multiply(x, bs, out=tmp)
        tmp -= bs2
        tmp += s_k
        bs2, bs, tmp = bs, tmp, bs2
        np.multiply(x, bc, out=tmp)
        tmp -= bc2
        tmp += c_k
        bc2, bc, tmp = bc, tmp, bc2
    # Σ s_k sin kθ = b_1 sin θ; Σ c_k cos kθ = b_1 cos θ - b_2.
    return bs * z1.imag + 0.5 * x * bc - bc2


def phase_bins(th: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Return each sample's phase bin (one bin a sample of the period) and the bins' counts."""
    step = float(np.median(np.diff(th))) if th.size > 1 else 1.0
    per = max(int(round(2.0 * np.pi / max(step, 1e-12))), 1)
    k = np.minimum((np.mod(th, 2.0 * np.pi) / (2.0 * np.pi) * per).astype(int), per - 1)
    return k, np.maximum(np.bincount(k, minlength=per), 1)


def bin_mean(x: np.ndarray, bins: Tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Return the mean of ``x`` in each of its samples' ``phase_bins``."""
    k, count = bins
    return np.bincount(k, x, minlength=count.size) / count


def phase_mean(th: np.ndarray, x: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """
    Return the mean of ``x`` at each phase (one bin a sample of the period) and each bin.

    ``th`` are the phases of the samples of ``x``; the bin count is the period in samples.
    """
    bins = phase_bins(th)
    return bin_mean(x, bins), bins[0]


def locked_edges(f0: float, dt: float) -> np.ndarray:
    """Band edges (Hz) of the locked power beyond harmonic ``HIGH``, up to ``LOCKED_TOP``."""
    lo = (HIGH + 0.5) * f0
    return np.geomspace(lo, max(LOCKED_TOP / dt, 2.0 * lo), LOCKED_BANDS + 1)


def locked_bands(mean: np.ndarray, f0: float, dt: float) -> np.ndarray:
    """
    Return the locked waveform's mean-square rate per band of ``locked_edges`` ((rad/s)²).

    ``mean`` is the phase mean of the residual rate over one period; its harmonic k carries
    2 |X_k / n|² of mean square. What the noise leaves in the phase mean (its variance over
    the number of periods) is a floor that the twins share.
    """
    n = mean.size
    power = 2.0 * np.abs(np.fft.rfft(mean) / n) ** 2
    f = f0 * np.arange(power.size)
    edges = locked_edges(f0, dt)
    band = np.digitize(f, edges) - 1
    inside = (band >= 0) & (band < LOCKED_BANDS)
    return np.bincount(band[inside], power[inside], minlength=LOCKED_BANDS)


def band_psd(rate: np.ndarray, dt: float, edges: np.ndarray) -> np.ndarray:
    """Welch PSD of a residual rate, averaged in the bands ``edges`` ((lo, hi) rows, Hz)."""
    f, p = signal.welch(rate, fs=1.0 / dt, nperseg=min(2048, rate.size // 8))
    return np.array([np.mean(p[(f >= a) & (f < b)]) if np.any((f >= a) & (f < b))
                     else np.interp(0.5 * (a + b), f, p) for a, b in edges])


def split_rate(th: np.ndarray, r: np.ndarray, dt: float) -> Tuple[np.ndarray, np.ndarray]:
    """
    Return the residual rate less its phase mean, and that phase mean (one period).

    The rate is the residual's difference over ``dt``, at the mid phases of the samples.
    """
    rate = np.diff(r) / dt
    mean, k = phase_mean(0.5 * (th[1:] + th[:-1]), rate)
    return rate - mean[k], mean
