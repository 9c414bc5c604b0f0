"""
Held-out swing set AJ: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_ai.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-R and AE-AI, and the kinds of
departure differ from shape to shape:

- time_delay: a flushing logger: the recorder flushes its cache to disk for FLUSH_ON = 2.6 s
  every FLUSH_S = 11.3 s (its first flush at a phase uniform over the period, drawn per run),
  and while it writes, the IMU driver's wake-ups take the slow path: every sample inside a
  flush is stamped d late, the others on time (``flush_stamps``; the stamps after a flush
  kept in order, a tenth of a step apart, until they catch up), the values untouched: an
  intermittent latency, a square wave of duty 0.230 unsynchronised with the swing, its mean
  0.230 d (``flush_mean``);
- g_sensitivity: a still-gated gravity reference: the IMU cancels its gyro's g_y f_y (f_y = g
  sin(phi)) with a gravity estimate that its firmware updates only while its motion detector
  calls it still (|rate| < W_STILL = 0.05 rad/s) and holds through any motion (the level's 0
  until the first still sample; ``still_held``): the residual g_y (f_y - f_held)
  (``still_error``) is nil near the turning points and swings to 2 g_y f_held just before the
  next (f_held = +-3.33 m/s^2 at 20 deg, 5 s): at 20 deg its fundamental 1.52 of the raw g_y
  f_y's and 56 deg ahead of it, its 3f 0.28 of that (odd lines only); a swing whose peak rate
  is under W_STILL (2.3 deg at 5 s) is always still and leaves none;
- scale_factor_nonlinearity: a chopped front end: the IMU's converter runs in chop mode, its
  input swapped at every output sample and the sign restored digitally, with the pair
  averaging off: the front end's quadratic term k2 w^2 (w the true rate, the read-out noise
  after it) comes out re-signed, (-1)^(k + b) k2 w^2 (``chopped_error``, b 0 or 1 per run,
  ``chop_signs``): an even-order nonlinearity carried to the Nyquist frequency, k2 w^2 on
  alternate signs, nothing of it at the swing's lines;
- scale_factor_asymmetry: a forming driver half: the rebalance driver's negative half has a
  capacitor stored unformed, whose leakage puts its gain off by a; the oxide re-forms with the
  charge passed, so the gain error falls e-fold with every FORM_Q = 40 rad of negative travel
  since power-on (``forming``): out = x + a exp(-Q / FORM_Q) w while w < 0
  (``forming_error``): a direction-dependent gain that fades with use (e-fold in 287 s at the
  5 s period, 143 s at 2.5 s; to 0.043 of a by the end of the 5 s run);
- timestamp_jitter: a self-timed DAQ: the encoder's DAQ converts back to back on self-timed
  logic, each conversion's length scattering, and stamps the samples by counting nominal
  steps from a frame sync that captures every FRAME = 8th sample (from an offset drawn per
  run): the stamp error is the scatter summed since the last sync, a random walk of steps of
  sd sigma / sqrt(FRAME) reset to 0 at each sync (``walk_errors``): its variance ramps
  linearly through each frame, 0.661 sigma rms over it, its averaged PSD ``walk_psd``
  (stamps in order);
- encoder_cyclic_error: a speed-dropped correction: the interpolator of the encoder's
  1024-line disk corrects its tracks' distortion from a table, but above W_HI = 0.30 rad/s
  it runs out of time and skips the correction, taking it up again below W_LO = 0.25 rad/s
  (``gate_flags``): the raw error a sin(4 L phi + GATE_PHASE), L = 1024, only while skipped
  (``gated_error``): a cyclic error present in the fast part of each half-swing, switched on
  and off at different speeds (56.7 % of the time at the 5 s period, at 196-286 Hz; 79.7 % at
  2.5 s), none at rest and none on a swing slower than W_HI (under 13.7 deg at 5 s).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW):

- flushing logger: the matched detector on the noise-free angle residual of the mean latency
  d (``flush_mean``), rate(t - d) - rate(t) integrated, offset, bias ramp and scale factor
  fitted out, against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and
  the preset's stamp jitter (as sets AG-AI); the square wave about the mean not counted;
- still-gated reference: the matched detector in the rate domain (AF's ``rate_z``, bias and
  scale factor fitted out);
- chopped front end: the same rate-domain matched detector, over the whole band (b = 0);
- forming half: the same, along the run;
- self-timed DAQ: the stamp error read through the swing's rate (``stamp_z``, as sets AG-AI),
  of the time-averaged PSD ``walk_psd``;
- speed-dropped correction: the matched detector on the noise-free angle residual, as the
  logger's.
Edges solve z = 4 at the 5 s period, weak and strong z = 25 and 100 (``levels``, 3 digits; at
2.5 s the edges' z are: logger 4.0x, chopped front end 4.0x, self-timed DAQ 2.7x, forming half
1.7x, still-gated reference 1.06x, speed-dropped correction 1.05x). Physical scale: flush
latencies d of 0.817 (edge), 5.11 and 20.4 ms (mean latencies 0.188, 1.18 and 4.70 ms); raw
g_y of 2.92e-5, 1.83e-4 and 7.31e-4 rad/s/(m/s^2) (0.016, 0.10 and 0.41 deg/s/g); k2 of
6.22e-4, 3.89e-3 and 0.0156 per rad/s (k2 w at the 5 s swing's peak rate 0.027 %, 0.17 % and
0.68 %); forming gain errors a of 0.12 %, 0.76 % and 3.1 % at power-on; frame sigmas of 9.59,
24 and 48 us (6.3, 16 and 32 us rms, steps of 3.4, 8.5 and 17 us sd, beside the preset's own
20 us white jitter); skipped-correction errors a of 0.022, 0.13 and 0.54 arcsec on the 316
arcsec period of the 4th harmonic.
"""
from heldout_detect import encoder_floor, matched_z, print_levels, solved_levels
from heldout_detect import stamp_z, step_of, swing_scales

