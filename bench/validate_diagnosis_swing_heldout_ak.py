"""
Held-out swing set AK: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_aj.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-R and AE-AJ, and the kinds of
departure differ from shape to shape:

- time_delay: a stalling logger: the recording host's logger stalls (garbage collection,
  write-back) at Poisson times STALL_S = 4 s apart on average, each stall exponential of mean
  m (``stalls``: the gaps drawn first, then the lengths, from STALL_PRE = 10 s before the run;
  overlapping stalls merged); the IMU's samples wait in the driver's buffer and are stamped
  when read, the reader catching up at DRAIN = 8 samples a step after each stall
  (``read_times``: r_k = max(p_k, r_(k-1) + dt / DRAIN), none read inside a stall), the values
  untouched: a latency S at a stall's start that drains linearly (at 1 - 1 / DRAIN) to nothing
  over S DRAIN / (DRAIN - 1), none between: random, Poisson-triggered triangular bursts of
  latency, the stamps bunched DRAIN to a step while they drain; the mean latency of isolated
  stalls m^2 DRAIN / ((DRAIN - 1) STALL_S) = 0.286 m^2 / s (``stall_mean``);
- g_sensitivity: an extrapolating compensation: the bench host cancels the gyro's g_y f_y (f_y
  = g sin(phi)) with the IMU's accelerometer topic, which a throttle has cut to a message every
  ACC_S = 0.93 s (the first at a phase uniform over the period, drawn per run,
  ``accel_phase``), and bridges the gaps by extrapolating linearly from the last two messages
  (``extrapolated``): the residual g_y (f_y - f_pred) (``extrapolated_error``) is nil at each
  message, for a steady tilt and for a tilt ramp, and grows with f_y's curvature between
  messages: a multi-rate, predictive error unsynchronised with the swing: its line at the
  swing's frequency H(w ACC_S) of the raw g_y f_y's, H(x) = 1 - (1 - e^(-ix)) / (ix) - (1 -
  e^(-ix)) (e^(-ix) (1 + ix) - 1) / x^2 (0.514, 127 deg ahead, at the 5 s period; 1.50, 75 deg
  ahead, at 2.5 s), a third of its power (at 5 s) in sidebands of the message rate;
- scale_factor_nonlinearity: an AC-coupled compressor: a DC servo on the IMU front end's first
  stage AC-couples what its second stage sees, v = w - LP(w) (LP a one-pole of TAU_AC = 1 s,
  settled over PRE_AC = 10 s before the run, ``ac_coupled``; w the true rate, the read-out
  noise after it), the low frequencies restored digitally and linearly, and the second stage
  compresses: out = x - k3 v^3 (``ac_error``): a cubic of a filtered rate (a Wiener system),
  nil for a steady rate; at the swing's frequency v is 0.782 of the rate and 38.5 deg ahead
  of it at the 5 s period (0.929, 21.7 deg at 2.5 s), so its 3f line is 0.478 of a memoryless
  -k3 w^3's and 115.5 deg ahead of it (0.801, 65.1 deg at 2.5 s), its line at f partly in
  quadrature with the rate;
- scale_factor_asymmetry: a hunting balance trim: the IMU's firmware balances its rebalance
  driver's halves in the background by a sign-only step at each reversal to negative rate, and
  with no dead zone it never settles but hunts across the balance: the negative half's gain is
  off by +a and -a on alternate swings (``hunt_signs``: (-1)^(j + b), j the count of reversals
  to w < 0, b 0 or 1 per run), out = x + (-1)^(j + b) a w while w < 0 (``hunt_error``; the
  true rate): a one-sided gain that flips every swing, a period-doubled pattern: no mean
  asymmetry, no line at any harmonic of the swing, its lines at the half-integer ones (f / 2,
  3 f / 2, ...);
- timestamp_jitter: a fractional-N sample clock: the encoder's DAQ times its 1 ms conversion
  period from a slow timer clock of period tick (the period not a whole number of ticks) by a
  dithered second-order MASH divider, each period a whole number of ticks, their mean exact,
  and stamps nominally: each conversion errs by the divider's phase error tick (q_k -
  q_(k-1)), q the second stage's residue, uniform in [0, 1) (``mash_errors``): triangular on
  (-tick, tick), sd tick / sqrt(6), its lag-1 correlation -0.5 and none beyond, its running
  sum bounded (no drift): noise-shaped (blue) jitter, PSD tick^2 sin^2(pi f / f_s) / (3 f_s)
  (``mash_psd``), nil at DC and twice white's at the Nyquist frequency (stamps in order);
- encoder_cyclic_error: a sagging read head: the stand's angle is read by a head on the
  swinging arm over a magnetic tape of HEAD_LINES = 2880 poles a turn (0.5 mm at a 229 mm
  radius) fixed to the frame; the head's thin bracket bends under the component of its weight
  along the tape, g sin(phi), tipping the head so that its sine and cosine bridges sit at
  different gaps: their amplitudes part in proportion to sin(phi), and the interpolation errs at
  twice the pole frequency: a sin(phi) sin(2 HEAD_LINES phi + HEAD_PHASE) (``head_error``; a at
  1 g): a cyclic error modulated by the tilt: nil on the level (and at rest there), changing
  sign through it, largest at the turning points (0.342 a at 20 deg), where the stand is
  slowest (its frequency 2 HEAD_LINES |phi_dot| / 2 pi: 266 Hz at 15 deg of the 5 s swing, 402
  Hz at its peak rate, where it is nil; at 2.5 s 804 Hz at the peak, aliased to 196 Hz).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW):

- stalling logger: the matched detector on the noise-free angle residual of the mean latency
  (``stall_mean``), rate(t - d) - rate(t) integrated, offset, bias ramp and scale factor fitted
  out, against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the
  preset's stamp jitter (as sets AG-AJ); the bursts about the mean not counted;
- extrapolating compensation: the matched detector in the rate domain (AF's ``rate_z``, bias
  and scale factor fitted out), the first message at the run's start;
- AC-coupled compressor: the same rate-domain matched detector;
- hunting trim: the same, b = 0;
- fractional-N clock: the stamp error read through the swing's rate (``stamp_z``, as sets
  AG-AJ), of its PSD ``mash_psd``;
- sagging head: the matched detector on the noise-free angle residual, as the logger's.
Edges solve z = 4 at the 5 s period, weak and strong z = 25 and 100 (``levels``, 3 digits; at
2.5 s the edges' z are: AC-coupled compressor 9.4x, logger 4.0x, compensation 2.5x, trim
2.0x, fractional-N clock 1.8x, sagging head 0.98x). Physical scale: stalls of mean m 25.7
(edge), 64.1 and 128 ms (mean latencies 0.189, 1.17 and 4.68 ms; latent 0.7, 1.8 and 3.7 % of
the time); raw g_y of 6.42e-5, 4.01e-4 and 1.6e-3 rad/s/(m/s^2) (0.036, 0.23 and 0.90
deg/s/g); k3 of 4.85e-3, 0.0303 and 0.121 (rad/s)^-2 (compressions k3 v^2 at the 5 s swing's
peak v of 0.343 rad/s: 0.057 %, 0.36 % and 1.4 %); trim hunts a of 0.033 %, 0.21 % and 0.84
%; ticks of 5.56, 13.9 and 27.8 us (timer clocks of 180, 72 and 36 kHz; sds of 2.3, 5.7 and
11 us beside the preset's own 20 us white jitter); head errors a of 4.1e-7, 2.56e-6 and
1.02e-5 rad at 1 g (0.029, 0.18 and 0.72 arcsec at the 20 deg turning points, on the 225
arcsec period of the pole pitch's second harmonic; bridge imbalances 2 HEAD_LINES a of 0.24 %,
1.5 % and 5.9 % at 1 g).
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, print_levels, solved_levels
from heldout_detect import stamp_z, step_of, swing_scales

import numpy as np

from scipy import signal

from validate_diagnosis_swing_heldout_af import increasing, rate_z

from validate_diagnosis_swing_heldout_m import fitted_residual

from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
STALL_S, DRAIN, STALL_PRE = 4.0, 8.0, 10.0   # s between stalls; catch-up pace; s run in before
ACC_S = 0.93                            # s: period of the accelerometer's messages
TAU_AC, PRE_AC = 1.0, 10.0              # s: the stage's AC coupling; s settled before the run
HEAD_LINES, HEAD_PHASE = 2880, 1.1      # the tape's lines a turn; the imbalance error's phase
KEY = {'time_delay': 'm', 'g_sensitivity': 'gy', 'scale_factor_nonlinearity': 'k3',
       'scale_factor_asymmetry': 'a', 'timestamp_jitter': 'tick', 'encoder_cyclic_error': 'a'}
TARGETS = (25.0, 100.0, 4.0)            # z of the weak, strong and edge levels
GUESS = {'time_delay': 0.03, 'g_sensitivity': 1e-4, 'scale_factor_nonlinearity': 1e-3,
         'scale_factor_asymmetry': 1e-3, 'timestamp_jitter': 1e-5, 'encoder_cyclic_error': 1e-6}
SLOPE = {'time_delay': 2.0, 'timestamp_jitter': 2.0}    # first guess of d ln z / d ln x


def stalls(t0: float, t1: float, m: float, rng):
    """
    Return the logger's stalls over [t0, t1] as merged (starts, ends).

    Starts a Poisson process of mean gap STALL_S from t0 (the gaps drawn first, then the
    lengths), lengths exponential of mean m; overlapping stalls merged into one.
    """
    gaps = rng.exponential(STALL_S, int((t1 - t0) / STALL_S * 2) + 20)
    start = t0 + np.cumsum(gaps)
    start = start[start < t1]
    if not start.size:
        return start, start
    end = np.maximum.accumulate(start + rng.exponential(m, start.size))
    first = np.r_[True, start[1:] > end[:-1]]
    last = np.r_[first[1:], True]
    return start[first], end[last]


def blocked_until(x, starts, ends) -> np.ndarray:
    """Return each time ``x``, or the end of the stall it falls in."""
    x = np.asarray(x, float)
    if not np.size(starts):
        return x.copy()
    k = np.searchsorted(starts, x, side='right') - 1
    inside = (k >= 0) & (x < ends[np.maximum(k, 0)])
    return np.where(inside, ends[np.maximum(k, 0)], x)


def read_times(p, step: float, starts, ends) -> np.ndarray:
    """
    Return the reader's times of the samples produced at ``p``: in order, none in a stall.

    r_k = max(p_k, r_(k-1) + step / DRAIN), pushed to a stall's end where it falls in one.
    """
    a = blocked_until(p, starts, ends)
    k = np.arange(a.size) * (step / DRAIN)
    while True:
        r = np.maximum.accumulate(a - k) + k
        late = blocked_until(r, starts, ends) > r + 1e-9
        if not np.any(late):
            return np.maximum(r, p)
        a[late] = blocked_until(r[late], starts, ends)


def stall_stamps(t, m: float, rng) -> np.ndarray:
    """Return the stamps of samples taken at ``t``: their read times (``read_times``)."""
    t = np.asarray(t, float)
    if not m:
        return t.copy()
    step = step_of(t)
    pre = int(round(STALL_PRE / step))
    p = np.r_[t[0] - step * np.arange(pre, 0, -1), t]
    starts, ends = stalls(p[0], p[-1], m, rng)
    return read_times(p, step, starts, ends)[pre:]


def stall_mean(m: float) -> float:
    """Return the mean latency m^2 DRAIN / ((DRAIN - 1) STALL_S) of isolated stalls."""
    return m * m * DRAIN / ((DRAIN - 1.0) * STALL_S)


def accel_phase(rng) -> float:
    """Return the first message's offset from the run's start, uniform in [0, ACC_S)."""
    return float(rng.uniform(0.0, ACC_S))


def extrapolated(t, f_of, u: float) -> np.ndarray:
    """
    Return the compensation's f_y: extrapolated from the last two messages.

    Messages of f_y = ``f_of(t)`` at t_0 + u + j ACC_S; at t, f_j + (t - t_j) (f_j - f_(j-1))
    / ACC_S, t_j the last at or before t.
    """
    t = np.asarray(t, float)
    tj = t[0] + u + np.floor((t - t[0] - u) / ACC_S) * ACC_S
    fj, fp = f_of(tj), f_of(tj - ACC_S)
    return fj + (t - tj) * (fj - fp) / ACC_S


def extrapolated_error(t, f_of, gy: float, u: float) -> np.ndarray:
    """Return the compensation's residual gy (f_y - ``extrapolated``)."""
    return gy * (f_of(np.asarray(t, float)) - extrapolated(t, f_of, u))


