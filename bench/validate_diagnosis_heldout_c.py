"""
Held-out set C of static effect shapes: written in session 5 without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_b.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A and B:

- internal_lowpass: a second-order Butterworth IIR at the output rate (the digital low-pass of
  a consumer MEMS IMU), cut-off given as a fraction of Nyquist;
- vibration: a fan tone whose speed wanders (frequency f0 (1 + w u(t)), u an Ornstein-Uhlenbeck
  process of unit sd and 30 s correlation), at 4.3 Hz and 42.5 Hz (outside earlier sets' range);
- temperature_drift: thermostat cycling: a triangular room temperature (period 1440 s), the die
  following it through a 240 s thermal lag, the bias through a hysteresis (play operator of
  half width 0.25 of the swing): thermal hysteresis, periodic rather than a warm-up;
- bias_instability: flicker as a sum of symmetric random telegraph signals with correlation
  times 3 per decade from 0.02 s to 2e4 s (McWhorter: two-level, non-Gaussian sources);
- rate_random_walk: an intermittent walk: Gaussian increments whose intensity switches between
  1.8 K^2 and 0.2 K^2 (two-state Markov, mean dwell 300 s; mean K^2);
- gauss_markov: one random telegraph signal (popcorn noise, two levels +-sigma, exponential
  correlation tau_c), at a short tau_c = 0.2 s (all earlier sets >= 0.5 s) and 8 s;
- quantization: an angle counter with sinusoidal dither (ring-laser body dither, amplitude
  3.3 steps at 413.7 Hz, sampled at the output rate), the known dither angle subtracted
  digitally after the read-out;
- resonance: a split mode pair (a symmetric structure's degenerate mode split by 4 %), two
  resonators at f0 (1 -+ 0.02), q = 30, independent drivers, each half the variance.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- lowpass: lag-1 autocorrelation rho1 = sum h_k h_(k+1) / sum h^2 of the filter's impulse
  response against its white spread 1 / sqrt(n): z = rho1 sqrt(n);
- vibration, resonance: power in the band that holds the effect against the white power there,
  known to 1 / sqrt(T B): fan, all of A^2 / 2 in B = 5 w f0 (+-2.5 sd of the wandering
  frequency): z = A^2 sqrt(T) / (4 sigma^2 dt sqrt(B)); mode pair, half of sigma_r^2 in the two
  -3 dB bands (B = 2 f0 / q): z = sigma_r^2 sqrt(2 T) / (8 sigma^2 dt sqrt(f0 / q));
- thermostat: the fundamental line c1 (at 1 / 1440 s, fitted over the record to the generator's
  own noise-free waveform, mean over the random start phase, which moves it by -15 to +5 %)
  against the sd of a fitted sine, N sqrt(2 / T): z = c1 / (N sqrt(2 / T));
- flicker, intermittent RRW, telegraph: Allan variance excess over N^2 / tau in units of the
  white null's spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]
  (as set B): telegraph signals have the Gauss-Markov Allan variance of their correlation
  (summed, exactly, for the flicker), the intermittent walk K^2 tau / 3 (mean intensity);
- quantization: the dithered angle error is uniform on one step and white (variance step^2 /
  12 whatever the step): relative Allan excess 3 v / (N^2 dt) at tau = dt less a tenth of it at
  10 dt, against sqrt(3 / n + 40 / (3 n)).
Edges are set at z ~ 4; weak and strong are 8-1600x further above.
"""
from gyro_char.sim.effects.vibration import resonance_coefficients
from heldout_detect import allan_taus, allan_z, gm_avar
import numpy as np
from scipy import signal

THERMO_PERIOD = 1440.0       # s, thermostat cycle (5 cycles in 2 h)
THERMO_LAG = 240.0           # s, die thermal time constant
THERMO_PLAY = 0.25           # half width of the hysteresis, in units of the room swing
FAN_TC = 30.0                # s, correlation time of the fan's speed wander
RTN_TC = np.geomspace(0.02, 2e4, 19)     # 3 per decade
DWELL = 300.0                # s, mean dwell of the intermittent walk's intensity states
DITHER = (3.3, 413.7)        # dither amplitude (steps), frequency (Hz)
SPLIT = 0.04                 # relative split of the mode pair


