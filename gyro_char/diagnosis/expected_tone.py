"""
The ``tone`` block's expectation and spread, from chi-square draws of the Welch bins.

A running-median prominence is not linear in the spectrum, so it is sampled from common draws
(the same for every model: two models' tone blocks then differ only by their spectra).
"""
from functools import lru_cache

import numpy as np
from scipy import ndimage, special

TONE_DRAWS = 48       # chi-square draws of the Welch bins for the tone block


def tone_block(noise: np.ndarray, lines: np.ndarray, g, layout) -> np.ndarray:
    """
    Tone prominence per band for ``TONE_DRAWS`` chi-square draws of the Welch bins.

    ``noise``, ``lines``: the expected Welch spectrum's noise and line parts; ``g``: the
    Welch grid (``expected.Grids``).

    The running median (~1/10 of the band wide) of a draw is that of the expected spectrum
    times the median of the bins' chi-square law (its own spread over ~100 bins is a few
    per cent of a bin's); the draws then only need the bins themselves.
    """
    z, ratio, med = tone_draws(g.nps // 2 + 1, round(g.k_eff, 1))
    # Noise bins: scaled chi-square (2 k_eff degrees of freedom); a line's bins: its power
    # plus the noise, with the line-noise cross term's spread.
    p = noise * ratio + lines + np.sqrt(2.0 * lines * noise / g.k_eff) * z
    p = np.maximum(p, 1e-300)
    size = max(31, (p.shape[1] // 10) | 1)
    base = np.broadcast_to(ndimage.median_filter(noise + lines, size=size, mode='nearest')
                           * med, p.shape).copy()
    # Within half a window of either end the 'nearest' padding repeats one noisy bin: there
    # the draws' own running median is taken.
    half = size // 2
    if p.shape[1] > 4 * size:
        rows = p.shape[0]
        both = _edge_median(np.concatenate([p[:, :size], p[:, ::-1][:, :size]]), half)
        base[:, :half] = both[:rows]
        base[:, -half:] = both[rows:, ::-1]
    prom = np.log10(p / np.maximum(base, 1e-300))
    f = np.arange(p.shape[1]) / (g.nps * g.dt)
    out = np.empty((p.shape[0], len(layout.ranges['tone'])))
    for i, (lo, hi) in enumerate(layout.ranges['tone']):
        sel = (f > max(lo, f[1])) & (f <= hi)
        out[:, i] = prom[:, sel].max(axis=1) if sel.any() else 0.0
    return out


def _edge_median(p: np.ndarray, half: int) -> np.ndarray:
    """Return the running median of the first ``half`` columns, the first one padded."""
    # Every row padded, end to end through one 1-D running median (scipy's is a running one,
    # ~50x a 2-D window's sort); each kept window lies within its own row.
    size = 2 * half + 1
    padded = np.concatenate([np.repeat(p[:, :1], half, axis=1), p[:, :size]], axis=1)
    run = ndimage.median_filter(padded.ravel(), size=size, mode='nearest')
    return run.reshape(padded.shape)[:, half:2 * half]


@lru_cache(maxsize=4)
def tone_draws(bins: int, k_eff: float):
    """
    Return common draws of the Welch bins (fixed seed, the same for every model).

    Normals with the correlation of neighbouring Hann bins (4/9, 1/36), the same mapped to
    chi-square / dof with 2 k_eff degrees of freedom, and that law's median.
    """
    rng = np.random.default_rng(20240613)
    ma = _bin_ma()
    e = rng.standard_normal((TONE_DRAWS, bins + 2))
    z = ma[0] * e[:, 2:] + ma[1] * e[:, 1:-1] + ma[2] * e[:, :-2]
    ratio = special.gammaincinv(k_eff, special.ndtr(z)) / k_eff
    return z, ratio, float(special.gammaincinv(k_eff, 0.5) / k_eff)


@lru_cache(maxsize=1)
def _bin_ma() -> np.ndarray:
    from scipy import optimize
    target = np.array([1.0, 4.0 / 9.0, 1.0 / 36.0])

    def res(b):
        return [b @ b - 1.0, b[0] * b[1] + b[1] * b[2] - target[1], b[0] * b[2] - target[2]]
    return optimize.fsolve(res, [0.8, 0.5, 0.05])
