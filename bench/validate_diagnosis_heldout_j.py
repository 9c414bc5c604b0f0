"""
Held-out set J of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_i.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-I, and
the kinds of departure differ from shape to shape:

- internal_lowpass: sync-interpolated output: the host's SYNC request reaches the sensor a
  random time after its latest conversion, uniform over 0..m sample periods, and the output
  stage interpolates linearly back to the request, y_k = (1 - mu_k) x_k + mu_k x_(k-1),
  mu_k ~ U(0, m) afresh each sample: a smoother with random coefficients, each output a
  convex mix of two neighbouring conversions;
- vibration: two beating fans: two fans of one model in the rack next to the bench run at
  27.3 and 27.9 Hz (1638 and 1674 rpm), equal unbalance, independent phases: two close lines
  of equal amplitude, the envelope beating fully at 0.6 Hz, no carrier between them;
- temperature_drift: a warming room: the lab warms at a constant rate through the whole
  record (the heating came on shortly before it) and the die follows through its 300 s
  thermal lag: bias rate (t' - tau (1 - e^(-t' / tau))), t' = t + t0, t0 uniform in 0-300 s:
  a curved start, then a straight, unbounded ramp (no settling, no extremum);
- bias_instability: lagged flicker: the bias follows the 1/f fluctuations of the air around
  the package (convective temperature noise) through the package's 2 s thermal lag: 1/f
  (fractional integration (1 - z^-1)^-1/2 of white noise of sd b) through a one-pole of 2 s,
  PSD b^2 / (pi f) below 0.08 Hz and 1/f^3 above;
- rate_random_walk: a settling walk: the die attach creeps after power-on, so the bias walk's
  intensity relaxes, K^2 (1 + 3 e^(-t' / 1200 s)), t' = t + t0, t0 in 0-60 s: a Gaussian
  walk whose increments shrink through the record (four times the settled variance at first);
- gauss_markov: charging events: sparse charge injections on the proof mass's electrodes (0.4
  per correlation time, random sign, Laplace-distributed sizes) that leak off with tc: a
  symmetric shot noise, jumps then exponential decays, heavy tails (excess kurtosis ~ 6 /
  (0.4) = 15), autocorrelation exactly exp(-|tau| / tc);
- quantization: a whole-angle read-out: the angle is the phase of two pickoff signals (a
  rate-integrating gyro's pattern angle, 450 deg of input a cycle, angular gain 0.4),
  theta = (P / 2 pi) atan2(S, C), with S and C rounded to ADC counts at an amplitude of M
  counts: the angle error is the phase error of two rounded channels, a non-uniform,
  quasi-random staircase whose size follows 1 / M;
- resonance: a velocity-response mode: white torque drives a mount mode's angle, and the gyro
  senses its RATE, the angle's difference: white noise through (1 - z^-1) / (1 - 2 r cos th
  z^-1 + r^2 z^-2): a zero at DC, the PSD rising as f^2 up to the mode and falling beyond.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- sync interpolation: lag-1 autocorrelation r1 = (m / 2)(1 - m / 2) / (1 - m + 2 m^2 / 3)
  (E over mu of the shared weight over E of the output's power) against 1 / sqrt(n);
- beating fans: both lines in a Welch bin (Hann, L = 16384) as set B, z_k = g_k^2 A^2
  sqrt(n L) / (6 sigma^2) (g_k the scalloping gain), in quadrature;
- warming room: matched to its own noise-free waveform, mean removed: |s - mean(s)| / sigma;
- lagged flicker, settling walk, charging events: Allan variance excess over N^2 / tau in
  units of the white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt,
  T / 10]: the flicker from the exact PSD of its sampled kernel and lag, the walk q^2 (2 m^2
  + 1) / (6 m) (a sampled walk, m samples a block) times its intensity's mean over the
  record, the events the first-order Gauss-Markov formula;
- whole-angle read-out: the periodic angle error's autocovariance c(m) = 2 sum_h |c_h|^2
  exp(-2 pi^2 h^2 m dt N^2 / P^2) (the angle walking by the white noise, as sets E, F and I):
  relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) at dt less at 10 dt, against
  sqrt(3 / n + 40 / (3 n));
- velocity mode: mean excess PSD / white over the band above half its peak, times sqrt(T B).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: SYNC latencies up to 0.096 (edge), 2.5 and 10 ms at 100 Hz; fan lines of
0.0051, 0.029 and 0.086 deg/s; room warming that moves the bias by 0.0063, 0.059 and 0.20
deg/s in 2 h (0.5-15 degC at 0.0135 (deg/s)/degC); flicker b of 4.7e-5, 2e-4 and 6e-4
rad/s; walks driven by 1.7e-7, 6e-7 and 2e-6 rad/s a sample (settled K of 1.7e-6 to 2e-5
rad/s/sqrt(s)); charging noise of 0.0078, 0.057 and 0.11 deg/s sd (tc 5 s, 5 s and 25 s);
pickoff amplitudes of 61000, 15000 and 5000 counts (angle error sd 1.2, 5 and 15 arcsec);
velocity modes of 0.021, 0.11 and 0.34 deg/s sd at 21.5 Hz (width 2 Hz) and 33 Hz (width
4 Hz).
"""
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar, psd_avar
import numpy as np
from scipy import signal

