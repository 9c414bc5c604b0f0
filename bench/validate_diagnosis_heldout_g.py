"""DOCSTRING"""
from functools import lru_cache

from gyro_char.allan.expected import markov_avar
import numpy as np
from scipy import signal, stats

WELCH_L = 16384
KNOCK_PERIOD, KNOCK_DECAY = 0.8, 0.12     # s: the knock interval, the ring's decay time
GRAD_AT, GRAD_WIDTH = 2700.0, 150.0       # s: the ambient step's midpoint and its width w
HOLD = 10.0                               # s: bias-register update interval
BOUND_TIME = 1800.0                       # s: the rails at +-k sqrt(BOUND_TIME)
CHAIN_GRID = 600                          # states of the Schmitt counter's error chain


def spike_filter(x: np.ndarray, thresh: float) -> np.ndarray:
    """Replace x_k by the median of (x_(k-1), x_k, x_(k+1)) where it differs by > thresh."""
    a, b, c = x[:-2], x[1:-1], x[2:]
    med = np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c))
    y = x.copy()
    hit = np.abs(b - med) > thresh
    y[1:-1][hit] = med[hit]
    return y


def _segments(lo, hi, c, t):
    """The parts [p, q] of [lo, hi] outside (c - t, c + t), as two (p, q, nonempty) triples."""
    q1 = np.minimum(hi, c - t)
    p2 = np.maximum(lo, c + t)
    return (lo, q1, q1 > lo), (p2, hi, hi > p2)


def spike_moments(c: np.ndarray, k: np.ndarray, t: float):
    """E[y], E[y^2] of the filtered sample: centre ``c``, one neighbour ``k``, the other N(0, 1)."""
    lo, hi = np.minimum(c, k), np.maximum(c, k)
    pdf, cdf = stats.norm.pdf, stats.norm.cdf
    m1, m2 = c.copy(), c * c
    for edge, mass in ((lo, cdf(lo)), (hi, stats.norm.sf(hi))):
        out = np.abs(edge - c) > t
        m1 = m1 + np.where(out, (edge - c) * mass, 0.0)
        m2 = m2 + np.where(out, (edge * edge - c * c) * mass, 0.0)
    for p, q, ok in _segments(lo, hi, c, t):
        i1 = pdf(p) - pdf(q) - c * (cdf(q) - cdf(p))
        i2 = (cdf(q) - cdf(p) + p * pdf(p) - q * pdf(q)) - c * c * (cdf(q) - cdf(p))
        m1 = m1 + np.where(ok, i1, 0.0)
        m2 = m2 + np.where(ok, i2, 0.0)
    return m1, m2


@lru_cache(maxsize=16)
def spike_lag1(t: float, grid: int = 801, span: float = 8.0) -> float:
    """
    Lag-1 autocorrelation of unit white noise through ``spike_filter`` (threshold t sigmas).

    Given the shared pair (x_k, x_(k+1)) = (a, b) the two outputs depend on independent outer
    samples, so E[y_k y_(k+1)] = E_ab[E(y_k | a, b) E(y_(k+1) | a, b)], each inner mean in
    closed form (``spike_moments``); the outer integral on a grid.
    """
    g = np.linspace(-span, span, grid)
    w = stats.norm.pdf(g) * (g[1] - g[0])
    a, b = np.meshgrid(g, g, indexing='ij')
    ya, y2 = spike_moments(a, b, t)
    yb, _ = spike_moments(b, a, t)
    ww = w[:, None] * w[None, :]
    return float(np.sum(ww * ya * yb) / np.sum(ww * y2))


def knock_spectrum(freq, f0: float, decay: float = KNOCK_DECAY) -> np.ndarray:
    """Fourier transform of one unit ring e^(-t / decay) sin(2 pi f0 t), t >= 0."""
    w0 = 2 * np.pi * f0
    return w0 / ((1 / decay + 2j * np.pi * np.asarray(freq)) ** 2 + w0 * w0)


def knock_wave(t: np.ndarray, f0: float) -> np.ndarray:
    """Steady-state periodic train of unit rings (one per KNOCK_PERIOD), closed form."""
    s = -1 / KNOCK_DECAY + 2j * np.pi * f0
    tm = np.mod(t, KNOCK_PERIOD)
    return np.imag(np.exp(s * tm) / (1 - np.exp(s * KNOCK_PERIOD)))


