"""
Held-out set E of static effect shapes: written in session 7 without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_d.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-D:

- internal_lowpass: stale reads: the sensor's internal output data rate runs slower than the
  host polls it (an RC oscillator off by 0.5-15 %, or a nominally lower ODR), so the host reads
  the last internal sample again now and then: y_k = x_floor(k r + phase), r = f_int / f_out,
  a duplicate every 1 / (1 - r) samples. A time-varying zero-order hold, not a filter: the
  output keeps the input's variance and values (catalogue moving averages; dev Hann; A binomial;
  B one-pole; C Butterworth; D windowed sinc: all linear time-invariant smoothing);
- vibration: a cycling compressor (refrigerator, chiller, vacuum pump): its motor tone (24.2 Hz
  4-pole, 48.3 Hz 2-pole slip speed) is on for 40 % of a 600 s cycle, restarting with a new
  phase each time: a gated tone (dev 20 % AM; A chirp; B harmonics; C wandering fan; D gearbox
  sidebands: all on for the whole record);
- temperature_drift: a turnover curve: the bias is quadratic in temperature (quartz-like
  turnover of the bias-temperature curve) while the room or an oven ramps linearly through the
  turnover, its vertex at a random time in the middle 40 %: a parabola in time
  a ((t - t_v) / (T / 2))^2 (catalogue exponential, dev hyperbolic, A two exponentials, B ramp:
  warm-ups; C periodic thermostat; D step mid-record: none a polynomial with an extremum);
- bias_instability: Dutta-Horn flicker with a tilted slope: a non-uniform trap activation-energy
  distribution makes the PSD 1 / f^0.8 (measured MEMS slopes are 0.7-1.3), one-sided
  S(f) = (b^2 / pi) f^-0.8 (f in Hz), Gaussian, by the fractional-integration kernel
  (1 - z^-1)^-0.4 (catalogue, A, B, C, D, dev: all aim at exactly 1 / f);
- rate_random_walk: an integrated telegraph: the bias ramps at +-v and its direction flips at
  Poisson times (mean 20 s), as an oven-stabilised gyro's bias follows a bang-bang heater that
  switches with the load: piecewise linear, K^2 = 2 v^2 tc at long times (catalogue rough
  Gaussian; dev held Laplace; A knots; B jumps; C intermittent; D thermally lagged: none with a
  bounded slope);
- gauss_markov: a kangaroo process: the bias jumps to a new independent Gaussian level at Poisson
  times (rate 1 / tc; a laser source's mode hops) and holds it: piecewise constant, Gaussian
  marginal, autocorrelation exactly exp(-|tau| / tc); tc 0.8 s and 12 s (catalogue/A/B
  continuous first order, dev second order, C two-level telegraph, D exponential pulses);
- quantization: the sub-fringe interpolation error of an interpolated angle counter (RLG or
  interferometric read-out): offset and gain mismatch of the quadrature detector pair leave a
  first and second harmonic of the fringe (Heydemann), e(theta) = depth step (sin(2 pi theta /
  step) + 2/3 sin(4 pi theta / step + 1)): a smooth periodic function of the angle, no
  staircase (catalogue floor, dev/A/B/C/D staircases, uniform or shaped errors);
- resonance: a parasitic mode in self-oscillation (a limit cycle pumped by the drive or a
  marginal control loop): constant amplitude, phase diffusing as a Wiener process of rate
  2 pi f0 / q, so a Lorentzian line of width f0 / q like a damped mode but an arcsine marginal
  and a constant envelope (catalogue, dev, A, B, C: noise-driven modes; D Duffing).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- stale reads: lag-1 autocorrelation of a white input, 1 - r, against 1 / sqrt(n);
- compressor: the tone in a Welch bin (Hann, L = 16384) as set B, times the 0.4 duty:
  z = 0.4 g^2 A^2 sqrt(n L) / (6 sigma^2), g the scalloping gain;
- turnover: the curvature (Legendre P2) component of the record, 2 a / 3 whatever the vertex,
  on a sample vector of norm sqrt(n / 5): z = (2 a / 3) sqrt(n / 5) / sigma;
- tilted flicker, integrated telegraph, kangaroo: Allan variance excess over N^2 / tau in units
  of the white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]:
  the first two from their PSDs (sampled kernel, exactly; telegraph 4 v^2 tc / (1 + (2 pi f
  tc)^2) / (2 pi f)^2), the kangaroo the first-order Gauss-Markov formula;
- interpolation error: an angle error of autocovariance c(m) = sum_h (a_h depth step)^2 / 2
  exp(-2 pi^2 h^2 m dt N^2 / step^2) (the angle walks by the white noise; the mean rate's
  cos term is left out): relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) at dt less
  at 10 dt, against sqrt(3 / n + 40 / (3 n)) (as sets B-D);
- limit cycle: half of sigma_r^2 within the Lorentzian's width f0 / q against the white band
  power (as set B): z = sigma_r^2 sqrt(T) / (4 sigma^2 dt sqrt(f0 / q)).
Edges are set at z ~ 4; weak and strong are 8-900x further above. Physical scale: the strong
turnover (3 mrad/s = 0.17 deg/s at the ends) is a cheap MEMS's curvature of ~3e-4 deg/s/degC^2
over a +-25 degC oven ramp; the interpolation errors (3-15 % of a 0.28-0.42 mrad period) are a
trimmed to a badly trimmed detector pair; the strong ODR mismatch is an 85 Hz ODR polled at
100 Hz, the edge's 0.5 % an RC oscillator's tolerance.
"""
from heldout_detect import allan_taus, allan_z, gm_avar, psd_avar
import numpy as np
from scipy import signal

