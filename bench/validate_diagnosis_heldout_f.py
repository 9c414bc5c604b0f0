"""
Held-out set F of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_e.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-E, and
the kinds of departure differ from shape to shape:

- internal_lowpass: slew-rate limiting, a nonlinear smoother: a torque-limited rebalance loop
  (or a slew-limited output stage) follows the sensed rate only as fast as its limit S allows,
  y_k = y_(k-1) + clip(x_k - y_(k-1), -S dt, S dt): small steps pass exactly, large ones are
  cut and the rest carried to the next samples (catalogue moving averages; dev Hann; A binomial;
  B one-pole; C Butterworth; D windowed sinc: linear filters; E stale reads: a time-varying
  hold; none nonlinear);
- vibration: a hunting pump: a drive-fed pump (or fan) whose pressure loop limit-cycles at
  0.3 Hz, so its rotation tone (24.6 Hz, 16.3 Hz) is frequency modulated with index
  beta = 2.405 (speed swing +-beta 0.3 Hz = +-0.72 Hz, 3-4.4 %): a constant envelope, lines at
  f + k 0.3 Hz of amplitude |J_k(beta)|, and no line at f itself (J_0(2.405) ~ 0) (dev 20 %
  AM; A linear chirp; B harmonics; C random frequency wander; D AM sidebands; E gated);
- temperature_drift: an underdamped oven: after power-on the sensor's heater loop overshoots
  and the set-point error, and the bias with it, rings down: A e^(-a t) (cos w_d t + a / w_d
  sin w_d t), period 900 s, damping ratio 0.2 (successive extrema -0.53 x each other), from A
  with zero slope at t = 0: sign changes (catalogue exponential, dev hyperbolic, A two
  exponentials, B ramp: monotonic warm-ups; C steady thermostat cycles; D a step; E parabola);
- bias_instability: noise switching: 1/f noise whose source toggles between two configurations
  (RTS-modulated 1/f noise of a bistable defect in the front end): the drive of the exact 1/f
  kernel (1 - z^-1)^-1/2 has an intensity that switches between 1.8 and 0.2 of its mean at
  Poisson times (mean dwell 600 s): non-stationary, a Gaussian scale mixture, PSD b^2 / (pi f)
  only on average (catalogue, dev, A-E: all stationary);
- rate_random_walk: stick-slip: the stress that sets the bias random-walks (coefficient K),
  but the die attach holds by static friction until the stress is h = K sqrt(60 s) away from
  it, then slips: a play operator on a Gaussian walk; the bias is constant for stretches (99 %
  of the 100 Hz samples) and follows the walk in short slips, K^2 tau / 3 at long tau
  (catalogue Gaussian; dev Laplace held at fixed times; A knots; B Poisson jumps; C
  intermittent; D thermally lagged; E bounded slope);
- gauss_markov: generation-recombination noise: traps capture charges at Poisson times (rate
  M / tc) and release each after an exponential time (mean tc), so the number trapped is
  Poisson (mean M = 2) with autocorrelation exactly exp(-|tau| / tc); the bias steps by one
  charge, q = sigma / sqrt(M): integer levels, skew 1 / sqrt(M) = 0.71; tc 0.6 s and 15 s
  (catalogue/A/B continuous Gaussian, dev second order, C two-level telegraph, D Gamma OU,
  E kangaroo);
- quantization: missing codes: one bit of the angle counter's read-out word is stuck at 0 (an
  open data line), so the read count skips 2^j codes after every 2^j: the angle error is a
  square wave of period 2^(j+1) steps (0 or -2^j steps) on top of the fine counter's floor;
  j = 2 (edge), 4 (weak), 5 (strong) on a 0.6 arcsec counter, step = N sqrt(dt) / 24 (a
  digital fault: catalogue floor; dev/A/B/C/D uniform or shaped staircases; E smooth
  interpolation error);
- resonance: a parametrically pumped mode: a structural mode whose stiffness is modulated at
  exactly 2 f0 (a shaft or a drive at twice the mode frequency), 80 % of the way to threshold:
  the quadrature in phase with the pump is de-damped to g (1 - 0.8), the other damped to
  g (1 + 0.8) (g = pi f0 / q), so the process is cyclostationary (its variance swings by
  +-80 % at 2 f0) and its line is a narrow Lorentzian (width 0.2 f0 / q, 90 % of the power) on
  a broad one (catalogue, dev, A, B, C: stationary noise-driven modes; D Duffing; E limit
  cycle).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- slew limit: lag-1 autocorrelation of the output against 1 / sqrt(n); the output is a Markov
  chain, y' = min(max(x, y - s), y + s), whose stationary law is solved on a 401-node grid
  and E[y y'] taken from the exact conditional mean;
- hunting pump: every FM line in a Welch bin (Hann, L = 16384) as set B, z_k = g_k^2 (A J_k)^2
  sqrt(n L) / (6 sigma^2) (g_k the scalloping gain), combined in quadrature;
- oven ringing: matched to its own noise-free waveform, mean removed (an unknown bias), as set
  C's thermostat line: z = |s - mean(s)| / sigma;
- noise switching, stick-slip, traps: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: the
  switching flicker's mean Allan variance is its mean intensity's (the intensity is
  independent of the drive), from the sampled kernel's PSD exactly; stick-slip K^2 tau / 3
  (the play's offset is a reflected walk, uniform on +-h, correlation time 8 h^2 /
  (pi^2 K^2) = 49 s: ~1 % at the T / 10 that sets z); traps the first-order Gauss-Markov
  formula (their autocorrelation);
- missing codes: the angle error is periodic, so for an angle walking by the white noise its
  autocovariance is c(m) = 2 sum_h |c_h|^2 exp(-2 pi^2 h^2 m dt N^2 / P^2) (Fourier
  coefficients c_h over one period P = 2^(j+1) step; the mean rate's phase drift left out, as
  set E): relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) at dt less at 10 dt,
  against sqrt(3 / n + 40 / (3 n));
- pumped mode: the narrow line alone, half of its power sigma_r^2 (1 + 0.8) / 2 within its
  width 0.2 f0 / q against the white band power (as set B): z = sigma_r^2 0.9 sqrt(T) /
  (4 sigma^2 dt sqrt(0.2 f0 / q)).
Edges are set at z ~ 4; weak and strong are 8-870x further above. Physical scale: slew limits
of 2.8 (edge), 1.4 and 0.7 rad/s^2 (the 5 s swing needs 0.55); the strong oven error 4e-3
rad/s (0.23 deg/s) is ~17 degC at the ADIS16405's 0.0135 deg/s/degC; the stuck bits leave gaps
of 4, 16 and 32 codes (2.4, 9.6 and 19 arcsec).
"""
from functools import lru_cache

