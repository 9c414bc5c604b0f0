"""
Held-out swing set J: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_i.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-I, and the kinds of departure
differ from shape to shape:

- time_delay: an asynchronous read: the gyro converts on its own clock (period Ti, not a
  divisor of the read interval) and every read returns the latest conversion, so a sample is
  as old as the time since that conversion, which sweeps through [0, Ti) at the beat of the
  two clocks: a sawtooth-varying delay of mean Ti / 2 (motion from the stand at the
  conversion instant; when Ti exceeds the read interval a conversion's noise is read again);
- g_sensitivity: an anisoelastic square law on top of the linear term: g_y f_y (1 + f_y / g),
  f_y = g sin(phi) (the g^2 coefficient equal to the g coefficient, per g): a smooth bias,
  larger on one side of the swing than on the other, a 2f line beside the fundamental;
- scale_factor_nonlinearity: counter dead time: a pulse-counting read-out (pulse rate
  proportional to |w|) loses the pulses that fall in its dead time, so the output is
  w / (1 + |w| / W) (non-paralysable dead time; output value, noise included): odd,
  compressive, and not analytic at zero (w - w |w| / W): all odd harmonics;
- scale_factor_asymmetry: a wandering asymmetry: the catalogue's a |w| (output value), its
  coefficient following the temperature difference between the torquer driver's two halves,
  a (1 + 0.5 u(t)), u a unit first-order Gauss-Markov process of 60 s: a random wander
  about a, never constant;
- timestamp_jitter: interrupt collisions: the gyro's interrupt service (h long, once per
  gyro period P) delays the encoder's interrupt whenever that falls inside it; the two
  clocks beat at 0.37 Hz, so the encoder stamps are late by max(0, h - psi P) (psi the
  beat phase, in [0, 1)), in bursts a fraction h / P of the time, ramping from h to 0; the
  mean h^2 / (2 P) calibrated out;
- encoder_cyclic_error: a scale joint: the encoder's tape scale is butted together at 7 deg
  with a gap error, so the reading steps by the gap while the head (0.05 deg wide) passes the
  joint and stays off by it beyond: an angle-locked step, crossed twice a swing.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- square law: the swing harmonics k = 1..6 of the memoryless rate error (Fourier over one
  period at A cos), in quadrature, against s;
- dead time, wandering asymmetry: the lines k >= 2 of the rate error at A w cos(wt) (k = 1
  a scale factor, k = 0 a bias), the error first averaged over the gyro's own noise (sd N
  sqrt(1 kHz), Gauss-Hermite), in quadrature, against s (the asymmetry at its mean
  coefficient a);
- asynchronous read, collisions, scale joint: matched detector on the noise-free angle
  residual (the integrated rate error of the aged samples; -phi_dot e; the joint's step with
  offset and scale fitted out) against the gyro angle noise N^2 / (2 pi f)^2, the encoder's
  white floor and the preset's stamp jitter (as sets D-I).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to tens of times further in
z. Physical scale: conversion periods of 0.335 ms (edge, 3 kHz), 2.13 ms and 5.71 ms (mean
ages 0.17, 1.07 and 2.86 ms); g_y of 3e-5, 2e-4 and 5e-4 rad/s/(m/s^2) (0.016-0.28
deg/s/g, the same per g^2); dead-time scales W of 315, 20 and 6 rad/s (compression
0.14 %, 2.1 % and 6.8 % at the 25 deg/s peak); asymmetries a of 5.5e-4 (edge), 0.01 and
0.04; service times h of 13, 150 and 400 us; scale gaps of 1.3, 8 and 30 arcsec (0.3-7 um
at a 50 mm radius).
"""
from heldout_detect import encoder_floor, fourier, matched_z, noise_lines, swing_scales
import numpy as np
from scipy import signal

G0 = 9.80665
SQUARE = 1.0                                # g^2 coefficient / g coefficient, per g
ASYM_SWING, ASYM_TC = 0.5, 60.0             # relative sd and correlation time of a(t)
BEAT_HZ = 0.37                              # beat of the gyro and encoder clocks
JOINT, HEAD = np.deg2rad(7.0), np.deg2rad(0.05)


def conversion_instants(t: np.ndarray, period: float, phase: float) -> np.ndarray:
    """Index j of the latest conversion at or before each read (conversions at j Ti + phase)."""
    return np.floor((np.asarray(t) - phase) / period).astype(np.int64)


def async_read(t, gyro, rate_at, period: float, phase: float) -> np.ndarray:
    """Return reads of the latest conversion: its motion and its noise (repeated if re-read)."""
    j = conversion_instants(t, period, phase)
    noise = gyro - rate_at(t)
    _, first, inverse = np.unique(j, return_index=True, return_inverse=True)
    return rate_at(j * period + phase) + noise[first[inverse]]


