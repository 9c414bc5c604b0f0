"""
Held-out set D of static effect shapes: written in session 7 without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_c.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out sets A-C:

- internal_lowpass: the linear-phase windowed-sinc FIR of a sigma-delta read-out's decimation
  stage (15 taps, Kaiser beta 5, cut-off a fraction of Nyquist): negative side lobes and a
  7-sample group delay (catalogue cascaded moving averages; dev Hann; A binomial; B one-pole
  IIR; C Butterworth IIR: all positive or recursive, none with negative taps);
- vibration: a gearbox: the mesh tone (teeth x shaft frequency) amplitude-modulated 60 % by the
  shaft's once-per-turn run-out, so resolved sidebands at mesh +- shaft, phase-locked to it
  (dev: 20 % AM at 1/37 Hz; A chirp; B harmonics; C wandering fan);
- temperature_drift: a draught: at an unknown time in the middle 30 % of the record an
  air-conditioning fan starts, the bias steps through the die's 150 s thermal lag (a step
  mid-record, not a warm-up from power-on as catalogue, dev, A, B; not periodic as C);
- bias_instability: fractal shot noise: sparse Poisson trapping events (0.5 per s, random sign)
  each relaxing diffusively as t^-1/2, the kernel of (1 - z^-1)^-1/2: a 1/f PSD from bursty,
  non-Gaussian events (catalogue Gaussian fractional integration; dev GM sums; A FFT; B Voss;
  C telegraph sums);
- rate_random_walk: a thermally lagged walk: the room temperature random-walks and the die
  follows through a 30 s lag: smooth (C^1) walk, PSD K^2 / (2 pi f)^2 / (1 + (2 pi f tau)^2)
  (catalogue rough Gaussian; dev held Laplace; A knots; B jumps; C intermittent);
- gauss_markov: a Gamma Ornstein-Uhlenbeck process (shot noise with exponential pulses: charge
  injections of exponential size, 2 per correlation time, each decaying with tau_c), mean
  removed: skewed, one-sided jumps, exact exponential correlation; tau_c 1.5 s and 30 s
  (catalogue/A/B Gaussian first order, dev second order, C two-level telegraph);
- quantization: second-order noise-shaped re-quantization of the rate word (error feedback,
  y = x + (1 - z^-1)^2 e): the angle error (1 - z^-1) e is blue, not white (catalogue floor of
  the angle = first-order; dev/A/B/C white angle errors);
- resonance: a hardening Duffing mode in its averaged form: frequency f0 (1 + kappa |z|^2 /
  E|z|^2) follows the instantaneous energy, so the line is skewed upward, its power-weighted
  mean at f0 (1 + 2 kappa) (catalogue, dev, A-C: linear modes).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- lowpass: lag-1 autocorrelation rho1 = sum h_k h_(k+1) / sum h^2 against 1 / sqrt(n);
- gearbox: the mesh line in a Welch bin (Hann, L = 16384) as set B: z = g^2 A^2 sqrt(n L) /
  (6 sigma^2), g the scalloping gain (sidebands not counted);
- draught: the difference of the means before and after the (known) step time t0, A (1 -
  tau / t2 (1 - e^(-t2 / tau))) against N sqrt(1 / t1 + 1 / t2), mean over t0 in its range;
- fractal shot, lagged walk, Gamma OU: Allan variance excess over N^2 / tau in units of the
  white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]: flicker
  2 ln2 / pi B^2 (PSD B^2 / (pi f) one-sided, exact for Poisson events), lagged walk K^2 tau / 3
  less the Gauss-Markov Allan of q = K, tc = 30 s (the lag's partial fraction), Gamma OU the
  first-order Gauss-Markov formula (its autocorrelation);
- noise shaping: e uniform, v = step^2 / 12; relative Allan excess 10 v / sigma^2 at tau = dt,
  6 v / (m sigma^2) at m dt >= 2 dt: at dt less at 10 dt, 9.4 v / sigma^2, against sqrt(3 / n
  + 40 / (3 n)) (as sets B and C);
- Duffing: half of sigma_r^2 in a band B = f0 / q + 2 kappa f0 (linear width plus the energy
  shift) against the white band power: z = sigma_r^2 sqrt(T) / (4 sigma^2 dt sqrt(B)).
Edges are set at z ~ 4; weak and strong are 8-1600x further above. Physical scale: the strong
draught (0.086 deg/s) is ~6 degC at the ADIS16405's 0.0135 deg/s/degC; the re-quantization
steps (0.06-0.48 deg/s) are a DSP output word cut to 8-11 bits; the Duffing shift 2 kappa is
4 % of f0.
"""
from gyro_char.allan.expected import markov_avar
from heldout_detect import allan_taus, allan_z, gm_avar
import numpy as np
from scipy import signal

