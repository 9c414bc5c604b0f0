"""
Held-out swing set K: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_j.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-J, and the kinds of departure
differ from shape to shape:

- time_delay: a notch: the gyro's second-order notch filter (set against a mount mode at f_n,
  width f_n / q) on the rate values, motion and noise alike; below the notch it delays by
  ~1 / (2 pi f_n q) with unit gain, and the gyro's noise leaves with a hole at f_n;
- g_sensitivity: creep of the die attach: the g-induced deflection relaxes through a broad
  spectrum of times (16 one-poles, 0.01-1000 s, equal weights, the relaxed compliance twice the
  unrelaxed): bias g_y (f_y + (1 / 16) sum_j LP_j(f_y)), f_y = g sin(phi), from rest: a linear
  response with a nearly constant loss angle (5.4, 5.2 and 5.0 deg at 2.5, 5 and 10 s);
- scale_factor_nonlinearity: a clipped carrier: the sense front end (range R) carries the
  Coriolis carrier w cos plus the quadrature 0.8 R sin and clips at +-R before demodulation,
  so the output is w g(R / sqrt(w^2 + 0.64 R^2)), g(r) = (2 / pi)(asin r + r sqrt(1 - r^2))
  the clip's describing function (output value, noise included): exactly linear up to |w| =
  0.6 R, then a 3/2-power onset, saturating at 4 R / pi;
- scale_factor_asymmetry: an oven-cycled asymmetry: the catalogue's a |w| (output value), its
  coefficient following the torquer driver's halves through the oven thermostat's 120 s
  cycle, a (1 + 0.8 tri(t / 120 s)): a periodic swing of the 2f line, sidebands at 1 / 120 s;
- timestamp_jitter: a busy host: the encoder's stamps are late by U h, U uniform, h = 5 us
  while the host is quiet and h (the level) while it is busy, in spells of mean 0.5 s every
  ~5 s (two-state Markov, 10 % of the time), the mean calibrated out: intermittent, clustered
  scatter plus a telegraph-like offset of the spell means;
- encoder_cyclic_error: cumulative pitch error: the disk's 4096 lines were ruled by a
  dividing engine whose line-to-line pitch errors add up, closed over the circle (a Brownian
  bridge, one fixed disk), linear between lines: a smooth, red, random function of the angle.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- creep: the harmonics k = 1..6 of g_y f_y times the creep's gain at k w, in quadrature,
  against s;
- clipped carrier, oven-cycled asymmetry: the lines k >= 2 of the rate error at A w cos(wt),
  the error first averaged over the gyro's own noise (Gauss-Hermite), in quadrature, against
  s (the asymmetry at its mean coefficient a, sidebands not counted);
- notch, disk: matched detector on the noise-free angle residual (the integrated rate error
  of the notched motion; the disk's error with offset and scale fitted out) against the gyro
  angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's stamp jitter;
- busy host: a quadratic detector on the angle error -phi_dot e(t), e of two-sided PSD
  ((h - h_q) / 2)^2 d (1 - d) 2 t_c / (1 + (2 pi f t_c)^2) (the spells' means) + E[h^2] / 12
  / f_s (the scatter), shifted by +-1 / 5 s, z = sqrt(T / 2 int (S_r / S_n)^2 df) (as set E).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: notches at 90 Hz (q 9.6, delay 0.19 ms), 53 Hz and 20 Hz (q 2,
1.5 and 4 ms); unrelaxed g_y of 2.2e-5, 2e-4 and 5e-4 rad/s/(m/s^2) (0.012-0.28 deg/s/g);
front-end ranges of 42, 39 and 32 deg/s (quadrature 34, 31, 25 deg/s; onsets 25.3, 23.4 and
18.9 deg/s against the swing's 25.1 deg/s peak); mean asymmetries a of 5.45e-4 (edge), 0.01
and 0.04; busy spreads of 29, 150 and 400 us; disk errors of 2.8, 12 and 40 arcsec rms.
"""
from heldout_detect import encoder_floor, matched_z, noise_lines, stamp_z, swing_scales
import numpy as np
from scipy import signal
from validate_diagnosis_heldout_k import two_state

