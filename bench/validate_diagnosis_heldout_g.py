"""
Held-out set G of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_f.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-F, and
the kinds of departure differ from shape to shape:

- internal_lowpass: a spike filter: the firmware replaces a sample by the median of it and its
  two neighbours when it differs from that median by more than a threshold (a Hampel
  identifier, one sample of latency); with threshold 0 a plain running median of three: an
  order-statistic smoother, data-selective (catalogue moving averages; dev Hann; A binomial;
  B one-pole; C Butterworth; D windowed sinc: linear; E stale reads: a time-varying hold; F
  slew limiting: a rate-limited follower);
- vibration: a knocking mechanism: a relay, valve or piston strikes the mount every 0.8 s and
  each knock rings a mount mode (31.2 Hz, 18.7 Hz) that decays with 0.12 s: a periodic train
  of ring-downs, lines at k / 0.8 s under the ring's Lorentzian-like envelope (the sampled
  lines include what sampling folds onto them) (dev 20 % AM; A chirp; B harmonics; C wander;
  D AM sidebands; E gated; F FM: all continuous tones);
- temperature_drift: a thermal-gradient response: the bias senses dT/dt (a gradient across
  the die), and the lab's HVAC moves the ambient along a logistic step of width w = 150 s
  centred at 2700 s, so the bias is a transient bump A sech^2((t - 2700 s) / 2w) that returns
  to where it started, area 4 w A (catalogue, dev, A, B, F: warm-ups from power-on; C
  cycles; D a step; E parabola);
- bias_instability: held flicker: the on-chip bias compensation writes a correction
  computed from a slow sensor (its 1/f noise) into a register every 10 s, so the bias is a 1/f
  sequence held constant between updates at a fixed cadence: PSD b^2 |sin(pi f H)| / (pi^2
  f^2 H), b^2 / (pi f) below 1 / H with nulls at k / H (catalogue, dev, A-E: continuously
  varying; F: intensity switching);
- rate_random_walk: a walk between rails: the bias random-walks (coefficient K) but is
  confined to +-K sqrt(1800 s) (a charge or stress walk that saturates at both ends),
  reflected at the rails: the free walk folded onto the band; stationary, uniform, a sum of
  exponential modes (Neumann), K^2 tau / 3 at short tau and flattening past ~1000 s
  (catalogue Gaussian; dev held Laplace; A knots; B jumps; C intermittent; D lagged; E bounded
  slope; F stick-slip: all unbounded);
- gauss_markov: a square-law process: the bias is the square of a Gaussian first-order Markov
  process (a fluctuating quadrature error through a square-law term), mean removed:
  chi-square marginal (skew 2 sqrt 2, bounded below), continuous paths, autocorrelation
  exactly exp(-|tau| / tc) with tc half the underlying process's; tc 0.6 s and 15 s
  (catalogue/A/B continuous Gaussian, dev second order, C telegraph, D Gamma OU, E kangaroo,
  F trap count);
- quantization: a counter with hysteresis: the angle counter's comparator counts up only
  once the angle passes the next code edge by h and down only once it falls h below the
  present code's edge (a Schmitt trigger against chatter), so the angle error depends on the
  direction of the last move and follows the angle while inside the dead band; h = 0.22
  (edge), 2 (weak) and 8 (strong) codes of a 0.6 arcsec counter, step = N sqrt(dt) / 24
  (catalogue floor; dev/A/B/C/D staircases; E interpolation error; F missing codes: none with
  memory);
- resonance: loop peaking: the sensor's force-rebalance loop has a small phase margin, so its
  sensitivity function S(z), monic and minimum phase (S(inf) = 1), amplifies the sensor's OWN
  noise near its crossover (31.5 Hz, 22.4 Hz) and attenuates it around it, with zero net log
  gain (Bode: the mean of ln |S|^2 over frequency is 0): a peak made of the record's own
  noise, no added process (catalogue, dev, A-F: an added mode's noise).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- spike filter: lag-1 autocorrelation of the output against 1 / sqrt(n): given the shared
  pair (x_k, x_(k+1)) the two outputs depend on independent outer samples, so E[y_k y_(k+1)]
  is a 2-D integral of products of closed-form conditional means;
- knocks: every line in a Welch bin (Hann, L = 16384) as set B, z_k = g_k^2 a_k^2 sqrt(n L) /
  (6 sigma^2) (a_k the line's phase-averaged amplitude, folded lines included), combined in
  quadrature;
- gradient bump: matched to its own noise-free waveform, mean removed: z = |s - mean(s)| /
  sigma;
- held flicker, railed walk, square-law: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10] (held
  flicker from 10 s): held flicker from its PSD; the railed walk as the sum of its modes'
  first-order Gauss-Markov variances (odd n, sd 2 sqrt 2 W / (n pi)^2, time 2 W^2 / (K n
  pi)^2, W the band's width); square-law the first-order formula;
- hysteresis counter: the angle error e (read = theta - e) is a Markov chain on [-h, step +
  h) driven by the white angle steps, solved on a 600-state grid; Allan excess times tau^2 =
  3 c0 - 4 c_m + c_2m - 4 K(m) + K(2m) (c the error's autocovariance, K(m) the summed
  covariance of the steps with the later errors: the error follows the angle); relative excess
  at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n));
- loop peaking: the mean excess |S|^2 - 1 over the band where it exceeds half its peak, times
  sqrt(T B) (B that band's width): the band power's spread against the white null.
Edges are set at z ~ 4; weak and strong are 6-510x further above. Physical scale: spike
thresholds 3.97 sigma (edge, 0.028 rad/s), 3 sigma, 0 (the plain median); knock rings of
0.035, 0.12 and 0.4 deg/s peak; gradient bumps of 0.0085, 0.057 and 0.23 deg/s peak (with a
5 degC ambient step, 0.5 degC/min at its steepest: 0.017-0.46 (deg/s)/(degC/min), the strong
a badly heat-sunk die); rails at +-0.006 to +-0.15 deg/s; hysteresis of 0.13, 1.2 and 4.8
arcsec; loop peaking of 0.2 dB (edge), 2.3 dB and 6 dB (a ~30 deg phase margin).
"""
from functools import lru_cache