FIR_TAPS, FIR_BETA = 15, 5.0
DEPTH = 0.6                  # AM depth of the mesh tone by the shaft's run-out
WELCH_L = 16384
DRAUGHT_LAG = 150.0          # s, die thermal lag behind the package
DRAUGHT_SPAN = (0.35, 0.65)  # step time, fraction of the record
SHOT_RATE = 0.5              # trapping events per s
WALK_LAG = 30.0              # s, thermal lag of the lagged walk
GAMMA_SHAPE = 2.0            # events per correlation time of the Gamma OU
KAPPA = 0.02                 # Duffing hardening at the mean energy


def fir(cutoff: float) -> np.ndarray:
    """Taps of the decimation FIR of ``cutoff`` (fraction of Nyquist), unit DC gain."""
    return signal.firwin(FIR_TAPS, cutoff, window=('kaiser', FIR_BETA))


def frac_kernel(n: int) -> np.ndarray:
    """First ``n`` coefficients of (1 - z^-1)^(-1/2): h_0 = 1, h_k = h_(k-1) (k - 1/2) / k."""
    k = np.arange(1, n)
    return np.r_[1.0, np.cumprod((k - 0.5) / k)]


def draught(t: np.ndarray, amplitude: float, t0: float) -> np.ndarray:
    """Bias of the draught: 0 before ``t0``, then A (1 - exp(-(t - t0) / lag))."""
    return amplitude * -np.expm1(-np.clip(t - t0, 0.0, None) / DRAUGHT_LAG)


def noise_shape(x: np.ndarray, step: float) -> np.ndarray:
    """Re-quantize ``x`` to ``step`` with second-order error feedback: x + (1 - z^-1)^2 e."""
    y = np.empty_like(x)
    e1 = e2 = 0.0
    for i, v in enumerate(x.tolist()):
        u = v - 2.0 * e1 + e2
        q = round(u / step) * step
        e1, e2 = q - u, e1
        y[i] = q
    return y


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""

    def decimation_fir(x, rng, cutoff):
        h = fir(cutoff)
        return signal.lfilter(h, [1.0], x, zi=signal.lfilter_zi(h, [1.0]) * x[0])[0]

    def gearbox(x, rng, amplitude, shaft, teeth):
        shaft_phase = 2 * np.pi * shaft * np.arange(x.size) * dt + rng.uniform(0, 2 * np.pi)
        env = 1.0 + DEPTH * np.cos(shaft_phase)
        return x + amplitude * env * np.sin(teeth * shaft_phase + rng.uniform(0, 2 * np.pi))

    def draught_step(x, rng, amplitude):
        t = np.arange(x.size) * dt
        return x + draught(t, amplitude, rng.uniform(*DRAUGHT_SPAN) * x.size * dt)

    def fractal_shot(x, rng, b):
        # Events of variance v at rate lam: one-sided PSD lam v dt / (pi f) = B^2 / (pi f).
        p = SHOT_RATE * dt
        e = (rng.random(x.size) < p) * rng.choice([-1.0, 1.0], x.size) * b / np.sqrt(p)
        return x + signal.fftconvolve(e, frac_kernel(x.size))[:x.size]

    def lagged_walk(x, rng, k):
        walk = np.cumsum(rng.standard_normal(x.size)) * k * np.sqrt(dt)
        a = np.exp(-dt / WALK_LAG)
        return x + signal.lfilter([1.0 - a], [1.0, -a], walk)

    def gamma_ou(x, rng, sigma, tc):
        a, lam = np.exp(-dt / tc), GAMMA_SHAPE / tc
        mu = sigma * np.sqrt((1.0 - a * a) / (2.0 * lam * dt))      # exponential pulse size
        e = (rng.random(x.size) < lam * dt) * rng.exponential(mu, x.size)
        start = rng.gamma(GAMMA_SHAPE, mu)
        y = signal.lfilter([1.0], [1.0, -a], e, zi=[a * start])[0]
        return x + y - lam * dt * mu / (1.0 - a)

    def shaped_requant(x, rng, step):
        return noise_shape(x, step)

    def duffing(x, rng, sigma, freq, q):
        # Averaged Duffing mode: z_k = r exp(i theta_k) z_(k-1) + eta_k, theta_k grows with
        # |z|^2. The rotation leaves |z| alone, so z = w exp(i cumsum(theta)) with w the
        # linear complex AR(1) (eta rotated stays circular white): vectorised, exact in law.
        r = np.exp(-np.pi * freq * dt / q)
        eta = rng.standard_normal(x.size) + 1j * rng.standard_normal(x.size)
        w = signal.lfilter([1.0], [1.0, -r], eta * np.sqrt(1 - r * r),
                           zi=[r * (rng.standard_normal() + 1j * rng.standard_normal())])[0]
        u = np.abs(w) ** 2 / 2.0                                   # E u = 1
        theta = 2 * np.pi * freq * dt * (1.0 + KAPPA * np.r_[u[0], u[:-1]])
        return x + sigma * np.real(w * np.exp(1j * np.cumsum(theta)))

    return {
        'internal_lowpass': (decimation_fir, [{'cutoff': 0.7}, {'cutoff': 0.45},
                                              {'cutoff': 0.9975}]),
        'vibration': (gearbox, [{'amplitude': 0.12 * sig, 'shaft': 2.35, 'teeth': 11},
                                {'amplitude': 0.3 * sig, 'shaft': 4.1, 'teeth': 9},
                                {'amplitude': 0.0155 * sig, 'shaft': 2.35, 'teeth': 11}]),
        'temperature_drift': (draught_step, [{'amplitude': 6e-4}, {'amplitude': 1.5e-3},
                                             {'amplitude': 7e-5}]),
        'bias_instability': (fractal_shot, [{'b': 2e-4}, {'b': 8e-4}, {'b': 4.8e-5}]),
        'rate_random_walk': (lagged_walk, [{'k': 2e-5}, {'k': 8e-5}, {'k': 2.1e-6}]),
        'gauss_markov': (gamma_ou, [{'sigma': 1.5e-3, 'tc': 1.5}, {'sigma': 2e-3, 'tc': 30.0},
                                    {'sigma': 1.85e-4, 'tc': 1.5}]),
        'quantization': (shaped_requant, [{'step': 0.6 * sig}, {'step': 1.2 * sig},
                                          {'step': 0.155 * sig}]),
        'resonance': (duffing, [{'sigma': 0.3 * sig, 'freq': 27.5, 'q': 30.0},
                                {'sigma': 0.8 * sig, 'freq': 12.5, 'q': 30.0},
                                {'sigma': 0.052 * sig, 'freq': 27.5, 'q': 30.0}]),
    }


