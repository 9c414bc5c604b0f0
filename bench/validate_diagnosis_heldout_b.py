"""
Held-out set B of static effect shapes: fixed before anybody saw diagnosis results, run once.

Same interface as ``validate_diagnosis_heldout.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]); every shape is a physical form unlike
the catalogue's, the development shapes (``validate_diagnosis.py``) and held-out set A:

- internal_lowpass: a one-pole IIR smoothing y_k = a y_(k-1) + (1 - a) x_k (DC gain 1);
- vibration: a periodic non-sinusoidal disturbance, fundamental + 2nd + 3rd harmonics (1, 1/2,
  1/3: a sawtooth's first three terms, e.g. a pump or fan), random phases;
- temperature_drift: a linear warm-up ramp A (1 - t / t_r) that saturates (0 after t_r);
- bias_instability: flicker by Voss-McCartney synthesis (octave rows of held random values);
- rate_random_walk: a piecewise-constant walk, Gaussian jumps at Poisson times (mean hold 30 s);
- gauss_markov: first order with correlation times 3 s and 60 s (dev 0.5-1 s, set A 20 s);
- quantization: an angle counter with uneven step widths (differential nonlinearity +-0.3
  step), no dither;
- resonance: a second-order mode rung by Poisson impulses (bursts, not Gaussian excitation).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- lowpass: lag-1 autocorrelation a against its white spread 1 / sqrt(n): z = a sqrt(n);
- vibration: fundamental A in a Welch bin (Hann, L = 16384, K = n / L segments): line / white
  = g^2 A^2 L / (6 sigma^2), chi-square spread 1 / sqrt(K): z = g^2 A^2 sqrt(n L) / (6 sigma^2),
  g the Hann scalloping gain at the line's offset from the nearest bin (0.90 at 8.7 Hz);
- warm-up: mean of the first 2/3 t_r (the best block) is 0.544 A sqrt(t_r) / N sigmas;
- flicker, RRW, Gauss-Markov: Allan variance excess over N^2 / tau in units of its spread
  N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau (overlapping, white FM), best tau in [10 dt, T/10]:
  flicker 0.441 B^2, RRW K^2 tau / 3, GM the first-order Allan formula;
- quantization: the angle error (variance v = step^2 (1/12 + d^2 / 3), white while step <<
  N sqrt(dt); from step ~ N sqrt(dt) on it correlates and the excess shrinks) adds 3 v / tau^2:
  relative excess 3 v / (N^2 dt) at tau = dt less a tenth of it at 10 dt, against
  sqrt(3 / n + 40 / (3 n)) (the two estimates' spreads);
- resonance: power in the -3 dB band f0 / q (half of sigma_r^2) against the white band power
  2 sigma^2 dt f0 / q, known to 1 / sqrt(T f0 / q): z = sigma_r^2 sqrt(T) / (4 sigma^2 dt
  sqrt(f0 / q)) (against the white null, so the bursts' statistics do not enter).
Edges are set at z ~ 4 (a few sigma); weak and strong are 6-800x further above.
"""
from gyro_char.sim.effects.vibration import resonance_coefficients
from heldout_detect import allan_taus, allan_z
import numpy as np
from scipy import signal