def telegraph(n: int, dt: float, tc: float, rng) -> np.ndarray:
    """Symmetric +-1 random telegraph signal, autocorrelation exp(-|lag| / tc), stationary."""
    flip = rng.random(n) < (1.0 - np.exp(-dt / tc)) / 2.0     # lag-1 correlation e^(-dt/tc)
    flip[0] = rng.random() < 0.5
    return 1.0 - 2.0 * (np.cumsum(flip) % 2)


def thermostat(t: np.ndarray, amplitude: float, phase: float = 0.0) -> np.ndarray:
    """Bias of the thermostat shape at times ``t`` (computed on a 1 s grid, interpolated)."""
    grid = np.arange(0.0, t[-1] + 2.0)
    c = (grid / THERMO_PERIOD + phase) % 1.0
    room = 4.0 * np.abs(c - 0.5) - 1.0                   # triangle in [-1, 1]
    a = np.exp(-1.0 / THERMO_LAG)
    die = signal.lfilter([1.0 - a], [1.0, -a], room, zi=[a * room[0]])[0]
    out, y = np.empty_like(die), die[0]
    for i, v in enumerate(die):                          # play operator (backlash)
        y = min(max(y, v - THERMO_PLAY), v + THERMO_PLAY)
        out[i] = y
    return amplitude * np.interp(t, grid, out)


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    inc = n_arw * np.sqrt(dt)                # per-sample white angle increment, rad

    def butter2(x, rng, cutoff):
        b, a = signal.butter(2, cutoff)
        return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]

    def fan(x, rng, amplitude, freq, wander):
        a = np.exp(-dt / FAN_TC)
        u = signal.lfilter([1.0], [1.0, -a], rng.standard_normal(x.size) * np.sqrt(1 - a * a),
                           zi=[a * rng.standard_normal()])[0]
        phase = 2 * np.pi * np.cumsum(freq * (1.0 + wander * u)) * dt + rng.uniform(0, 2 * np.pi)
        return x + amplitude * np.sin(phase)

    def hvac(x, rng, amplitude):
        return x + thermostat(np.arange(x.size) * dt, amplitude, rng.uniform())

    def rtn_flicker(x, rng, b):
        a = b * np.sqrt(np.log(RTN_TC[1] / RTN_TC[0]) / np.pi)
        return x + a * sum(telegraph(x.size, dt, tc, rng) for tc in RTN_TC)

    def intermittent_rw(x, rng, k):
        state = telegraph(x.size, dt, DWELL / 2.0, rng)   # switching rate 1 / DWELL per state
        q = k * k * (1.0 + 0.8 * state)
        return x + np.cumsum(np.sqrt(q * dt) * rng.standard_normal(x.size))

    def popcorn(x, rng, sigma, tc):
        return x + sigma * telegraph(x.size, dt, tc, rng)

    def dithered_counter(x, rng, step):
        theta = np.r_[0.0, np.cumsum(x)] * dt
        k = np.arange(theta.size)
        d = DITHER[0] * step * np.sin(2 * np.pi * DITHER[1] * k * dt + rng.uniform(0, 2 * np.pi))
        angle = np.floor((theta + d) / step) * step - d
        return np.diff(angle) / dt

    def mode_pair(x, rng, sigma, freq, q):
        out = np.zeros(x.size)
        for f in (freq * (1 - SPLIT / 2), freq * (1 + SPLIT / 2)):
            a1, a2, var_e = resonance_coefficients(f, q, dt)
            burn = int(20 * q / (np.pi * f * dt))
            e = rng.standard_normal(x.size + burn) * np.sqrt(var_e)
            out += signal.lfilter([1.0], [1.0, -a1, -a2], e)[burn:]
        return x + sigma * out / np.sqrt(2.0)

    return {
        'internal_lowpass': (butter2, [{'cutoff': 0.6}, {'cutoff': 0.3}, {'cutoff': 0.9955}]),
        'vibration': (fan, [{'amplitude': 0.12 * sig, 'freq': 4.3, 'wander': 0.01},
                            {'amplitude': 0.3 * sig, 'freq': 42.5, 'wander': 0.01},
                            {'amplitude': 0.03 * sig, 'freq': 4.3, 'wander': 0.01}]),
        'temperature_drift': (hvac, [{'amplitude': 1e-3}, {'amplitude': 5e-3},
                                     {'amplitude': 1.15e-4}]),
        'bias_instability': (rtn_flicker, [{'b': 2e-4}, {'b': 8e-4}, {'b': 4.8e-5}]),
        'rate_random_walk': (intermittent_rw, [{'k': 2e-5}, {'k': 8e-5}, {'k': 2e-6}]),
        'gauss_markov': (popcorn, [{'sigma': 2e-3, 'tc': 0.2}, {'sigma': 3e-3, 'tc': 8.0},
                                   {'sigma': 3.1e-4, 'tc': 0.2}]),
        'quantization': (dithered_counter, [{'step': 1.2 * inc}, {'step': 3.0 * inc},
                                            {'step': 0.29 * inc}]),
        'resonance': (mode_pair, [{'sigma': 0.3 * sig, 'freq': 33.0, 'q': 30.0},
                                  {'sigma': 0.8 * sig, 'freq': 6.2, 'q': 30.0},
                                  {'sigma': 0.053 * sig, 'freq': 33.0, 'q': 30.0}]),
    }


