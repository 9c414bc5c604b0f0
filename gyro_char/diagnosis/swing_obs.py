"""
Observables of a swing record for the diagnosis, computed identically on record and twins.

The gyro angle (trapezoid integral of the rate at its stamps) minus the least-squares fit of
``(1 + Δρ) · encoder angle + offset + bias · t + drift · t² / 2`` (encoder interpolated at the
gyro stamps), decomposed on the swing phase θ = ωt + ψ of the encoder's own sine fit:

- ``quadrature``: the residual's cos θ component (rad). A stamp delay d leaves -A ω d cos θ;
  a g-sensitivity g_y leaves -g_y g A / ω cos θ - the same shape on one period and amplitude,
  hence the ambiguity the engine reports for that pair;
- no in-phase (sin θ) block: ``(1 + Δρ)`` absorbs anything in phase with the angle, so in one
  run it is unobservable; across runs it is the ``scale_factor_shift`` block
  (``diagnosis.swing``);
- ``harmonic_2f`` / ``harmonic_3f``: sin and cos of 2θ and 3θ (scale-factor asymmetry and the
  quadratic term give 2f, the cubic term 3f);
- ``harmonic_high``: sin and cos of kθ for k = 4..16; ``locked_power``: log10 of the mean
  square of the residual rate's phase mean in four bands beyond the 16th harmonic, up to
  2 % of the sample rate (``swing_locked``: what a waveform's harmonics say it depends on);
- ``residual_psd``: log10 Welch PSD of the residual's rate (its difference over dt) less its
  harmonics 1..16, in log bins from 1 Hz to 1/8 of the sample rate (stamp jitter, encoder
  interpolation error, smoothing: noise, not the waveform the harmonic blocks score).

The same fit, evaluated on the ENCODER stamps (gyro angle interpolated there), gives the
residual the encoder's own errors show in at full encoder rate (``encoder_residual``):

- ``encoder_lines``: its spectrum against the encoder ANGLE (``line_spectrum``), log10 of the
  largest amplitude (rad) in each log band of line counts (cycles per revolution) from 64 to
  16384. A sine-cosine interpolation error is periodic in the angle, 2π / L, whatever the
  rate: every pass over an angle adds coherently, while the gyro's and the encoder's noise
  do not. Bands reaching above the encoder's angle Nyquist π / (peak rate x encoder
  interval) (7100 lines at 1 kHz on a 0.44 rad/s swing) read 0 (log10 of 1: not measured).
  The peak's line count per band is kept unscored (``SwingObs.line_peaks``) for
  ``diagnosis.swing_spaces.signs``;
- ``rate_locked``: the (high-passed) residual's increment variance, its harmonics 1..16 out,
  in bins of |cos θ| (i.e. of the swing rate) minus that of the slowest bin, per unit of
  rate² (``rate_locked``). An encoder stamp error δ reads as an angle error rate · δ, a noise
  whose variance grows as the rate squared; the gyro's white noise, the quantizations and
  the encoder's white noise do not depend on the swing phase;
- ``rate_sign``: per |cos θ| bin (but the slowest), the increments' mean square where the
  rate is negative less where it is positive, over the bin's: zero for every noise that
  follows the rate's size alone (a stamp error, a scale-factor noise), not for one on one
  sign of the rate (one driver half noisier than the other);
- ``rate_acf``: per |cos θ| bin (but the slowest), the increments' lag-1 product less the
  slowest bin's, over the bin's mean square: about -1/2 of the rate's share for a stamp
  error (white in the angle), 0 for a rate noise (white in the rate);
- ``increment_acf``: normalised autocorrelation at lags 1..4 of the GYRO-stamp residual's
  increments (harmonics 1..16 out and high-passed like the encoder-stamp one). This is the
  residual's whiteness, not the swing filter's innovations (``swing.batch`` folds rows into
  a square-root information factor and never forms them); for the gyro stream the two
  differ by the fitted deterministic part only. Colouring of the gyro noise (a sensor FIR
  such as a fractional group delay, smoothing) shows here.

Whole-record components rather than per-window ones: a constant effect's z grows with the
record length instead of being spread over windows; the twins' repeats give the scatter.
"""
import functools
from typing import Optional, Tuple

from gyro_char.diagnosis.swing_locked import (
    band_psd, bin_mean, harmonic_basis, HIGH, high_harmonics, locked_bands, locked_edges,
    phase_bins, split_rate, wave)
from gyro_char.diagnosis.swing_residuals import (
    column_normal, Residuals, residuals, solve_columns)
