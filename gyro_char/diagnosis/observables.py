"""
Observables the sim-to-real diagnosis compares, computed identically on real and twin records.

Each observable is a short vector ("block") with a coordinate per element, so that a gap can be
located on it (which τ, which frequency, which lag). All blocks are cheap (O(n) or one Welch
transform) because they are recomputed on every repeated simulation.

Static blocks of one rate channel ``x`` (rad/s) sampled every ``dt`` seconds:

- ``adev``: log10 of the overlapping Allan deviation on an octave τ grid (τ ≤ record / 8, where
  the estimator still has some tens of degrees of freedom);
- ``psd``: log10 of the Welch PSD averaged in log-spaced frequency bins (shape of the spectrum:
  smoothing filters, coloured noise);
- ``tone``: log10 prominence of the largest narrow peak over a running median of the PSD, in
  equal-width frequency bands (tone detection);
- ``acf``: autocorrelation at lags 1..8 samples (correlated neighbouring samples);
- ``drift``: mean of each early window minus the mean of the second half (warm-up transients,
  curvature), in rad/s. The windows are disjoint shells, [0, 1/64), [1/64, 1/32), ...
  [1/4, 1/2) of the record: nested windows (the first 1/64, 1/32, ...) correlated up to 0.7, so
  one chance excursion at the start moved all six together and the block's mean z^2 had a
  tail far heavier than a chi-square of six.

Every block is computed on the record minus its least-squares line: bias and linear drift are
part of the paper's model, so they never count as a gap.
"""
from dataclasses import dataclass
from typing import Dict, Tuple

from gyro_char.allan import kernel as allan
import numpy as np
from scipy import ndimage, signal

STATIC_BLOCKS = ('adev', 'psd', 'tone', 'acf', 'drift')
BLOCK_UNITS = {'adev': 's', 'psd': 'Hz', 'tone': 'Hz', 'acf': 'samples', 'drift': 's'}
ACF_LAGS = 8
PSD_BINS = 20
TONE_BANDS = 10
DRIFT_FRACTIONS = (1 / 64, 1 / 32, 1 / 16, 1 / 8, 1 / 4, 1 / 2)


def drift_windows(n: int):
    """(start, stop) of each early window of the ``drift`` block: disjoint shells to n / 2."""
    stops = [max(int(fr * n), 1) for fr in DRIFT_FRACTIONS]
    return list(zip([0] + stops[:-1], stops))