def lag1(cutoff: float) -> float:
    """Lag-1 autocorrelation of white noise through the Butterworth of ``cutoff``."""
    b, a = signal.butter(2, cutoff)
    h = signal.lfilter(b, a, np.r_[1.0, np.zeros(4095)])
    return float(h[:-1] @ h[1:] / (h @ h))


def fundamental(amplitude: float, dt: float, n: int) -> float:
    """Thermostat waveform's line at 1 / THERMO_PERIOD over ``n`` samples, mean over phases."""
    t = np.arange(n) * dt
    cols = np.c_[np.sin(2 * np.pi * t / THERMO_PERIOD), np.cos(2 * np.pi * t / THERMO_PERIOD),
                 np.ones(n)]
    c = [np.linalg.lstsq(cols, thermostat(t, amplitude, ph), rcond=None)[0] for ph in
         np.arange(8) / 8]
    return float(np.mean([np.hypot(ci[0], ci[1]) for ci in c]))


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn = n * dt, n_arw ** 2
    p = params
    if name == 'internal_lowpass':
        return lag1(p['cutoff']) * np.sqrt(n)
    if name == 'vibration':
        band = 5 * p['wander'] * p['freq']
        return p['amplitude'] ** 2 * np.sqrt(big_t) / (4 * sig ** 2 * dt * np.sqrt(band))
    if name == 'resonance':
        return (p['sigma'] ** 2 * np.sqrt(2 * big_t)
                / (8 * sig ** 2 * dt * np.sqrt(p['freq'] / p['q'])))
    if name == 'temperature_drift':
        return fundamental(p['amplitude'], dt, n) / (n_arw * np.sqrt(2 / big_t))
    if name == 'quantization':
        v = p['step'] ** 2 / 12
        return 0.9 * 3 * v / (nn * dt) / np.sqrt(3 / n + 40 / (3 * n))
    tau = allan_taus(dt, big_t, 200)
    if name == 'bias_instability':
        a2 = p['b'] ** 2 * np.log(RTN_TC[1] / RTN_TC[0]) / np.pi
        excess = sum(gm_avar(tau, np.sqrt(a2), tc) for tc in RTN_TC)
    elif name == 'rate_random_walk':
        excess = p['k'] ** 2 * tau / 3
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