def ac_coupled(t, w_of) -> np.ndarray:
    """
    Return the AC-coupled rate v = w - LP(w) at ``t`` (w = ``w_of(t)``, the true rate).

    LP the one-pole of TAU_AC (steps exp(-dt / TAU_AC)), run over PRE_AC s before the run
    from the rate there.
    """
    t = np.asarray(t, float)
    step = step_of(t)
    pre = int(round(PRE_AC / step))
    w = w_of(np.r_[t[0] - step * np.arange(pre, 0, -1), t])
    a = float(np.exp(-step / TAU_AC))
    low = signal.lfilter([1.0 - a], [1.0, -a], w, zi=[a * w[0]])[0]
    return (w - low)[pre:]


def ac_error(v, k3: float) -> np.ndarray:
    """Return the AC-coupled stage's compression -k3 v^3."""
    v = np.asarray(v, float)
    return -k3 * v * v * v


def hunt_signs(w, rng) -> np.ndarray:
    """
    Return the trim's sign (-1)^(j + b) of each sample, j its count of reversals to w < 0.

    b 0 or 1 per run.
    """
    neg = np.asarray(w, float) < 0
    j = np.cumsum(neg & ~np.r_[False, neg[:-1]])
    return np.where((j + rng.integers(2)) % 2 == 0, 1.0, -1.0)


