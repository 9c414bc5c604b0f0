"""
Held-out swing set AF: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_ae.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-R and AE, and the kinds of
departure differ from shape to shape:

- time_delay: re-anchored stamps: the host reads the IMU's FIFO in blocks and stamps the
  samples by counting back from an anchor, the host time of the first block read after the
  stream's (re)start; the anchor is late by however long that block had waited, a fresh
  uniform draw in [0, 2 d], and the driver re-anchors at every FIFO overrun, at Poisson times
  DWELL_S = 30 s apart on average (and once at the start): the gyro's stamps are late by a
  piecewise constant latency with random levels (mean d, sd d / sqrt(3)) that change at random
  instants, the values untouched (stamps kept in order, at least STAMP_GAP = a tenth of a step
  apart: the samples read just after a re-anchoring that shortened the latency are stamped
  bunched): random regime switches, no two runs alike;
- g_sensitivity: blanked compensation: the IMU cancels its gyro's g-sensitivity with its own
  accelerometer (exactly, while it runs), but the firmware runs the accelerometer's built-in
  self-test for SELFTEST_ON = 0.9 s every SELFTEST_S = 7.3 s (a housekeeping cycle of its own
  phase, drawn per run, unsynchronised with the swing), flags its data invalid meanwhile and
  skips the compensation: the raw g-sensitivity g_y f_y, f_y = g sin(phi), shows in those
  windows only (12.3 % of the time) and is exactly absent elsewhere: an intermittent,
  periodically gated g-sensitivity, the tilt-locked bias in bursts (sidebands of the swing's
  lines every 1 / 7.3 s);
- scale_factor_nonlinearity: auto-ranging with a hold timer: the IMU reads its front end in a
  fine range and uses its coarse range (gain off by e) from the sample after a reading x (the
  front end's value, noise and bias included) first exceeds R_UP = 0.35 rad/s in magnitude,
  and goes back only after HOLD_S = 0.15 s of readings in a row within R_DN = 0.30 rad/s (a
  timer that any louder reading restarts): out = x (1 + e h_k), h the range flag: a gain step
  whose on and off points are set by the gyro's own noise (its first excursion beyond R_UP
  comes about 1.8 noise sd early, its first quiet run of 150 readings late) and by time, not by
  the rate alone: each peak is read in the coarse range, entered early and left late (59 % of
  the time at the 5 s period; 89 % at 2.5 s, the fine range still used around each crossing);
- scale_factor_asymmetry: a self-heating driver half: the rebalance driver's negative half is a
  class-B output stage on a small heat sink of its own, dissipating in proportion to the
  current it carries (the true rate, while negative; the loop's noise enters after it), and its
  gain falls with its temperature: the negative half reads low by kappa T(t), T the one-pole
  (HEAT_S = 120 s, steps exp(-dt / HEAT_S)) of |w| 1(w < 0) from a cold start at the beginning
  of the run, the positive half untouched: out = x - kappa T w while w < 0: a one-sided gain
  that grows through the run towards kappa W / pi (W the peak rate), its settled size set by
  the swing itself (twice as large at the 2.5 s period, so its 2f line four times): a
  non-stationary, self-driven asymmetry;
- timestamp_jitter: a ringing time-sync servo: the host stamps the encoder's samples with its
  estimate of the DAQ's clock offset, from a PI servo that it updates at every sample from the
  sample's arrival time, whose latency scatters (white, Gaussian); the servo is tuned fast and
  under-damped (natural frequency SERVO_HZ = 25 Hz, damping SERVO_ZETA = 0.2), so the stamps err
  by the latency noise through the closed loop (2 zeta w_n s + w_n^2) / (s^2 + 2 zeta w_n s +
  w_n^2) (bilinear, prewarped at 25 Hz): a Gaussian stamp error of sd sigma (2.1 sigma of
  latency noise behind it) whose spectrum is flat below the loop, peaks 7.25 times higher at 25
  Hz and falls as f^-2 above it, its autocorrelation ringing (-0.52 at 20 ms); drawn in steady
  state (a burn-in of SERVO_BURN samples), stamps kept in order;
- encoder_cyclic_error: a tracking interpolator: the encoder's TRACK_LINES = 1440-line scale
  has a static interpolation error a (sin(u + 0.9) + 0.6 sin(2 u + 2.2)), u = 1440 phi (a
  track offset and an amplitude mismatch), but the converter does not take atan2 of the tracks
  at the sample instants: a type-II tracking loop (PI, natural frequency TRACK_HZ = 40 Hz,
  damping 0.7, clocked TRACK_TICKS = 4 times per encoder sample, ``track_loop``) follows the
  measured phase, the motion's own tracking error removed by the converter's velocity
  feed-forward, so the error reaches the output through the loop's closed-loop response at its
  own frequency k 1440 |phi_dot| / 2 pi: whole at the turning points, lagged and cut at speed
  (to 0.61 and 0.30 for the first and second harmonics at the 5 s swing's peak rate, 100 and
  201 Hz, phase -75 and -90 deg): a cyclic error whose size and phase follow the speed.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine; s_n =
N sqrt(f_s) the gyro's per-sample noise):

- re-anchored stamps: the matched detector on the noise-free angle residual of the mean
  latency d, rate(t - d) - rate(t) integrated, offset, bias ramp and scale factor fitted out,
  against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's
  stamp jitter (as sets M-R and AE); the latency's random part is not counted (a run's mean
  latency scatters by 0.15 d about d, its z with it);
- blanked compensation: the matched detector in the rate domain (``rate_z``: the windowed
  g_y f_y, window phase 0, bias and scale factor fitted out, against the gyro's white rate
  noise): the angle-domain one wraps the run around, and this residual's angle does not close
  over it (its z would then swing 1x-3x with the window phase; this one stays within +-1 %);
- auto-ranging: the lines k = 2..60 of the expected error e P(h_k) (w_k + b) along the swing
  (b the preset's bias), P(h_k) from the range logic's Markov chain (fine; or coarse with
  0..149 quiet readings counted, ``range_chain``) driven by Gaussian readings w + b + s_n n,
  from the fine range over three periods, against s; the switching's random part not counted;
- self-heating half: the lines k = 2..60 (the line at f is a scale factor, k = 0 a bias) of the
  noise-free run's error folded over the swing period, against s (its bias transient and the
  growth's sidebands not counted);
- ringing servo: the stamp error read through the swing's rate (``stamp_z``, as sets E, K-R
  and AE), its two-sided PSD sigma^2 |H(f)|^2 / (f_s sum h^2) of the digital loop;
- tracking interpolator: the matched detector on the noise-free angle residual of the error
  (offset, bias ramp and scale factor fitted out), as the re-anchored stamps'.
Edges are at z ~ 4 at the 5 s period (at 2.5 s: stamps 4x, self-heating 4x, servo 3.9x, g 1x,
interpolator 0.87x, auto-ranging 0.64x); weak and strong are 5 to 120 times further in z.
Physical scale: mean latencies of 0.188 (edge), 1 and 3 ms (uniform up to 0.376, 2 and 6 ms);
raw g_y of 8.7e-5, 5e-4 and 2e-3 rad/s/(m/s^2) (0.049, 0.28 and 1.1 deg/s/g, shown 12.3 % of
the time); range gain mismatches e of 0.079 %, 1 % and 4 %; heating coefficients kappa of
0.009, 0.05 and 0.2 per rad/s (settled gain drops of 0.13 %, 0.70 % and 2.8 % at the 5 s
period); servo stamp errors of 13.6, 40 and 150 us sd (from 29, 84 and 316 us of latency
noise); static interpolation errors a of 0.055, 1.0 and 6.2 arcsec (first harmonic; the
second 0.6 of it) on the 900 arcsec pitch.
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, stamp_z, swing_scales

import numpy as np

from scipy import signal, special

from validate_diagnosis_swing_heldout_m import fitted_residual

from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
DWELL_S = 30.0                              # mean time between re-anchorings, s
STAMP_GAP = 0.1                             # stamps kept this share of a step apart
SELFTEST_S, SELFTEST_ON = 7.3, 0.9          # s: self-test cycle; its blanking window
R_UP, R_DN, HOLD_S = 0.35, 0.30, 0.15       # rad/s, rad/s, s: range thresholds and hold
HEAT_S = 120.0                              # s: the driver half's thermal time constant
SERVO_HZ, SERVO_ZETA, SERVO_BURN = 25.0, 0.2, 4000   # the time-sync servo; burn-in
TRACK_LINES, TRACK_HZ, TRACK_ZETA, TRACK_TICKS = 1440, 40.0, 0.7, 4
TRACK_HARMONICS = ((1, 1.0, 0.9), (2, 0.6, 2.2))    # (k, relative amplitude, phase)


def increasing(s, step: float) -> np.ndarray:
    """Return stamps ``s`` kept in order: each at least STAMP_GAP ``step`` after the last."""
    s = np.asarray(s, float)
    gap = STAMP_GAP * step
    if s.size < 2 or np.all(np.diff(s) >= gap):
        return s
    k = np.arange(s.size) * gap
    return np.maximum.accumulate(s - k) + k


def anchor_latency(t, d: float, rng) -> np.ndarray:
    """
    Return each stamp's latency: uniform in [0, 2 d], redrawn at Poisson re-anchorings.

    The first anchor is at t[0]; re-anchorings follow at exponential gaps of mean DWELL_S.
    """
    t = np.asarray(t, float)
    span = float(t[-1] - t[0])
    gaps = rng.exponential(DWELL_S, int(span / DWELL_S * 2) + 20)
    while gaps.sum() <= span:
        gaps = np.r_[gaps, rng.exponential(DWELL_S, gaps.size)]
    starts = np.cumsum(gaps)
    starts = starts[starts < span]
    levels = rng.uniform(0.0, 2.0 * d, starts.size + 1)
    return levels[np.searchsorted(starts, t - t[0], side='right')]


def anchored_stamps(t, d: float, rng) -> np.ndarray:
    """Return the stamps t + latency (``anchor_latency``), kept in order."""
    t = np.asarray(t, float)
    lat = anchor_latency(t, d, rng)
    if not d:
        return t.copy()
    return increasing(t + lat, float(np.median(np.diff(t))))


def selftest_gate(t, phase: float) -> np.ndarray:
    """Return the self-test windows: (t - t[0] + phase) mod SELFTEST_S < SELFTEST_ON."""
    t = np.asarray(t, float)
    return np.mod(t - t[0] + phase, SELFTEST_S) < SELFTEST_ON


def range_flags(x, dt: float) -> np.ndarray:
    """
    Return the coarse-range flag h_k of each reading of ``x`` (fine range at the start).

    Fine -> coarse from the sample after a reading |x_k| > R_UP; coarse -> fine from the sample
    after the HOLD_S / dt-th reading in a row with |x| <= R_DN (counted while coarse).
    """
    x = np.asarray(x, float)
    m = max(int(round(HOLD_S / dt)), 1)
    ax = np.abs(x)
    loud = np.flatnonzero(ax > R_UP)
    idx = np.arange(x.size)
    last = np.maximum.accumulate(np.where(ax <= R_DN, -1, idx))   # last non-quiet reading
    done = np.flatnonzero(idx - last >= m)                         # m quiet readings ending
    flags = np.zeros(x.size, bool)
    k = 0
    while True:
        j = int(np.searchsorted(loud, k))
        if j == loud.size:
            break
        enter = int(loud[j])
        i = int(np.searchsorted(done, enter + 1))
        if i == done.size:
            flags[enter + 1:] = True
            break
        leave = int(done[i])
        flags[enter + 1:leave + 1] = True
        k = leave + 1
    return flags


def range_chain(mean, s_n: float, m: int, periods: int = 3) -> np.ndarray:
    """
    Return the probability of the coarse range at each sample of a periodic mean reading ``mean``.

    The range logic's Markov chain (state 0 fine; 1..m coarse with 0..m-1 quiet readings
    counted) driven by readings N(mean_k, s_n^2), from the fine range, over ``periods``
    repetitions of ``mean``; returns the last one's P(h_k).
    """
    mean = np.asarray(mean, float)
    sf = special.ndtr
    loud = sf((mean - R_UP) / s_n) + sf((-R_UP - mean) / s_n)
    quiet = sf((R_DN - mean) / s_n) - sf((-R_DN - mean) / s_n)
    pi = np.zeros(m + 1)
    pi[0] = 1.0
    out = np.empty(mean.size)
    new = np.empty(m + 1)
    for _ in range(periods):
        for k, (pl, pq) in enumerate(zip(loud.tolist(), quiet.tolist())):
            out[k] = 1.0 - pi[0]
            coarse = pi[1:]
            new[0] = pi[0] * (1.0 - pl) + coarse[-1] * pq
            new[1] = pi[0] * pl + (1.0 - pq) * coarse.sum()
            new[2:] = coarse[:-1] * pq
            pi, new = new, pi
    return out


def heating(t, w) -> np.ndarray:
    """Return the negative half's temperature T (rad/s units): one-pole HEAT_S of |w| 1(w < 0)."""
    t, w = np.asarray(t, float), np.asarray(w, float)
    a = float(np.exp(-float(np.median(np.diff(t))) / HEAT_S))
    return signal.lfilter([1.0 - a], [1.0, -a], np.where(w < 0, -w, 0.0))


