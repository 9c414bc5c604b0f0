"""
Expected static observables of a twin, in closed form from its spectrum (no simulation).

Every block of ``gyro_char.diagnosis.observables`` is (a function of) a quadratic or linear
form of the record, so its expectation is a linear functional of the model's PSD S(f)
(``gyro_char.diagnosis.spectra``), plus the same form evaluated on the deterministic part:

- Allan variance at tau = m dt (sampled data, aliasing included in S):
  sigma^2(m) = int_0^(fs/2) S(f) 2 sin^4(pi f m dt) / (m^2 sin^2(pi f dt)) df
  (the continuous kernel sin^4(pi f tau)/(pi f tau)^2 with the discrete cluster average);
  beyond 32 periods of sin^4 the kernel is replaced by its mean (3/8 of its envelope);
- Welch PSD (Hann, 50 % overlap): S convolved with the window's |W(f)|^2, on a grid 8 times
  finer than the segment's bins (the bins used are >= 2, where the segment-mean removal has
  no effect); lines add |W(f - f0)|^2 exactly;
- autocorrelation at small lags of the detrended record: 1 - D(k) / 2 r(0), with the
  variogram D(k) = 2 int S (1 - cos 2 pi f k dt) df and E r(0) = int S (1 - G(f T)) df,
  G = the share of a sinusoid's power the record's least-squares line removes (this keeps
  random walks and flicker finite); the ratio's mean and spread by the delta method over the
  periodogram's bins (``acf_moments``: a slow process makes r(0) itself scatter);
- early-minus-late means (``drift``): linear, so the expectation is the deterministic part's.

Spreads (``spread``): chi-square with the Welch and Allan equivalent degrees of freedom
(Greenhall's EDF per component, combined by Satterthwaite), the delta method for the
autocorrelation (``acf_moments``), the exact variance of the linear ``drift`` forms; the
``tone`` block (a running-median prominence, not linear) is sampled from the Welch bins'
chi-square law (``expected_tone``).
"""
from dataclasses import dataclass
from functools import lru_cache
from typing import Dict

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.deterministic import Deterministic, deterministic
from gyro_char.diagnosis.expected_tone import tone_block
from gyro_char.diagnosis.spectra import ModelSpectrum
import numpy as np
from scipy import signal

LN10 = np.log(10.0)
PERIODS = 32          # sin^4 periods integrated exactly before the kernel is averaged
FINE = 8              # Welch grid refinement
OVERLAP_RHO2 = None   # set by _welch_consts


@dataclass(frozen=True)
class Grids:
    """Frequency grids and fixed kernels for one record length and sample time."""

    n: int
    dt: float
    m: np.ndarray
    nu_log: np.ndarray            # global log grid in cycles/sample, (0, 1/2]
    exact_nu: np.ndarray          # the exact regions' grids, one per m, end to end
    exact_wk: np.ndarray          # their Allan kernels times trapezoid weights
    exact_starts: np.ndarray      # where each m's region starts in those
    welch_nu: np.ndarray          # fine Welch grid, cycles/sample, [0, 1)
    welch_w2_hat: np.ndarray      # rfft of |W|^2 on that grid (periodic)
    nps: int
    k_eff: float                  # equivalent number of independent Welch segments
    g_detrend: np.ndarray         # 1 - G(f T) on nu_log
    low_bins: np.ndarray          # |C_k|^2 on the Welch grid for bins 0, 1 (mean removed)


def _detrend_keep(x: np.ndarray) -> np.ndarray:
    """1 - G(x): share of a sinusoid of x cycles per record left after the LS line."""
    a = 2.0 * np.pi * np.asarray(x, dtype=np.float64)
    out = np.empty_like(a)
    small = a < 0.5
    # Series for small a (G = 1 - a^4 / 720 + ...), exact elsewhere.
    s = a[small]
    out[small] = s ** 4 / 720.0 - s ** 6 / 33600.0
    b = a[~small]
    e = np.exp(1j * b)
    i0 = (e - 1.0) / (1j * b)
    i1 = e / (1j * b) + (e - 1.0) / b ** 2 - 0.5 * i0
    out[~small] = 1.0 - (np.abs(i0) ** 2 + 12.0 * np.abs(i1) ** 2)
    return np.clip(out, 0.0, 1.0)