import numpy as np

from validate_diagnosis_swing_heldout_af import increasing, rate_z

from validate_diagnosis_swing_heldout_m import fitted_residual

from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
FLUSH_S, FLUSH_ON = 11.3, 2.6           # s: the logger's flush period; each flush's length
W_STILL = 0.05                          # rad/s: the motion detector's still threshold
FORM_Q = 40.0                           # rad of negative travel an e-fold of the forming
FRAME = 8                               # samples a frame: the DAQ's sync comes every frame
GATE_LINES, GATE_ORDER, GATE_PHASE = 1024, 4, 0.7   # the disk's lines; the error's order, phase
W_HI, W_LO = 0.30, 0.25                 # rad/s: the correction dropped above, restored below
KEY = {'time_delay': 'd', 'g_sensitivity': 'gy', 'scale_factor_nonlinearity': 'k2',
       'scale_factor_asymmetry': 'a', 'timestamp_jitter': 'sigma', 'encoder_cyclic_error': 'a'}
TARGETS = (25.0, 100.0, 4.0)            # z of the weak, strong and edge levels
GUESS = {'time_delay': 1e-3, 'g_sensitivity': 1e-4, 'scale_factor_nonlinearity': 1e-3,
         'scale_factor_asymmetry': 1e-3, 'timestamp_jitter': 1e-5, 'encoder_cyclic_error': 1e-6}
SLOPE = {'timestamp_jitter': 2.0}       # first guess of d ln z / d ln x (else 1)


def flush_gate(t, rng) -> np.ndarray:
    """
    Return True where a sample falls in one of the logger's flushes.

    Flushes FLUSH_ON long every FLUSH_S from t_0 + u, u uniform in [0, FLUSH_S) per run.
    """
    t = np.asarray(t, float)
    u = rng.uniform(0.0, FLUSH_S)
    return np.mod(t - t[0] - u, FLUSH_S) < FLUSH_ON


def flush_stamps(t, d: float, rng) -> np.ndarray:
    """Return the stamps t + d inside the flushes (``flush_gate``), t elsewhere, in order."""
    t = np.asarray(t, float)
    if not d:
        return t.copy()
    return increasing(t + d * flush_gate(t, rng), step_of(t))