WELCH_L = 16384
CYCLE, DUTY = 600.0, 0.4      # s, compressor cycle; share of it running
VERTEX_SPAN = (0.3, 0.7)      # turnover time, fraction of the record
ALPHA = 0.8                   # flicker PSD slope
FLIP_TC = 20.0                # s, correlation time of the heater's telegraph
HARM = ((1, 1.0, 0.0), (2, 2.0 / 3.0, 1.0))   # interpolation error: harmonic, amplitude, phase


def frac_kernel(n: int, d: float = ALPHA / 2) -> np.ndarray:
    """First ``n`` coefficients of (1 - z^-1)^-d: h_0 = 1, h_k = h_(k-1) (k - 1 + d) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 1 + d) / k)]


def telegraph(n: int, dt: float, tc: float, rng) -> np.ndarray:
    """Symmetric +-1 random telegraph signal, autocorrelation exp(-|lag| / tc), stationary."""
    flip = rng.random(n) < (1.0 - np.exp(-dt / tc)) / 2.0
    flip[0] = rng.random() < 0.5
    return 1.0 - 2.0 * (np.cumsum(flip) % 2)


def interp_error(theta: np.ndarray, step: float, depth: float) -> np.ndarray:
    """Interpolation error of the angle ``theta``: fringe ``step``, first harmonic ``depth``."""
    return depth * step * sum(a * np.sin(2 * np.pi * h * theta / step + ph)
                              for h, a, ph in HARM)


def gated(t: np.ndarray, phase: float) -> np.ndarray:
    """Compressor state (0 / 1) at ``t``, cycle phase ``phase`` in [0, 1), and the cycle index."""
    c = t / CYCLE + phase
    return (c % 1.0) < DUTY, np.floor(c).astype(int)


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    inc = n_arw * np.sqrt(dt)                # per-sample white angle increment, rad

    def stale_reads(x, rng, ratio):
        j = np.floor(np.arange(x.size) * ratio + rng.uniform()).astype(int)
        return x[np.minimum(j, x.size - 1)]

    def compressor(x, rng, amplitude, freq):
        t = np.arange(x.size) * dt
        on, cycle = gated(t, rng.uniform())
        phase = rng.uniform(0, 2 * np.pi, cycle.max() + 1)[cycle]
        return x + on * amplitude * np.sin(2 * np.pi * freq * t + phase)

    def turnover(x, rng, amplitude):
        t = np.arange(x.size) * dt
        t_v = rng.uniform(*VERTEX_SPAN) * x.size * dt
        return x + amplitude * ((t - t_v) / (x.size * dt / 2)) ** 2

    def tilted_flicker(x, rng, b):
        sw = b * np.sqrt((2 * np.pi * dt) ** ALPHA / (2 * np.pi * dt))
        w = rng.standard_normal(x.size) * sw
        return x + signal.fftconvolve(w, frac_kernel(x.size))[:x.size]

    def heater_walk(x, rng, k):
        v = k / np.sqrt(2 * FLIP_TC)
        return x + np.cumsum(v * telegraph(x.size, dt, FLIP_TC, rng)) * dt

    def kangaroo(x, rng, sigma, tc):
        hop = rng.random(x.size) < -np.expm1(-dt / tc)
        seg = np.cumsum(hop)
        return x + sigma * rng.standard_normal(seg[-1] + 1)[seg]

    def interpolated_counter(x, rng, step, depth):
        theta = np.r_[0.0, np.cumsum(x)] * dt + rng.uniform(0, step)
        return np.diff(theta + interp_error(theta, step, depth)) / dt

    def limit_cycle(x, rng, sigma, freq, q):
        diff = 2 * np.pi * freq / q                       # phase diffusion rate, rad^2/s
        phi = np.cumsum(rng.standard_normal(x.size)) * np.sqrt(diff * dt)
        t = np.arange(x.size) * dt
        return x + sigma * np.sqrt(2.0) * np.cos(2 * np.pi * freq * t + phi
                                                 + rng.uniform(0, 2 * np.pi))

    return {
        'internal_lowpass': (stale_reads, [{'ratio': 0.96}, {'ratio': 0.85},
                                           {'ratio': 0.9953}]),
        'vibration': (compressor, [{'amplitude': 0.12 * sig, 'freq': 24.2},
                                   {'amplitude': 0.3 * sig, 'freq': 48.3},
                                   {'amplitude': 0.0236 * sig, 'freq': 24.2}]),
        'temperature_drift': (turnover, [{'amplitude': 1e-3}, {'amplitude': 3e-3},
                                         {'amplitude': 1.1e-4}]),
        'bias_instability': (tilted_flicker, [{'b': 3e-4}, {'b': 8e-4}, {'b': 1.035e-4}]),
        'rate_random_walk': (heater_walk, [{'k': 2e-5}, {'k': 6e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (kangaroo, [{'sigma': 1.5e-3, 'tc': 0.8}, {'sigma': 2e-3, 'tc': 12.0},
                                    {'sigma': 2.16e-4, 'tc': 0.8}]),
        'quantization': (interpolated_counter, [{'step': 4.0 * inc, 'depth': 0.1},
                                                {'step': 6.0 * inc, 'depth': 0.15},
                                                {'step': 4.0 * inc, 'depth': 0.029}]),
        'resonance': (limit_cycle, [{'sigma': 0.3 * sig, 'freq': 14.5, 'q': 40.0},
                                    {'sigma': 0.8 * sig, 'freq': 39.0, 'q': 25.0},
                                    {'sigma': 0.0337 * sig, 'freq': 14.5, 'q': 40.0}]),
    }


def scalloping(bins: float) -> float:
    """Amplitude gain of a Hann window of ``WELCH_L`` for a line ``bins`` bins from 0 (mod 1)."""
    delta = bins - np.round(bins)
    w = np.hanning(WELCH_L)
    return float(abs(np.sum(w * np.exp(2j * np.pi * delta * np.arange(WELCH_L) / WELCH_L)))
                 / w.sum())


def flicker_psd(f, b, dt):
    """One-sided PSD of the tilted flicker (sampled kernel, exact): (b^2 / pi) f^-0.8 at low f."""
    sw2 = b * b * (2 * np.pi * dt) ** ALPHA / (2 * np.pi * dt)
    return 2 * sw2 * dt * (2 * np.sin(np.pi * f * dt)) ** -ALPHA


def heater_psd(f, k):
    """One-sided PSD of the integrated telegraph of RRW coefficient ``k``."""
    v2 = k * k / (2 * FLIP_TC)
    return 4 * v2 * FLIP_TC / (1 + (2 * np.pi * f * FLIP_TC) ** 2) / (2 * np.pi * f) ** 2


def interp_cov(m, step: float, depth: float, inc: float, mu_dt: float = 0.0) -> np.ndarray:
    """Autocovariance at lag ``m`` of the interpolation error (angle walk of sd ``inc``)."""
    m = np.asarray(m, float)
    return sum((a * depth * step) ** 2 / 2
               * np.exp(-2 * np.pi ** 2 * h * h * m * inc ** 2 / step ** 2)
               * np.cos(2 * np.pi * h * m * mu_dt / step) for h, a, _ in HARM)


def interp_excess(m: int, step: float, depth: float, inc: float, mu_dt: float = 0.0) -> float:
    """Allan variance excess of the interpolation error at tau = m dt, times (m dt)^2."""
    c = interp_cov([0, m, 2 * m], step, depth, inc, mu_dt)
    return float(3 * c[0] - 4 * c[1] + c[2])


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn = n * dt, n_arw ** 2
    p = params
    if name == 'internal_lowpass':
        return (1.0 - p['ratio']) * np.sqrt(n)
    if name == 'vibration':
        return (DUTY * scalloping(p['freq'] * WELCH_L * dt) ** 2 * p['amplitude'] ** 2
                * np.sqrt(n * WELCH_L) / (6 * sig ** 2))
    if name == 'temperature_drift':
        return 2 * p['amplitude'] / 3 * np.sqrt(n / 5) / sig
    if name == 'quantization':
        inc = n_arw * np.sqrt(dt)
        rel = [interp_excess(m, p['step'], p['depth'], inc) / (m * dt * nn) for m in (1, 10)]
        return (rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        return (p['sigma'] ** 2 * np.sqrt(big_t)
                / (4 * sig ** 2 * dt * np.sqrt(p['freq'] / p['q'])))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: flicker_psd(f, p['b'], dt), tau, dt)
    elif name == 'rate_random_walk':
        excess = psd_avar(lambda f: heater_psd(f, p['k']), tau, dt)
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
