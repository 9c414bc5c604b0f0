"""
Held-out swing set C: written in session 5 without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout.py``: ``shapes(rate_hz)`` gives ``{name:
(fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng, **params) ->
(imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape is unlike the
catalogue's, the development harness's (``validate_diagnosis_swing.py``) and set B's:

- time_delay: an integrate-and-dump read-out: each sample is the mean true rate over the last
  ``window_s`` (continuous time, exact from the stand angle), noise added after it; delay
  window / 2 (catalogue: shifted stamps; dev: Lagrange FIR; B: one-pole IIR on the gyro);
- g_sensitivity: a viscoelastic g-sensitivity: the bias g_y f_y reaches the output through a
  first-order relaxation of 0.15 s (die-attach creep), so it lags the tilt by 11 deg at 5 s;
- scale_factor_nonlinearity: a range switch with a gain mismatch: the scale factor is (1 + e)
  above |rate| 0.2 rad/s and 1 below (a discontinuous gain step; dev tanh, B a continuous knee);
- scale_factor_asymmetry: a direction-dependent gain switched by a comparator with an offset:
  a |w - 0.04 rad/s| (catalogue a |w|; dev, B: smoothed |w| centred at 0);
- timestamp_jitter: host-side encoder stamps late by a one-sided, heavy-tailed latency
  (95 % exponential of mean m, 5 % scheduler stalls exponential of mean 10 m), its mean
  1.45 m removed (a nominal latency calibrated out), stamps kept increasing;
- encoder_cyclic_error: a triangle-shaped sub-division error within each line of a coarse
  360-line disk (all odd harmonics, 1 / k^2), unlike the sinusoidal 1st-4th harmonics on
  512-2048 lines of the catalogue, dev and B.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- delay: the angle residual's cos component A w d (d = window / 2) against s / w;
- viscoelastic g: the fundamental of g_y g sin(A sin wt), 2 g_y g J1(A), through the lag's
  gain 1 / sqrt(1 + (w tau)^2), against s;
- range switch, comparator asymmetry: the 3f (range switch) or 2f (asymmetry) Fourier line of
  the rate error at the swing's rate W cos(wt), by quadrature, against s;
- latency: angle error -phi_dot e(t), e white of variance 9.80 m^2 (the mixture's): quadratic
  detector z^2 = (T/2) int (S_r / S_n)^2 df, S_r = (A w)^2 / 2 var(e) / f_enc, S_n the gyro
  angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's own stamp jitter;
- triangle cyclic error: the harmonics a_k = 8 a / (pi^2 k^2) (odd k) are chirps at k L
  |phi_dot| / 2 pi; a matched detector gives z^2 = sum_k int (a_k^2 / 2) / S_n(f_k(t)) dt over
  the times the chirp is below the encoder's Nyquist frequency (aliased parts not counted).
Edges are at z ~ 4 at the 5 s period (at 2.5 s: delay 4x, asymmetry, latency and cyclic error
2x, g 0.95x, range switch 0.27x: its 3f line shrinks when the switch sits lower in the
swing); weak and strong are 4-50x further in z, the latency's 450-4000x (its z grows with
the variance; weak is a typical 63 us sd).
"""
from heldout_detect import encoder_floor, quadratic_z, swing_scales
import numpy as np
from scipy import signal, special

G0 = 9.80665
G_LAG = 0.15         # s, relaxation time of the viscoelastic g-sensitivity
RANGE_SWITCH = 0.2   # rad/s
COMPARATOR = 0.04    # rad/s, offset of the direction comparator
STALL = (0.05, 10.0)  # share of stalls, their mean latency in units of m
LINES = 360


def latency_moments(mean_s: float) -> tuple:
    """Mean and variance of the latency mixture of base mean ``mean_s``."""
    p, k = STALL
    m1 = (1 - p) * mean_s + p * k * mean_s
    m2 = (1 - p) * 2 * mean_s ** 2 + p * 2 * (k * mean_s) ** 2
    return m1, m2 - m1 * m1