import numpy as np

PSD_BINS = 10
# Line-count bands (cycles per revolution) of ``encoder_lines``.
LINE_EDGES = np.geomspace(64.0, 16384.0, 9)
# Angle bins of the line spectrum: Nyquist 1.25 x the top band edge.
ANGLE_BIN = np.pi / (1.25 * LINE_EDGES[-1])
# Residual high-pass (span of a centred moving mean, s) before the line spectrum, the rate
# bins and the whiteness: the gyro angle's random walk is slow in time and would leak into
# every line count at the turning points, where the angle stands still; an effect's swing
# harmonics would dominate the increments.
HP_SECONDS = 0.2
# |cos θ| bin edges of ``rate_locked`` (the first bin is the reference).
RATE_EDGES = (0.0, 0.3, 0.6, 0.85, 1.0001)
STAMP_UNIT = 1e-6  # s, scale of ``rate_locked``
ACF_LAGS = 4
TWO_PI = 2.0 * np.pi


class SwingObs(dict):
    """Observable blocks of one record, plus the unscored ``line_peaks`` (see module doc)."""

    line_peaks: np.ndarray = np.array([])


def layout(n_psd: int, dt: float, period_s: float) -> dict:
    """Per block, the (lo, hi) range of every element (units in ``UNITS``)."""
    f0 = 1.0 / period_s
    # Up to 1/8 of the sample rate: above it the residual is shaped by where the gyro stamps
    # fall between encoder samples (linear interpolation), which says nothing about the gyro.
    edges = np.geomspace(1.0, 0.125 / dt, PSD_BINS + 1)
    lags = np.arange(1, ACF_LAGS + 1) * dt
    high = np.repeat(np.arange(4, HIGH + 1) * f0, 2)
    locked = locked_edges(f0, dt)
    return {'quadrature': np.array([[f0, f0]]),
            'harmonic_2f': np.array([[2 * f0, 2 * f0]] * 2),
            'harmonic_3f': np.array([[3 * f0, 3 * f0]] * 2),
            'harmonic_high': np.c_[high, high],
            'locked_power': np.c_[locked[:-1], locked[1:]],
            'residual_psd': np.c_[edges[:-1], edges[1:]],
            'encoder_lines': np.c_[LINE_EDGES[:-1], LINE_EDGES[1:]],
            'rate_locked': np.c_[RATE_EDGES[1:-1], RATE_EDGES[2:]],
            'rate_sign': np.c_[RATE_EDGES[1:-1], RATE_EDGES[2:]],
            'rate_acf': np.c_[RATE_EDGES[1:-1], RATE_EDGES[2:]],
            'increment_acf': np.c_[lags, lags]}


UNITS = {'quadrature': 'Hz', 'harmonic_2f': 'Hz', 'harmonic_3f': 'Hz',
         'harmonic_high': 'Hz', 'locked_power': 'Hz', 'residual_psd': 'Hz',
         'encoder_lines': '1/rev', 'rate_locked': '|cos(phase)|', 'rate_sign': '|cos(phase)|',
         'rate_acf': '|cos(phase)|', 'increment_acf': 's'}


def highpass(x: np.ndarray, n: int) -> np.ndarray:
    """``x`` minus its centred moving mean over ``n`` samples (shorter at the ends)."""
    c = np.concatenate(([0.0], np.cumsum(x)))
    lo, hi, width = _window(x.size, n)
    return x - (c[hi] - c[lo]) / width