WELCH_L = 16384


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    inc = n_arw * np.sqrt(dt)                # per-sample white angle increment, rad

    def one_pole(x, rng, pole):
        return signal.lfilter([1.0 - pole], [1.0, -pole], x,
                              zi=[pole * x[0]])[0] if pole else x

    def harmonics(x, rng, amplitude, freq):
        t = np.arange(x.size) * dt
        out = x.copy()
        for k in (1, 2, 3):
            out += amplitude / k * np.sin(2 * np.pi * k * freq * t + rng.uniform(0, 2 * np.pi))
        return out

    def ramp(x, rng, amplitude, t_r):
        t = np.arange(x.size) * dt
        return x + amplitude * np.clip(1.0 - t / t_r, 0.0, None)

    def voss(x, rng, b):
        # Row j holds a random value for 2^j samples (random grid offset): sum of sinc^2
        # spectra ~ s^2 / (ln2 f), so s = B sqrt(ln2 / pi) gives the PSD B^2 / (pi f).
        s, out = b * np.sqrt(np.log(2.0) / np.pi), np.zeros(x.size)
        for j in range(int(np.ceil(np.log2(x.size))) + 1):
            h = 2 ** j
            off = int(rng.integers(h))
            vals = s * rng.standard_normal((x.size + off) // h + 1)
            out += np.repeat(vals, h)[off:off + x.size]
        return x + out

    def jump_walk(x, rng, k, hold):
        # Jumps with probability dt / hold per sample, variance K^2 hold: K^2 per second.
        jumps = rng.random(x.size) < dt / hold
        return x + np.cumsum(jumps * rng.standard_normal(x.size)) * k * np.sqrt(hold)

    def gm1(x, rng, sigma, tc):
        a = np.exp(-dt / tc)
        w = rng.standard_normal(x.size) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal()
        return x + sigma * signal.lfilter([1.0], [1.0, -a], w)

    def dnl_counter(x, rng, step, dnl):
        # Threshold k sits at (k + d_k) step, d_k uniform in +-dnl (fixed per level).
        u = np.r_[0.0, np.cumsum(x)] * dt / step
        k = np.floor(u).astype(np.int64)
        lo = k.min()
        d = rng.uniform(-dnl, dnl, k.max() - lo + 2)
        counts = k + (u >= k + d[k - lo]) + (u >= k + 1 + d[k - lo + 1])
        return np.diff(counts) * step / dt

    def burst_mode(x, rng, sigma, freq, q, rate):
        a1, a2, var_e = resonance_coefficients(freq, q, dt)
        burn = int(20 * q / (np.pi * freq * dt))
        hits = rng.random(x.size + burn) < rate * dt
        e = hits * rng.standard_normal(x.size + burn) / np.sqrt(rate * dt)   # unit variance
        y = signal.lfilter([1.0], [1.0, -a1, -a2], e * np.sqrt(var_e))[burn:]
        return x + sigma * y

    return {
        'internal_lowpass': (one_pole, [{'pole': 0.3}, {'pole': 0.6}, {'pole': 0.005}]),
        'vibration': (harmonics, [{'amplitude': 0.1 * sig, 'freq': 8.7},
                                  {'amplitude': 0.25 * sig, 'freq': 15.9},
                                  {'amplitude': 0.017 * sig, 'freq': 8.7}]),
        'temperature_drift': (ramp, [{'amplitude': 3e-3, 't_r': 120.0},
                                     {'amplitude': 1e-2, 't_r': 300.0},
                                     {'amplitude': 5e-4, 't_r': 120.0}]),
        'bias_instability': (voss, [{'b': 1.5e-4}, {'b': 5e-4}, {'b': 5e-5}]),
        'rate_random_walk': (jump_walk, [{'k': 1.5e-5, 'hold': 30.0},
                                         {'k': 6e-5, 'hold': 30.0},
                                         {'k': 2e-6, 'hold': 30.0}]),
        'gauss_markov': (gm1, [{'sigma': 6e-4, 'tc': 3.0}, {'sigma': 2e-3, 'tc': 60.0},
                               {'sigma': 1.7e-4, 'tc': 3.0}]),
        'quantization': (dnl_counter, [{'step': 1.0 * inc, 'dnl': 0.3},
                                       {'step': 2.0 * inc, 'dnl': 0.3},
                                       {'step': 0.26 * inc, 'dnl': 0.3}]),
        'resonance': (burst_mode, [{'sigma': 0.25 * sig, 'freq': 21.5, 'q': 25.0, 'rate': 1.0},
                                   {'sigma': 0.8 * sig, 'freq': 36.0, 'q': 12.0, 'rate': 1.0},
                                   {'sigma': 0.045 * sig, 'freq': 21.5, 'q': 25.0,
                                    'rate': 1.0}]),
    }


def scalloping(bins: float) -> float:
    """Amplitude gain of a Hann window of ``WELCH_L`` for a line ``bins`` bins from 0 (mod 1)."""
    delta = bins - np.round(bins)
    w = np.hanning(WELCH_L)
    return float(abs(np.sum(w * np.exp(2j * np.pi * delta * np.arange(WELCH_L) / WELCH_L)))
                 / w.sum())


def gm_avar(tau, sigma, tc):
    """Allan variance of first-order Gauss-Markov noise (standard deviation sigma)."""
    x = tau / tc
    return 2 * sigma ** 2 * tc / tau * (1 - (3 - 4 * np.exp(-x) + np.exp(-2 * x)) / (2 * x))


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    big_t, nn = n * dt, n_arw ** 2
    p = params
    if name == 'internal_lowpass':
        return p['pole'] * np.sqrt(n)
    if name == 'vibration':
        return (scalloping(p['freq'] * WELCH_L * dt) ** 2 * p['amplitude'] ** 2
                * np.sqrt(n * WELCH_L) / (6 * sig ** 2))
    if name == 'temperature_drift':
        return 0.544 * p['amplitude'] * np.sqrt(p['t_r']) / n_arw
    if name == 'quantization':
        v = p['step'] ** 2 * (1 / 12 + p['dnl'] ** 2 / 3)
        return 0.9 * 3 * v / (nn * dt) / np.sqrt(3 / n + 40 / (3 * n))
    if name == 'resonance':
        return (p['sigma'] ** 2 * np.sqrt(big_t)
                / (4 * sig ** 2 * dt * np.sqrt(p['freq'] / p['q'])))
    tau = allan_taus(dt, big_t, 200)
    if name == 'bias_instability':
        excess = 2 * np.log(2) / np.pi * p['b'] ** 2 * np.ones_like(tau)
    elif name == 'rate_random_walk':
        excess = p['k'] ** 2 * tau / 3
    else:
        excess = gm_avar(tau, p['sigma'], p['tc'])
    return allan_z(excess, tau, nn, big_t)