G0 = 9.80665
CREEP_TAUS = np.geomspace(0.01, 1000.0, 16)     # s: the die attach's relaxation times
CREEP = 1.0                                     # relaxed / unrelaxed compliance - 1
QUAD = 0.8                                      # carrier quadrature, of the front end's range
OVEN_S, OVEN_DEPTH = 120.0, 0.8                 # thermostat cycle, swing of the asymmetry
BUSY_S, QUIET_S = 0.5, 4.5                      # mean busy and quiet spells of the host
QUIET = 5e-6                                    # s: latency spread while quiet
LINES, MOUNT = 4096, np.deg2rad(137.0)          # disk lines; where the swing sits on the disk
DISK_SEED = 4096


def notched(x: np.ndarray, notch_hz: float, q: float, rate_hz: float) -> np.ndarray:
    """``x`` through the second-order notch at ``notch_hz`` (width f_n / q), steady start."""
    b, a = signal.iirnotch(notch_hz, q, fs=rate_hz)
    return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]


def creep(f_y: np.ndarray, dt: float) -> np.ndarray:
    """f_y + (CREEP / J) sum_j LP_j(f_y): J one-poles of CREEP_TAUS, from rest (zero state)."""
    out = np.array(f_y, float)
    for tau in CREEP_TAUS:
        c = np.exp(-dt / tau)
        out += CREEP / CREEP_TAUS.size * signal.lfilter([1 - c], [1, -c], f_y)
    return out


def creep_gain(w, dt: float) -> np.ndarray:
    """Complex gain of ``creep`` at angular frequencies ``w`` (its one-poles exactly)."""
    z1 = np.exp(-1j * np.asarray(w, float)[..., None] * dt)
    c = np.exp(-dt / CREEP_TAUS)
    return 1 + CREEP / CREEP_TAUS.size * np.sum((1 - c) / (1 - c * z1), axis=-1)


def clip_gain(r) -> np.ndarray:
    """Return the describing function of a clip at r (of the carrier's amplitude), 1 if r >= 1."""
    r = np.minimum(np.asarray(r, float), 1.0)
    return 2 / np.pi * (np.arcsin(r) + r * np.sqrt(1 - r * r))


def carrier_clip(w, full: float) -> np.ndarray:
    """Demodulated rate when carrier w cos + QUAD full sin is clipped at +-full."""
    w = np.asarray(w, float)
    return w * clip_gain(full / np.hypot(w, QUAD * full))


def oven_cycle(t) -> np.ndarray:
    """1 + OVEN_DEPTH tri(t / OVEN_S): the asymmetry's factor through the thermostat cycle."""
    u = np.mod(np.asarray(t, float) / OVEN_S, 1.0)
    return 1 + OVEN_DEPTH * (1 - 4 * np.abs(u - 0.5))


def bursty(t: np.ndarray, busy: float, rng) -> np.ndarray:
    """Stamp latency U h less its mean, h = ``busy`` in busy spells and QUIET otherwise."""
    dt = float(np.median(np.diff(t)))
    spread = np.where(two_state(t.size, dt, BUSY_S, QUIET_S, rng) > 0, busy, QUIET)
    d = BUSY_S / (BUSY_S + QUIET_S)
    return spread * rng.uniform(size=t.size) - (d * busy + (1 - d) * QUIET) / 2


def bursty_psd(f, busy: float, rate_hz: float) -> np.ndarray:
    """Two-sided PSD of ``bursty``: the spells' mean (a telegraph) plus the white scatter."""
    d = BUSY_S / (BUSY_S + QUIET_S)
    tc = 1 / (1 / BUSY_S + 1 / QUIET_S)
    slow = ((busy - QUIET) / 2) ** 2 * d * (1 - d) * 2 * tc / (1 + (2 * np.pi * f * tc) ** 2)
    return slow + (d * busy ** 2 + (1 - d) * QUIET ** 2) / 12 / rate_hz