def heated_error(t, w, kappa: float) -> np.ndarray:
    """Return the rate error -kappa T w of the self-heated negative half (0 while w >= 0)."""
    w = np.asarray(w, float)
    return np.where(w < 0, -kappa * heating(t, w) * w, 0.0)


@lru_cache(maxsize=8)
def servo_filter(fs: float):
    """
    Return (b, a, sum h^2) of the servo (2 zeta w s + w^2) / (s^2 + 2 zeta w s + w^2).

    Bilinear, prewarped at SERVO_HZ; sum h^2 over 2^15 samples of its impulse response.
    """
    w = 2.0 * fs * np.tan(np.pi * SERVO_HZ / fs)
    b, a = signal.bilinear([2.0 * SERVO_ZETA * w, w * w], [1.0, 2.0 * SERVO_ZETA * w, w * w], fs)
    h = signal.lfilter(b, a, np.r_[1.0, np.zeros(2 ** 15 - 1)])
    return b, a, float(np.sum(h * h))


def servo_error(n: int, fs: float, sigma: float, rng) -> np.ndarray:
    """Return n samples of the servo's offset error (s), sd sigma, after SERVO_BURN of burn-in."""
    b, a, energy = servo_filter(float(fs))
    x = rng.standard_normal(n + SERVO_BURN)
    return sigma / np.sqrt(energy) * signal.lfilter(b, a, x)[SERVO_BURN:]


