"""
Equivalent degrees of freedom and 68 % confidence intervals of the overlapping Allan deviation.

EDF: Greenhall & Riley (2004), "Uncertainty of stability variances based on finite
differences" (the algorithm NIST SP1065 and Stable32 use), for the fully overlapping Allan
variance (d = 2, F = S = m), power-law noise alpha in {2, 1, 0, -1, -2}. The noise type at each
tau comes either from the lag-1 autocorrelation of the m-averaged rate (Riley & Greenhall 2004)
or from the fitted model (the dominant IEEE term at that tau). The interval is the chi-square
one: sigma^2 edf / chi2_{0.841}(edf) .. sigma^2 edf / chi2_{0.159}(edf).
"""
from typing import Optional

from gyro_char.allan.kernel import AllanResult
from gyro_char.allan.model import ALPHA, term_avar, TERMS
import numpy as np
from scipy import special

try:  # optional, as in gyro_char.allan
    import numba
except ImportError:  # pragma: no cover - exercised only where numba is absent
    numba = None

CI68 = float(special.erf(1.0 / np.sqrt(2.0)))
J_MAX = 100
# Greenhall's table 2 (alpha <= 0 .. 2, d = 2): (a0, a1) for 1/edf = (a0 - a1/r) / r.
_TABLE2 = {2: (35.0 / 18.0, 1.0), 1: (790.0, 410.0), 0: (2.0 / 3.0, 1.0 / 3.0),
           -1: (0.852, 0.375), -2: (1.079, 0.368)}
_TABLE3_B = (15.23, 12.0)  # alpha = 1, d = 2: b0 + b1 ln m
# A lag-1 ACF needs about 30 averaged samples to identify the noise (Riley & Greenhall).
MIN_ACF_POINTS = 30
# ... and more than this many add nothing but time (first points used).
MAX_ACF_POINTS = 100_000
MIN_PM_POINTS = 1000


def _sw(t, alpha: int):
    t = np.asarray(t, dtype=np.float64)
    a = np.abs(t)
    with np.errstate(divide='ignore', invalid='ignore'):
        log = np.where(a > 0, np.log(np.where(a > 0, a, 1.0)), 0.0)
    return {2: -a, 1: t ** 2 * log, 0: a ** 3, -1: t ** 4 * log, -2: a ** 5,
            -3: t ** 6 * log, -4: a ** 7}[alpha]


def _sx(t, big_f: float, alpha: int):
    if np.isinf(big_f):
        return _sw(t, alpha + 2)
    return big_f ** 2 * (2.0 * _sw(t, alpha) - _sw(t - 1.0 / big_f, alpha)
                         - _sw(t + 1.0 / big_f, alpha))


def _sz(t, big_f: float, alpha: int):  # d = 2
    return (6.0 * _sx(t, big_f, alpha) - 4.0 * _sx(t - 1.0, big_f, alpha)
            - 4.0 * _sx(t + 1.0, big_f, alpha) + _sx(t - 2.0, big_f, alpha)
            + _sx(t + 2.0, big_f, alpha))


def _basic_sum(big_j: float, big_m: float, s: float, big_f: float, alpha: int) -> float:
    j = np.arange(1, int(big_j))
    third = np.sum(2.0 * (1.0 - j / big_m) * _sz(j / s, big_f, alpha) ** 2)
    return float(_sz(0.0, big_f, alpha) ** 2
                 + (1.0 - big_j / big_m) * _sz(big_j / s, big_f, alpha) ** 2 + third)


def edf_oadev(alpha: int, m: int, n_phase: int) -> float:
    """
    Return Greenhall's EDF of the overlapping Allan variance at averaging factor ``m``.

    ``n_phase`` is the number of phase points (rate samples + 1); ``alpha`` in {2..-2}.
    Same cases as ``allantools.ci.edf_greenhall(alpha, 2, m, N, overlapping=True)``.
    """
    alpha, m, d = int(alpha), int(m), 2
    big_l = 1 + m * d
    big_m = 1 + np.floor(n_phase - big_l)
    big_j = min(big_m, (d + 1) * m)
    r = big_m / m
    if big_m < 1:
        return float('nan')
    if alpha <= 0:
        if big_j <= J_MAX:
            mp = m if m * (d + 1) <= J_MAX else float('inf')
            inv = _basic_sum(big_j, big_m, m, mp, alpha) / (_sz(0.0, mp, alpha) ** 2 * big_m)
        elif r > d + 1:
            a0, a1 = _TABLE2[alpha]
            inv = (a0 - a1 / r) / r
        else:
            mp = J_MAX / r
            inv = (_basic_sum(J_MAX, J_MAX, mp, float('inf'), alpha)
                   / (_sz(0.0, float('inf'), alpha) ** 2 * J_MAX))
    elif alpha == 1:
        if big_j <= J_MAX:
            inv = _basic_sum(big_j, big_m, m, m, 1) / (_sz(0.0, m, 1) ** 2 * big_m)
        elif r > d + 1:
            a0, a1 = _TABLE2[1]
            b0, b1 = _TABLE3_B
            inv = (a0 - a1 / r) / ((b0 + b1 * np.log(m)) ** 2 * r)
        else:
            mp = J_MAX / r
            b0, b1 = _TABLE3_B
            inv = (_basic_sum(J_MAX, J_MAX, mp, mp, 1)
                   / ((b0 + b1 * np.log(m)) ** 2 * J_MAX))
    elif alpha == 2:
        if np.ceil(r) <= d:
            # Greenhall leaves this corner (fewer than 3 tau-spans of data) to a direct sum;
            # the conservative choice is one degree of freedom.
            return 1.0
        a0 = special.binom(4 * d, 2 * d) / special.binom(2 * d, d) ** 2
        inv = (a0 - (d / 2.0) / r) / big_m
    else:
        raise ValueError(f'alpha must be one of 2, 1, 0, -1, -2, got {alpha}')
    return float(1.0 / inv)