from heldout_detect import allan_taus, allan_z, gm_avar, psd_avar
import numpy as np
from scipy import signal, special, stats

WELCH_L = 16384
HUNT_BETA = 2.405             # FM index of the hunting pump (J0(beta) ~ 0: no carrier line)
HUNT_FM = 0.3                 # Hz, the pressure loop's limit cycle
RING_ZETA, RING_PERIOD = 0.2, 900.0   # oven loop: damping ratio, ringing period (s)
SWITCH_DWELL, SWITCH_DEPTH = 600.0, 0.8   # noise switching: mean dwell (s), +-depth of intensity
STICK_HOLD = 60.0             # s: play half width h = k sqrt(STICK_HOLD)
GR_MEAN = 2.0                 # mean number of occupied traps
PUMP = 0.8                    # parametric pump depth, as a fraction of the threshold
MC_GRID = 401                 # states of the slew limiter's Markov chain (detectability)


def frac_kernel(n: int, d: float = 0.5) -> np.ndarray:
    """First ``n`` coefficients of (1 - z^-1)^-d: h_0 = 1, h_k = h_(k-1) (k - 1 + d) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 1 + d) / k)]


def telegraph(n: int, dt: float, tc: float, rng) -> np.ndarray:
    """Symmetric +-1 random telegraph signal, autocorrelation exp(-|lag| / tc), stationary."""
    flip = rng.random(n) < (1.0 - np.exp(-dt / tc)) / 2.0
    flip[0] = rng.random() < 0.5
    return 1.0 - 2.0 * (np.cumsum(flip) % 2)


def slew(x: np.ndarray, s: float) -> np.ndarray:
    """Slew-rate limiter: y_k = y_(k-1) + clip(x_k - y_(k-1), -s, s), started at x_0."""
    out, y = np.empty_like(x), float(x[0])
    for i, v in enumerate(x.tolist()):
        y = min(max(v, y - s), y + s)
        out[i] = y
    return out


def play(x: np.ndarray, half: float) -> np.ndarray:
    """Play operator (stick-slip) of half width ``half``, started at x_0."""
    out, y = np.empty_like(x), float(x[0])
    for i, v in enumerate(x.tolist()):
        y = min(max(y, v - half), v + half)
        out[i] = y
    return out


def ring(t: np.ndarray) -> np.ndarray:
    """Return the oven loop's unit set-point error after power-on (1 at t = 0, slope 0)."""
    wd = 2 * np.pi / RING_PERIOD
    a = RING_ZETA * wd / np.sqrt(1 - RING_ZETA ** 2)
    return np.exp(-a * t) * (np.cos(wd * t) + a / wd * np.sin(wd * t))