def servo_stamps(t, sigma: float, rng) -> np.ndarray:
    """Return the stamps t + e (``servo_error`` at the stamps' own rate), kept in order."""
    t = np.asarray(t, float)
    if not sigma:
        return t.copy()
    step = float(np.median(np.diff(t)))
    return increasing(t + servo_error(t.size, 1.0 / step, sigma, rng), step)


def servo_psd(f, sigma: float, fs: float) -> np.ndarray:
    """Return the two-sided PSD (s^2/Hz) of the stamp error ``servo_error`` at ``f``."""
    b, a, energy = servo_filter(float(fs))
    h = signal.freqz(b, a, worN=2 * np.pi * np.asarray(f, float) / fs)[1]
    return sigma ** 2 * np.abs(h) ** 2 / (energy * fs)


def static_error(phi, a: float) -> np.ndarray:
    """Return the static interpolation error a sum_k r_k sin(k u + p_k), u = L phi (rad)."""
    u = TRACK_LINES * np.asarray(phi, float)
    return a * sum(r * np.sin(k * u + p) for k, r, p in TRACK_HARMONICS)


def track_loop(tick: float):
    """
    Return (b, a) of the tracking loop's closed-loop response at the loop's tick.

    PI loop: v_(n+1) = v_n + T K_i e_n, psi_(n+1) = psi_n + T (v_(n+1) + K_p e_n), e = m - psi,
    K_p = 2 zeta w_n, K_i = w_n^2 (w_n = 2 pi TRACK_HZ): H(z) = (B z^-1 - P z^-2) / (1 + (B -
    2) z^-1 + (1 - P) z^-2), B = T^2 K_i + T K_p, P = T K_p; H(1) = 1.
    """
    wn = 2.0 * np.pi * TRACK_HZ
    p = tick * 2.0 * TRACK_ZETA * wn
    big = tick * tick * wn * wn + p
    return np.array([0.0, big, -p]), np.array([1.0, big - 2.0, 1.0 - p])