def gradient_pulse(t: np.ndarray) -> np.ndarray:
    """Unit-peak bias of a die sensing dT/dt while the ambient moves along a logistic step."""
    return np.cosh((t - GRAD_AT) / (2 * GRAD_WIDTH)) ** -2.0


def frac_kernel(n: int, d: float = 0.5) -> np.ndarray:
    """First ``n`` coefficients of (1 - z^-1)^-d: h_0 = 1, h_k = h_(k-1) (k - 1 + d) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 1 + d) / k)]


def held_flicker_psd(f, b: float, hold: float = HOLD) -> np.ndarray:
    """One-sided PSD of 1/f samples (spacing ``hold``) held between updates: b^2/(pi f) near 0."""
    x = np.pi * np.asarray(f) * hold
    return b * b * np.abs(np.sin(x)) / (np.pi * x * np.asarray(f))


def fold(z: np.ndarray, half: float) -> np.ndarray:
    """Fold the line onto [-half, half] (mirror images): a free walk so folded is reflected."""
    u = np.mod(z + half, 4 * half)
    return np.where(u <= 2 * half, u, 4 * half - u) - half


def reflected_modes(k: float, half: float, nmax: int = 99):
    """(sd, correlation time) of the reflected walk's exponential modes (odd n, Neumann)."""
    n = np.arange(1, nmax + 1, 2)
    width = 2 * half
    sd = np.sqrt(8.0) * width / (n * np.pi) ** 2
    tc = 2 * width ** 2 / (k * k * (n * np.pi) ** 2)
    return sd, tc


def schmitt_count(theta: np.ndarray, step: float, hyst: float) -> np.ndarray:
    """Counter with hysteresis: up once theta passes the next code edge by ``hyst``, down once
    it falls ``hyst`` below the present code's edge; started at floor(theta_0 / step)."""
    out = np.empty(theta.size, dtype=np.int64)
    c = int(np.floor(theta[0] / step))
    for i, v in enumerate(theta.tolist()):
        if v >= (c + 1) * step + hyst:
            c = int(np.floor((v - hyst) / step))
        elif v < c * step - hyst:
            c = int(np.floor((v + hyst) / step))
        out[i] = c
    return out


def schmitt_map(z: np.ndarray, step: float, hyst: float) -> np.ndarray:
    """Counter error e = theta - step c after a move taking it to ``z`` (the chain's map)."""
    out = np.where(z >= step + hyst, hyst + np.mod(z - hyst, step), z)
    return np.where(z < -hyst, -hyst + np.mod(z + hyst, step), out)


@lru_cache(maxsize=16)
def schmitt_chain(step: float, hyst: float, inc: float, grid: int = CHAIN_GRID):
    """Grid states, transition matrix, stationary law and E[delta; next state] of the error."""
    e = -hyst + (np.arange(grid) + 0.5) * (step + 2 * hyst) / grid
    q = np.linspace(-7, 7, 2801)
    wq = stats.norm.pdf(q)
    wq /= wq.sum()
    z = schmitt_map(e[:, None] + inc * q[None, :], step, hyst)
    j = np.clip((z - e[0]) / (e[1] - e[0]), 0, grid - 1 - 1e-9)
    i0 = np.floor(j).astype(int)
    frac = j - i0
    rows = np.arange(grid)[:, None] * grid
    m, d = np.zeros(grid * grid), np.zeros(grid * grid)
    for shift, part in ((0, 1 - frac), (1, frac)):
        idx, wt = (rows + i0 + shift).ravel(), (wq[None, :] * part).ravel()
        m += np.bincount(idx, wt, grid * grid)
        d += np.bincount(idx, wt * np.tile(inc * q, grid), grid * grid)
    m, d = m.reshape(grid, grid), d.reshape(grid, grid)
    lhs = m.T - np.eye(grid)
    lhs[-1] = 1.0
    p = np.linalg.solve(lhs, np.r_[np.zeros(grid - 1), 1.0])
    return e, m, p, p @ d