FANS_HZ = (27.3, 27.9)               # the two fans' rotation frequencies
WELCH_L = 16384
ROOM_LAG, ROOM_LATE = 300.0, 300.0   # s: the die's thermal lag; heating on <= ROOM_LATE early
PACKAGE_LAG = 2.0                    # s: thermal lag between the air and the die
SETTLE_EXCESS, SETTLE_TAU, POWER_ON = 3.0, 1200.0, 60.0
EVENTS_PER_TC = 0.4                  # charging events per correlation time
CYCLE = np.deg2rad(450.0)            # input angle per cycle of the pickoff phase (gain 0.4)
GRID = 2 ** 22                       # points per cycle for the read-out error's Fourier series


def sync_interp(x: np.ndarray, m: float, rng) -> np.ndarray:
    """Return (1 - mu_k) x_k + mu_k x_(k-1), mu_k ~ U(0, m) (y_0 = x_0)."""
    mu = rng.uniform(0.0, m, x.size)
    prev = np.r_[x[:1], x[:-1]]
    return (1 - mu) * x + mu * prev


def sync_lag1(m: float) -> float:
    """Lag-1 autocorrelation of ``sync_interp`` on unit white noise."""
    return (m / 2) * (1 - m / 2) / (1 - m + 2 * m * m / 3)


def hann_gain(f, dt: float) -> np.ndarray:
    """Amplitude gain of a Hann window of WELCH_L for lines at ``f`` (offset from their bin)."""
    b = np.asarray(f, float) * dt * WELCH_L
    delta = b - np.round(b)
    w = np.hanning(WELCH_L)
    ph = np.exp(2j * np.pi * np.outer(np.atleast_1d(delta), np.arange(WELCH_L)) / WELCH_L)
    return np.abs(ph @ w) / w.sum()


def room(t, rate: float) -> np.ndarray:
    """Bias of a die lagging (ROOM_LAG) a room that warms linearly from t = 0."""
    t = np.asarray(t, float)
    return rate * (t - ROOM_LAG * (1 - np.exp(-t / ROOM_LAG)))


