"""
Held-out effect shapes for ``validate_diagnosis.py --held-out``: fixed before tuning, run last.

Each shape is another physical form of a catalogue effect, unlike both the catalogue's and the
development shapes of ``validate_diagnosis.py``; levels are [weak, strong, edge of
detectability on a 2 h record], as there:

- internal_lowpass: a binomial FIR at the output rate ([1, 2, 1] / 4, [1, 3, 3, 1] / 8);
- vibration: a tone whose frequency drifts linearly by 0.03 Hz over the record;
- temperature_drift: two warm-up exponentials, a fast one (15 s) and a slow one (400 s);
- bias_instability: flicker by spectral synthesis (white noise shaped to 1/f by one FFT);
- rate_random_walk: Gaussian random-walk knots 1 s apart, linearly interpolated;
- gauss_markov: first-order Markov with a long correlation time (20 s);
- quantization: the accumulated angle rounded with a triangular dither (two uniform draws);
- resonance: a second-order resonance whose centre frequency wanders by +-1 % (a slow
  Gauss-Markov walk of the pole angle).
"""
import numpy as np
from scipy import signal


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def binomial(x, rng, taps):
        h = np.array([1.0, 2.0, 1.0]) / 4 if taps == 3 else np.array([1.0, 3.0, 3.0, 1.0]) / 8
        h = np.array([0.8, 0.2]) if taps == 2 else h
        return signal.lfilter(h, [1.0], x)

    def chirp(x, rng, amplitude, freq):
        t = np.arange(x.size) * dt
        f = freq + 0.03 * t / t[-1]
        phase = 2 * np.pi * np.cumsum(f) * dt + rng.uniform(0, 6.3)
        return x + amplitude * np.sin(phase)

    def two_exp(x, rng, amplitude):
        t = np.arange(x.size) * dt
        return x + amplitude * (0.6 * np.exp(-t / 15.0) + 0.4 * np.exp(-t / 400.0))

    def fft_flicker(x, rng, b):
        # Unit white noise has a two-sided PSD of dt per Hz: shape it to B^2 / (2 pi f).
        f = np.fft.rfftfreq(x.size, dt)
        spec = np.fft.rfft(rng.standard_normal(x.size))
        spec[0] = 0.0
        spec[1:] *= np.sqrt(b * b / (2 * np.pi * f[1:] * dt))
        return x + np.fft.irfft(spec, x.size)

    def knot_rw(x, rng, k):
        step = int(round(1.0 / dt))
        knots = np.cumsum(rng.standard_normal(x.size // step + 2)) * k * np.sqrt(1.0)
        return x + np.interp(np.arange(x.size), np.arange(knots.size) * step, knots)

    def gm1(x, rng, sigma, tc):
        a = np.exp(-dt / tc)
        w = rng.standard_normal(x.size) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal()
        return x + sigma * signal.lfilter([1.0], [1.0, -a], w)

    def tri_quant(x, rng, step):
        theta = np.cumsum(x) * dt / step
        dither = rng.uniform(-0.5, 0.5, x.size) + rng.uniform(-0.5, 0.5, x.size)
        counts = np.round(theta + dither)
        return np.diff(counts, prepend=0.0) * step / dt

    def wandering(x, rng, sigma, freq, q):
        a = np.exp(-dt / 30.0)
        walk = signal.lfilter([1.0], [1.0, -a], rng.standard_normal(x.size) * np.sqrt(1 - a * a))
        f = freq * (1.0 + 0.01 * walk / max(np.std(walk), 1e-12))
        r = np.exp(-np.pi * freq * dt / q)
        y = np.zeros(x.size)
        e = rng.standard_normal(x.size)
        c = 2 * r * np.cos(2 * np.pi * f * dt)
        for k in range(2, x.size):            # time-varying AR(2): a loop is the clearest
            y[k] = c[k] * y[k - 1] - r * r * y[k - 2] + e[k]
        return x + sigma * y / np.std(y)

    return {
        'internal_lowpass': (binomial, [{'taps': 3}, {'taps': 4}, {'taps': 2}]),
        'vibration': (chirp, [{'amplitude': 0.15 * sig, 'freq': 11.1},
                              {'amplitude': 0.3 * sig, 'freq': 27.3},
                              {'amplitude': 0.02 * sig, 'freq': 11.1}]),
        'temperature_drift': (two_exp, [{'amplitude': 3e-3}, {'amplitude': 1e-2},
                                        {'amplitude': 5e-4}]),
        'bias_instability': (fft_flicker, [{'b': 3e-4}, {'b': 1e-3}, {'b': 2e-5}]),
        'rate_random_walk': (knot_rw, [{'k': 3e-5}, {'k': 1e-4}, {'k': 1e-6}]),
        'gauss_markov': (gm1, [{'sigma': 1e-3, 'tc': 20.0}, {'sigma': 3e-3, 'tc': 20.0},
                               {'sigma': 2e-4, 'tc': 20.0}]),
        'quantization': (tri_quant, [{'step': 4 * n_arw * np.sqrt(dt)},
                                     {'step': 8 * n_arw * np.sqrt(dt)},
                                     {'step': 1.5 * n_arw * np.sqrt(dt)}]),
        'resonance': (wandering, [{'sigma': 0.3 * sig, 'freq': 19.0, 'q': 20.0},
                                  {'sigma': sig, 'freq': 24.0, 'q': 10.0},
                                  {'sigma': 0.08 * sig, 'freq': 19.0, 'q': 20.0}]),
    }