from heldout_detect import allan_taus, allan_z, gm_avar, psd_avar
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


def spike_moments(c: np.ndarray, k: np.ndarray, t: float):
    """E[y], E[y^2] of the filtered sample: centre ``c``, one neighbour ``k``, other N(0, 1)."""
    lo, hi = np.minimum(c, k), np.maximum(c, k)
    pdf, cdf = stats.norm.pdf, stats.norm.cdf
    m1, m2 = c.copy(), c * c
    for edge, mass in ((lo, cdf(lo)), (hi, stats.norm.sf(hi))):
        out = np.abs(edge - c) > t
        m1 = m1 + np.where(out, (edge - c) * mass, 0.0)
        m2 = m2 + np.where(out, (edge * edge - c * c) * mass, 0.0)
    q1, p2 = np.minimum(hi, c - t), np.maximum(lo, c + t)     # [lo, hi] outside (c -+ t)
    for p, q, ok in ((lo, q1, q1 > lo), (p2, hi, hi > p2)):
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
    """Count up past the next code edge + ``hyst``, down below this code's edge - ``hyst``."""
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
    """
    Return (m dt)^2 times the counter's Allan excess at tau = m dt (angle steps of sd inc).

    The read angle is theta - e: 3 c0 - 4 c_m + c_2m - 4 K(m) + K(2m), c the error's
    autocovariance, K(m) = sum_(l<m) E[delta_i e_(i+l)] (the error follows the walk).
    """
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
    """Return monic (b, a) of S(z): poles e^(-pi f0 dt / q), zeros e^(-gain pi f0 dt / q)."""
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
    """Return the lines k / P below Nyquist, rms amplitudes per unit ring, folded lines added."""
    f = np.arange(1, int(0.5 / dt * KNOCK_PERIOD)) / KNOCK_PERIOD
    fa = f[:, None] + np.arange(-fold, fold + 1)[None, :] / dt
    return f, 2 * np.sqrt(np.sum(np.abs(knock_spectrum(fa, f0)) ** 2, axis=1)) / KNOCK_PERIOD


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
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        tau = tau[tau >= HOLD]
        excess = psd_avar(lambda f: held_flicker_psd(f, p['b']), tau, dt)
    elif name == 'rate_random_walk':
        sd, tc = reflected_modes(p['k'], p['k'] * np.sqrt(BOUND_TIME))
        excess = sum(gm_avar(tau, s, c) for s, c in zip(sd, tc))
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
