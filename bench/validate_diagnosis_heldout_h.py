"""
Held-out set H of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_g.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-G, and
the kinds of departure differ from shape to shape:

- internal_lowpass: skipped conversions: every m-th conversion slot the converter reads
  another channel and the firmware fills the gap with the mean of its two neighbours
  (two-sided linear interpolation): a periodically time-varying, non-causal smoother acting on
  one sample in m;
- vibration: a rocking kick: every 1.73 s a stepping mechanism on the bench jerks the mount,
  which rocks and returns within one sample period: a doublet (+a, then -a one sample later)
  per kick, no net angle: a comb of lines k / 1.73 s whose amplitudes rise as sin(pi f dt)
  toward Nyquist;
- temperature_drift: a compensation table's residual: the die warms by 5 degC with 1500 s,
  and the firmware subtracts c T with T read in 0.25 degC table cells, so the output keeps
  c (T - floor(T)): a sawtooth whose teeth lengthen as the warming slows (height h = c LSB);
- bias_instability: dispersive trapping: at random instants (mean 20 s apart) a charge is
  trapped and then relaxes by dispersive transport, t^(-1/2): a sparse train of +-steps,
  each with a slowly decaying tail, whose sum is 1/f (PSD b^2 dt / sin(pi f dt)) yet visibly
  event-like, not Gaussian;
- rate_random_walk: a walk with memory: stress in the die attach relaxes by creep with
  power-law kinetics, so the bias walks with persistent increments: fractional Brownian
  motion (white noise through (1 - z^-1)^-1.25, Hurst 0.75), rate PSD ~ f^-2.5, Allan
  ~ tau^1.5: steeper than a random walk's tau, smoother paths;
- gauss_markov: a phase-diffusing beat: a pickup from an oscillator at the sense frequency
  whose relative phase diffuses, bias a cos(phi), phi Brownian: autocorrelation exactly
  (a^2 / 2) exp(-|tau| / tc), bounded arcsine marginal (bimodal), continuous paths;
- quantization: noise shaping: the firmware requantizes the rate to an output step q with a
  second-order error-feedback loop, so the output carries the second difference of a
  uniform error: Allan excess (dt / tau)^2 q^2 / 12 x 10 at tau = dt and x 6 beyond;
- resonance: a rattle: a loose clip strikes the mount at Poisson times (3 /s) with random
  sign, each strike ringing a mount mode: impulsive, non-Gaussian excitation of the mode.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- skipped conversions: lag-1 autocorrelation r1 = (1 / m) / (1 - 1 / (2 m)) against 1 / sqrt(n);
- rocking kicks: every line in a Welch bin (Hann, L = 16384) as sets B and G, z_k = g_k^2 a_k^2
  sqrt(n L) / (6 sigma^2), a_k = (4 a / M) |sin(pi k / M)| (M samples a period), in quadrature;
- table residual: matched to its own noise-free waveform, mean removed: |s - mean(s)| / sigma;
- trapping, walk with memory, beat: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10];
- noise shaping: relative Allan excess at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n));
- rattle: mean excess p A^2 |H|^2 / sigma^2 over the band above half its peak, times
  sqrt(T B) (p = 3 dt the strike probability per sample, H the sampled ring's response).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: one conversion in 212 (edge), 25 and 2 filled; kicks of 0.11, 0.24 and 0.6
deg/s for one sample (angle excursions of 1.1-6 mdeg); table residuals of 0.007, 0.023 and
0.086 deg/s (tempcos 0.028-0.34 (deg/s)/degC against 0.25 degC cells); trapping b of 4.7e-5,
3e-4 and 8e-4 rad/s (steps b / sqrt(p) of 0.12-2 deg/s, p = dt / 20 s); walks with memory
driven by q = 1.1e-8, 3e-8 and 1.5e-7 rad/s a sample; beats of 0.018, 0.057 and 0.11 deg/s
(tc 0.8 s, 0.8 s, 20 s); output steps q of 0.16, 0.3 and 0.6 sigma (0.062-0.24 deg/s); rattle
rings of 0.14, 0.29 and 0.8 deg/s a strike (a 37 Hz, 37 Hz and 23 Hz mount mode).
"""
from gyro_char.allan.expected import markov_avar
from heldout_detect import allan_taus, allan_z, psd_avar
import numpy as np
from scipy import signal