def flicker_kernel(n: int) -> np.ndarray:
    """Coefficients of (1 - z^-1)^-1/2: h_0 = 1, h_k = h_(k-1) (k - 1/2) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 0.5) / k)]


def lagged_flicker(n: int, b: float, dt: float, rng) -> np.ndarray:
    """White noise of sd b through (1 - z^-1)^-1/2 and a one-pole of PACKAGE_LAG."""
    u = signal.fftconvolve(rng.standard_normal(n) * b, flicker_kernel(n))[:n]
    c = np.exp(-dt / PACKAGE_LAG)
    return signal.lfilter([1 - c], [1, -c], u)


def lagged_flicker_psd(f, b: float, dt: float) -> np.ndarray:
    """One-sided PSD of ``lagged_flicker``: 2 dt b^2 / |2 sin(pi f dt)| |H_lag|^2."""
    f = np.asarray(f, float)
    c = np.exp(-dt / PACKAGE_LAG)
    z1 = np.exp(-2j * np.pi * f * dt)
    lag = np.abs((1 - c) / (1 - c * z1)) ** 2
    return 2 * dt * b * b / np.abs(2 * np.sin(np.pi * f * dt)) * lag


def settling(t) -> np.ndarray:
    """Intensity factor of the settling walk: 1 + 3 e^(-t / 1200 s)."""
    return 1 + SETTLE_EXCESS * np.exp(-np.asarray(t, float) / SETTLE_TAU)


def settling_walk(n: int, q: float, t0: float, dt: float, rng) -> np.ndarray:
    """Walk with increments q sqrt(settling(t + t0)) w_k."""
    t = np.arange(n) * dt + t0
    return np.cumsum(q * np.sqrt(settling(t)) * rng.standard_normal(n))


def walk_avar(m, q: float) -> np.ndarray:
    """Allan variance of a sampled walk of step sd q, blocks of m samples: q^2 (2m^2+1)/(6m)."""
    m = np.asarray(m, float)
    return q * q * (2 * m * m + 1) / (6 * m)


def charging(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Symmetric shot noise: Poisson events (EVENTS_PER_TC / tc), Laplace jumps, decay tc."""
    a = np.exp(-dt / tc)
    lam = EVENTS_PER_TC / tc * dt                       # events per sample
    beta = sd * np.sqrt((1 - a * a) / (2 * lam))        # Laplace scale: stationary sd = sd
    burn = int(10 * tc / dt)
    count = rng.poisson(lam, n + burn)
    jumps = np.zeros(n + burn)
    hit = np.flatnonzero(count)
    for k in range(1, count.max(initial=0) + 1):
        at = hit[count[hit] >= k]
        jumps[at] += rng.laplace(0.0, beta, at.size)
    return signal.lfilter([1.0], [1, -a], jumps)[burn:]


def readout_error(theta, amplitude: float) -> np.ndarray:
    """Read minus true angle of the whole-angle read-out (pickoffs of ``amplitude`` counts)."""
    u = 2 * np.pi * np.asarray(theta, float) / CYCLE
    phase = np.arctan2(np.round(amplitude * np.sin(u)), np.round(amplitude * np.cos(u)))
    return np.angle(np.exp(1j * (phase - u))) * CYCLE / (2 * np.pi)


def readout_excess(m: int, amplitude: float, dt: float, n_arw: float) -> float:
    """Relative Allan excess (3 c0 - 4 c_m + c_2m) / (m dt N^2) of the walking read-out error."""
    e = readout_error(np.arange(GRID) * CYCLE / GRID, amplitude)
    ch = np.abs(np.fft.rfft(e) / GRID)[1:]
    h = np.arange(1, ch.size + 1)
    c0 = float(np.mean((e - e.mean()) ** 2))

    def c(k):
        return 2 * np.sum(ch ** 2 * np.exp(-2 * np.pi ** 2 * h ** 2 * k * dt * n_arw ** 2
                                           / CYCLE ** 2))
    return (3 * c0 - 4 * c(m) + c(2 * m)) / (m * dt * n_arw ** 2)


def velocity_mode_coeffs(freq: float, q: float, dt: float):
    """(b, a) of the velocity-response mode: (1 - z^-1) / (1 - 2 r cos th z^-1 + r^2 z^-2)."""
    r = np.exp(-np.pi * freq * dt / q)
    return np.array([1.0, -1.0]), np.array([1.0, -2 * r * np.cos(2 * np.pi * freq * dt), r * r])


def velocity_mode(n: int, freq: float, q: float, dt: float, rng) -> np.ndarray:
    """Unit-sd velocity-response mode, run in from 20 time constants before the record."""
    b, a = velocity_mode_coeffs(freq, q, dt)
    burn = int(20 * q / (np.pi * freq * dt)) + 10
    y = signal.lfilter(b, a, rng.standard_normal(n + burn))[burn:]
    return y / np.sqrt(velocity_mode_var(freq, q, dt))


def velocity_mode_var(freq: float, q: float, dt: float) -> float:
    """Variance of the filter's output on unit white noise (sum of its impulse response^2)."""
    b, a = velocity_mode_coeffs(freq, q, dt)
    imp = np.zeros(int(60 * q / (np.pi * freq * dt)) + 100)
    imp[0] = 1.0
    return float(np.sum(signal.lfilter(b, a, imp) ** 2))


