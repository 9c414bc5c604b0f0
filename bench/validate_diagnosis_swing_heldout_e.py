"""
Held-out swing set E: written in session 7 without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_d.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B, C and D:

- time_delay: a vibration isolator: the IMU sits on elastomer mounts, a mechanical second-order
  low-pass (natural frequency f_n, damping 0.2) between the stand and the sensor, so the gyro
  senses the motion late by 2 zeta / w_n at the swing frequency; applied in continuous time to
  the motion (first-order-hold discretisation, run in from before the record), noise after it
  (catalogue stamps or a one-pole lag; dev Lagrange; B one-pole; C integrate-dump; D FIR: all
  electronic, none an underdamped mechanical mode);
- g_sensitivity: bilinear: the proof mass meets a stiffer suspension on one side (an
  anti-stiction bump or a one-sided electrostatic spring), so the g-sensitivity is g_y (1 + 0.6)
  for f_y > 0 and g_y (1 - 0.6) for f_y < 0: bias g_y (f_y + 0.6 |f_y|), a kink at level
  (catalogue, dev linear; B f_y f_z; C linear relaxation; D play hysteresis);
- scale_factor_nonlinearity: torquer self-heating: the rebalance power goes as w^2, heats the
  sensor through a 0.25 s thermal lag, and the scale factor follows the temperature: output
  w (1 + k LP(w^2)), a lagged cubic (catalogue static k2, k3, k5; dev tanh; B knee; C range
  switch; D lock-in dead band: all memoryless);
- scale_factor_asymmetry: magnetic after-effect of the torquer magnet: the direction-dependent
  gain a follows the current's direction through a 0.3 s relaxation, output w (1 + a m),
  m = LP(sign w): the gain relaxes after every reversal (catalogue a |w| instantly; dev, B
  smoothed in w; C comparator offset; D Schmitt trigger: switches at a threshold);
- timestamp_jitter: packet stamping: the encoder's samples reach the host in packets of 10
  (USB bulk transfers), each packet is stamped on arrival with a latency uniform in +-h around
  its calibrated mean and the samples back-filled at the nominal interval: an error held for
  10 samples, new each packet (catalogue Gaussian; dev white uniform, Gauss-Markov; B
  second-order Gauss-Markov; C heavy-tailed latency; D deterministic sawtooth);
- encoder_cyclic_error: graduation errors of the disk: each of the 4096 lines sits off its
  nominal place by an independent Gaussian error (one fixed disk, the same in every run),
  linear between lines: a random, non-periodic function of the angle (catalogue, dev, B
  sinusoidal harmonics of the line pitch; C triangle; D per-revolution harmonics).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- isolator: the angle residual's cos component A w d, d = -arg H(i w) / w ~ 2 zeta / w_n,
  against s / w;
- bilinear g: the fundamental of g_y (f + 0.6 |f|), f = g sin(A sin wt), by quadrature, against
  s (the |f| part adds a 2f line of 0.6 g_y g A 4 / (3 pi), not counted);
- self-heating: the 3f line of w k LP(w^2), k (A w)^3 / (4 sqrt(1 + (2 w tau)^2)), by
  quadrature of the settled waveform, against s;
- after-effect: the 2f line (both phases) of a w LP(sign w), settled, by quadrature, against s;
- packets, graduation: as set C's latency and set D's disk: a quadratic detector on the angle
  error -phi_dot e(t) with e held white (two-sided PSD (h^2 / 3) M dt sinc^2(f M dt)), and a
  matched detector on the disk's noise-free angle residual (offset and scale fitted out),
  against the gyro angle noise N^2 / (2 pi f)^2 plus the encoder's floor and stamp jitter.
Edges are at z ~ 4 at the 5 s period (at 2.5 s: isolator 4x, self-heating 5.9x, packets 3.1x,
after-effect 1.8x, disk 1.6x, bilinear g 1x); weak and strong are 5-20x further in z, the
packets' 12-130x (z goes as h^2). Physical scale: isolator resonances 335 Hz (edge) to 20 Hz
(strong, a soft mount); the strong g_y 5e-4 rad/s/(m/s^2) is 0.28 deg/s/g; the strong
self-heating k = 0.1 / (rad/s)^2 is 1.9 % of scale factor at the 0.44 rad/s peak (a torquer run
hard), the weak 0.6 %; packet latencies uniform in +-60 us (a USB high-speed microframe) to
+-200 us (a busy host); graduation errors of 0.3-1 arcsec rms are a glass disk's.
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, quadratic_z, swing_scales
import numpy as np
from scipy import signal

G0 = 9.80665
ZETA = 0.2                # damping of the isolator mode
ONE_SIDE = 0.6            # bilinear g-sensitivity: (1 +- ONE_SIDE) g_y
HEAT_TAU = 0.25           # s, thermal lag of the torquer's self-heating
MAG_TAU = 0.3             # s, relaxation of the torquer magnet's direction memory
PACKET = 10               # encoder samples per packet
LINES, DISK_SEED = 4096, 4096
RUN_IN = 10.0             # s of stand motion run through the lags before the record


def isolator(fn: float):
    """Continuous-time isolator transfer function (num, den) of natural frequency ``fn``."""
    wn = 2 * np.pi * fn
    return [wn * wn], [1.0, 2 * ZETA * wn, wn * wn]


def with_run_in(imu_t: np.ndarray, stand, seconds: float = RUN_IN):
    """Stand rate at ``seconds`` of nominal samples before ``imu_t`` and at ``imu_t``; count."""
    dt = float(np.median(np.diff(imu_t)))
    k = int(round(seconds / dt))
    t = np.r_[imu_t[0] - dt * np.arange(k, 0, -1), imu_t]
    return stand(t)[1], k, dt


def lag(x: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """One-pole low-pass of time constant ``tau`` (exponential form), started at x[0]."""
    a = np.exp(-dt / tau)
    return signal.lfilter([1.0 - a], [1.0, -a], x, zi=[a * x[0]])[0]


@lru_cache(maxsize=2)
def disk() -> np.ndarray:
    """Unit-sd graduation errors of the fixed disk's LINES lines (closed: last = first)."""
    g = np.random.default_rng(DISK_SEED).standard_normal(LINES)
    return np.r_[g, g[0]]


