"""
The deterministic mean term (warm-ups, a thermal cycle) seen through the static observables.

A mean term adds to each quadratic form (Allan variance, Welch PSD, lag products) its own
value on the detrended term, and to each linear form (early-minus-late means) likewise; the
closed-form expectation (``gyro_char.diagnosis.expected``) adds these to the noise's. The
forms are evaluated without per-sample loops: a warm-up and a cycle (periods of twice a Welch
segment or more) are smooth on the scale of a Welch segment and of the short clusters.
"""
from dataclasses import dataclass

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.spectra import ModelSpectrum
from gyro_char.sim.effects.base import cycle_envelope
import numpy as np
from scipy import signal


@dataclass
class Deterministic:
    """Observables' quadratic and linear forms evaluated on the (detrended) mean term."""

    avar: np.ndarray
    welch: np.ndarray
    acov: np.ndarray   # r(0..lags) / n sums
    drift: np.ndarray


def has_mean_term(spec: ModelSpectrum) -> bool:
    """Return True where the model has a deterministic mean term (a warm-up or a cycle)."""
    return bool(spec.warmups or spec.cycles)


def mean_term(spec: ModelSpectrum, n: int) -> np.ndarray:
    """Return the mean term at the ``n`` output sample instants (zeros without one)."""
    t = np.arange(n) * spec.dt
    out = np.zeros(n)
    for amp, tau, t0 in spec.warmups:
        out += warmup_at(spec, t, amp, tau, t0)
    if spec.cycles:
        out += cycle_at(spec, t)
    return out


def cycle_at(spec: ModelSpectrum, t: np.ndarray) -> np.ndarray:
    """Return the cycle's sinusoids at output times ``t``, times its envelope."""
    u = np.asarray(t, dtype=np.float64) + spec.time_shift
    out = sum(amp * np.sin(2.0 * np.pi * u / period + phase)
              for amp, period, phase in spec.cycles)
    return out * cycle_envelope(u, *spec.cycle_onset)


def warmup_at(spec: ModelSpectrum, t: np.ndarray, amp: float, tau: float,
              t0: float = 0.0) -> np.ndarray:
    """One warm-up term at output times ``t`` (decimation phase and filter delay included)."""
    since = np.asarray(t) + spec.time_shift
    if t0 > 0.0:
        since = np.maximum(since - t0, 0.0)
    return amp * np.exp(-since / tau)


def deterministic(spec: ModelSpectrum, g, lags: int) -> Deterministic:
    """
    Evaluate the observables' forms on the detrended warm-up (a smooth mean term), fast.

    Allan variance from 64-sample block means (exact for clusters of whole blocks up to the
    block-start sampling; below, the smooth signal's (m / 64)^2 law); Welch from the exact
    per-segment decomposition a_s exp(-j dt / tau) + line (one FFT per term); the lag
    products from the signal's variance and its increments' (a smooth signal's D(k) = k^2
    D(1)).
    """
    m = g.m
    n_blocks = len(obs.DRIFT_FRACTIONS)
    if not has_mean_term(spec):
        return Deterministic(np.zeros(m.size), np.zeros(g.nps // 2 + 1), np.zeros(lags + 1),
                             np.zeros(n_blocks))
    raw = mean_term(spec, g.n)
    d = obs.detrend(raw)
    line = raw - d
    slope = (line[-1] - line[0]) / (g.n - 1)          # per sample
    blk = 64 if g.n >= 64 * 64 else 1
    nb = g.n // blk
    bm = d[:nb * blk].reshape(nb, blk).mean(axis=1)
    c = np.r_[0.0, np.cumsum(bm)]
    av = np.zeros(m.size)
    for i, mm in enumerate(m):
        if mm < blk:
            continue
        k = mm // blk
        if 2 * k > nb:
            continue
        means = (c[k:] - c[:-k]) / k
        diff = means[k:] - means[:-k]
        av[i] = 0.5 * float(np.mean(diff * diff))
    ref = np.flatnonzero(m == blk)
    if blk > 1 and ref.size:
        small = m < blk
        av[small] = av[ref[0]] * (m[small] / blk) ** 2
    p = _det_welch(spec, g, slope)
    d1 = float(np.mean(np.diff(d) ** 2))
    r0 = float(np.dot(d, d)) / g.n
    acov = r0 - 0.5 * d1 * np.arange(lags + 1) ** 2
    drift = obs.drift_means(d)
    return Deterministic(av, p, acov, drift)


def _det_welch(spec: ModelSpectrum, g, slope: float) -> np.ndarray:
    """
    Welch PSD of the detrended mean term: per segment s, sum_i a_is e_i(j) - slope j.

    Each e_i is a warm-up's exponential or a cycle's cosine or sine.

    A transient that starts mid-record (t0 > 0) is constant before t0, which each segment's
    mean removes, and exponential after it; the one or two segments it starts in are terms
    of their own, with the transient's own values.
    """
    L = g.nps
    step = L // 2
    nseg = (g.n - L) // step + 1
    w = signal.get_window('hann', L)
    j = np.arange(L, dtype=np.float64)
    t0 = np.arange(nseg) * step * g.dt
    coef, shapes = [], []
    for amp, tau, start in spec.warmups:
        a = warmup_at(spec, t0, amp, tau, start)
        if start > 0.0:
            first = t0 + spec.time_shift
            before = first + (L - 1) * g.dt <= start
            inside = ~before & (first < start)
            a = np.where(before | inside, 0.0, a)
            for s in np.flatnonzero(inside):
                coef.append(np.where(np.arange(nseg) == s, 1.0, 0.0))
                shapes.append(warmup_at(spec, t0[s] + j * g.dt, amp, tau, start))
        coef.append(a)
        shapes.append(np.exp(-j * g.dt / tau))
    if spec.cycles:
        # A cycle's envelope is 1 over most segments, 0 over those before its start; the few
        # it rises in are terms of their own, with the cycle's own values.
        start = cycle_envelope(t0 + spec.time_shift, *spec.cycle_onset)
        end = cycle_envelope(t0 + (L - 1) * g.dt + spec.time_shift, *spec.cycle_onset)
        on = (start >= 1.0).astype(np.float64)
        for amp, period, phase in spec.cycles:
            # sin(w (t_s + j dt) + phase) = sin(theta_s) cos(w j dt) + cos(theta_s) sin(w j dt)
            w_rad = 2.0 * np.pi / period
            theta = w_rad * (t0 + spec.time_shift) + phase
            coef += [on * amp * np.sin(theta), on * amp * np.cos(theta)]
            shapes += [np.cos(w_rad * j * g.dt), np.sin(w_rad * j * g.dt)]
        for k in np.flatnonzero((start < 1.0) & (end > 0.0)):
            coef.append(np.where(np.arange(nseg) == k, 1.0, 0.0))
            shapes.append(cycle_at(spec, t0[k] + j * g.dt))
    coef.append(np.full(nseg, -slope))
    shapes.append(j)
    spectra_ = []
    for e in shapes:
        spectra_.append(np.fft.rfft(w * (e - e.mean())))
    a = np.array(coef)                      # terms x segments
    x = np.array(spectra_)                  # terms x bins
    gram = a @ a.T / nseg
    p = np.real(np.einsum('ij,ik,jk->k', gram, x, np.conj(x)))
    scale = np.full(p.size, 2.0)
    scale[0] = 1.0
    if L % 2 == 0:
        scale[-1] = 1.0
    return p * scale * g.dt / np.dot(w, w)
