"""
Held-out swing set P: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_o.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-O, and the kinds of departure
differ from shape to shape:

- time_delay: a growing backlog: the host consumes the IMU's samples a little slower than they
  arrive, so its driver queue fills and each rate value is published (and stamped) later and
  later: the latency grows linearly, d t / QUEUE_S (QUEUE_S = 900 s, d the latency after a
  whole run): rate(t - d t / QUEUE_S), a delay ramp, not a constant;
- g_sensitivity: a softening flexure: the sense mass's g-induced deflection has a cubic part
  that the factory's linear g-compensation leaves behind: bias c f_y^3 / g^2, f_y = g
  sin(phi): odd in tilt, zero for small tilts, lines at the swing's odd harmonics;
- scale_factor_nonlinearity: mismatched companding: the IMU's link compresses the rate word by
  mu-law (mu = 255, full scale W_FS = 5 rad/s) and the host expands it with mu (1 + e), a
  stale table: a smooth odd error that vanishes at zero and at full scale;
- scale_factor_asymmetry: a soaking driver half: the rebalance driver's negative half is
  switched in at each reversal to negative rate and its gain error a soaks away with SOAK_S =
  0.4 s (dielectric absorption in its hold capacitor): out = w + a e^(-(t - t_r) / SOAK_S) w
  while w < 0, t_r the last reversal to negative: an asymmetry that lives just after each
  reversal, none on the positive half;
- timestamp_jitter: two cores' clocks: the host's encoder thread is migrated by the scheduler
  between two cores whose time-stamp counters differ by Delta, at Poisson times (mean
  MIGRATE_S = 2 s): the encoder stamps' error is a random telegraph +-Delta / 2, two-sided PSD
  (Delta / 2)^2 2 tau / (1 + (2 pi f tau)^2), tau = MIGRATE_S / 2;
- encoder_cyclic_error: a Moire beat: a replacement scale's pitch is off the read head's
  reticle, and the head's averaging across its window leaves an error that beats every BEAT
  = 37 lines of a 4096-line disk (3.25 deg): a sin(2 pi phi / BEAT_RAD + p): a cyclic error of a
  period many lines long (about twelve cycles in each half swing).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine; s_n =
N sqrt(f_s) the gyro's per-sample noise):

- backlog, Moire beat: matched detector on the noise-free angle residual (the integrated rate
  error; the beat's error itself), offset, bias ramp and scale factor fitted out, against the
  gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's stamp jitter;
- flexure, soaking half: the lines k = 1..60 of the periodic rate error along the swing, in
  quadrature, against s;
- companding: lines k = 2..60 of the memoryless error averaged over the gyro's noise
  (``noise_lines``), against s;
- two cores: the stamp error read through the swing's rate (``stamp_z``, as sets E and K-O).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: backlogs reaching 0.15 ms (edge), 2 and 10 ms
after 900 s; flexures c of 3.3e-4, 5e-3 and 0.03 (rad/s)/(m/s^2) at 1 g; companding mismatches
e of 0.63, 3 and 10 %; soaking gain errors a of 0.3, 3 and 15 %; core clock offsets Delta of
227, 400 and 800 us; Moire beats of 0.62, 4.1 and 21 arcsec.
"""
from heldout_detect import encoder_floor, matched_z, noise_lines, stamp_z, swing_scales
import numpy as np
from validate_diagnosis_swing_heldout_m import fitted_residual
from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
QUEUE_S = 900.0                         # s: the run over which the backlog reaches d
MU, W_FS = 255.0, 5.0                   # mu-law; full scale (rad/s)
SOAK_S = 0.4                            # s: the driver half's soak time
MIGRATE_S = 2.0                         # s: mean time between thread migrations
BEAT_RAD = 37 * 2 * np.pi / 4096        # rad: the Moire beat's period in angle


def backlog(t, d: float) -> np.ndarray:
    """Latency d t / QUEUE_S of each sample."""
    return d * np.asarray(t, float) / QUEUE_S


def flexure(phi, c: float) -> np.ndarray:
    """Bias c f_y^3 / g^2, f_y = g sin(phi)."""
    return c * G0 * np.sin(np.asarray(phi, float)) ** 3


def compand(w, e: float) -> np.ndarray:
    """Compress w by mu-law (MU, W_FS), expand with MU (1 + e)."""
    w = np.asarray(w, float)
    c = np.log1p(MU * np.abs(w) / W_FS) / np.log1p(MU)
    mu2 = MU * (1 + e)
    return np.sign(w) * W_FS * np.expm1(c * np.log1p(mu2)) / mu2