def stuck_read(count: np.ndarray, bit: int) -> np.ndarray:
    """Return the counter word ``count`` as read with ``bit`` stuck at 0."""
    return count & ~np.int64(1 << bit)


def stuck_error(theta: np.ndarray, step: float, bit: int) -> np.ndarray:
    """Angle error theta - step read(floor(theta / step)): periodic, period 2^(bit+1) step."""
    return theta - step * stuck_read(np.floor(theta / step).astype(np.int64), bit)


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    inc = n_arw * np.sqrt(dt)                # per-sample white angle increment, rad

    def slew_limited(x, rng, rate):
        return slew(x, rate * dt)

    def hunting(x, rng, amplitude, freq):
        t = np.arange(x.size) * dt
        ph = rng.uniform(0, 2 * np.pi, 2)
        return x + amplitude * np.sin(2 * np.pi * freq * t
                                      + HUNT_BETA * np.sin(2 * np.pi * HUNT_FM * t + ph[0])
                                      + ph[1])

    def oven_ring(x, rng, amplitude):
        return x + amplitude * ring(np.arange(x.size) * dt)

    def switching_flicker(x, rng, b):
        level = 1.0 + SWITCH_DEPTH * telegraph(x.size, dt, SWITCH_DWELL / 2, rng)
        w = rng.standard_normal(x.size) * b * np.sqrt(level)
        return x + signal.fftconvolve(w, frac_kernel(x.size))[:x.size]

    def stick_slip(x, rng, k):
        walk = np.cumsum(rng.standard_normal(x.size)) * k * np.sqrt(dt)
        return x + play(walk, k * np.sqrt(STICK_HOLD))

    def trap_count(x, rng, sigma, tc):
        n, big_t = x.size, x.size * dt
        start = np.r_[np.zeros(rng.poisson(GR_MEAN)),
                      rng.uniform(0, big_t, rng.poisson(GR_MEAN * big_t / tc))]
        end = start + rng.exponential(tc, start.size)
        edges = np.zeros(n + 1)
        np.add.at(edges, np.minimum(np.ceil(start / dt).astype(int), n), 1.0)
        np.add.at(edges, np.minimum(np.ceil(end / dt).astype(int), n), -1.0)
        return x + sigma / np.sqrt(GR_MEAN) * (np.cumsum(edges)[:n] - GR_MEAN)

    def stuck_counter(x, rng, step, bit):
        theta = np.r_[0.0, np.cumsum(x)] * dt + (rng.integers(2 ** 20) + rng.uniform()) * step
        return np.diff(stuck_read(np.floor(theta / step).astype(np.int64), bit)) * step / dt

    def pumped_mode(x, rng, sigma, freq, q):
        g = np.pi * freq / q                                  # amplitude decay rate, 1/s
        t = np.arange(x.size) * dt
        quad = []
        for rate, var in ((g * (1 - PUMP), 1 + PUMP), (g * (1 + PUMP), 1 - PUMP)):
            a = np.exp(-rate * dt)
            w = rng.standard_normal(x.size) * np.sqrt(1 - a * a)
            w[0] = rng.standard_normal()
            quad.append(sigma * np.sqrt(var) * signal.lfilter([1.0], [1.0, -a], w))
        arg = 2 * np.pi * freq * t + rng.uniform(0, 2 * np.pi)
        return x + quad[0] * np.cos(arg) + quad[1] * np.sin(arg)

    return {
        'internal_lowpass': (slew_limited, [{'rate': 2.0 * sig / dt}, {'rate': 1.0 * sig / dt},
                                            {'rate': 3.96 * sig / dt}]),
        'vibration': (hunting, [{'amplitude': 0.12 * sig, 'freq': 24.6},
                                {'amplitude': 0.3 * sig, 'freq': 16.3},
                                {'amplitude': 0.0231 * sig, 'freq': 24.6}]),
        'temperature_drift': (oven_ring, [{'amplitude': 1.5e-3}, {'amplitude': 4e-3},
                                          {'amplitude': 1.96e-4}]),
        'bias_instability': (switching_flicker, [{'b': 3e-4}, {'b': 8e-4}, {'b': 4.73e-5}]),
        'rate_random_walk': (stick_slip, [{'k': 2e-5}, {'k': 6e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (trap_count, [{'sigma': 1.5e-3, 'tc': 0.6}, {'sigma': 2e-3, 'tc': 15.0},
                                      {'sigma': 2.32e-4, 'tc': 0.6}]),
        'quantization': (stuck_counter, [{'step': inc / 24, 'bit': 4},
                                         {'step': inc / 24, 'bit': 5},
                                         {'step': inc / 24, 'bit': 2}]),
        'resonance': (pumped_mode, [{'sigma': 0.3 * sig, 'freq': 21.3, 'q': 25.0},
                                    {'sigma': 0.8 * sig, 'freq': 33.7, 'q': 20.0},
                                    {'sigma': 0.0294 * sig, 'freq': 21.3, 'q': 25.0}]),
    }


@lru_cache(maxsize=16)
def slew_lag1(s: float, grid: int = MC_GRID, span: float = 7.0) -> float:
    """
    Lag-1 autocorrelation of unit white noise through the slew limiter of step ``s`` (sigmas).

    y is a Markov chain, y' = min(max(x, y - s), y + s): its stationary law on a grid (the
    clipped Gaussian's continuous part binned, its two atoms split to the neighbouring nodes),
    then E[y y'] from the exact conditional mean E[y' | y].
    """
    y = np.linspace(-span, span, grid)
    h = y[1] - y[0]
    edges = np.clip(np.r_[y - h / 2, y[-1] + h / 2][None, :], y[:, None] - s, y[:, None] + s)
    m = np.diff(stats.norm.cdf(edges), axis=1)
    rows = np.arange(grid)
    for pos, mass in ((y - s, stats.norm.cdf(y - s)), (y + s, stats.norm.sf(y + s))):
        j = np.clip((pos - y[0]) / h, 0, grid - 1 - 1e-9)
        i0 = np.floor(j).astype(int)
        np.add.at(m, (rows, i0), mass * (1 - (j - i0)))
        np.add.at(m, (rows, i0 + 1), mass * (j - i0))
    p = stats.norm.pdf(y) / stats.norm.pdf(y).sum()
    for _ in range(80):
        p = p @ m
    a, b = y - s, y + s
    cond = (a * stats.norm.cdf(a) + stats.norm.pdf(a) - stats.norm.pdf(b)
            + b * stats.norm.sf(b))                              # E[y' | y]
    mu = p @ y
    return float((p @ (y * cond) - mu * mu) / (p @ y ** 2 - mu * mu))


def scalloping(bins: float) -> float:
    """Amplitude gain of a Hann window of ``WELCH_L`` for a line ``bins`` bins from 0 (mod 1)."""
    delta = bins - np.round(bins)
    w = np.hanning(WELCH_L)
    return float(abs(np.sum(w * np.exp(2j * np.pi * delta * np.arange(WELCH_L) / WELCH_L)))
                 / w.sum())


def hunting_lines(freq: float, kmax: int = 8):
    """Frequencies and amplitudes (per unit tone amplitude) of the FM lines, |J_k(beta)|."""
    k = np.arange(-kmax, kmax + 1)
    return freq + k * HUNT_FM, np.abs(special.jv(k, HUNT_BETA))


def flicker_psd(f, b, dt):
    """One-sided PSD of the flicker at mean intensity (sampled kernel, exact): b^2 / (pi f)."""
    return 2 * b * b * dt / (2 * np.sin(np.pi * f * dt))


def stuck_coefficients(step: float, bit: int, m: int = 4096) -> np.ndarray:
    """|c_h|^2, h = 1..m/2 - 1, of the stuck-bit angle error over its period 2^(bit+1) step."""
    period = 2 ** (bit + 1) * step
    e = stuck_error((np.arange(m) + 0.5) / m * period, step, bit)
    c = np.fft.rfft(e) / m
    return np.abs(c[1:m // 2]) ** 2


def stuck_cov(lag, step: float, bit: int, inc: float) -> np.ndarray:
    """Autocovariance at ``lag`` samples of the stuck-bit angle error (angle walk of sd inc)."""
    c2 = stuck_coefficients(step, bit)
    h = np.arange(1, c2.size + 1)
    period = 2 ** (bit + 1) * step
    lag = np.atleast_1d(np.asarray(lag, float))
    return np.array([2 * np.sum(c2 * np.exp(-2 * np.pi ** 2 * h * h * m * inc ** 2
                                            / period ** 2)) for m in lag])


def stuck_excess(m: int, step: float, bit: int, inc: float) -> float:
    """Allan variance excess of the stuck-bit angle error at tau = m dt, times (m dt)^2."""
    c = stuck_cov([0, m, 2 * m], step, bit, inc)
    return float(3 * c[0] - 4 * c[1] + c[2])


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn = n * dt, n_arw ** 2
    p = params
    if name == 'internal_lowpass':
        return slew_lag1(round(p['rate'] * dt / sig, 9)) * np.sqrt(n)
    if name == 'vibration':
        f, a = hunting_lines(p['freq'])
        z = [scalloping(fk * WELCH_L * dt) ** 2 * (ak * p['amplitude']) ** 2
             * np.sqrt(n * WELCH_L) / (6 * sig ** 2) for fk, ak in zip(f, a)]
        return float(np.sqrt(np.sum(np.square(z))))
    if name == 'temperature_drift':
        s = p['amplitude'] * ring(np.arange(n) * dt)
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        inc = n_arw * np.sqrt(dt)
        rel = [stuck_excess(m, p['step'], p['bit'], inc) / (m * dt * nn) for m in (1, 10)]
        return (rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        narrow = p['freq'] / p['q'] * (1 - PUMP)
        return (p['sigma'] ** 2 * (1 + PUMP) / 2 * np.sqrt(big_t)
                / (4 * sig ** 2 * dt * np.sqrt(narrow)))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: flicker_psd(f, p['b'], dt), tau, dt)
    elif name == 'rate_random_walk':
        excess = p['k'] ** 2 * tau / 3
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