def track_error(t, stand, a: float) -> np.ndarray:
    """
    Return the angle error of the tracking interpolator at the encoder's sample instants ``t``.

    The static error at TRACK_TICKS ticks per sample interval (the stand's true angle there),
    through the loop ``track_loop`` (started settled on the first tick), read at the samples.
    """
    t = np.asarray(t, float)
    if not a:
        return np.zeros(t.size)
    frac = np.arange(TRACK_TICKS) / TRACK_TICKS
    ticks = np.r_[(t[:-1, None] + np.diff(t)[:, None] * frac[None, :]).ravel(), t[-1]]
    e = static_error(stand(ticks)[0], a)
    b, den = track_loop(float(np.median(np.diff(t))) / TRACK_TICKS)
    out = signal.lfilter(b, den, e, zi=signal.lfilter_zi(b, den) * e[0])[0]
    return out[::TRACK_TICKS]


def rate_z(err, rate, n_arw: float, rate_hz: float) -> float:
    """
    Return the matched-detector z of a deterministic rate error in the gyro's white rate noise.

    Bias and scale factor (``rate``) fitted out: sqrt(sum r^2 / f_s) / N. The angle-domain
    detector (``matched_z``) less the encoder's floor, which is below the gyro's angle noise
    up to 600 Hz, without its wrap-around: a residual whose angle does not close over the run.
    """
    cols = np.c_[np.ones(np.size(err)), rate]
    r = err - cols @ np.linalg.lstsq(cols, err, rcond=None)[0]
    return float(np.sqrt(np.sum(r * r) / rate_hz) / n_arw)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def anchor(imu_t, gyro, enc_t, enc, stand, rng, d):
        return anchored_stamps(imu_t, d, rng), gyro, enc_t, enc

    def blank(imu_t, gyro, enc_t, enc, stand, rng, gy):
        gate = selftest_gate(imu_t, rng.uniform(0.0, SELFTEST_S))
        return imu_t, gyro + gy * G0 * np.sin(stand(imu_t)[0]) * gate, enc_t, enc

    def ranging(imu_t, gyro, enc_t, enc, stand, rng, e):
        h = range_flags(gyro, float(np.median(np.diff(imu_t))))
        return imu_t, gyro * (1.0 + e * h), enc_t, enc

    def heated(imu_t, gyro, enc_t, enc, stand, rng, kappa):
        return imu_t, gyro + heated_error(imu_t, stand(imu_t)[1], kappa), enc_t, enc

    def ringing(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, servo_stamps(enc_t, sigma, rng), enc

    def tracking(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + track_error(enc_t, stand, a)

    return {
        'time_delay': (anchor, [{'d': 1e-3}, {'d': 3e-3}, {'d': 1.88e-4}]),
        'g_sensitivity': (blank, [{'gy': 5e-4}, {'gy': 2e-3}, {'gy': 8.7e-5}]),
        'scale_factor_nonlinearity': (ranging, [{'e': 0.01}, {'e': 0.04}, {'e': 7.9e-4}]),
        'scale_factor_asymmetry': (heated, [{'kappa': 0.05}, {'kappa': 0.2}, {'kappa': 9e-3}]),
        'timestamp_jitter': (ringing, [{'sigma': 4e-5}, {'sigma': 1.5e-4},
                                       {'sigma': 1.36e-5}]),
        'encoder_cyclic_error': (tracking, [{'a': 5e-6}, {'a': 3e-5}, {'a': 2.67e-7}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    s_n = n_arw * np.sqrt(rate_hz)
    per = int(round(period_s * rate_hz))                     # samples a period
    if name == 'scale_factor_nonlinearity':
        from gyro_char.sim.config import BenchConfig
        bias = BenchConfig.from_preset('adis16405').gyro.bias['x']
        mean = amp * w * np.cos(w * np.arange(per) / rate_hz) + bias
        prob = range_chain(mean, s_n, max(int(round(HOLD_S * rate_hz)), 1))
        c = np.fft.rfft(p['e'] * prob * mean) / per
        return float(2 * np.linalg.norm(c[2:61]) / s)
    n = int(duration * rate_hz)
    t = np.arange(n) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'scale_factor_asymmetry':
        err = heated_error(t, rate, p['kappa'])
        fold = err[:n // per * per].reshape(-1, per).mean(axis=0)
        return float(2 * np.linalg.norm((np.fft.rfft(fold) / per)[2:61]) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: servo_psd(f, p['sigma'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    if name == 'encoder_cyclic_error':
        def stand(u):
            return amp * np.sin(w * u), amp * w * np.cos(w * u)
        return matched_z(angle_residual(track_error(t, stand, p['a']), t, phi), rate_hz,
                         n_arw, floor)
    if name == 'g_sensitivity':
        return rate_z(p['gy'] * G0 * np.sin(phi) * selftest_gate(t, 0.0), rate, n_arw, rate_hz)
    err = amp * w * np.cos(w * (t - p['d'])) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