def schmitt_excess(mm: int, step: float, hyst: float, inc: float) -> float:
    """(m dt)^2 times the Allan excess of the counter at tau = m dt (white angle walk of sd inc).

    The read angle is theta - e: 3 c0 - 4 c_m + c_2m - 4 K(m) + K(2m), c the error's
    autocovariance, K(m) = sum_(l<m) E[delta_i e_(i+l)] (the error follows the walk)."""
    e, m, p, dvec = schmitt_chain(step, hyst, inc)
    mu = p @ e
    v, kappa, cov = e - mu, [], []
    vec = v.copy()
    for lag in range(2 * mm + 1):
        cov.append(p @ (v * vec))
        kappa.append(dvec @ vec)
        vec = m @ vec
    big_k = np.cumsum(np.r_[0.0, kappa])
    return float(3 * cov[0] - 4 * cov[mm] + cov[2 * mm] - 4 * big_k[mm] + big_k[2 * mm])


def peaking(gain: float, freq: float, q: float, dt: float):
    """(b, a) of the loop's sensitivity S(z): monic biquads, poles at radius e^(-pi f0 dt / q),
    zeros at e^(-gain pi f0 dt / q), both at f0: a peak of ~gain at f0, S(inf) = 1."""
    w0 = 2 * np.pi * freq * dt
    rp, rz = np.exp(-np.pi * freq * dt / q), np.exp(-gain * np.pi * freq * dt / q)
    return (np.array([1.0, -2 * rz * np.cos(w0), rz * rz]),
            np.array([1.0, -2 * rp * np.cos(w0), rp * rp]))


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    inc = n_arw * np.sqrt(dt)                # per-sample white angle increment, rad

    def hampel(x, rng, thresh):
        return spike_filter(x, thresh)

    def knocks(x, rng, amplitude, freq):
        t = np.arange(x.size) * dt + rng.uniform(0, KNOCK_PERIOD)
        return x + amplitude * knock_wave(t, freq)

    def thermal_gradient(x, rng, amplitude):
        return x + amplitude * gradient_pulse(np.arange(x.size) * dt)

    def held_flicker(x, rng, b):
        per = int(round(HOLD / dt))
        m = x.size // per + 2
        f = signal.fftconvolve(rng.standard_normal(m) * b, frac_kernel(m))[:m]
        start = rng.integers(per)
        return x + np.repeat(f, per)[start:start + x.size]

    def railed_walk(x, rng, k):
        half = k * np.sqrt(BOUND_TIME)
        walk = rng.uniform(-half, half) + np.cumsum(rng.standard_normal(x.size)) * k * np.sqrt(dt)
        return x + fold(walk, half)

    def squared_ou(x, rng, sigma, tc):
        a = np.exp(-dt / (2 * tc))
        w = rng.standard_normal(x.size) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal()
        q = signal.lfilter([1.0], [1.0, -a], w)
        return x + sigma / np.sqrt(2) * (q * q - 1)

    def schmitt_counter(x, rng, step, hyst):
        theta = np.r_[0.0, np.cumsum(x)] * dt + (rng.integers(2 ** 20) + rng.uniform()) * step
        return np.diff(schmitt_count(theta, step, hyst)) * step / dt

    def loop_peaking(x, rng, gain, freq, q):
        b, a = peaking(gain, freq, q, dt)
        return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]

    return {
        'internal_lowpass': (hampel, [{'thresh': 3.0 * sig}, {'thresh': 0.0},
                                      {'thresh': 3.97 * sig}]),
        'vibration': (knocks, [{'amplitude': 0.3 * sig, 'freq': 31.2},
                               {'amplitude': 1.0 * sig, 'freq': 18.7},
                               {'amplitude': 0.088 * sig, 'freq': 31.2}]),
        'temperature_drift': (thermal_gradient, [{'amplitude': 1e-3}, {'amplitude': 4e-3},
                                                 {'amplitude': 1.49e-4}]),
        'bias_instability': (held_flicker, [{'b': 3e-4}, {'b': 8e-4}, {'b': 4.73e-5}]),
        'rate_random_walk': (railed_walk, [{'k': 2e-5}, {'k': 6e-5}, {'k': 2.67e-6}]),
        'gauss_markov': (squared_ou, [{'sigma': 1.5e-3, 'tc': 0.6}, {'sigma': 2e-3, 'tc': 15.0},
                                      {'sigma': 2.32e-4, 'tc': 0.6}]),
        'quantization': (schmitt_counter, [{'step': inc / 24, 'hyst': 2 * inc / 24},
                                           {'step': inc / 24, 'hyst': 8 * inc / 24},
                                           {'step': inc / 24, 'hyst': 0.22 * inc / 24}]),
        'resonance': (loop_peaking, [{'gain': 1.3, 'freq': 31.5, 'q': 20.0},
                                     {'gain': 2.0, 'freq': 22.4, 'q': 15.0},
                                     {'gain': 1.0254, 'freq': 31.5, 'q': 20.0}]),
    }