def disk_errors() -> np.ndarray:
    """Unit-rms error of every line of the fixed disk: cumulative pitch errors, closed."""
    pitch = np.random.default_rng(DISK_SEED).standard_normal(LINES)
    pos = np.r_[0.0, np.cumsum(pitch)]
    pos -= np.arange(LINES + 1) / LINES * pos[-1]             # the circle closes
    return pos / np.sqrt(np.mean(pos[:-1] ** 2))


def disk_error(phi, rms: float) -> np.ndarray:
    """Read minus true angle on the fixed disk (linear between lines), ``rms`` rad."""
    u = np.mod(np.asarray(phi, float) + MOUNT, 2 * np.pi) / (2 * np.pi) * LINES
    return rms * np.interp(u, np.arange(LINES + 1), disk_errors())


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def notch_delay(imu_t, gyro, enc_t, enc, stand, rng, notch_hz, q):
        return imu_t, notched(gyro, notch_hz, q, rate_hz), enc_t, enc

    def creeping(imu_t, gyro, enc_t, enc, stand, rng, gy):
        dt = float(np.median(np.diff(imu_t)))
        return imu_t, gyro + gy * creep(G0 * np.sin(stand(imu_t)[0]), dt), enc_t, enc

    def clipped(imu_t, gyro, enc_t, enc, stand, rng, full):
        return imu_t, carrier_clip(gyro, full), enc_t, enc

    def cycled(imu_t, gyro, enc_t, enc, stand, rng, a):
        factor = oven_cycle(imu_t + rng.uniform(0, OVEN_S))
        return imu_t, gyro + a * factor * np.abs(gyro), enc_t, enc

    def busy_host(imu_t, gyro, enc_t, enc, stand, rng, busy):
        return imu_t, gyro, enc_t + bursty(enc_t, busy, rng), enc

    def ruled(imu_t, gyro, enc_t, enc, stand, rng, rms):
        return imu_t, gyro, enc_t, enc + disk_error(enc, rms)

    arcsec = np.pi / 180 / 3600
    return {
        'time_delay': (notch_delay, [{'notch_hz': 53.0, 'q': 2.0},
                                     {'notch_hz': 20.0, 'q': 2.0},
                                     {'notch_hz': 90.0, 'q': 9.6}]),
        'g_sensitivity': (creeping, [{'gy': 2e-4}, {'gy': 5e-4}, {'gy': 2.2e-5}]),
        'scale_factor_nonlinearity': (clipped, [{'full': 0.68}, {'full': 0.55},
                                                {'full': 0.7365}]),
        'scale_factor_asymmetry': (cycled, [{'a': 0.01}, {'a': 0.04}, {'a': 5.45e-4}]),
        'timestamp_jitter': (busy_host, [{'busy': 1.5e-4}, {'busy': 4e-4}, {'busy': 2.9e-5}]),
        'encoder_cyclic_error': (ruled, [{'rms': 12 * arcsec}, {'rms': 40 * arcsec},
                                         {'rms': 2.8 * arcsec}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    s_n = n_arw * np.sqrt(rate_hz)
    p = params
    if name == 'g_sensitivity':
        th = np.arange(4096) * 2 * np.pi / 4096
        c = np.fft.rfft(G0 * np.sin(amp * np.sin(th)))[1:7] / th.size
        lines = 2 * np.abs(c * creep_gain(w * np.arange(1, 7), 1 / rate_hz)) * p['gy']
        return float(np.linalg.norm(lines) / s)
    if name == 'scale_factor_nonlinearity':
        return noise_lines(lambda v: carrier_clip(v, p['full']) - v, amp * w, s_n) / s
    if name == 'scale_factor_asymmetry':
        return noise_lines(lambda v: p['a'] * np.abs(v), amp * w, s_n) / s
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: bursty_psd(f, p['busy'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        residual = np.cumsum(notched(rate, p['notch_hz'], p['q'], rate_hz) - rate) / rate_hz
        residual -= residual.mean()
    else:
        residual = disk_error(phi, p['rms'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    return matched_z(residual, rate_hz, n_arw, floor)