def drift_means(x: np.ndarray) -> np.ndarray:
    """Mean of each early window of ``x`` minus the mean of its second half."""
    half = x[x.size // 2:].mean()
    return np.array([x[a:b].mean() - half for a, b in drift_windows(x.size)])


@dataclass(frozen=True)
class Layout:
    """Coordinates of every element of every block, for one record length and sample time."""

    n: int
    dt: float
    coords: Dict[str, np.ndarray]
    # Per block, the (lo, hi) range each element covers, in BLOCK_UNITS.
    ranges: Dict[str, np.ndarray]


def welch_segment(n: int) -> int:
    """Welch segment length: fine enough to resolve tones, ≥ 16 segments for a stable PSD."""
    return int(min(2048, 2 ** int(np.floor(np.log2(max(n // 16, 64))))))


def octave_m(n: int) -> np.ndarray:
    """Cluster sizes 1, 2, 4, ... up to n / 8 samples."""
    top = max(int(np.floor(np.log2(n / 8))), 0)
    return 2 ** np.arange(top + 1)


def static_layout(n: int, dt: float) -> Layout:
    if n < 1024:
        raise ValueError(f'record too short for the diagnosis: {n} samples (need >= 1024)')
    m = octave_m(n)
    tau = m * dt
    fs = 1.0 / dt
    nps = welch_segment(n)
    f = np.fft.rfftfreq(nps, dt)
    edges = np.geomspace(2 * f[1], fs / 2, PSD_BINS + 1)
    band = np.linspace(0, fs / 2, TONE_BANDS + 1)
    lags = np.arange(1, ACF_LAGS + 1, dtype=float)
    win = np.asarray(drift_windows(n), dtype=float) * dt
    coords = {
        'adev': tau,
        'psd': np.sqrt(edges[:-1] * edges[1:]),
        'tone': 0.5 * (band[:-1] + band[1:]),
        'acf': lags,
        'drift': win[:, 1],
    }
    ranges = {
        'adev': np.c_[tau, tau],
        'psd': np.c_[edges[:-1], edges[1:]],
        'tone': np.c_[band[:-1], band[1:]],
        'acf': np.c_[lags, lags],
        'drift': win,
    }
    return Layout(n=n, dt=dt, coords=coords, ranges=ranges)


def overlapping_adev(x: np.ndarray, m: np.ndarray, dt: float = 1.0) -> np.ndarray:
    """Fully overlapping Allan deviation of rate samples for cluster sizes ``m`` (samples)."""
    _, avar, _ = allan.overlapping_avar(x, dt, m=m)
    return np.sqrt(avar)


def _dot(a: np.ndarray, b: np.ndarray) -> float:
    # einsum, not np.dot: a threaded BLAS call on a busy 2-core machine costs ~40x more.
    return float(np.einsum('i,i->', a, b))


def detrend(x: np.ndarray) -> np.ndarray:
    """Remove the least-squares line: bias and linear drift belong to the paper's baseline."""
    k = np.arange(x.size, dtype=np.float64)
    k -= k.mean()
    y = x - x.mean()
    return y - k * (_dot(k, y) / _dot(k, k))


def welch_psd(x: np.ndarray, dt: float) -> Tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD (Hann, 50 % overlap) of the mean-removed record."""
    return signal.welch(x - x.mean(), fs=1.0 / dt, nperseg=welch_segment(x.size))


def white_band(f: np.ndarray, dt: float) -> np.ndarray:
    """
    Mask of the frequencies ``f`` in 1-5 % of the sample rate: where white rate noise is read.

    Above the flicker / random-walk corner, below where an internal smoothing filter bites.
    """
    return (f >= 0.01 / dt) & (f <= 0.05 / dt)


def running_median(p: np.ndarray) -> np.ndarray:
    """Return the PSD's running median over ~1/10 of the band: the floor peaks stand on."""
    return ndimage.median_filter(p, size=max(31, (p.size // 10) | 1), mode='nearest')


def tone_prominence(f: np.ndarray, p: np.ndarray, base=None) -> np.ndarray:
    """log10(PSD / running median of the PSD) per frequency: narrow peaks stand out."""
    base = running_median(p) if base is None else base
    return np.log10(np.maximum(p, 1e-300) / np.maximum(base, 1e-300))


def autocorrelation(x: np.ndarray, lags: int = ACF_LAGS) -> np.ndarray:
    y = x - x.mean()
    v = _dot(y, y)
    if v <= 0:
        return np.zeros(lags)
    return np.array([_dot(y[:-k], y[k:]) / v for k in range(1, lags + 1)])


def static_observables(x: np.ndarray, layout: Layout) -> Dict[str, np.ndarray]:
    """All static blocks of one rate channel (rad/s) whose length matches ``layout``."""
    x = detrend(np.asarray(x, dtype=np.float64))
    if x.size != layout.n:
        raise ValueError(f'record has {x.size} samples, layout expects {layout.n}')
    m = octave_m(layout.n)
    f, p = welch_psd(x, layout.dt)
    edges = layout.ranges['psd']
    psd = np.empty(len(edges))
    for i, (lo, hi) in enumerate(edges):
        sel = (f >= lo) & (f < hi) if i < len(edges) - 1 else (f >= lo) & (f <= hi)
        psd[i] = np.mean(p[sel]) if sel.any() else np.interp(0.5 * (lo + hi), f, p)
    prom = tone_prominence(f, p)
    tone = np.empty(len(layout.ranges['tone']))
    for i, (lo, hi) in enumerate(layout.ranges['tone']):
        sel = (f > max(lo, f[1])) & (f <= hi)
        tone[i] = prom[sel].max() if sel.any() else 0.0
    drift = drift_means(x)
    return {
        'adev': np.log10(np.maximum(overlapping_adev(x, m, layout.dt), 1e-300)),
        'psd': np.log10(np.maximum(psd, 1e-300)),
        'tone': tone,
        'acf': autocorrelation(x),
        'drift': drift,
    }


def detected_tones(x: np.ndarray, dt: float, *, min_prominence: float = 0.5,
                   max_tones: int = 3, psd=None) -> np.ndarray:
    """
    Frequencies (Hz) of the strongest narrow peaks, 3x above the running median or more.

    ``psd``: the record's ``welch_psd``, if the caller has it already.
    """
    f, p = welch_psd(np.asarray(x, dtype=np.float64), dt) if psd is None else psd
    prom = tone_prominence(f, p)
    prom[:2] = 0.0
    order = np.argsort(prom)[::-1]
    found = []
    for i in order:
        if prom[i] < min_prominence or len(found) >= max_tones:
            break
        if all(abs(f[i] - g) > 3 * f[1] for g in found):
            found.append(f[i])
    return np.asarray(found, dtype=float)


COMB_MIN_LINES = 3      # lines on one lattice before a comb is searched
COMB_MAX_LINES = 64
COMB_Z = 6.0            # a line stands this many robust sds of the bins' own scatter out
BUMP_RISE = 0.2         # a broad bump rises this much (natural log) on both sides
BUMP_MIN_BIN = 20       # the lowest Welch bin a broad bump is looked for in


def narrow_lines(x: np.ndarray, dt: float, *, z: float = COMB_Z, psd=None):
    """
    Return the record's narrow lines, strongest first: frequencies (Hz), amplitudes (rad/s).

    A line is a local maximum of the Welch PSD that stands ``z`` robust sds of the bins' own
    log scatter above the running median and above the PSD three bins to either side (beyond
    a Hann line's main lobe: a smooth band is not a line). Averaged Welch bins scatter by a
    few per cent, so many weak lines (kicks spread over a hundred harmonics) count, not only
    prominent ones. Frequencies are interpolated within the bin (a parabola through the log
    PSD at the peak and its neighbours); at most ``COMB_MAX_LINES``. A line's power is its
    excess over the running median summed over its main lobe (three bins either side) times
    the bin width, its amplitude sqrt(2 power): a starting point for a search of several
    tones at once, whose gap valley (their total power fixed) a one-at-a-time search from one
    tone would crawl along. ``psd``: the record's ``welch_psd``, if the caller has it already.
    """
    f, p = welch_psd(np.asarray(x, dtype=np.float64), dt) if psd is None else psd
    if p.size < 16:
        return np.zeros(0), np.zeros(0)
    base = running_median(p)
    prom = tone_prominence(f, p, base)
    q = np.pad(p, 3, mode='edge')
    narrow = np.log10(np.maximum(p, 1e-300) / np.maximum(np.maximum(q[:-6], q[6:]), 1e-300))
    scatter = 1.4826 * float(np.median(np.abs(prom[3:] - np.median(prom[3:]))))
    peak = (prom >= z * scatter) & (narrow >= z * scatter)
    peak[:3] = False
    peak[1:-1] &= (p[1:-1] >= p[:-2]) & (p[1:-1] >= p[2:])
    idx = np.flatnonzero(peak)
    idx = idx[np.argsort(prom[idx])[::-1][:COMB_MAX_LINES]]
    i = np.clip(idx, 1, p.size - 2)
    freqs = f[i] + peak_shift(p, i) * f[1]
    excess = np.maximum(p - base, 0.0)
    power = [excess[max(k - 3, 0):k + 4].sum() * f[1] for k in np.round(freqs / f[1]).astype(int)]
    return freqs, np.sqrt(2.0 * np.asarray(power, dtype=float))


def peak_shift(p: np.ndarray, i: np.ndarray) -> np.ndarray:
    """
    Offset (bins, within +-1/2) of the peaks at interior bins ``i`` of the PSD ``p``.

    The vertex of the parabola through the log PSD at each peak and its two neighbours (0
    where the three do not bend down).
    """
    lp = np.log(np.maximum(p, 1e-300))
    den = lp[i - 1] - 2.0 * lp[i] + lp[i + 1]
    shift = np.where(den < 0, 0.5 * (lp[i - 1] - lp[i + 1]) / np.where(den < 0, den, -1.0), 0.0)
    return np.clip(shift, -0.5, 0.5)


def broad_peak(psd, *, rise: float = BUMP_RISE):
    """
    Return the frequency (Hz) of the PSD's highest broad bump, or None.

    A bump is a local maximum of the log PSD averaged over +-10 % in frequency.
    It must rise by ``rise`` (natural log) above that average's minimum within an octave on
    each side, so a spectrum that only falls or only rises has none. A narrow line averages
    into a small bump. Only bins from BUMP_MIN_BIN up count: below, the +-10 % average holds
    too few bins to be steady.
    """
    f, p = psd
    if p.size < 4 * BUMP_MIN_BIN:
        return None
    lp = np.log(np.maximum(p, 1e-300))
    k = np.arange(p.size)
    cs = np.r_[0.0, np.cumsum(lp)]
    lo = np.maximum(np.floor(0.9 * k).astype(int), 1)
    hi = np.minimum(np.ceil(1.1 * k).astype(int) + 1, p.size)
    sm = (cs[hi] - cs[np.minimum(lo, hi - 1)]) / np.maximum(hi - lo, 1)
    best, best_f = None, None
    for i in range(BUMP_MIN_BIN, p.size - 1):
        below, above = sm[i // 2:i + 1], sm[i:min(2 * i, p.size - 1) + 1]
        if sm[i] < below.max() or sm[i] < above.max():
            continue
        if min(sm[i] - below.min(), sm[i] - above.min()) >= rise and (
                best is None or sm[i] > best):
            best, best_f = sm[i], float(f[i])
    return best_f


def comb_of(lines: np.ndarray, df: float):
    """
    Return (centre, spacing) in Hz of a comb among ``lines`` (strongest first), or None.

    The centre is the strongest line; the spacing is the largest one that puts at least
    ``COMB_MIN_LINES`` lines (centre included) on the lattice centre + k spacing within a bin
    ``df``, refined by least squares over those lines.
    """
    if lines.size < COMB_MIN_LINES:
        return None
    centre, best = lines[0], None
    for d in sorted({abs(a - b) for a in lines for b in lines if abs(a - b) > 3 * df},
                    reverse=True):
        k = np.round((lines - centre) / d)
        on = np.abs(lines - centre - k * d) <= df
        if on.sum() >= COMB_MIN_LINES and (best is None or on.sum() > best[0]):
            best = (int(on.sum()), d, k[on], lines[on])
    if best is None:
        return None
    _, d, k, fk = best
    a = np.vstack([np.ones_like(k), k]).T
    c0, d = np.linalg.lstsq(a, fk, rcond=None)[0]
    return float(c0), float(d)