def flush_mean(d: float) -> float:
    """Return the mean latency d FLUSH_ON / FLUSH_S of the flushed stamps."""
    return d * FLUSH_ON / FLUSH_S


def still_held(f, w) -> np.ndarray:
    """
    Return the gravity reference: ``f`` where |w| < W_STILL, else its last still value.

    The level's 0 until the first still sample.
    """
    f, w = np.asarray(f, float), np.asarray(w, float)
    still = np.abs(w) < W_STILL
    last = np.maximum.accumulate(np.where(still, np.arange(f.size), -1))
    return np.where(last >= 0, f[np.maximum(last, 0)], 0.0)


def still_error(phi, w, gy: float) -> np.ndarray:
    """Return the compensation's residual gy (f_y - ``still_held``), f_y = g sin(phi)."""
    f = G0 * np.sin(np.asarray(phi, float))
    return gy * (f - still_held(f, w))


def chop_signs(n: int, rng) -> np.ndarray:
    """Return the chopper's sign (-1)^(k + b) of each output sample, b 0 or 1 per run."""
    return np.where((np.arange(n) + rng.integers(2)) % 2 == 0, 1.0, -1.0)


def chopped_error(w, k2: float, signs) -> np.ndarray:
    """Return the front end's quadratic term k2 w^2, re-signed by the chopper: signs k2 w^2."""
    w = np.asarray(w, float)
    return signs * k2 * w * w


def forming(w, step: float) -> np.ndarray:
    """Return the forming envelope exp(-Q / FORM_Q), Q the negative travel up to each sample."""
    q = np.cumsum(np.maximum(-np.asarray(w, float), 0.0)) * step
    return np.exp(-q / FORM_Q)


def forming_error(w, step: float, a: float) -> np.ndarray:
    """Return the negative half's gain error a exp(-Q / FORM_Q) w while w < 0, else 0."""
    w = np.asarray(w, float)
    return np.where(w < 0, a * forming(w, step) * w, 0.0)


def sync_anchors(n: int, rng) -> np.ndarray:
    """
    Return each sample's anchor index: the last frame sync at or before it.

    The first sample is an anchor; the frame syncs capture every FRAME-th sample from an
    offset uniform in 0..FRAME - 1 per run.
    """
    k = np.arange(n)
    mark = (k - rng.integers(FRAME)) % FRAME == 0
    mark[0] = True
    return np.maximum.accumulate(np.where(mark, k, 0))


def walk_errors(n: int, sigma: float, rng) -> np.ndarray:
    """
    Return n stamp errors of the self-timed DAQ: its conversions' scatter summed since a sync.

    Steps of sd sigma / sqrt(FRAME) a sample (sigma: the sd a whole frame would reach), the
    error 0 at each anchor (``sync_anchors``).
    """
    anchor = sync_anchors(n, rng)
    c = np.cumsum(sigma / np.sqrt(FRAME) * rng.standard_normal(n))
    return c - c[anchor]


def walk_stamps(t, sigma: float, rng) -> np.ndarray:
    """Return the stamps t + ``walk_errors`` (kept in order)."""
    t = np.asarray(t, float)
    if not sigma:
        return t.copy()
    return increasing(t + walk_errors(t.size, sigma, rng), step_of(t))


def walk_psd(f, sigma: float, fs: float) -> np.ndarray:
    """
    Return the time-averaged two-sided PSD (s^2/Hz) of ``walk_errors`` at ``f``.

    (R(0) + 2 sum_(l=1..M-1) R(l) cos(2 pi f l / fs)) / fs, R(l) = sigma^2 (M - 1 - l) (M - l)
    / (2 M^2) the error's autocovariance averaged over the frame (M = FRAME).
    """
    x = 2 * np.pi * np.asarray(f, float) / fs
    m = FRAME
    out = np.full(np.shape(x), (m - 1) / (2.0 * m))
    for lag in range(1, m - 1):
        out += 2 * (m - 1 - lag) * (m - lag) / (2.0 * m * m) * np.cos(lag * x)
    return sigma * sigma * out / fs