def _lag1_numpy(x: np.ndarray) -> np.ndarray:
    t = np.arange(x.shape[0], dtype=np.float64)
    t -= t.mean()
    xc = x - x.mean(axis=0)
    slope = (t @ xc) / (t @ t)
    res = xc - np.outer(t, slope)
    den = np.sum(res * res, axis=0)
    return np.sum(res[1:] * res[:-1], axis=0) / np.where(den > 0, den, np.inf)


if numba is not None:
    @numba.njit(cache=True, nogil=True)
    def _lag1_numba(x):  # pragma: no cover - compiled
        # Same as _lag1_numpy in two fused passes (no temporaries): Sum t_c = 0, so the
        # slope needs no centred copy of x.
        n, nc = x.shape
        mean = np.zeros(nc)
        tx = np.zeros(nc)
        for i in range(n):
            tc = i - (n - 1) / 2.0
            for c in range(nc):
                mean[c] += x[i, c]
                tx[c] += tc * x[i, c]
        tt = n * (n * n - 1.0) / 12.0
        slope = tx / tt
        mean /= n
        num = np.zeros(nc)
        den = np.zeros(nc)
        prev = np.zeros(nc)
        for i in range(n):
            tc = i - (n - 1) / 2.0
            for c in range(nc):
                r = x[i, c] - mean[c] - tc * slope[c]
                den[c] += r * r
                if i > 0:
                    num[c] += r * prev[c]
                prev[c] = r
        out = np.zeros(nc)
        for c in range(nc):
            if den[c] > 0:
                out[c] = num[c] / den[c]
        return out


def _lag1(x: np.ndarray) -> np.ndarray:
    """Lag-1 autocorrelation along axis 0 after removing a linear trend."""
    if numba is not None and x.shape[0] >= 2:
        return _lag1_numba(np.ascontiguousarray(x, dtype=np.float64))
    return _lag1_numpy(x)


def alpha_from_acf(rate: np.ndarray, m: np.ndarray, beyond: Optional[np.ndarray] = None,
                   csum: Optional[np.ndarray] = None) -> np.ndarray:
    """
    Return the integer noise exponent alpha per (m, channel) from lag-1 autocorrelation.

    Riley & Greenhall (2004) on rate ("frequency") data averaged over m: with r1 the lag-1 ACF,
    rho = r1 / (1 + r1), and alpha = -2 rho (d = 0), else the series is differenced (d = 1, 2)
    and alpha = -2 (rho + d). Where the averaged series has fewer than 30 points the ACF cannot
    identify anything: there ``beyond`` (K, C) is used if given (e.g. ``alpha_from_slope`` of
    the curve), else the largest identifiable m's alpha is carried forward. At most the first
    100 000 averages are used; alpha 1 or 2 needs at least 1000 (else capped at 0).

    ``csum`` (n + 1, C): the cumulative sum of the mean-removed rate from 0, at any positive
    scale (the ACF is scale-free), e.g. ``kernel.phase(rate, dt)``; computed if None.
    """
    rate = np.asarray(rate, dtype=np.float64)
    rate2 = rate[:, None] if rate.ndim == 1 else rate
    # One cumulative sum serves every m: block means are differences of it, O(n / m) each.
    if csum is None:
        csum = np.zeros((rate2.shape[0] + 1, rate2.shape[1]))
        np.cumsum(rate2 - rate2.mean(axis=0), axis=0, out=csum[1:])
    out = np.zeros((m.size, rate2.shape[1]), dtype=np.int64)
    last = np.zeros(rate2.shape[1], dtype=np.int64)
    for k, mm in enumerate(m):
        n_avg = rate2.shape[0] // int(mm)
        if n_avg < MIN_ACF_POINTS:
            out[k] = last if beyond is None else beyond[k]
            continue
        n_avg = min(n_avg, MAX_ACF_POINTS)
        y = np.diff(csum[:n_avg * mm + 1:mm], axis=0) / mm
        alpha = np.zeros(rate2.shape[1], dtype=np.int64)
        todo = np.ones(rate2.shape[1], dtype=bool)
        for d in range(3):
            rho = _lag1(y)
            rho = rho / (1.0 + rho)
            done = todo & ((rho < 0.25) | (d == 2))
            alpha[done] = (-np.round(2.0 * rho[done]) - 2 * d).astype(np.int64)
            todo &= ~done
            if not todo.any():
                break
            y = np.diff(y, axis=0)
        # Phase-noise types (alpha 1, 2) keep a near-constant, huge EDF at every m: claim
        # them only with plenty of averages, not from a chance negative ACF of 30 points.
        out[k] = last = np.clip(alpha, -2, 2 if n_avg >= MIN_PM_POINTS else 0)
    return out


