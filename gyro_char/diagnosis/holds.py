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

Runs of holds (``run`` > 0: a register frozen for several samples, mean run length L): the
Markov chain P(hold | none before) = a, P(hold | hold) = c = 1 - 1 / L, share p = a / (1 - c +
a). The lags D_0, D_m are computed through the chain's renewal at its last fresh sample:
P(fresh at j | fresh at 0) = pi_0 + pi_h l^j, P(fresh at j | held at 0) = pi_0 (1 - l^j), l = c
- a, and g(d) = pi_0 a c^(d-1) (d >= 1) is the stationary age law. The spectrum is
|G|^2 S, G(z) = pi_0 (1 - l z^-1) / (1 - c z^-1), plus the transform of R'(m) - (g * g~ *
R)(m), evaluated lag by lag on the variogram -D(k) / 2 in place of R (the weights of both sum
to 1, so R(0) cancels and a random walk stays finite) to ``lags`` where c^m and l^m are
below 1e-9. L = 1 is the isolated form, L = 1 / (1 - p) the independent one (tested).

All keep the variance; on white noise of variance s^2 they give R'(m) = s^2 p^|m| and
R'(+-1) = s^2 p only; runs R'(m) = s^2 p c^(|m|-1). The integrals are trapezoids on ``GRID``
points; every integrand carries a factor sin^2(pi f dt), so a random walk's or flicker's low
end stays finite.
"""
from dataclasses import dataclass
from typing import Sequence, Tuple

from gyro_char.sim.effects.timing import hold_chain
import numpy as np
from scipy import fft, signal

GRID = 1 << 14      # points of the integrals behind the holds' broadband share
# Beyond this many lags the half variogram comes from the first difference's spectrum by one
# cosine transform (``_half_variogram_fft``) instead of a lag-by-lag sum on the grid.
FFT_LAGS = 1024


@dataclass(frozen=True)
class Holds:
    """Stale samples of one output: share ``p``; independent, ``isolated``, or in runs."""

    p: float
    isolated: bool = False
    run: float = 0.0            # mean run length of held samples (> 0: the run form)

    @classmethod
    def from_params(cls, params: dict) -> 'Holds':
        """Return the holds of a ``stale_samples`` parameter dict (the simulator's names)."""
        return cls(float(params['p']), bool(params.get('isolated', 0.0)),
                   float(params.get('run', 0.0)))

    def chain(self) -> Tuple[float, float, float, float]:
        """Return the run form's chain: a, c, the fresh share pi_0 and l = c - a."""
        a, c = hold_chain(self.p, self.run)
        return a, c, 1.0 - self.p, c - a

    def gain(self) -> float:
        """
        Return the holds' gain on white noise (in N) where the baseline's N is read.

        Single-sample holds: the long-τ gain sqrt(S'(0) / S(0)) (within 1 % of the white
        band's at p <= 0.1). Runs: S'/S averaged over the white band, 1-5 % of the sample
        rate (``static_expect.calibrate_n``): runs lower it far below the long-τ level
        1 + 2 p run, and the baseline's N is the band's.
        """
        p = self.p
        if self.run > 0.0:
            _, c, pi0, _ = self.chain()
            w = 2.0 * np.pi * np.linspace(0.01, 0.05, 65)
            z = np.exp(1j * w)
            ratio = 1.0 + 2.0 * (1.0 - pi0) * np.real(z / (1.0 - c * z))
            return float(np.sqrt(np.mean(ratio)))
        return float(np.sqrt(1.0 + 2.0 * p if self.isolated else (1.0 + p) / (1.0 - p)))

    def g2(self, f, dt: float) -> np.ndarray:
        """Return |G|^2 at output frequencies ``f`` (the holds' averaging of a slow part)."""
        p, s2 = self.p, _s2(f, dt)
        if self.run > 0.0:
            _, c, pi0, lam = self.chain()
            num = (1.0 - lam) ** 2 + 4.0 * lam * s2
            return pi0 * pi0 * num / ((1.0 - c) ** 2 + 4.0 * c * s2)
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
        if self.run > 0.0:
            return self._run_terms(f, s, f0, power, dt)
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

    def _run_terms(self, f, s, f0, power, dt) -> np.ndarray:
        """Return R'(m) - (g * g~ * R)(m), m = 0 .. lags - 1, of the run form (module doc)."""
        a, c, pi0, lam = self.chain()
        m_max = self.lags()
        depth = _decay_length(c)
        k = np.arange(m_max + depth + 2)
        rv = _half_variogram(f, s, f0, power, dt, k.size)
        w = np.r_[1.0, a * c ** np.arange(depth)]            # w(0) = 1, w(e) = a c^(e-1)
        # Q(j) = sum_(d >= 1) pi_0 a c^(d-1) Rv(j + d): a backward recursion.
        q = signal.lfilter([0.0, pi0 * a], [1.0, -c], rv[::-1])[::-1]
        j = np.arange(m_max)
        v0 = np.where(j > 0, (pi0 + (1.0 - pi0) * lam ** j) * rv[:m_max], 0.0)
        v1 = np.where(j > 0, pi0 * (1.0 - lam ** j) * q[:m_max], 0.0)
        exact = (pi0 * signal.convolve(w, v0)[:m_max]
                 + signal.convolve(w, v1)[:m_max])
        g = pi0 * w
        rho = signal.correlate(g, g, mode='full')            # lags -(len-1) .. len-1
        full = np.r_[rv[::-1], rv[1:]]                       # Rv(-K) .. Rv(K)
        conv = signal.convolve(full, rho[::-1], mode='same')
        centre = rv.size - 1
        return exact - conv[centre:centre + m_max]

    def lags(self) -> int:
        """Return how many lags of the correction are kept (isolated: |l|^m > 1e-7)."""
        if self.run > 0.0:
            _, c, _, lam = self.chain()
            return max(_decay_length(c), _decay_length(abs(lam))) + 1
        lam = self.p / (1.0 - self.p)
        return 1 if lam <= 0.0 else int(np.ceil(np.log(1e-7) / np.log(lam))) + 1

    def apply(self, f, s: np.ndarray, terms: np.ndarray, dt: float) -> np.ndarray:
        """Return the held one-sided PSD at ``f`` from the unheld one ``s`` and ``terms``."""
        p = self.p
        f = np.asarray(f, dtype=np.float64)
        if self.isolated or self.run > 0.0:
            extra = cosine_series(terms, f * dt, by_fft=self.run > 0.0 and terms.size > 32)
            return self.g2(f, dt) * s + 2.0 * dt * extra
        ar1 = 2.0 * (1.0 - p * p) * dt / ((1.0 - p) ** 2 + 4.0 * p * _s2(f, dt))
        return self.g2(f, dt) * s + terms[0] * ar1


def cosine_series(c: np.ndarray, nu, by_fft: bool = False) -> np.ndarray:
    """
    Return c_0 + 2 sum_(k >= 1) c_k cos(2 pi nu k) at ``nu`` cycles a sample.

    ``by_fft`` (hundreds of lags): the series on a fine uniform grid by one FFT (it is smooth
    on the scale 1 / lags), interpolated; else summed term by term.
    """
    nu = np.asarray(nu, dtype=np.float64)
    if by_fft:
        size = 1 << int(np.ceil(np.log2(64 * c.size)))
        series = np.fft.rfft(np.r_[c, np.zeros(size - 2 * c.size + 1), c[:0:-1]]).real
        return np.interp(np.mod(nu, 1.0), np.arange(series.size) / size, series)
    w = 2 * np.pi * nu
    return c[0] + 2.0 * sum(ck * np.cos(k * w) for k, ck in enumerate(c) if k)


def _half_variogram(f, s, f0, power, dt: float, count: int) -> np.ndarray:
    """
    Return -D(k) / 2 = integral of S (cos(w k) - 1), k = 0 .. count - 1, plus the lines'.

    cos(w k) - 1 by the Chebyshev recurrence from the exact -2 sin^2(w / 2): one vector
    operation a lag instead of a sine matrix, no cancellation where w k is small. Beyond
    ``FFT_LAGS`` lags (long runs of holds): ``_half_variogram_fft``.
    """
    f = np.asarray(f, dtype=np.float64)
    if count > FFT_LAGS:
        return _half_variogram_fft(f, s, f0, power, dt, count)
    step = np.diff(f)
    ws = np.zeros(f.size)
    ws[:-1] += 0.5 * step
    ws[1:] += 0.5 * step
    ws *= s
    c1 = -2.0 * _s2(f, dt)
    two_cos = 2.0 * (1.0 + c1)
    out = np.zeros(count)
    prev, cur = np.zeros(f.size), c1.copy()
    for j in range(1, count):
        out[j] = float(np.dot(ws, cur))
        prev, cur = cur, two_cos * cur - prev + 2.0 * c1
    if np.size(f0):
        out += _line_half_variogram(f0, power, dt, count)
    return out


def _decay_length(r: float, tol: float = 1e-9) -> int:
    """Return the number of powers of ``r`` above ``tol`` (at least 1)."""
    return 1 if r <= 0.0 else int(np.ceil(np.log(tol) / np.log(r))) + 1


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
    k = _steps(x, lsb)
    n = k.size
    if n < 2:
        return float('nan'), float('nan')
    if lsb <= 0.0:
        share = float(np.count_nonzero(k == 0.0)) / n
        return share, float(np.sqrt(max(share, 1.0 / n) / n))
    v = float(np.var(k))
    if v < 1.0:
        return float('nan'), float('nan')
    p0 = float(np.count_nonzero(k == 0)) / n
    p1 = 0.5 * float(np.count_nonzero(np.abs(k) == 1)) / n
    expected = p1 * float(np.exp(0.5 / v))
    return p0 - expected, float(np.sqrt((p0 + 0.5 * p1) / n))


def repeat_runs(x: np.ndarray, lsb: float) -> Tuple[float, float]:
    """
    Return the mean length of the record's runs of two or more exact repeats, and their share.

    The share is of all exact repeats (zero first differences, in output steps where
    ``lsb`` > 0). Rounding repeats a sample now and then, rarely twice in a row where the
    noise spans several steps; a register frozen for several samples repeats in runs. (0, 0)
    where the record has no run of two.
    """
    zero = _steps(x, lsb) == 0.0
    if not zero.any():
        return 0.0, 0.0
    edges = np.flatnonzero(np.diff(np.r_[0, zero.astype(np.int8), 0]))
    lengths = edges[1::2] - edges[::2]
    long = lengths[lengths >= 2]
    if long.size == 0:
        return 0.0, 0.0
    return float(long.mean()), float(long.sum() / lengths.sum())


def _steps(x: np.ndarray, lsb: float) -> np.ndarray:
    """Return the record's first differences in output steps (as they are where ``lsb`` 0)."""
    d = np.diff(np.asarray(x, dtype=np.float64))
    return np.round(d / lsb) if lsb > 0.0 else d


def _line_half_variogram(f0, power, dt: float, count: int) -> np.ndarray:
    """Return the lines' part of -D(k) / 2, k = 0 .. count - 1."""
    kk = np.arange(count)
    return (np.asarray(power)[:, None]
            * (-2.0 * np.sin(np.pi * np.asarray(f0)[:, None] * dt * kk) ** 2)).sum(axis=0)


def _half_variogram_fft(f, s, f0, power, dt: float, count: int) -> np.ndarray:
    """
    Return ``_half_variogram`` for many lags through the first difference's spectrum.

    D(k) = integral of U F_k, U = 4 S sin^2(pi f dt) the first difference's PSD (bounded
    where S has a random walk's 1 / f^2) and F_k = sin^2(pi f k dt) / sin^2(pi f dt) =
    sum_(|j| < k) (k - |j|) cos(2 pi f j dt) Fejer's kernel: D(k) = sum_(|j| < k) (k - |j|)
    r_U(j), two running sums of U's autocovariance r_U. U is taken piecewise linear on M + 1
    uniform points (from the grid, which keeps narrow peaks), whose cosine coefficients are
    exact: a DCT-I times sinc^2(j h), h the spacing in cycles a sample; M is at least 8 count
    (2^17 or more).
    """
    u = 4.0 * s * _s2(f, dt)
    bins = 1 << max(17, int(np.ceil(np.log2(8 * count))))
    nu = np.linspace(0.0, 0.5, bins + 1)
    fine = np.interp(nu, f * dt, u)
    # Below the grid's first point U follows the power law of its first two points (S as
    # f^-a, a in [0, 2]: 0 at f = 0 unless S has a random walk's 1 / f^2).
    low = nu < f[0] * dt
    slope = np.log(max(u[1], 1e-300) / max(u[0], 1e-300)) / np.log(f[1] / f[0])
    fine[low] = u[0] * (nu[low] / (f[0] * dt)) ** float(np.clip(slope, 0.0, 2.0))
    h = 0.5 / bins
    j = np.arange(count)
    r_u = (0.5 * h / dt) * fft.dct(fine, type=1)[:count] * np.sinc(j * h) ** 2
    c = np.cumsum(np.r_[r_u[0], 2.0 * r_u[1:]])          # C(i) = sum_(|j| <= i) r_U(j)
    d = np.r_[0.0, np.cumsum(c)[:count - 1]]             # D(k) = sum_(i < k) C(i)
    out = -0.5 * d
    if np.size(f0):
        out += _line_half_variogram(f0, power, dt, count)
    return out