def scalloping(bins: float) -> float:
    """Amplitude gain of a Hann window of ``WELCH_L`` for a line ``bins`` bins from 0 (mod 1)."""
    delta = bins - np.round(bins)
    w = np.hanning(WELCH_L)
    return float(abs(np.sum(w * np.exp(2j * np.pi * delta * np.arange(WELCH_L) / WELCH_L)))
                 / w.sum())


def knock_lines(f0: float, dt: float, fold: int = 3000):
    """Frequencies k / P below Nyquist and rms amplitudes (unit ring) of the sampled train's
    lines: each the lines sampling folds onto it (f + j / dt), power-averaged over the phase."""
    f = np.arange(1, int(0.5 / dt * KNOCK_PERIOD)) / KNOCK_PERIOD
    fa = f[:, None] + np.arange(-fold, fold + 1)[None, :] / dt
    return f, 2 * np.sqrt(np.sum(np.abs(knock_spectrum(fa, f0)) ** 2, axis=1)) / KNOCK_PERIOD


@lru_cache(maxsize=8)
def _grid(dt: float):
    return np.geomspace(1e-9, 0.5 / dt, 40000)


def psd_avar(psd, tau: np.ndarray, dt: float) -> np.ndarray:
    """Allan variance 2 int S(f) sin^4(pi f tau) / (pi f tau)^2 df of a one-sided PSD."""
    f = _grid(dt)
    s = psd(f)
    out = []
    for tt in np.atleast_1d(tau):
        x = np.pi * f * tt
        k = np.where(f * tt > 30, 3.0 / 8.0, np.sin(x) ** 4) / x ** 2
        out.append(2 * np.trapezoid(s * k, f))
    return np.array(out)


def gm_avar(tau, sigma, tc):
    """Allan variance of exponentially correlated noise of sd ``sigma`` (q^2 = 2 sigma^2 / tc)."""
    return markov_avar(tau, tc) * 2 * sigma ** 2 / tc


def peaking_band(gain: float, freq: float, q: float, dt: float):
    """Excess |S|^2 - 1 over the band where it exceeds half its peak, and that band's width."""
    b, a = peaking(gain, freq, q, dt)
    f = np.linspace(0, 0.5 / dt, 200001)
    ex = np.abs(signal.freqz(b, a, worN=f, fs=1 / dt)[1]) ** 2 - 1
    band = ex >= ex.max() / 2
    return float(ex[band].mean()), float(band.sum() * (f[1] - f[0]))


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn = n * dt, n_arw ** 2
    p = params
    if name == 'internal_lowpass':
        return spike_lag1(round(p['thresh'] / sig, 9)) * np.sqrt(n)
    if name == 'vibration':
        f, a = knock_lines(p['freq'], dt)
        z = [scalloping(fk * WELCH_L * dt) ** 2 * (ak * p['amplitude']) ** 2
             * np.sqrt(n * WELCH_L) / (6 * sig ** 2) for fk, ak in zip(f, a)]
        return float(np.sqrt(np.sum(np.square(z))))
    if name == 'temperature_drift':
        s = p['amplitude'] * gradient_pulse(np.arange(n) * dt)
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        inc = n_arw * np.sqrt(dt)
        rel = [schmitt_excess(m, p['step'], p['hyst'], inc) / (m * dt * nn) for m in (1, 10)]
        return abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        ex, width = peaking_band(p['gain'], p['freq'], p['q'], dt)
        return ex * np.sqrt(big_t * width)
    tau = np.geomspace(10 * dt, big_t / 10, 60)
    if name == 'bias_instability':
        tau = tau[tau >= HOLD]
        excess = psd_avar(lambda f: held_flicker_psd(f, p['b']), tau, dt)
    elif name == 'rate_random_walk':
        sd, tc = reflected_modes(p['k'], p['k'] * np.sqrt(BOUND_TIME))
        excess = sum(gm_avar(tau, s, c) for s, c in zip(sd, tc))
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    z = excess / (nn / tau) * np.sqrt(1.5 * big_t / tau / 2)
    return float(z.max())