def square_law(f_y, gy: float) -> np.ndarray:
    """Bias g_y f_y (1 + SQUARE f_y / g)."""
    return gy * f_y * (1 + SQUARE * f_y / G0)


def dead_time(w, scale: float) -> np.ndarray:
    """Non-paralysable dead time: w / (1 + |w| / W)."""
    return w / (1 + np.abs(w) / scale)


def wandering(n: int, dt: float, rng) -> np.ndarray:
    """Asymmetry factor 1 + 0.5 u, u a unit first-order Gauss-Markov process (stationary)."""
    c = np.exp(-dt / ASYM_TC)
    w = rng.standard_normal(n) * np.sqrt(1 - c * c)
    w[0] = rng.standard_normal()
    return 1 + ASYM_SWING * signal.lfilter([1.0], [1, -c], w)


def collisions(t, period: float, busy: float, phase: float) -> np.ndarray:
    """Stamp delay max(0, h - psi P), psi = frac(phase + 0.37 Hz t), less its mean h^2/(2P)."""
    psi = np.mod(phase + BEAT_HZ * np.asarray(t), 1.0)
    return np.maximum(busy - psi * period, 0.0) - busy * busy / (2 * period)


def joint_error(phi, gap: float) -> np.ndarray:
    """Read minus true angle at a scale joint: 0 before, gap beyond, a ramp over the head."""
    return gap * np.clip((np.asarray(phi) - JOINT) / HEAD + 0.5, 0.0, 1.0)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def aged(imu_t, gyro, enc_t, enc, stand, rng, period):
        phase = rng.uniform(0, period) + imu_t[0] - period
        return imu_t, async_read(imu_t, gyro, lambda s: stand(s)[1], period, phase), enc_t, enc

    def anisoelastic(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + square_law(G0 * np.sin(stand(imu_t)[0]), gy), enc_t, enc

    def counter(imu_t, gyro, enc_t, enc, stand, rng, scale):
        return imu_t, dead_time(gyro, scale), enc_t, enc

    def wander(imu_t, gyro, enc_t, enc, stand, rng, a):
        dt = float(np.median(np.diff(imu_t)))
        return imu_t, gyro + a * wandering(gyro.size, dt, rng) * np.abs(gyro), enc_t, enc

    def collide(imu_t, gyro, enc_t, enc, stand, rng, busy):
        period = float(np.median(np.diff(imu_t)))
        return imu_t, gyro, enc_t + collisions(enc_t, period, busy, rng.uniform()), enc

    def joint(imu_t, gyro, enc_t, enc, stand, rng, gap):
        return imu_t, gyro, enc_t, enc + joint_error(enc, gap)

    arcsec = np.pi / 180 / 3600
    return {
        'time_delay': (aged, [{'period': 2.13e-3}, {'period': 5.71e-3}, {'period': 3.35e-4}]),
        'g_sensitivity': (anisoelastic, [{'gy': 2e-4}, {'gy': 5e-4}, {'gy': 3.03e-5}]),
        'scale_factor_nonlinearity': (counter, [{'scale': 20.0}, {'scale': 6.0},
                                                {'scale': 315.0}]),
        'scale_factor_asymmetry': (wander, [{'a': 0.01}, {'a': 0.04}, {'a': 5.45e-4}]),
        'timestamp_jitter': (collide, [{'busy': 1.5e-4}, {'busy': 4e-4}, {'busy': 1.29e-5}]),
        'encoder_cyclic_error': (joint, [{'gap': 8 * arcsec}, {'gap': 30 * arcsec},
                                         {'gap': 1.29 * arcsec}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    s_n = n_arw * np.sqrt(rate_hz)
    p = params
    if name == 'g_sensitivity':
        lines = [fourier(lambda phi, th: square_law(G0 * np.sin(phi), p['gy']), amp, k)
                 for k in range(1, 7)]
        return float(np.linalg.norm(lines) / s)
    if name == 'scale_factor_nonlinearity':
        return noise_lines(lambda v: dead_time(v, p['scale']) - v, amp * w, s_n) / s
    if name == 'scale_factor_asymmetry':
        return noise_lines(lambda v: p['a'] * np.abs(v), amp * w, s_n) / s
    floor = encoder_floor(enc, rate_hz)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        j = conversion_instants(t, p['period'], 0.0)
        err = amp * w * np.cos(w * j * p['period']) - rate
        residual = np.cumsum(err) / rate_hz
        residual -= residual.mean()
    elif name == 'encoder_cyclic_error':
        residual = joint_error(phi, p['gap'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    else:
        e = collisions(t, 1.0 / rate_hz, p['busy'], 0.0)
        residual = -rate * e
    return matched_z(residual, rate_hz, n_arw,
                     floor + (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz)