def soak(t, rate, a: float) -> np.ndarray:
    """Rate error a e^(-(t - t_r) / SOAK_S) w while w < 0, t_r the last reversal to w < 0."""
    t, rate = np.asarray(t, float), np.asarray(rate, float)
    neg = rate < 0
    start = np.r_[neg[0], neg[1:] & ~neg[:-1]]
    t_r = t[np.maximum.accumulate(np.where(start, np.arange(t.size), 0))]
    return np.where(neg, a * np.exp(-(t - t_r) / SOAK_S) * rate, 0.0)


def cores(n: int, delta: float, rate_hz: float, rng) -> np.ndarray:
    """Random telegraph +-delta / 2 flipping at Poisson times of mean MIGRATE_S."""
    dur = n / rate_hz
    jumps = np.cumsum(rng.exponential(MIGRATE_S, int(3 * dur / MIGRATE_S) + 20))
    flips = np.searchsorted(jumps, np.arange(n) / rate_hz, side='right')
    sign = 1.0 if rng.uniform() < 0.5 else -1.0
    return sign * delta / 2 * (1 - 2 * (flips % 2))


def cores_psd(f, delta: float) -> np.ndarray:
    """Two-sided PSD (delta / 2)^2 2 tau / (1 + (2 pi f tau)^2), tau = MIGRATE_S / 2."""
    tau = MIGRATE_S / 2
    return (delta / 2) ** 2 * 2 * tau / (1 + (2 * np.pi * np.asarray(f, float) * tau) ** 2)


def moire(phi, a: float, phase: float = 0.0) -> np.ndarray:
    """Return the encoder error a sin(2 pi phi / BEAT_RAD + phase)."""
    return a * np.sin(2 * np.pi * np.asarray(phi, float) / BEAT_RAD + phase)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def queue(imu_t, gyro, enc_t, enc, stand, rng, d):
        late = stand(imu_t - backlog(imu_t - imu_t[0], d))[1]
        return imu_t, gyro + late - stand(imu_t)[1], enc_t, enc

    def flex(imu_t, gyro, enc_t, enc, stand, rng, c):
        return imu_t, gyro + flexure(stand(imu_t)[0], c), enc_t, enc

    def link(imu_t, gyro, enc_t, enc, stand, rng, e):
        return imu_t, compand(gyro, e), enc_t, enc

    def half(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + soak(imu_t, stand(imu_t)[1], a), enc_t, enc

    def migrate(imu_t, gyro, enc_t, enc, stand, rng, delta):
        return imu_t, gyro, enc_t + cores(enc_t.size, delta, rate_hz, rng), enc

    def beat(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + moire(stand(enc_t)[0], a, rng.uniform(0, 2 * np.pi))

    return {
        'time_delay': (queue, [{'d': 2e-3}, {'d': 1e-2}, {'d': 1.48e-4}]),
        'g_sensitivity': (flex, [{'c': 5e-3}, {'c': 3e-2}, {'c': 3.31e-4}]),
        'scale_factor_nonlinearity': (link, [{'e': 0.03}, {'e': 0.1}, {'e': 6.3e-3}]),
        'scale_factor_asymmetry': (half, [{'a': 0.03}, {'a': 0.15}, {'a': 3.04e-3}]),
        'timestamp_jitter': (migrate, [{'delta': 4e-4}, {'delta': 8e-4},
                                       {'delta': 2.27e-4}]),
        'encoder_cyclic_error': (beat, [{'a': 2e-5}, {'a': 1e-4}, {'a': 3e-6}]),
    }


def lines(err, amp: float, w: float, kmin: int = 1) -> float:
    """Norm of lines kmin..60 of ``err(t)`` over one swing period (4096 points)."""
    t = np.arange(4096) * (2 * np.pi / w) / 4096
    c = np.fft.rfft(err(t)) / t.size
    return float(2 * np.linalg.norm(c[kmin:61]))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    s_n = n_arw * np.sqrt(rate_hz)
    n = int(duration * rate_hz)
    if name == 'g_sensitivity':
        return float(lines(lambda t: flexure(amp * np.sin(w * t), p['c']), amp, w) / s)
    if name == 'scale_factor_asymmetry':
        def err(t):
            tt = np.r_[t, t + 2 * np.pi / w]                    # a second period: t_r known
            return soak(tt, amp * w * np.cos(w * tt), p['a'])[t.size:]
        return float(lines(err, amp, w) / s)
    if name == 'scale_factor_nonlinearity':
        return float(noise_lines(lambda v: compand(v, p['e']) - v, amp * w, s_n) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: cores_psd(f, p['delta']), amp * w, w / (2 * np.pi), n_arw,
                       floor, duration, rate_hz, 400001)
    t = np.arange(n) / rate_hz
    phi = amp * np.sin(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(moire(phi, p['a']), t, phi), rate_hz, n_arw, floor)
    err = amp * w * (np.cos(w * (t - backlog(t, p['d']))) - np.cos(w * t))
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