def lag1(cutoff: float) -> float:
    """Lag-1 autocorrelation of white noise through the FIR of ``cutoff``."""
    h = fir(cutoff)
    return float(h[:-1] @ h[1:] / (h @ h))


def scalloping(bins: float) -> float:
    """Amplitude gain of a Hann window of ``WELCH_L`` for a line ``bins`` bins from 0 (mod 1)."""
    delta = bins - np.round(bins)
    w = np.hanning(WELCH_L)
    return float(abs(np.sum(w * np.exp(2j * np.pi * delta * np.arange(WELCH_L) / WELCH_L)))
                 / w.sum())


def step_z(amplitude: float, n_arw: float, big_t: float) -> float:
    """Mean-difference z of the draught over the step times of its range (module docstring)."""
    t1 = np.linspace(*DRAUGHT_SPAN, 31) * big_t
    t2 = big_t - t1
    mean2 = amplitude * (1.0 - DRAUGHT_LAG / t2 * -np.expm1(-t2 / DRAUGHT_LAG))
    return float(np.mean(mean2 / (n_arw * np.sqrt(1 / t1 + 1 / t2))))


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn = n * dt, n_arw ** 2
    p = params
    if name == 'internal_lowpass':
        return lag1(p['cutoff']) * np.sqrt(n)
    if name == 'vibration':
        mesh = p['teeth'] * p['shaft']
        return (scalloping(mesh * WELCH_L * dt) ** 2 * p['amplitude'] ** 2
                * np.sqrt(n * WELCH_L) / (6 * sig ** 2))
    if name == 'temperature_drift':
        return step_z(p['amplitude'], n_arw, big_t)
    if name == 'quantization':
        return 9.4 * p['step'] ** 2 / 12 / sig ** 2 / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        band = p['freq'] / p['q'] + 2 * KAPPA * p['freq']
        return p['sigma'] ** 2 * np.sqrt(big_t) / (4 * sig ** 2 * dt * np.sqrt(band))
    tau = allan_taus(dt, big_t, 200)
    if name == 'bias_instability':
        excess = 2 * np.log(2) / np.pi * p['b'] ** 2 * np.ones_like(tau)
    elif name == 'rate_random_walk':
        excess = p['k'] ** 2 * (tau / 3 - markov_avar(tau, WALK_LAG))
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
