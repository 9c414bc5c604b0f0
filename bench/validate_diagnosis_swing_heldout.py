"""
Held-out swing effect shapes: fixed before anybody saw diagnosis results, run once at the end.

``shapes(rate_hz)`` gives ``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t,
enc_angle, stand, rng, **params) -> (imu_t, gyro, enc_t, enc_angle)``; ``stand(t)`` is the true
(angle, rate). Each shape is unlike the catalogue's and the development shapes
(``validate_diagnosis_swing.py``):

- time_delay: a one-pole IIR smoothing of the gyro, group delay d at low frequency (catalogue:
  shifted stamps; dev: a Lagrange fractional-delay FIR);
- g_sensitivity: an anisoelastic g x g term k f_y f_z = k g^2 sin(phi) cos(phi) (catalogue and
  dev: linear in f);
- scale_factor_nonlinearity: a piecewise-linear knee, slope change s above |rate| 0.3 rad/s
  (catalogue: k2 w^2 + k3 w^3; dev: tanh saturation);
- scale_factor_asymmetry: a w erf(w / 0.15 rad/s) (catalogue a |w|; dev tanh, width 0.05);
- timestamp_jitter: a slowly wandering encoder stamp error, a second-order Gauss-Markov
  (0.3 s per stage; catalogue: white Gaussian, dev: white uniform);
- encoder_cyclic_error: 2nd + 4th harmonics (a4 = a2 / 2) on 512 lines (catalogue 1st + 2nd
  on 2048, dev 1st + 3rd on 1000).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg,
N = 1.89 deg/sqrt(h), so the sd of a fitted rate-residual sine is s = N sqrt(2 / T)). Given
at T_swing = 5 s; at 2.5 s the delay's z is 4x, the knee's ~2x, the asymmetry's and the cyclic
error's 2x, the jitter's ~6x, the g x g term's the same:

- delay: the angle residual's cos component A w d against N / w sqrt(2 / T);
- g x g: fundamental of k g^2 sin(2 phi) / 2 in the rate, k g^2 J1(2 A), against s;
- knee, asymmetry: the 3f (knee) or 2f (asymmetry) Fourier line of the rate error at the
  swing's rate W cos(wt), computed by quadrature, against s;
- jitter: angle error -phi_dot e(t); quadratic-detector deflection z^2 = (T/2) int
  (S_r / S_n)^2 df, S_r the modulated Lorentzian-squared spectrum, S_n the gyro angle
  noise N^2 / (2 pi f)^2 plus the encoder's white floor;
- cyclic: a chirp at k L |phi_dot| / 2 pi against the gyro angle noise N^2 / (2 pi f)^2:
  z^2 = sum over harmonics of a_k^2 (k L)^2 T (A w)^2 / (4 N^2).
Edges are at z ~ 4; weak and strong are 5-50x further.
"""
from gyro_char.sim.effects.base import second_order_gm
from heldout_detect import encoder_floor, stamp_z, swing_scales
import numpy as np
from scipy import signal, special

G0 = 9.80665
KNEE = 0.3          # rad/s
ASYM_WIDTH = 0.15   # rad/s
LINES = 512
JITTER_TC = 0.3     # s, per stage of the second-order Gauss-Markov


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    dt = 1.0 / rate_hz

    def iir_delay(imu_t, gyro, enc_t, enc, stand, rng, delay_s):
        a = delay_s / (delay_s + dt)            # DC group delay a / (1 - a) samples
        y = signal.lfilter([1.0 - a], [1.0, -a], gyro, zi=[a * gyro[0]])[0]
        return imu_t, y, enc_t, enc

    def g_by_g(imu_t, gyro, enc_t, enc, stand, rng, k):
        phi = stand(imu_t)[0]
        return imu_t, gyro + k * G0 * G0 * np.sin(phi) * np.cos(phi), enc_t, enc

    def knee(imu_t, gyro, enc_t, enc, stand, rng, s):
        w = stand(imu_t)[1]
        return imu_t, gyro + s * np.sign(w) * np.maximum(np.abs(w) - KNEE, 0.0), enc_t, enc

    def erf_asym(imu_t, gyro, enc_t, enc, stand, rng, a):
        w = stand(imu_t)[1]
        return imu_t, gyro + a * w * special.erf(w / ASYM_WIDTH), enc_t, enc

    def wander(imu_t, gyro, enc_t, enc, stand, rng, sigma_s):
        step = float(np.median(np.diff(enc_t)))
        e = sigma_s * second_order_gm(np.exp(-step / JITTER_TC), rng.standard_normal(enc_t.size),
                                      rng.standard_normal(2))
        return imu_t, gyro, np.maximum.accumulate(enc_t + e), enc

    def cyclic(imu_t, gyro, enc_t, enc, stand, rng, a2):
        x = LINES * enc
        return imu_t, gyro, enc_t, enc + a2 * np.sin(2 * x + 0.7) + 0.5 * a2 * np.sin(4 * x + 2.1)

    return {
        'time_delay': (iir_delay, [{'delay_s': 1e-3}, {'delay_s': 4e-3}, {'delay_s': 2e-4}]),
        'g_sensitivity': (g_by_g, [{'k': 2e-5}, {'k': 8e-5}, {'k': 3.3e-6}]),
        'scale_factor_nonlinearity': (knee, [{'s': -1e-2}, {'s': -4e-2}, {'s': -2.1e-3}]),
        'scale_factor_asymmetry': (erf_asym, [{'a': 3e-3}, {'a': 1e-2}, {'a': 5.2e-4}]),
        'timestamp_jitter': (wander, [{'sigma_s': 1e-3}, {'sigma_s': 2.5e-3},
                                      {'sigma_s': 3.5e-4}]),
        'encoder_cyclic_error': (cyclic, [{'a2': 2e-6}, {'a2': 1e-5}, {'a2': 2.3e-7}]),
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
        return amp * w * p['delay_s'] / (s / w)
    if name == 'g_sensitivity':
        return abs(p['k']) * G0 ** 2 * special.j1(2 * amp) / s
    if name == 'scale_factor_nonlinearity':
        line = harmonic(lambda r: np.sign(r) * np.maximum(np.abs(r) - KNEE, 0.0), amp * w, 3)
        return abs(p['s'] * line) / s
    if name == 'scale_factor_asymmetry':
        return abs(p['a'] * harmonic(lambda r: r * special.erf(r / ASYM_WIDTH), amp * w, 2)) / s
    if name == 'encoder_cyclic_error':
        big_a = p['a2'] ** 2 * (2 * LINES) ** 2 + (p['a2'] / 2) ** 2 * (4 * LINES) ** 2
        return float(np.sqrt(big_a * duration * (amp * w) ** 2 / (4 * n_arw ** 2)))

    def s_e(x):
        return 4 * p['sigma_s'] ** 2 * JITTER_TC / (1 + (2 * np.pi * x * JITTER_TC) ** 2) ** 2
    return stamp_z(s_e, amp * w, 1 / period_s, n_arw, encoder_floor(enc, rate_hz), duration,
                   rate_hz, 2000001)