@lru_cache(maxsize=8)
def grids(n: int, dt: float) -> Grids:
    m = obs.octave_m(n)
    lo = 0.01 / n
    nu_log = np.geomspace(lo, 0.5, 6000)
    exact = []
    for mm in m:
        top = min(0.5, PERIODS / mm)
        step = 1.0 / 128
        u = np.r_[np.geomspace(1e-4, step, 60)[:-1], np.arange(step, top * mm, step), top * mm]
        exact.append(u / mm)
    nps = obs.welch_segment(n)
    size = FINE * nps
    w = signal.get_window('hann', nps)
    w2 = np.abs(np.fft.fft(w, size)) ** 2
    segs = (n - nps) // (nps // 2) + 1
    rho = float(np.dot(w[:nps // 2], w[nps // 2:]) / np.dot(w, w))
    k_eff = segs / (1.0 + 2.0 * rho * rho * (segs - 1) / segs)
    keep = _detrend_keep(nu_log * n)
    nu_w = np.arange(size) / size
    low = []
    for k in (0, 1):
        d = _dirichlet(nu_w, nps)
        c = _hann_w(nu_w - k / nps, nps) - _hann_w(np.array([-k / nps]), nps)[0] * d / nps
        low.append(np.abs(c) ** 2)
    return Grids(low_bins=np.array(low), n=n, dt=dt, m=m, nu_log=nu_log,
                 exact_nu=np.concatenate(exact),
                 exact_wk=np.concatenate([_kernel_weights(x, k) for x, k in zip(exact, m)]),
                 exact_starts=np.cumsum([0] + [x.size for x in exact[:-1]]),
                 welch_nu=np.arange(size) / size, welch_w2_hat=np.fft.rfft(w2), nps=nps,
                 k_eff=k_eff,
                 g_detrend=keep)


def _trapz(y, x):
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def _trapz_weights(nu: np.ndarray, starts=(0,)) -> np.ndarray:
    """Trapezoid weights on ``nu``: several grids end to end (at ``starts``), each its own."""
    d = 0.5 * np.diff(nu)
    d[np.asarray(starts[1:], dtype=int) - 1] = 0.0       # no interval across two grids
    return np.r_[d, 0.0] + np.r_[0.0, d]


def _kernel_weights(nu: np.ndarray, mm, starts=(0,)) -> np.ndarray:
    """
    Return the Allan kernel 2 sin^4(pi nu m) / (m^2 sin^2(pi nu)) times trapezoid weights.

    ``nu`` may hold several grids end to end (beginning at ``starts``), ``mm`` then one
    cluster size per point; each grid's weights are its own.
    """
    s = np.sin(np.pi * nu)
    q = np.sin(np.pi * nu * mm)
    q *= q
    return 2.0 * q * q / (mm * mm * s * s) * _trapz_weights(nu, starts)


def _exact_region(spec: ModelSpectrum, g: Grids):
    """(grid, kernel weights, starts) of every m's exact region, refined across the peaks."""
    if not spec.peaks:
        return g.exact_nu, g.exact_wk, g.exact_starts
    nus = []
    for x in np.split(g.exact_nu, g.exact_starts[1:]):
        r = spec.refine(x)
        nus.append(r[(r >= x[0]) & (r <= x[-1])])     # a peak outside adds nothing here
    sizes = [x.size for x in nus]
    starts = np.cumsum([0] + sizes[:-1])
    nu = np.concatenate(nus)
    return nu, _kernel_weights(nu, np.repeat(g.m.astype(float), sizes), starts), starts


def avar(spec: ModelSpectrum, g: Grids, parts=None) -> np.ndarray:
    """Return the expected Allan variance of the stochastic part at the grid's cluster sizes."""
    dt = g.dt
    nu = spec.refine(g.nu_log)
    e_nu, e_wk, starts = _exact_region(spec, g)
    s_all = spec.one_sided(np.concatenate([nu, e_nu]) / dt, parts) / dt
    s_log = s_all[:nu.size]
    sn = np.sin(np.pi * nu)
    avg = s_log * 0.75 / (sn * sn)
    cum = np.r_[0.0, np.cumsum(0.5 * (avg[1:] + avg[:-1]) * np.diff(nu))]
    out = np.add.reduceat(s_all[nu.size:] * e_wk, starts)
    top = PERIODS / g.m
    tail = top < 0.5
    out[tail] += (cum[-1] - np.interp(top[tail], nu, cum)) / (g.m[tail] * g.m[tail])
    if parts is None and spec.lines:
        f0, power = (np.array(v, dtype=np.float64) for v in zip(*spec.lines))
        x = f0 * dt
        s2 = np.sin(np.pi * x) ** 2
        ok = s2 >= 1e-12        # a line at DC: the record's line fit removes it
        m = np.asarray(g.m, dtype=np.float64)
        out += (power[ok] / s2[ok]) @ (2.0 * np.sin(np.pi * np.outer(x[ok], m)) ** 4) / (m * m)
    return out


def welch_expected(spec: ModelSpectrum, g: Grids):
    """Return the expected one-sided Welch PSD at the segment's bins: (noise part, line part)."""
    dt = g.dt
    size = g.welch_nu.size
    nu = g.welch_nu
    f = np.minimum(nu, 1.0 - nu) / dt
    s_two = np.zeros(size)
    pos = f > 0
    s_two[pos] = 0.5 * spec.one_sided(f[pos]) / dt     # two-sided per cycle/sample
    conv = np.fft.irfft(np.fft.rfft(s_two) * g.welch_w2_hat, size) / size
    w = signal.get_window('hann', g.nps)
    norm = dt / np.dot(w, w)
    bins = np.arange(g.nps // 2 + 1)
    e = conv[bins * FINE] * norm
    scale = np.full(bins.size, 2.0)
    scale[0] = 1.0
    if g.nps % 2 == 0:
        scale[-1] = 1.0
    # Bins 0 and 1: the segment mean is removed before windowing, which the plain window
    # kernel ignores there (bins >= 2 of a Hann window are untouched by it).
    e[:2] = g.low_bins @ s_two / size * norm
    noise = e * scale
    return noise, line_bins(spec.lines, dt, g.nps) * norm * scale


# Bins either side of a line where its Hann leakage is kept: beyond 64 bins the sidelobes are
# below 1e-10 of the line's power, far under any noise floor a line can stand on.
LEAK_BINS = 64


def line_bins(lines, dt: float, nps: int) -> np.ndarray:
    """
    Return sum over lines of (power / 2) |W(bin / nps - f0 dt)|^2 and of its image at -f0.

    The images at -x and 1 - x are the same (W has period 1), so each line has three centres
    in the band; around each, ``LEAK_BINS`` bins (a comb has hundreds of lines).
    """
    out = np.zeros(nps // 2 + 1)
    if not lines:
        return out
    f0, power = (np.asarray(v, dtype=np.float64) for v in zip(*lines))
    x = f0 * dt
    j = np.arange(-LEAK_BINS, LEAK_BINS + 1)
    for centre in (x, -x, 1.0 - x):
        b = np.round(centre * nps)[:, None] + j
        nu = b / nps - centre[:, None]
        keep = (b >= 0) & (b <= nps // 2)
        np.add.at(out, b[keep].astype(int),
                  (0.5 * power[:, None] * _hann_w2(nu, nps))[keep])
    return out


def _dirichlet(v, L):
    """sum_(j<L) exp(-2 pi i v j) = (1 - z^L) / (1 - z), z = exp(-2 pi i v)."""
    v = np.asarray(v, dtype=np.float64)
    den = 1.0 - np.exp(-2j * np.pi * v)
    near = np.abs(den) < 1e-12
    return np.where(near, L, (1.0 - np.exp(-2j * np.pi * L * v)) / np.where(near, 1.0, den))


def _hann_w(nu, L):
    """
    DFT W(nu) of the periodic Hann window of length L (cycles/sample).

    0.5 D(nu) - 0.25 D(nu - 1 / L) - 0.25 D(nu + 1 / L), D(v) = sum_(j<L) exp(-2 pi i v j) =
    (1 - z^L) / (1 - z), z = exp(-2 pi i v): the three share z^L (a shift of 1 / L turns it
    by a whole cycle), so two complex exponentials serve all three.
    """
    v = np.asarray(nu, dtype=np.float64)
    z = np.exp(-2j * np.pi * v)
    num = 1.0 - np.exp(-2j * np.pi * L * v)
    out = np.zeros(v.shape, dtype=np.complex128)
    for weight, shift in ((0.5, 0.0), (-0.25, 1.0 / L), (-0.25, -1.0 / L)):
        den = 1.0 - z * np.exp(2j * np.pi * shift)        # 1 - exp(-2 pi i (v - shift))
        near = np.abs(den) < 1e-12
        out += weight * np.where(near, L, num / np.where(near, 1.0, den))
    return out


def _hann_w2(nu, L):
    """|W(nu)|^2 of the periodic Hann window of length L (cycles/sample)."""
    return np.abs(_hann_w(nu, L)) ** 2


def acf_integrals(spec: ModelSpectrum, g: Grids, lags: int):
    """E r(0) of the detrended record and the variogram D(k), k = 1..lags (stochastic part)."""
    nu = spec.refine(g.nu_log)
    s = spec.one_sided(nu / g.dt) / g.dt
    k = np.arange(1, lags + 1)
    if nu.size == g.nu_log.size:
        keep, (sin2, weights) = g.g_detrend, _acf_kernels(g.n, g.dt, lags)['log']
    else:
        keep, sin2, weights = (_detrend_keep(nu * g.n), np.sin(np.pi * np.outer(k, nu)) ** 2,
                               _trapz_weights(nu))
    r0 = _trapz(s * keep, nu)
    dk = 4.0 * (sin2 @ (s * weights))  # 2(1 - cos)
    if spec.lines:
        f0, power = (np.array(v, dtype=np.float64) for v in zip(*spec.lines))
        x = f0 * g.dt
        r0 += float(power @ _detrend_keep(x * g.n))
        dk += 2.0 * (1.0 - np.cos(2.0 * np.pi * np.outer(k, x))) @ power
    return r0, dk


# DFT bins of the record summed one by one in ``acf_moments`` (beyond, integrals).
ACF_BINS = 1024


@lru_cache(maxsize=8)
def _acf_kernels(n: int, dt: float, lags: int) -> dict:
    """
    Return the autocorrelation's fixed kernels for ``grids(n, dt)`` (once per record shape).

    ``log``: sin^2(pi k nu) and trapezoid weights on ``nu_log``; ``bins`` / ``tail``: the
    frequencies (Hz) of ``acf_moments``' DFT bins and of its integral beyond them, with their
    detrend share or trapezoid weights, 4 sin^2(pi k nu) and its square.
    """
    g = grids(n, dt)
    k = np.arange(1, lags + 1, dtype=float)
    j = np.arange(1, min(ACF_BINS, n // 2) + 1, dtype=float)
    w = 4.0 * np.sin(np.pi * np.outer(k, j / n)) ** 2
    nu = np.geomspace((ACF_BINS + 0.5) / n, 0.5, 2000)
    w_tail = 4.0 * np.sin(np.pi * np.outer(k, nu)) ** 2
    out = {'log': (np.sin(np.pi * np.outer(k, g.nu_log)) ** 2,
                   _trapz_weights(g.nu_log)),
           'bins': (j / n / dt, _detrend_keep(j), w, w * w),
           'tail': (nu / dt, _trapz_weights(nu), w_tail, w_tail * w_tail)}
    for arrays in out.values():
        for a in arrays:
            a.flags.writeable = False
    return out


def acf_moments(spec: ModelSpectrum, g: Grids, lags: int, det: Deterministic = None):
    """
    Return the mean and the standard deviation of the autocorrelation at lags 1..``lags``.

    1 - acf(k) = D(k) / 2 r(0), a ratio of two sums over the detrended record's periodogram
    bins (independent exponentials of mean S(j / n) (1 - G(j)) / n): r(0) weighs them by 1,
    the variogram D(k) by 4 sin^2(pi k j / n). The ratio's moments by the delta method with
    their variances and covariance: it is Bartlett's formula when the variance is spread over
    many bins, and it keeps the scatter of 1 / r(0) when a slow process puts the variance in a
    few (a random walk: r(0) a chi-square of some 20 degrees of freedom). A line adds its
    power to the means and its cross term with the noise in its bin to the variances; the
    deterministic part adds to the means only.
    """
    r0, dk = acf_integrals(spec, g, lags)
    k = np.arange(1, lags + 1, dtype=float)
    det0 = 0.0 if det is None else float(det.acov[0])
    detk = 0.0 if det is None else det.acov[1:lags + 1]
    mu0, mu_d = r0 + det0, dk + 2.0 * (det0 - detk)
    kern = _acf_kernels(g.n, g.dt, lags)
    f, keep, w, ww = kern['bins']
    a = spec.one_sided(f) / g.dt * keep / g.n
    a2 = a * a
    v0, v_d, c = float(a2.sum()), ww @ a2, w @ a2
    if g.n // 2 > ACF_BINS:
        f, weights, w, ww = kern['tail']
        s2 = (spec.one_sided(f) / g.dt) ** 2 * weights / g.n
        v0, v_d, c = v0 + float(s2.sum()), v_d + ww @ s2, c + w @ s2
    if spec.lines:                 # a line's bin: noise and line, a cross term 2 a P
        f0, power = (np.array(v, dtype=np.float64) for v in zip(*spec.lines))
        nu0 = f0 * g.dt
        keep = _detrend_keep(nu0 * g.n)
        cross = 2.0 * power * keep * spec.one_sided(f0) / g.dt * keep / g.n
        w = 4.0 * np.sin(np.pi * np.outer(k, nu0)) ** 2
        v0, v_d, c = v0 + float(cross.sum()), v_d + (w * w) @ cross, c + w @ cross
    ratio = mu_d / (2.0 * mu0)
    rel0, cov = v0 / mu0 ** 2, c / (mu_d * mu0)
    mean = (1.0 - k / g.n) * (1.0 - ratio * (1.0 + rel0 - cov))
    sd = np.abs(ratio) * np.sqrt(np.maximum(v_d / mu_d ** 2 + rel0 - 2.0 * cov, 0.0))
    return mean, sd


def psd_bins(layout, g: Grids):
    """Welch bin indices of each log-spaced PSD bin (as the observable selects them)."""
    f = np.arange(g.nps // 2 + 1) / (g.nps * g.dt)
    edges = layout.ranges['psd']
    out = []
    for i, (lo, hi) in enumerate(edges):
        sel = (f >= lo) & (f < hi) if i < len(edges) - 1 else (f >= lo) & (f <= hi)
        out.append(np.flatnonzero(sel))
    return out


def expected_blocks(spec: ModelSpectrum, layout, det: Deterministic = None,
                    log_bias: np.ndarray = None) -> Dict[str, np.ndarray]:
    """
    Return the expected value of every static block of a twin described by ``spec``.

    ``log_bias``: E[log10 adev] - log10 sqrt(E[AVAR]) per tau (from the EDF; 0 if None).
    """
    g = grids(layout.n, layout.dt)
    lags = obs.ACF_LAGS
    if det is None:
        det = deterministic(spec, g, lags)
    av = avar(spec, g) + det.avar
    adev = 0.5 * np.log10(np.maximum(av, 1e-300)) + (0.0 if log_bias is None else log_bias)
    noise, lines = welch_expected(spec, g)
    total = noise + lines + det.welch
    bins = psd_bins(layout, g)
    f = np.arange(total.size) / (g.nps * g.dt)
    psd = np.array([total[b].mean() if b.size else
                    np.interp(0.5 * (lo + hi), f, total)
                    for b, (lo, hi) in zip(bins, layout.ranges['psd'])])
    tone = tone_block(noise + det.welch, lines, g, layout)
    acf, _ = acf_moments(spec, g, lags, det)
    return {'adev': adev, 'psd': np.log10(np.maximum(psd, 1e-300)), 'tone': tone.mean(axis=0),
            'acf': acf, 'drift': det.drift.copy()}