def graduation(phi: np.ndarray, sigma: float) -> np.ndarray:
    """Angle error of the disk at ``phi``: sigma times the line errors, linear between lines."""
    u = np.mod(phi, 2 * np.pi) * LINES / (2 * np.pi)
    return sigma * np.interp(u, np.arange(LINES + 1), disk())


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def mount(imu_t, gyro, enc_t, enc, stand, rng, fn):
        u, k, dt = with_run_in(imu_t, stand)
        b, a, _ = signal.cont2discrete(isolator(fn), dt, method='foh')
        b = np.ravel(b)
        y = signal.lfilter(b, a, u, zi=signal.lfilter_zi(b, a) * u[0])[0]
        return imu_t, gyro + y[k:] - u[k:], enc_t, enc

    def bilinear_g(imu_t, gyro, enc_t, enc, stand, rng, gy):
        f = G0 * np.sin(stand(imu_t)[0])
        return imu_t, gyro + gy * (f + ONE_SIDE * np.abs(f)), enc_t, enc

    def self_heating(imu_t, gyro, enc_t, enc, stand, rng, k):
        u, n0, dt = with_run_in(imu_t, stand)
        return imu_t, gyro + k * u[n0:] * lag(u * u, HEAT_TAU, dt)[n0:], enc_t, enc

    def after_effect(imu_t, gyro, enc_t, enc, stand, rng, a):
        u, n0, dt = with_run_in(imu_t, stand)
        return imu_t, gyro + a * u[n0:] * lag(np.sign(u), MAG_TAU, dt)[n0:], enc_t, enc

    def packets(imu_t, gyro, enc_t, enc, stand, rng, h):
        block = (np.arange(enc_t.size) + rng.integers(PACKET)) // PACKET
        return imu_t, gyro, enc_t + rng.uniform(-h, h, block[-1] + 1)[block], enc

    def disk_lines(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, enc_t, enc + graduation(enc, sigma)

    return {
        'time_delay': (mount, [{'fn': 64.0}, {'fn': 20.0}, {'fn': 335.0}]),
        'g_sensitivity': (bilinear_g, [{'gy': 1.5e-4}, {'gy': 5e-4}, {'gy': 3.08e-5}]),
        'scale_factor_nonlinearity': (self_heating, [{'k': 3e-2}, {'k': 0.1}, {'k': 5.8e-3}]),
        'scale_factor_asymmetry': (after_effect, [{'a': 2.5e-3}, {'a': 1e-2}, {'a': 4.97e-4}]),
        'timestamp_jitter': (packets, [{'h': 6e-5}, {'h': 2e-4}, {'h': 1.76e-5}]),
        'encoder_cyclic_error': (disk_lines, [{'sigma': 1.5e-6}, {'sigma': 5e-6},
                                              {'sigma': 2.74e-7}]),
    }


def lines(err, amp: float, k: int, period_s: float, m: int = 20000, settle: int = 6) -> float:
    """Magnitude of harmonic ``k`` of ``err(W cos(theta), dt)`` over its last period (settled)."""
    th = np.arange(settle * m) * 2 * np.pi / m
    y = err(amp * np.cos(th), period_s / m)[-m:]
    th = th[-m:]
    return float(2 * np.hypot(np.mean(y * np.cos(k * th)), np.mean(y * np.sin(k * th))))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'time_delay':
        num, den = isolator(p['fn'])
        d = -np.angle(np.polyval(num, 1j * w) / np.polyval(den, 1j * w)) / w
        return amp * w * d / (s / w)
    if name == 'g_sensitivity':
        def bil(r, dt):
            f = G0 * np.sin(amp * np.sin(np.arange(r.size) * dt * w))
            return p['gy'] * (f + ONE_SIDE * np.abs(f))
        return lines(bil, amp * w, 1, period_s, settle=1) / s
    if name == 'scale_factor_nonlinearity':
        return lines(lambda r, dt: p['k'] * r * lag(r * r, HEAT_TAU, dt), amp * w, 3,
                     period_s) / s
    if name == 'scale_factor_asymmetry':
        return lines(lambda r, dt: p['a'] * r * lag(np.sign(r), MAG_TAU, dt), amp * w, 2,
                     period_s) / s
    floor = encoder_floor(enc, rate_hz)
    if name == 'encoder_cyclic_error':
        t = np.arange(int(duration * rate_hz)) / rate_hz
        phi = amp * np.sin(w * t)
        residual = graduation(phi, p['sigma'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
        return matched_z(residual, rate_hz, n_arw,
                         floor + (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz)
    f = np.linspace(-rate_hz / 2, rate_hz / 2, 200001)
    hold = PACKET / rate_hz
    s_r = (amp * w) ** 2 / 2 * p['h'] ** 2 / 3 * hold * np.sinc(f * hold) ** 2
    return quadratic_z(s_r, f, n_arw, encoder_floor(enc, rate_hz, amp * w), duration)
