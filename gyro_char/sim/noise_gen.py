"""
Synthetic static sensor noise with a known IEEE 952 Allan variance (formula (4) of docs/method.md).

``generate`` returns rate samples (the channel's SI unit, e.g. rad/s) built as the sum of five
independent terms, each constructed so that its Allan variance is the closed form of
``gyro_char.allan.model``:

- N (angle random walk): white rate noise of variance N^2/dt -> N^2/tau exactly.
- B (bias instability): true 1/f rate noise, fractional integration (alpha = 1) of white noise
  by the Kasdin & Walter (1992) FFT filter with unit-variance innovations scaled by B. Its
  one-sided PSD is 2 B^2 dt / |2 sin(pi f dt)| ~ B^2 / (pi f), whose Allan variance is
  2 ln2 B^2 / pi = 0.664^2 B^2 (the IEEE flat floor) once tau >> dt.
- K (rate random walk): cumulative sum of white increments of variance K^2 dt ->
  K^2 tau / 3 + K^2 dt^2 / (6 tau) (the second term is the discrete-time remainder, negligible
  for tau >> dt).
- Q (quantization): white *angle* noise of standard deviation Q, differenced into rate ->
  3 Q^2 / tau^2 exactly.
- R (rate ramp): the deterministic ramp R t -> R^2 tau^2 / 2 exactly.

Everything is vectorised; 3.6 M samples take about a second. ``expected_avar`` gives the exact
discrete-time expectation of the generator's Allan variance (tests compare both with
``gyro_char.allan.model``).
"""
from functools import lru_cache

import numpy as np
from scipy import fft as sfft


def flicker(n: int, rng: np.random.Generator, alpha: float = 1.0,
            corner: float = 0.0) -> np.ndarray:
    """
    Return ``n`` samples of 1/f^alpha noise (Kasdin & Walter 1992), unit innovation variance.

    The filter h_0 = 1, h_k = h_{k-1} (k - 1 + alpha/2) / k is the impulse response of
    (1 - z^-1)^(-alpha/2); it is applied by a zero-padded FFT convolution (no wrap-around).
    ``corner`` > 0 (cycles per sample): band-limited flicker, the same noise also through
    (1 - b)^(alpha/2) (1 - b z^-1)^(-alpha/2), b = exp(-2 pi corner), whose impulse response
    is (1 - b)^(alpha/2) b^k h_k: unit gain at low frequency, PSD times
    ((1 - b) / |1 - b e^(-i w)|)^alpha, i.e. 1/f turning 1/f^2 above the corner (alpha = 1).
    The same random numbers are drawn with or without the corner.
    """
    if n <= 0:
        return np.zeros(0)
    w = rng.standard_normal(n)
    nfft = sfft.next_fast_len(2 * n, real=True)
    return sfft.irfft(_kernel_spectrum(n, float(alpha), float(corner), nfft)
                      * sfft.rfft(w, nfft), nfft)[:n]


@lru_cache(maxsize=1)
def _kernel_spectrum(n: int, alpha: float, corner: float, nfft: int) -> np.ndarray:
    """Return the rfft of ``flicker``'s filter (kept: a record's twins draw many of one length)."""
    k = np.arange(1, n, dtype=np.float64)
    h = np.empty(n)
    h[0] = 1.0
    h[1:] = np.cumprod((k - 1.0 + alpha / 2.0) / k)
    spec = sfft.rfft(h, nfft)
    if corner > 0:
        b = float(np.exp(-2.0 * np.pi * corner))
        # b^k underflows to 0 beyond ~700 / (2 pi corner) samples: the tail is exactly 0 there.
        g = (1.0 - b) ** (alpha / 2.0) * np.exp(np.arange(n) * np.log(b)) * h
        spec = spec * sfft.rfft(g, nfft)
    spec.flags.writeable = False
    return spec


def generate(n: int, dt: float, *, N: float = 0.0, B: float = 0.0, K: float = 0.0,
             Q: float = 0.0, R: float = 0.0, rng: np.random.Generator) -> np.ndarray:
    """
    Return ``n`` rate samples at interval ``dt`` whose Allan variance follows formula (4).

    Coefficients are the IEEE ones of noise.json (gyro: N rad/sqrt(s), B rad/s, K rad/s/sqrt(s),
    Q rad, R rad/s^2; accelerometer analogues). Terms with a zero coefficient cost nothing and
    draw no random numbers.
    """
    n = int(n)
    if n < 1:
        raise ValueError(f'need at least one sample, got n={n}')
    if not dt > 0:
        raise ValueError(f'dt must be > 0, got {dt}')
    for name, value in (('N', N), ('B', B), ('K', K), ('Q', Q), ('R', R)):
        if not np.isfinite(value) or value < 0:
            raise ValueError(f'{name} must be finite and >= 0, got {value}')
    rate = np.zeros(n)
    if N:
        rate += (N / np.sqrt(dt)) * rng.standard_normal(n)
    if B:
        rate += B * flicker(n, rng)
    if K:
        rate += (K * np.sqrt(dt)) * np.cumsum(rng.standard_normal(n))
    if Q:
        rate += (Q / dt) * np.diff(rng.standard_normal(n + 1))
    if R:
        rate += R * dt * np.arange(n, dtype=np.float64)
    return rate


def _flicker_avar_unit(m: int, length_factor: int = 2000) -> float:
    # Stationary-limit Allan variance of unit flicker: the Allan estimator is the filter
    # (H_j - 2 H_{j-m} + H_{j-2m}) / (sqrt(2) m) on the innovations, H = cumsum of h.
    length = length_factor * m
    k = np.arange(1, length, dtype=np.float64)
    h = np.concatenate([[1.0], np.cumprod((k - 0.5) / k)])
    big_h = np.concatenate([np.zeros(2 * m + 1), np.cumsum(h)])
    g = big_h[2 * m:] - 2.0 * big_h[m:-m] + big_h[:-2 * m]
    return float(np.dot(g, g) / (2.0 * m * m))


def expected_avar(m, dt: float, *, N: float = 0.0, B: float = 0.0, K: float = 0.0,
                  Q: float = 0.0, R: float = 0.0) -> np.ndarray:
    """
    Return the exact expected Allan variance of ``generate`` at tau = m dt (m integers).

    Equals formula (4) except for the discrete-time remainders: flicker is 1/ln2 = 1.44 times
    the IEEE floor at m = 1, 1.005 at m = 16; random walk adds K^2 dt^2 / (6 tau).
    """
    m = np.atleast_1d(np.asarray(m, dtype=np.int64))
    tau = m * dt
    out = N ** 2 / tau + K ** 2 * (tau / 3.0 + dt ** 2 / (6.0 * tau)) + 3.0 * Q ** 2 / tau ** 2
    out = out + R ** 2 * tau ** 2 / 2.0
    if B:
        out = out + B ** 2 * np.array([_flicker_avar_unit(int(mm)) for mm in m])
    return out