def velocity_mode_psd(f, sigma: float, freq: float, q: float, dt: float) -> np.ndarray:
    """One-sided PSD of sigma x ``velocity_mode``: 2 dt sigma^2 |H|^2 / var."""
    b, a = velocity_mode_coeffs(freq, q, dt)
    h = signal.freqz(b, a, worN=np.asarray(f, float), fs=1 / dt)[1]
    return 2 * dt * sigma ** 2 * np.abs(h) ** 2 / velocity_mode_var(freq, q, dt)


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def synced(x, rng, m):
        return sync_interp(x, m, rng)

    def fans(x, rng, amplitude):
        t = np.arange(x.size) * dt
        p = rng.uniform(0, 2 * np.pi, 2)
        return x + amplitude * sum(np.sin(2 * np.pi * f * t + pk) for f, pk in zip(FANS_HZ, p))

    def warming(x, rng, rate):
        return x + room(np.arange(x.size) * dt + rng.uniform(0, ROOM_LATE), rate)

    def flicker(x, rng, b):
        return x + lagged_flicker(x.size, b, dt, rng)

    def settle(x, rng, q):
        return x + settling_walk(x.size, q, rng.uniform(0, POWER_ON), dt, rng)

    def events(x, rng, sd, tc):
        return x + charging(x.size, sd, tc, dt, rng)

    def whole_angle(x, rng, amplitude):
        theta = rng.uniform(0, CYCLE) + np.cumsum(x) * dt
        read = readout_error(np.r_[theta[0] - x[0] * dt, theta], amplitude)
        return x + np.diff(read) / dt

    def mode(x, rng, sigma, freq, q):
        return x + sigma * velocity_mode(x.size, freq, q, dt, rng)

    return {
        'internal_lowpass': (synced, [{'m': 0.25}, {'m': 1.0}, {'m': 0.0096}]),
        'vibration': (fans, [{'amplitude': 5e-4}, {'amplitude': 1.5e-3},
                             {'amplitude': 8.85e-5}]),
        'temperature_drift': (warming, [{'rate': 1.5e-7}, {'rate': 5e-7}, {'rate': 1.6e-8}]),
        'bias_instability': (flicker, [{'b': 2e-4}, {'b': 6e-4}, {'b': 4.7e-5}]),
        'rate_random_walk': (settle, [{'q': 6e-7}, {'q': 2e-6}, {'q': 1.66e-7}]),
        'gauss_markov': (events, [{'sd': 1e-3, 'tc': 5.0}, {'sd': 2e-3, 'tc': 25.0},
                                  {'sd': 1.37e-4, 'tc': 5.0}]),
        'quantization': (whole_angle, [{'amplitude': 15000.0}, {'amplitude': 5000.0},
                                       {'amplitude': 61000.0}]),
        'resonance': (mode, [{'sigma': 2e-3, 'freq': 21.5, 'q': 21.5 / 2},
                             {'sigma': 6e-3, 'freq': 33.0, 'q': 33.0 / 4},
                             {'sigma': 3.6e-4, 'freq': 21.5, 'q': 21.5 / 2}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(sync_lag1(p['m']) * np.sqrt(n))
    if name == 'vibration':
        z = hann_gain(FANS_HZ, dt) ** 2 * p['amplitude'] ** 2 * np.sqrt(n * WELCH_L) / (
            6 * sig ** 2)
        return float(np.sqrt(np.sum(z ** 2)))
    if name == 'temperature_drift':
        s = room(np.arange(n) * dt, p['rate'])
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = [readout_excess(m, p['amplitude'], dt, n_arw) for m in (1, 10)]
        return float(abs(rel[0] - rel[1]) / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(lambda f: velocity_mode_psd(f, p['sigma'], p['freq'], p['q'], dt),
                                dt, sig)
        return float(ex * np.sqrt(big_t * width))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = psd_avar(lambda f: lagged_flicker_psd(f, p['b'], dt), tau, dt)
    elif name == 'rate_random_walk':
        mean = np.mean(settling(np.arange(n) * dt))
        excess = mean * walk_avar(np.round(tau / dt), p['q'])
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