@functools.lru_cache(maxsize=8)
def _window(size: int, n: int) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    i = np.arange(size)
    lo, hi = np.maximum(i - n // 2, 0), np.minimum(i + n // 2 + 1, size)
    out = lo, hi, (hi - lo).astype(float)
    for a in out:
        a.flags.writeable = False     # shared by every caller of the cache
    return out


def line_spectrum(phi: np.ndarray, r: np.ndarray,
                  grid: Optional[tuple] = None) -> Tuple[np.ndarray, np.ndarray]:
    """
    Amplitude spectrum (rad) of ``r`` against the angle ``phi``: line counts, amplitudes.

    The Fourier integral over the angle, ∫ r(φ) e^(-i L φ) dφ along the whole record (every
    pass over an angle adds coherently), as a Riemann sum: each sample weighs the angle step
    it covers (so a slow passage, where the encoder dwells, weighs no more than a fast one),
    Hann-windowed over the angle span. The sum is gridded onto bins of ``ANGLE_BIN`` and
    Fourier-transformed with zero padding to twice the bin count (two bincounts and one FFT
    of a few thousand points). A term a sin(L φ + p) reads a at line count L, down to ~0.8 a
    at the top band edge (phase spread within a bin). Lines above π / (peak rate x sample
    interval), 7100 for a 1 kHz encoder on a 0.44 rad/s swing, alias where the swing is
    fastest: a line L also shows at about 2π / (peak rate x interval) - L (some 20 %).
    ``grid``: ``angle_grid(phi)``, when several ``r`` share the angles.
    """
    j, w, wsum, nfft, lines = angle_grid(phi) if grid is None else grid
    s = np.bincount(j, r * w, minlength=nfft // 2)
    amp = 2.0 * np.abs(np.fft.rfft(s, nfft)) / wsum
    return lines, amp


def angle_grid(phi: np.ndarray) -> tuple:
    """``line_spectrum``'s angle bins, weights, their sum, FFT size and line counts."""
    span = max(float(phi.max() - phi.min()), ANGLE_BIN)
    j = ((phi - phi.min()) / ANGLE_BIN).astype(np.intp)
    n = int(j.max()) + 1
    step = np.abs(np.gradient(phi))
    w = step * (1.0 - np.cos(TWO_PI * (phi - phi.min()) / span))
    nfft = 1 << int(np.ceil(np.log2(2 * n)))
    lines = TWO_PI * np.arange(nfft // 2 + 1) / (nfft * ANGLE_BIN)
    return j, w, max(float(w.sum()), 1e-300), nfft, lines


def band_peaks(lines: np.ndarray, amp: np.ndarray,
               edges: np.ndarray = LINE_EDGES) -> Tuple[np.ndarray, np.ndarray]:
    """Largest amplitude per band and its line count (parabolic interpolation on log amp)."""
    la = np.log(np.maximum(amp, 1e-300))
    dl = lines[1] - lines[0]
    peaks, where = np.zeros(edges.size - 1), np.zeros(edges.size - 1)
    for b, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        idx = np.flatnonzero((lines >= lo) & (lines < hi))
        k = int(idx[np.argmax(amp[idx])])
        off = 0.0
        if 0 < k < amp.size - 1:
            den = la[k - 1] - 2.0 * la[k] + la[k + 1]
            off = 0.5 * (la[k - 1] - la[k + 1]) / den if den < 0 else 0.0
        peaks[b], where[b] = amp[k], lines[k] + off * dl
    return peaks, where


def rate_bin_index(th: np.ndarray) -> dict:
    """``rate_bins``' geometry: each sample's |cos th| bin, the bins' counts, their cos² th."""
    nb = len(RATE_EDGES) - 1
    c = np.cos(th)
    k = np.clip(np.digitize(np.abs(c), RATE_EDGES) - 1, 0, nb - 1)
    cnt = np.maximum(np.bincount(k, minlength=nb), 1)
    sides = [(m, k[m], np.maximum(np.bincount(k[m], minlength=nb), 1)) for m in (c < 0, c >= 0)]
    return {'k': k, 'count': cnt, 'sides': sides,
            'cos2': np.bincount(k, c * c, minlength=nb) / cnt,
            'pairs': np.maximum(np.bincount(k[:-1], minlength=nb), 1)}


def rate_bins(index: dict, d: np.ndarray, peak_rate: float) -> Tuple[np.ndarray, ...]:
    """
    Return per |cos th| bin the increments' mean square, mean squared rate, split and lag 1.

    The split: the mean square of ``d`` where cos th < 0 less where cos th > 0 (``rate_sign``);
    lag 1: the mean of d_j d_(j+1) (``rate_acf``). ``index``: ``rate_bin_index`` of the
    increments' phases th.
    """
    nb, k = len(RATE_EDGES) - 1, index['k']
    d2 = d * d
    side = [np.bincount(km, d2[m], minlength=nb) / cm for m, km, cm in index['sides']]
    return (np.bincount(k, d2, minlength=nb) / index['count'],
            peak_rate * peak_rate * index['cos2'], side[0] - side[1],
            np.bincount(k[:-1], d[:-1] * d[1:], minlength=nb) / index['pairs'])


def rate_locked_of(ms: np.ndarray, w2: np.ndarray) -> np.ndarray:
    """
    Apparent stamp-error variance per |cos th| bin (asinh, µs²) from ``rate_bins``.

    Per bin k, the mean square of the increments minus that of the slowest bin, over twice
    the mean squared swing rate minus the slowest bin's: a white stamp error of σ reads σ² in
    every bin. A difference, not a ratio, so that white angle noise (which the baseline fit
    may have inflated with an encoder error it cannot model) cancels instead of diluting it;
    asinh(x / 1 µs²) keeps the sign and compresses like a log above 1 µs².
    """
    var = (ms[1:] - ms[0]) / np.maximum(2.0 * (w2[1:] - w2[0]), 1e-300)
    return np.arcsinh(var / STAMP_UNIT ** 2)


def rate_locked(th: np.ndarray, d: np.ndarray, peak_rate: float) -> np.ndarray:
    """Apparent stamp-error variance per |cos th| bin of the increments ``d`` (asinh, µs²)."""
    return rate_locked_of(*rate_bins(rate_bin_index(th), d, peak_rate)[:2])


def rate_sign_of(msd: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """
    ``rate_sign`` from ``rate_bins``: negative- less positive-rate mean square, over the bin's.

    A ratio, not ``rate_locked``'s asinh: the difference is zero-mean on most records, where
    the asinh of a spread far above 1 µs² splits into two lobes at +-log, and a shift of the
    mean shows only a few sds.
    """
    return msd[1:] / np.maximum(ms[1:], 1e-300)


def rate_acf_of(mp: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """
    ``rate_acf`` from ``rate_bins``: the lag-1 product less the slowest bin's, over the bin's ms.

    What the rate adds to the increments, and how it correlates at lag 1: a stamp error's
    angle error rate x error is white, its increments -1/2 correlated; a rate noise (a
    scale-factor noise, a noisier range) is white in the rate, its increments uncorrelated.
    The slowest bin's product takes out what does not follow the rate (the encoder's white
    noise, -1/2 correlated too).
    """
    return (mp[1:] - mp[0]) / np.maximum(ms[1:], 1e-300)


def increment_sums(r: np.ndarray, lags: int = ACF_LAGS) -> np.ndarray:
    """Per-sample lagged products of the centred increments of ``r`` at lags 0..``lags``."""
    d = np.diff(r)
    d = d - d.mean()
    # einsum, not np.dot: a threaded BLAS call costs more than the sum on a busy machine.
    return np.array([np.einsum('i,i->', d[:d.size - k], d[k:]) / max(d.size, 1)
                     for k in range(lags + 1)])


def increment_acf(r: np.ndarray, lags: int = ACF_LAGS) -> np.ndarray:
    """Normalised autocorrelation of the increments of ``r`` at lags 1..``lags``."""
    c = increment_sums(r, lags)
    return c[1:] / max(c[0], 1e-300)


def unlocked_psd(res: Residuals, ranges: dict) -> np.ndarray:
    """
    ``residual_psd`` of the residual rate less its mean at each phase of the swing.

    That mean (``swing_locked.split_rate``) is what the motion and any effect locked to it
    leave every period alike; the rest is the sensors' noise, less 1 / (number of periods) of
    its power, on record and twins alike. The baseline's N is pinned on it
    (``swing_calibrate.calibrate_n``): a sharp residual at every turning point (a dead band)
    spreads over all Welch bins and would otherwise be read as gyro noise.
    """
    return band_psd(split_rate(res.th, res.r, res.dt)[0], res.dt, ranges['residual_psd'])


def raw_parts(res: Residuals, ranges: dict, r: Optional[np.ndarray] = None,
              r_e: Optional[np.ndarray] = None) -> dict:
    """
    Return the additive parts of the observables of residual streams ``r`` and ``r_e``.

    The record's own streams by default, on the geometry of ``res``. Linear parts (``harm``:
    the harmonic coefficients) or quadratic ones (``psd`` power per bin, ``line2`` squared
    line peaks and ``mean2`` mean squared amplitude per band, ``ms`` rate-bin mean squares
    and ``msd`` their negative-less-positive-rate difference, ``mp`` lag-1 products,
    ``acf`` lagged sums), so that the parts of a sum of independent residuals add in
    expectation. ``finish`` turns them into the blocks.
    """
    r = res.r if r is None else r
    r_e = res.r_e if r_e is None else r_e
    th, ts = res.th, res.ts
    basis = res.geometry('harmonics', lambda: harmonic_basis(th))
    z1, z2 = basis[0], basis[0] * basis[0]
    z3 = z2 * z1
    cols = [z1.imag, z1.real, z2.imag, z2.real, z3.imag, z3.real, np.ones_like(ts), ts, ts * ts]
    h = solve_columns(cols, r, res.geometry('columns', lambda: column_normal(np.array(cols))))
    low = r - sum(c * col for c, col in zip(h, cols))
    high = high_harmonics(th, low, basis)
    # What the harmonic blocks score is not the noise blocks' (``swing_locked``): they see the
    # residuals less the harmonics 1..16, at each stream's own phases.
    r_u = low - wave(th, np.zeros(6), high, z1)
    r_eu = r_e - wave(res.th_e, h[:6], high, res.geometry('z1_e', lambda: np.exp(1j * res.th_e)))
    rate_u = np.diff(r_u) / res.dt
    psd = band_psd(rate_u, res.dt, ranges['residual_psd'])
    mid = res.geometry('phase_bins', lambda: phase_bins(0.5 * (th[1:] + th[:-1])))
    mean = bin_mean(rate_u, mid)
    f0 = ranges['quadrature'][0][0]
    # High-passed residuals (about 0.2 s): what an effect leaves at the swing's harmonics -
    # large, deterministic, and the harmonic blocks' business - must not pass for noise here.
    hp_e = highpass(r_e, int(round(HP_SECONDS / res.dt_e)))
    grid = res.geometry('angles', lambda: angle_grid(res.phi))
    lines, amp = line_spectrum(res.phi, hp_e, grid)
    peaks, where = band_peaks(lines, amp)
    band = np.clip(np.digitize(lines, LINE_EDGES) - 1, 0, LINE_EDGES.size - 2)
    inside = (lines >= LINE_EDGES[0]) & (lines < LINE_EDGES[-1])
    mean2 = (np.bincount(band[inside], amp[inside] ** 2, minlength=LINE_EDGES.size - 1)
             / np.maximum(np.bincount(band[inside], minlength=LINE_EDGES.size - 1), 1))
    # Bands reaching above the encoder's angle Nyquist at the peak swing rate hold aliases of
    # the gyro/encoder stamp pattern, which twins at rates differing by ppm do not share (z
    # of 3 on clean records): a constant, so that they score nothing.
    above = LINE_EDGES[1:] > np.pi / max(res.peak_rate * res.dt_e, 1e-300)
    hp_eu = highpass(r_eu, int(round(HP_SECONDS / res.dt_e)))
    ix = res.geometry('rate_bins', lambda: rate_bin_index(0.5 * (res.th_e[1:] + res.th_e[:-1])))
    ms, w2, msd, mp = rate_bins(ix, np.diff(hp_eu), res.peak_rate)
    acf = increment_sums(highpass(r_u, int(round(HP_SECONDS / res.dt))))
    # h[0] (sin θ) is sin 2θ and 3θ leaking through the trend columns: not a block (module doc).
    return {'harm': np.r_[h[1:6], high], 'psd': psd, 'locked': locked_bands(mean, f0, res.dt),
            'line2': peaks * peaks, 'mean2': mean2, 'where': where,
            'above': above, 'ms': ms, 'w2': w2, 'msd': msd, 'mp': mp, 'acf': acf}


def finish(raw: dict) -> 'SwingObs':
    """Return the observable blocks from ``raw_parts`` (or sums of them)."""
    lines = np.log10(np.sqrt(np.maximum(raw['line2'], 1e-300)))
    where = np.array(raw['where'], dtype=float)
    lines[raw['above']], where[raw['above']] = 0.0, np.nan
    c = raw['acf']
    out = SwingObs({'quadrature': raw['harm'][0:1], 'harmonic_2f': raw['harm'][1:3],
                    'harmonic_3f': raw['harm'][3:5], 'harmonic_high': raw['harm'][5:],
                    'locked_power': np.log10(np.maximum(raw['locked'], 1e-300)),
                    'residual_psd': np.log10(np.maximum(raw['psd'], 1e-300)),
                    'encoder_lines': lines,
                    'rate_locked': rate_locked_of(raw['ms'], raw['w2']),
                    'rate_sign': rate_sign_of(raw['msd'], raw['ms']),
                    'rate_acf': rate_acf_of(raw['mp'], raw['ms']),
                    'increment_acf': c[1:] / max(c[0], 1e-300)})
    out.line_peaks = where
    return out


def swing_observables(t_g: np.ndarray, rate: np.ndarray, t_e: np.ndarray, enc: np.ndarray,
                      period_s: float, ranges: dict) -> 'SwingObs':
    """All swing blocks of one record (gyro rate rad/s at ``t_g``, encoder rad at ``t_e``)."""
    return finish(raw_parts(residuals(t_g, rate, t_e, enc, period_s), ranges))