def hunt_error(w, a: float, signs) -> np.ndarray:
    """Return the negative half's gain error: signs a w while w < 0, else 0."""
    w = np.asarray(w, float)
    return np.where(w < 0, a * signs * w, 0.0)


def mash_errors(n: int, tick: float, rng) -> np.ndarray:
    """Return n trigger-time errors tick (q_k - q_(k-1)), q uniform in [0, 1), n + 1 drawn."""
    q = rng.random(n + 1)
    return tick * np.diff(q)


def mash_stamps(t, tick: float, rng) -> np.ndarray:
    """Return the stamps t + ``mash_errors`` (kept in order)."""
    t = np.asarray(t, float)
    if not tick:
        return t.copy()
    return increasing(t + mash_errors(t.size, tick, rng), step_of(t))


def mash_psd(f, tick: float, fs: float) -> np.ndarray:
    """Return the two-sided PSD (s^2/Hz) tick^2 sin^2(pi f / fs) / (3 fs) of ``mash_errors``."""
    return tick * tick * np.sin(np.pi * np.asarray(f, float) / fs) ** 2 / (3.0 * fs)


def head_error(phi, a: float) -> np.ndarray:
    """Return the loaded head's error a sin(phi) sin(2 HEAD_LINES phi + HEAD_PHASE)."""
    phi = np.asarray(phi, float)
    return a * np.sin(phi) * np.sin(2 * HEAD_LINES * phi + HEAD_PHASE)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def stalled(imu_t, gyro, enc_t, enc, stand, rng, m):
        return stall_stamps(imu_t, m, rng), gyro, enc_t, enc

    def predicted(imu_t, gyro, enc_t, enc, stand, rng, gy):
        err = extrapolated_error(imu_t, lambda u: G0 * np.sin(stand(u)[0]), gy,
                                 accel_phase(rng))
        return imu_t, gyro + err, enc_t, enc

    def coupled(imu_t, gyro, enc_t, enc, stand, rng, k3):
        return imu_t, gyro + ac_error(ac_coupled(imu_t, lambda u: stand(u)[1]), k3), enc_t, enc

    def hunted(imu_t, gyro, enc_t, enc, stand, rng, a):
        w = stand(imu_t)[1]
        return imu_t, gyro + hunt_error(w, a, hunt_signs(w, rng)), enc_t, enc

    def divided(imu_t, gyro, enc_t, enc, stand, rng, tick):
        return imu_t, gyro, mash_stamps(enc_t, tick, rng), enc

    def loaded(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + head_error(stand(enc_t)[0], a)

    return {
        'time_delay': (stalled, [{'m': 0.0641}, {'m': 0.128}, {'m': 0.0257}]),
        'g_sensitivity': (predicted, [{'gy': 4.01e-4}, {'gy': 1.6e-3}, {'gy': 6.42e-5}]),
        'scale_factor_nonlinearity': (coupled, [{'k3': 0.0303}, {'k3': 0.121},
                                                {'k3': 4.85e-3}]),
        'scale_factor_asymmetry': (hunted, [{'a': 2.09e-3}, {'a': 8.36e-3}, {'a': 3.34e-4}]),
        'timestamp_jitter': (divided, [{'tick': 1.39e-5}, {'tick': 2.78e-5},
                                       {'tick': 5.56e-6}]),
        'encoder_cyclic_error': (loaded, [{'a': 2.56e-6}, {'a': 1.02e-5}, {'a': 4.1e-7}]),
    }


@lru_cache(maxsize=16)
def _unit(name: str, period_s: float, duration: float, rate_hz: float) -> np.ndarray:
    """Return a linear shape's error at unit level on the noise-free run (cached)."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'g_sensitivity':
        return extrapolated_error(t, lambda u: G0 * np.sin(amp * np.sin(w * u)),
                                  1.0, 0.0)
    if name == 'scale_factor_nonlinearity':
        return ac_error(ac_coupled(t, lambda u: amp * w * np.cos(w * u)), 1.0)
    if name == 'scale_factor_asymmetry':
        neg = rate < 0
        j = np.cumsum(neg & ~np.r_[False, neg[:-1]])
        return hunt_error(rate, 1.0, np.where(j % 2 == 0, 1.0, -1.0))
    return angle_residual(head_error(phi, 1.0), t, phi)


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: mash_psd(f, p['tick'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    if name == 'encoder_cyclic_error':
        return matched_z(p['a'] * _unit(name, period_s, duration, rate_hz), rate_hz, n_arw,
                         floor)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name != 'time_delay':
        return rate_z(p[KEY[name]] * _unit(name, period_s, duration, rate_hz), rate, n_arw,
                      rate_hz)
    err = amp * w * np.cos(w * (t - stall_mean(p['m']))) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)


def levels(names=None, digits: int = 3) -> dict:
    """Return ``{name: [weak, strong, edge]}`` solved for z = TARGETS, to ``digits`` digits."""
    return solved_levels(detectability, KEY, GUESS, TARGETS, names, slope=SLOPE,
                         digits=digits)


if __name__ == '__main__':
    print_levels(levels(), detectability)