WELCH_L = 16384
KICK_SAMPLES = 173                  # samples between kicks (1.73 s at 100 Hz)
WARM_RISE, WARM_TIME, CELL = 5.0, 1500.0, 0.25     # degC, s, degC: warming and table cell
WALK_ORDER = 1.25                   # fractional order of the walk with memory
TRAP_INTERVAL = 20.0                # s: mean time between trapping events
RATTLE_RATE, RATTLE_DECAY = 3.0, 0.05              # strikes per s; ring decay time, s


def fill_gaps(x: np.ndarray, every: int, first: int) -> np.ndarray:
    """Replace samples first, first + every, ... (not the ends) by their neighbours' mean."""
    y = x.copy()
    k = np.arange(max(first, 1), x.size - 1, every)
    y[k] = 0.5 * (x[k - 1] + x[k + 1])
    return y


def gap_lag1(every: int) -> float:
    """Lag-1 autocorrelation of unit white noise after ``fill_gaps`` (m >= 2)."""
    return (1.0 / every) / (1.0 - 0.5 / every)


def kick_train(n: int, amplitude: float, start: int) -> np.ndarray:
    """Doublets +a, -a (one sample apart) every KICK_SAMPLES samples, the first at ``start``."""
    y = np.zeros(n)
    k = np.arange(start, n - 1, KICK_SAMPLES)
    y[k] = amplitude
    y[k + 1] = -amplitude
    return y