def triangle(x: np.ndarray) -> np.ndarray:
    """Triangle wave of period 2 pi and peak 1, sin-like phase (Fourier 8 / pi^2 sum ...)."""
    return 2.0 / np.pi * np.arcsin(np.sin(x))


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    dt = 1.0 / rate_hz

    def integrate_dump(imu_t, gyro, enc_t, enc, stand, rng, window_s):
        phi, rate = stand(imu_t)
        mean_rate = (phi - stand(imu_t - window_s)[0]) / window_s
        return imu_t, gyro + mean_rate - rate, enc_t, enc

    def viscoelastic_g(imu_t, gyro, enc_t, enc, stand, rng, gy):
        f_y = G0 * np.sin(stand(imu_t)[0])
        a = np.exp(-dt / G_LAG)
        lagged = signal.lfilter([1.0 - a], [1.0, -a], f_y, zi=[a * f_y[0]])[0]
        return imu_t, gyro + gy * lagged, enc_t, enc

    def range_switch(imu_t, gyro, enc_t, enc, stand, rng, e):
        w = stand(imu_t)[1]
        return imu_t, gyro + e * w * (np.abs(w) > RANGE_SWITCH), enc_t, enc

    def comparator_asym(imu_t, gyro, enc_t, enc, stand, rng, a):
        w = stand(imu_t)[1]
        return imu_t, gyro + a * np.abs(w - COMPARATOR), enc_t, enc

    def latency(imu_t, gyro, enc_t, enc, stand, rng, mean_s):
        stall = rng.random(enc_t.size) < STALL[0]
        lat = rng.exponential(mean_s, enc_t.size) * np.where(stall, STALL[1], 1.0)
        eps = 1e-7 * np.arange(enc_t.size)                  # keeps stamps strictly increasing
        te = np.maximum.accumulate(enc_t + lat - latency_moments(mean_s)[0] - eps) + eps
        return imu_t, gyro, te, enc

    def triangle_cyclic(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + a * triangle(LINES * enc + 0.9)

    return {
        'time_delay': (integrate_dump, [{'window_s': 2e-3}, {'window_s': 8e-3},
                                        {'window_s': 3.8e-4}]),
        'g_sensitivity': (viscoelastic_g, [{'gy': 1.5e-4}, {'gy': 6e-4}, {'gy': 3.1e-5}]),
        'scale_factor_nonlinearity': (range_switch, [{'e': 1e-2}, {'e': 3e-2}, {'e': 2.2e-3}]),
        'scale_factor_asymmetry': (comparator_asym, [{'a': 2.5e-3}, {'a': 1e-2},
                                                     {'a': 5.6e-4}]),
        'timestamp_jitter': (latency, [{'mean_s': 2e-5}, {'mean_s': 6e-5},
                                       {'mean_s': 9.5e-7}]),
        'encoder_cyclic_error': (triangle_cyclic, [{'a': 1e-5}, {'a': 5e-5}, {'a': 1.05e-6}]),
    }


def harmonic(func, amp: float, k: int, m: int = 200000) -> float:
    """Cosine coefficient of the k-th harmonic of ``func(amp cos(theta))`` over one period."""
    th = np.arange(m) * 2 * np.pi / m
    return float(2 * np.mean(func(amp * np.cos(th)) * np.cos(k * th)))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'time_delay':
        return amp * w * p['window_s'] / 2 / (s / w)
    if name == 'g_sensitivity':
        return abs(p['gy']) * G0 * 2 * special.j1(amp) / np.hypot(1.0, w * G_LAG) / s
    if name == 'scale_factor_nonlinearity':
        return abs(p['e'] * harmonic(lambda r: r * (np.abs(r) > RANGE_SWITCH), amp * w, 3)) / s
    if name == 'scale_factor_asymmetry':
        return abs(p['a'] * harmonic(lambda r: np.abs(r - COMPARATOR), amp * w, 2)) / s
    floor = encoder_floor(enc, rate_hz)
    if name == 'encoder_cyclic_error':
        th = np.arange(100000) * 2 * np.pi / 100000
        rate = np.abs(amp * w * np.cos(th))
        z2 = 0.0
        for k in range(1, 200, 2):
            f = k * LINES * rate / (2 * np.pi)
            s_n = n_arw ** 2 / np.maximum((2 * np.pi * f) ** 2, 1e-30) + floor
            z2 += np.mean(np.where(f < rate_hz / 2, 1.0 / s_n, 0.0)) * duration * (
                8 * p['a'] / (np.pi * k) ** 2) ** 2 / 2
        return float(np.sqrt(z2))
    f = np.linspace(-rate_hz / 2, rate_hz / 2, 200001)
    s_r = (amp * w) ** 2 / 2 * latency_moments(p['mean_s'])[1] / rate_hz
    return quadratic_z(s_r, f, n_arw, encoder_floor(enc, rate_hz, amp * w), duration)