def gate_flags(w) -> np.ndarray:
    """Return the interpolator's coarse mode: on once |w| > W_HI, off again once |w| < W_LO."""
    w = np.abs(np.asarray(w, float))
    event = np.where(w > W_HI, 1, np.where(w < W_LO, -1, 0))
    idx = np.maximum.accumulate(np.where(event != 0, np.arange(w.size), -1))
    return (idx >= 0) & (event[np.maximum(idx, 0)] == 1)


def gated_error(phi, w, a: float) -> np.ndarray:
    """Return a sin(GATE_ORDER GATE_LINES phi + GATE_PHASE) where ``gate_flags(w)``, else 0."""
    phi = np.asarray(phi, float)
    raw = a * np.sin(GATE_ORDER * GATE_LINES * phi + GATE_PHASE)
    return np.where(gate_flags(w), raw, 0.0)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def flushed(imu_t, gyro, enc_t, enc, stand, rng, d):
        return flush_stamps(imu_t, d, rng), gyro, enc_t, enc

    def held(imu_t, gyro, enc_t, enc, stand, rng, gy):
        phi, w = stand(imu_t)
        return imu_t, gyro + still_error(phi, w, gy), enc_t, enc

    def chopped(imu_t, gyro, enc_t, enc, stand, rng, k2):
        signs = chop_signs(np.size(imu_t), rng)
        return imu_t, gyro + chopped_error(stand(imu_t)[1], k2, signs), enc_t, enc

    def formed(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + forming_error(stand(imu_t)[1], step_of(imu_t), a), enc_t, enc

    def walked(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, walk_stamps(enc_t, sigma, rng), enc

    def gated(imu_t, gyro, enc_t, enc, stand, rng, a):
        phi, w = stand(enc_t)
        return imu_t, gyro, enc_t, enc + gated_error(phi, w, a)

    return {
        'time_delay': (flushed, [{'d': 5.11e-3}, {'d': 0.0204}, {'d': 8.17e-4}]),
        'g_sensitivity': (held, [{'gy': 1.83e-4}, {'gy': 7.31e-4}, {'gy': 2.92e-5}]),
        'scale_factor_nonlinearity': (chopped, [{'k2': 3.89e-3}, {'k2': 0.0156},
                                                {'k2': 6.22e-4}]),
        'scale_factor_asymmetry': (formed, [{'a': 7.63e-3}, {'a': 0.0305}, {'a': 1.22e-3}]),
        'timestamp_jitter': (walked, [{'sigma': 2.4e-5}, {'sigma': 4.8e-5},
                                      {'sigma': 9.59e-6}]),
        'encoder_cyclic_error': (gated, [{'a': 6.54e-7}, {'a': 2.61e-6}, {'a': 1.05e-7}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: walk_psd(f, p['sigma'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(gated_error(phi, rate, p['a']), t, phi), rate_hz,
                         n_arw, floor)
    if name == 'g_sensitivity':
        return rate_z(still_error(phi, rate, p['gy']), rate, n_arw, rate_hz)
    if name == 'scale_factor_nonlinearity':
        signs = np.where(np.arange(t.size) % 2 == 0, 1.0, -1.0)
        return rate_z(chopped_error(rate, p['k2'], signs), rate, n_arw, rate_hz)
    if name == 'scale_factor_asymmetry':
        return rate_z(forming_error(rate, 1.0 / rate_hz, p['a']), rate, n_arw, rate_hz)
    err = amp * w * np.cos(w * (t - flush_mean(p['d']))) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)


def levels(names=None, digits: int = 3) -> dict:
    """Return ``{name: [weak, strong, edge]}`` solved for z = TARGETS, to ``digits`` digits."""
    return solved_levels(detectability, KEY, GUESS, TARGETS, names, slope=SLOPE,
                         digits=digits)


if __name__ == '__main__':
    print_levels(levels(), detectability)