def kick_lines(amplitude: float):
    """Harmonic numbers k below Nyquist and each line's sinusoid amplitude (per period M)."""
    k = np.arange(1, (KICK_SAMPLES + 1) // 2)
    return k, 4 * amplitude / KICK_SAMPLES * np.abs(np.sin(np.pi * k / KICK_SAMPLES))


def scalloping(bins: np.ndarray) -> np.ndarray:
    """Amplitude gain of a Hann window of ``WELCH_L`` for lines ``bins`` bins from 0 (mod 1)."""
    delta = np.asarray(bins) - np.round(bins)
    w = np.hanning(WELCH_L)
    ph = np.exp(2j * np.pi * np.outer(delta, np.arange(WELCH_L)) / WELCH_L)
    return np.abs(ph @ w) / w.sum()


def table_residual(t: np.ndarray, height: float, offset: float = 0.0) -> np.ndarray:
    """Residual c (T - cell floor(T / cell)) of a warming die, height h = c cell, T0 = offset."""
    temp = offset + WARM_RISE * (1.0 - np.exp(-t / WARM_TIME))
    return height * np.mod(temp, CELL) / CELL


def frac_kernel(n: int, d: float = 0.5) -> np.ndarray:
    """First ``n`` coefficients of (1 - z^-1)^-d: h_0 = 1, h_k = h_(k-1) (k - 1 + d) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 1 + d) / k)]


def trap_psd(f, b: float, dt: float) -> np.ndarray:
    """One-sided PSD of the trapping process: b^2 dt / sin(pi f dt) (b^2 / (pi f) near 0)."""
    return b * b * dt / np.sin(np.pi * np.asarray(f) * dt)


def walk_psd(f, q: float, dt: float) -> np.ndarray:
    """One-sided PSD of white noise (sd q a sample) through (1 - z^-1)^-WALK_ORDER."""
    return 2 * dt * q * q * (2 * np.sin(np.pi * np.asarray(f) * dt)) ** (-2 * WALK_ORDER)


def noise_shape(x: np.ndarray, step: float) -> np.ndarray:
    """Requantize to ``step``, second-order error feedback: y = x + e_k - 2 e_(k-1) + e_(k-2)."""
    y = np.empty_like(x)
    e1 = e2 = 0.0
    for i, v in enumerate(x.tolist()):
        u = v - 2.0 * e1 + e2
        q = step * round(u / step)
        e1, e2 = q - u, e1
        y[i] = q
    return y


def shaped_excess(m: int, step: float, dt: float) -> float:
    """(m dt)^2 times the Allan excess of the shaped error: dt^2 q^2 / 12 x (10 | 6)."""
    return dt * dt * step * step / 12.0 * (10.0 if m == 1 else 6.0)


def ring(freq: float, dt: float):
    """(b, a) of the sampled ring e^(-t / RATTLE_DECAY) sin(2 pi f t) (one strike, unit)."""
    r, w0 = np.exp(-dt / RATTLE_DECAY), 2 * np.pi * freq * dt
    return np.array([0.0, r * np.sin(w0)]), np.array([1.0, -2 * r * np.cos(w0), r * r])


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def skipped(x, rng, every):
        return fill_gaps(x, every, int(rng.integers(every)))

    def kicks(x, rng, amplitude):
        return x + kick_train(x.size, amplitude, int(rng.integers(KICK_SAMPLES)))

    def table(x, rng, height):
        return x + table_residual(np.arange(x.size) * dt, height, rng.uniform(0, CELL))

    def trapping(x, rng, b):
        m, p = 2 * x.size, dt / TRAP_INTERVAL
        ev = (rng.random(m) < p) * rng.choice([-1.0, 1.0], m) * b / np.sqrt(p)
        return x + signal.fftconvolve(ev, frac_kernel(m))[m - x.size:m]

    def memory_walk(x, rng, q):
        w = rng.standard_normal(x.size) * q
        return x + signal.fftconvolve(w, frac_kernel(x.size, WALK_ORDER))[:x.size]

    def beat(x, rng, amplitude, tc):
        phi = rng.uniform(0, 2 * np.pi) + np.cumsum(rng.standard_normal(x.size)) * np.sqrt(
            2 * dt / tc)
        return x + amplitude * np.cos(phi)

    def shaped(x, rng, step):
        return noise_shape(x, step)

    def rattle(x, rng, amplitude, freq):
        ev = (rng.random(x.size) < RATTLE_RATE * dt) * rng.choice([-1.0, 1.0], x.size)
        b, a = ring(freq, dt)
        return x + amplitude * signal.lfilter(b, a, ev)

    return {
        'internal_lowpass': (skipped, [{'every': 25}, {'every': 2}, {'every': 212}]),
        'vibration': (kicks, [{'amplitude': 0.6 * sig}, {'amplitude': 1.5 * sig},
                              {'amplitude': 0.285 * sig}]),
        'temperature_drift': (table, [{'height': 4e-4}, {'height': 1.5e-3},
                                      {'height': 1.22e-4}]),
        'bias_instability': (trapping, [{'b': 3e-4}, {'b': 8e-4}, {'b': 4.73e-5}]),
        'rate_random_walk': (memory_walk, [{'q': 3e-8}, {'q': 1.5e-7}, {'q': 1.07e-8}]),
        'gauss_markov': (beat, [{'amplitude': 1e-3, 'tc': 0.8},
                                {'amplitude': 2e-3, 'tc': 20.0},
                                {'amplitude': 3.06e-4, 'tc': 0.8}]),
        'quantization': (shaped, [{'step': 0.3 * sig}, {'step': 0.6 * sig},
                                  {'step': 0.156 * sig}]),
        'resonance': (rattle, [{'amplitude': 5e-3, 'freq': 37.0},
                               {'amplitude': 1.4e-2, 'freq': 23.0},
                               {'amplitude': 2.48e-3, 'freq': 37.0}]),
    }


def rattle_band(amplitude: float, freq: float, dt: float, sig: float):
    """Excess p A^2 |H|^2 / sigma^2 over the band above half its peak, and the band's width."""
    b, a = ring(freq, dt)
    f = np.linspace(0, 0.5 / dt, 200001)
    ex = RATTLE_RATE * dt * amplitude ** 2 * np.abs(
        signal.freqz(b, a, worN=f, fs=1 / dt)[1]) ** 2 / sig ** 2
    band = ex >= ex.max() / 2
    return float(ex[band].mean()), float(band.sum() * (f[1] - f[0]))


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return gap_lag1(p['every']) * np.sqrt(n)
    if name == 'vibration':
        k, amp = kick_lines(p['amplitude'])
        g = scalloping(k * WELCH_L / KICK_SAMPLES)
        z = g ** 2 * amp ** 2 * np.sqrt(n * WELCH_L) / (6 * sig ** 2)
        return float(np.sqrt(np.sum(z ** 2)))
    if name == 'temperature_drift':
        s = table_residual(np.arange(n) * dt, p['height'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [shaped_excess(m, p['step'], dt) / (m * dt * nn) for m in (1, 10)]
        return abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        ex, width = rattle_band(p['amplitude'], p['freq'], dt, sig)
        return ex * np.sqrt(big_t * width)
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: trap_psd(f, p['b'], dt), tau, dt)
    elif name == 'rate_random_walk':
        excess = psd_avar(lambda f: walk_psd(f, p['q'], dt), tau, dt)
    else:
        excess = markov_avar(tau, p['tc']) * p['amplitude'] ** 2 / p['tc']
    return allan_z(excess, tau, nn, big_t)
