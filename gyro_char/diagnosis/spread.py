"""
Sampling spread of the static observables of a twin, in closed form (the gap's yardstick).

- ``adev`` (log10): chi-square with nu equivalent degrees of freedom: sd = sqrt(psi'(nu/2)) /
  (2 ln 10). nu combines Greenhall's EDF of each noise component (its power-law type read off
  the local slope of its own Allan variance) by Satterthwaite: nu = (sum a_i)^2 / sum a_i^2/nu_i.
  Lines and the deterministic mean term add no spread.
- ``psd`` (log10 of a bin mean): each Welch bin is chi-square with 2 k_eff degrees of freedom;
  neighbouring Hann bins correlate by 4/9 and 1/36; a line adds its cross term with the noise.
- ``tone``: spread of the chi-square draws (``expected_tone.tone_block``).
- ``acf``: the delta method over the periodogram's bins (``expected.acf_moments``).
- ``drift``: the exact variance of each linear form (record minus its line, early minus late
  mean), as the integral of the PSD against the form's |C(f)|^2.
"""
from functools import lru_cache
from typing import Dict

from gyro_char.allan.edf import edf_oadev
from gyro_char.diagnosis import expected as ex, expected_tone
from gyro_char.diagnosis import observables as obs
import numpy as np
from scipy import special

LN10 = np.log(10.0)
BIN_RHO = (1.0, 4.0 / 9.0, 1.0 / 36.0)


@lru_cache(maxsize=4096)
def _edf(alpha: int, m: int, n: int) -> float:
    return edf_oadev(alpha, m, n + 1)


def adev_edf(spec, g) -> np.ndarray:
    """Satterthwaite EDF of the overlapping Allan variance at each cluster size."""
    parts = [ex.avar(spec, g, parts=())]
    for i in range(len(spec.internal)):
        parts.append(np.maximum(ex.avar(spec, g, parts=(i,)) - parts[0], 0.0))
    lm = np.log(g.m)
    num = np.zeros(g.m.size)
    den = np.zeros(g.m.size)
    for a in parts:
        if not np.any(a > 0):
            continue
        slope = np.gradient(np.log(np.maximum(a, 1e-300)), lm) if g.m.size > 1 else np.zeros(1)
        alpha = np.clip(np.round(-slope - 1.0), -2, 2).astype(int)
        nu = np.array([_edf(int(al), int(mm), g.n) for al, mm in zip(alpha, g.m)])
        num += a
        den += a * a / nu
    return np.where(den > 0, num * num / np.maximum(den, 1e-300), 1e6)


def log_adev_moments(nu: np.ndarray):
    """(bias, sd) of log10 adev against log10 sqrt(E[AVAR]) for a chi-square with nu dof."""
    h = 0.5 * nu
    bias = 0.5 * (special.digamma(h) - np.log(h)) / LN10
    sd = 0.5 * np.sqrt(special.polygamma(1, h)) / LN10
    return bias, sd


@lru_cache(maxsize=4)
def drift_forms(n: int):
    """|C|^2 of each early-minus-late form of the detrended record, binned in log frequency."""
    k = np.arange(n, dtype=np.float64)
    kc = k - k.mean()
    edges = np.unique(np.round(np.geomspace(1, n // 2 + 1, 400)).astype(int))
    out = []
    for a, b in obs.drift_windows(n):
        c = np.zeros(n)
        c[a:b] += 1.0 / (b - a)
        c[n // 2:] -= 1.0 / (n - n // 2)
        c -= c.mean()
        c -= kc * (kc @ c) / (kc @ kc)
        p = np.abs(np.fft.rfft(c)) ** 2
        sums = np.add.reduceat(p, edges[:-1])
        out.append(sums)
    nu = np.sqrt(edges[:-1] * np.maximum(edges[1:] - 1, edges[:-1])) / n
    return nu, np.array(out)


def drift_sd(spec, g) -> np.ndarray:
    nu, sums = drift_forms(g.n)
    s = spec.one_sided(nu / g.dt) / g.dt     # one-sided per cycle/sample
    var = sums @ s / g.n
    return np.sqrt(np.maximum(var, 0.0))


def spreads(spec, layout, det=None) -> Dict[str, np.ndarray]:
    """Return the standard deviation of every static block of a twin described by ``spec``."""
    g = ex.grids(layout.n, layout.dt)
    if det is None:
        det = ex.deterministic(spec, g, obs.ACF_LAGS)
    _, sd_adev = log_adev_moments(adev_edf(spec, g))
    noise, lines = ex.welch_expected(spec, g)
    noise = noise + det.welch
    total = noise + lines
    var = (noise * noise + 2.0 * lines * noise) / g.k_eff
    sd = np.sqrt(var)
    psd = []
    for b, (lo, hi) in zip(ex.psd_bins(layout, g), layout.ranges['psd']):
        if b.size == 0:
            k = int(np.clip(np.round(0.5 * (lo + hi) * g.nps * g.dt), 0, total.size - 1))
            b = np.array([k])
        v = 0.0
        for lag, rho in enumerate(BIN_RHO):
            if lag >= b.size:
                break
            prod = sd[b[lag:]] * sd[b[:b.size - lag]]
            v += (1.0 if lag == 0 else 2.0) * rho * float(prod.sum())
        psd.append(np.sqrt(v) / b.size / (total[b].mean() * LN10))
    tone = expected_tone.tone_block(noise, lines, g, layout).std(axis=0, ddof=1)
    return {'adev': sd_adev, 'psd': np.array(psd), 'tone': tone,
            'acf': ex.acf_moments(spec, g, obs.ACF_LAGS, det)[1], 'drift': drift_sd(spec, g)}