def chi2_ppf(q, edf):
    """Return the chi-square quantile (= scipy.stats.chi2.ppf, without importing scipy.stats)."""
    return 2.0 * special.gammaincinv(np.asarray(edf, dtype=np.float64) / 2.0, q)


def chi2_interval(adev: np.ndarray, edf: np.ndarray, ci: float = CI68):
    """Return (lo, hi) of the deviation for ``edf`` degrees of freedom (NIST SP1065 eq. 45)."""
    lo_p = (1.0 - ci) / 2.0
    edf = np.asarray(edf, dtype=np.float64)
    var = np.asarray(adev, dtype=np.float64) ** 2
    lo = np.sqrt(edf * var / chi2_ppf(1.0 - lo_p, edf))
    hi = np.sqrt(edf * var / chi2_ppf(lo_p, edf))
    return lo, hi


def add_confidence(res: AllanResult, alpha: np.ndarray, ci: float = CI68) -> AllanResult:
    """
    Fill ``edf``, ``alpha``, ``adev_lo``, ``adev_hi`` of ``res`` in place and return it.

    ``alpha`` is (K, C) (or broadcastable): from ``alpha_from_acf`` or ``alpha_from_model``.
    Counts are the term counts, so pooled gap segments are treated as one record of the same
    total length (slightly optimistic across gaps).
    """
    alpha = np.broadcast_to(np.asarray(alpha, dtype=np.int64), res.avar.shape).copy()
    edf = np.empty(res.avar.shape)
    cache = {}
    for k, (mm, cnt) in enumerate(zip(res.m, res.counts)):
        n_phase = int(cnt) + 2 * int(mm)
        for c in range(res.avar.shape[1]):
            key = (int(alpha[k, c]), int(mm), n_phase)
            if key not in cache:
                cache[key] = edf_oadev(*key)
            edf[k, c] = cache[key]
    res.alpha, res.edf = alpha, edf
    res.adev_lo, res.adev_hi = chi2_interval(res.adev, edf, ci)
    return res


def alpha_from_model(tau: np.ndarray, coeffs: dict, kind_alpha: Optional[dict] = None
                     ) -> np.ndarray:
    """Return alpha of the dominant term of formula (4) at each tau (K,) for one channel."""
    alpha_map = kind_alpha or ALPHA
    parts = np.stack([term_avar(t, tau, coeffs.get(t, 0.0)) for t in TERMS], axis=-1)
    dominant = np.argmax(parts, axis=-1)
    return np.array([alpha_map[TERMS[i]] for i in dominant], dtype=np.int64)


def alpha_from_slope(tau: np.ndarray, avar: np.ndarray) -> np.ndarray:
    """
    Return alpha per (K, C) from the local log-log slope mu of sigma^2(tau).

    sigma^2 ~ tau^mu with mu = -alpha - 1 for alpha in {0, -1, -2}, rounded and clipped to that
    range. Steeper slopes (white / flicker phase noise, alpha 2 / 1) are NOT returned: their EDF
    hardly falls with m, so a chance steep stretch of a noisy long-tau curve would get absurd
    (10^4) degrees of freedom; alpha = 0 is the conservative choice there. The slope is taken
    over +-1 octave to damp the scatter; used where the samples are no longer available
    (streaming) or where the ACF has too few averaged points (long tau).
    """
    tau = np.asarray(tau, dtype=np.float64)
    avar = np.asarray(avar, dtype=np.float64)
    avar2 = avar[:, None] if avar.ndim == 1 else avar
    lt = np.log(tau)
    la = np.log(np.maximum(avar2, np.finfo(float).tiny))
    out = np.zeros(avar2.shape, dtype=np.int64)
    for k in range(tau.size):
        sel = np.abs(lt - lt[k]) <= np.log(2.0) + 1e-12
        if np.count_nonzero(sel) < 2:
            sel = np.argsort(np.abs(lt - lt[k]))[:2]
        x = lt[sel] - lt[sel].mean()
        mu = (x @ (la[sel] - la[sel].mean(axis=0))) / max(x @ x, 1e-300)
        out[k] = np.clip(-np.round(mu) - 1, -2, 0)
    return out if avar.ndim > 1 else out[:, 0]
