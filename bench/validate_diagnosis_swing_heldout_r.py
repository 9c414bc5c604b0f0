"""
Held-out swing set R: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_p.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-P, and the kinds of departure
differ from shape to shape:

- time_delay: a backlog that follows the speed: the stand's microcontroller stamps each gyro
  sample in a low-priority task that runs when the encoder's edge decoding (software
  interpolation, its load proportional to the speed) leaves it time, so each gyro sample is
  stamped late by c |w| (w the true rate when it was taken): a latency that swells at
  mid-swing and vanishes at the turning points (the values untouched, the stamps moved,
  still increasing);
- g_sensitivity: a wavy suspension: micro-fabrication left the sense mass's folded springs
  with a random waviness, so its g-induced deflection, and the bias, carry a smooth random
  function of f_y = g sin(phi) beside the linear part, which the factory's linear calibration
  over +-1 g removed: bias c r(f_y / g), r a fixed (one sensor, every run alike) sum of
  WAVE_K = 12 sines of f_y / g (k = 1..12, amplitudes ~ 1 / k, seeded phases) less its
  least-squares line over +-1 g, unit rms there: a static, non-parametric nonlinearity in
  f_y, lines at all harmonics of the swing;
- scale_factor_nonlinearity: torquer DAC bit errors: the rebalance loop drives its torquer
  through a sign-magnitude DAC (DAC_BITS = 8 magnitude bits, full scale DAC_FS = 4 rad/s, the
  loop dithering between neighbouring codes) whose binary-weighted current sources are
  mismatched, unit cell sd sigma_u (bit b off by sigma_u sqrt(cells_b) z_b unit cells, z_b
  fixed: one DAC), so the read code errs by the set bits' weight errors: a Walsh-type
  staircase in |w| (linear across each code), odd, zero at zero rate, steps one code wide
  where bits toggle (multiples of 0.25, 0.125, ... rad/s), its least-squares slope over the
  range calibrated out (output value, noise included);
- scale_factor_asymmetry: a drooping bootstrap: the rebalance driver's negative half is fed
  from a bootstrap capacitor that is recharged only while the positive half conducts, so
  through each negative half its gain droops linearly, out = w (1 - a (t - t_r) / DROOP_S)
  while w < 0 (true rate), t_r the last reversal to negative, DROOP_S = 1 s: an asymmetry
  that grows through every negative half and is gone on the positive one;
- timestamp_jitter: a congested link: the encoder's samples reach the host over a link (USB,
  SLOT_S = 1 ms frames) shared with another device's stream, which adds a random amount of
  data each frame (Gaussian: many small packets) while the link serves slightly more than
  that on average; the sample waits for the backlog, a Lindley (reflected Gaussian) walk,
  V' = max(0, V + X), X ~ N(-2 m / QUEUE_TC, 4 m^2 / QUEUE_TC) (QUEUE_TC = 50 frames), and is
  stamped on arrival (packets out of a draining queue PACKET_S = 20 us apart); the mean
  backlog (0.846 m) calibrated out: one-sided (a share of the samples at zero wait, an
  exponential-like tail of scale m), correlated over ~QUEUE_TC frames;
- encoder_cyclic_error: LED drive crosstalk: the read head's LED is PWM-dimmed at PWM_HZ =
  240 Hz and its drive couples into the sine track's photodiode amplifier alone, S = sin u + r
  sin(2 pi PWM_HZ t + p), C = cos u, u = ENC_LINES phi (3600 lines): the atan2 interpolation
  errs by ~ r sin(2 pi PWM_HZ t + p) cos(u) / ENC_LINES: a line-periodic error whose size and
  sign are set by the PWM's phase: zero on average, a product of time and angle.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine; s_n =
N sqrt(f_s) the gyro's per-sample noise):

- speed backlog, LED crosstalk: matched detector on the noise-free angle residual (the
  integrated rate error, rate(t - c |rate(t)|) - rate(t); the crosstalk's error itself, its
  phase p = 0), offset, bias ramp and scale factor fitted out, against the gyro angle noise
  N^2 / (2 pi f)^2, the encoder's white floor and the preset's stamp jitter (as set P);
- wavy suspension, drooping bootstrap: the lines k = 1..60 of the periodic rate error along
  the swing, in quadrature, against s;
- DAC bit errors: lines k = 2..60 of the memoryless error averaged over the gyro's noise
  (``noise_lines``), against s;
- congested link: the stamp error read through the swing's rate (``stamp_z``, as sets E and
  K-P), its two-sided PSD from the autocovariance of the backlog's Markov chain (solved on a
  401-state grid, m = 1, and scaled by m^2).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: backlogs c of 0.86 (edge), 5 and 20 ms per rad/s (0.38, 2.2 and
8.8 ms at the swing's 0.44 rad/s peak); wavy suspensions c of 1.5e-4, 1e-3 and 5e-3 rad/s rms
over +-1 g (0.0086, 0.057 and 0.29 deg/s); unit cell mismatches sigma_u of 0.3 %, 3 % and 10 %;
bootstrap droops a of 0.031 %, 0.5 % and 2 % a second; link backlogs m of 18, 100 and 300 us;
LED crosstalk r of 4e-4, 3e-3 and 2e-2 of the track amplitude (angle errors up to 0.023, 0.17
and 1.1 arcsec).
"""
from functools import lru_cache

from heldout_detect import (encoder_floor, matched_z, noise_lines, period_lines, stamp_z,
                            swing_scales)
import numpy as np
from scipy import special
from validate_diagnosis_swing_heldout_m import fitted_residual
from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
WAVE_K, WAVE_SEED = 12, 20250717        # sines in the waviness; its fixed draw (one sensor)
DAC_BITS, DAC_FS, DAC_SEED = 8, 4.0, 4117   # magnitude bits; full scale (rad/s); bit errors
DROOP_S = 1.0                           # s: the droop's time unit
SLOT_S, QUEUE_TC, PACKET_S = 1e-3, 50, 20e-6   # link frame; backlog memory (frames); a packet
PWM_HZ, ENC_LINES = 240.0, 3600         # LED PWM; lines of the encoder disk


def backlog(rate, c: float) -> np.ndarray:
    """Stamp latency c |w| of each gyro sample."""
    return c * np.abs(np.asarray(rate, float))


def _wave_terms():
    g = np.random.default_rng(WAVE_SEED)
    k = np.arange(1, WAVE_K + 1)
    return k, g.standard_normal(WAVE_K) / k, g.uniform(0, 2 * np.pi, WAVE_K)


def _wave_raw(u) -> np.ndarray:
    k, amp, ph = _wave_terms()
    return np.sin(np.pi * np.asarray(u, float)[..., None] * k + ph) @ amp


def _wave_fit():
    u = np.linspace(-1, 1, 20001)
    raw = _wave_raw(u)
    line = np.polyfit(u, raw, 1)
    res = raw - np.polyval(line, u)
    return line, float(np.sqrt(np.mean(res * res)))


WAVE_LINE, WAVE_RMS = _wave_fit()


def waviness(f_y, c: float) -> np.ndarray:
    """Bias c r(f_y / g): the fixed waviness less its line over +-1 g, unit rms there."""
    u = np.asarray(f_y, float) / G0
    return c * (_wave_raw(u) - np.polyval(WAVE_LINE, u)) / WAVE_RMS


def dac_table(sigma_u: float) -> np.ndarray:
    """Weight error (rad/s) of each magnitude code: the set bits' errors summed."""
    b = np.arange(DAC_BITS)
    cells = 2.0 ** (DAC_BITS - 1 - b)                 # unit cells of bit b (MSB first)
    z = np.random.default_rng(DAC_SEED).standard_normal(DAC_BITS)
    code = np.arange(2 ** DAC_BITS)
    bits = (code[:, None] >> (DAC_BITS - 1 - b)) & 1
    return bits @ (DAC_FS / 2 ** DAC_BITS * sigma_u * np.sqrt(cells) * z)


def _dac_raw(m, sigma_u: float) -> np.ndarray:
    """Weight error at magnitude m, linear between codes (the loop dithers between them)."""
    x = np.asarray(m, float) / (DAC_FS / 2 ** DAC_BITS)
    return np.interp(x, np.arange(2 ** DAC_BITS), dac_table(sigma_u))


def _dac_slope() -> float:
    m = np.linspace(0, DAC_FS, 200001)
    return float(np.sum(m * _dac_raw(m, 1.0)) / np.sum(m * m))


DAC_SLOPE = _dac_slope()


def dac_error(w, sigma_u: float) -> np.ndarray:
    """Output error -sign(w) (e(|w|) - slope |w|) of the mismatched sign-magnitude DAC."""
    w = np.asarray(w, float)
    m = np.abs(w)
    return -np.sign(w) * (_dac_raw(m, sigma_u) - sigma_u * DAC_SLOPE * m)


def droop(t, rate, a: float) -> np.ndarray:
    """Rate error -a (t - t_r) / DROOP_S w while w < 0, t_r the last reversal to w < 0."""
    t, rate = np.asarray(t, float), np.asarray(rate, float)
    neg = rate < 0
    start = np.r_[neg[0], neg[1:] & ~neg[:-1]]
    t_r = t[np.maximum.accumulate(np.where(start, np.arange(t.size), 0))]
    return np.where(neg, -a * (t - t_r) / DROOP_S * rate, 0.0)


def queue_chain(states: int = 401, top: float = 14.0):
    """
    Return (grid, stationary law, transition matrix) of the unit backlog (m = 1) on a grid.

    V' = max(0, V + X), X ~ N(-2 / QUEUE_TC, 4 / QUEUE_TC) per frame; states 0..top, the
    mass above the top kept in the last state.
    """
    v = np.linspace(0.0, top, states)
    h = v[1] - v[0]
    edges = np.r_[-np.inf, v[:-1] + h / 2, np.inf]
    mu, sd = -2.0 / QUEUE_TC, 2.0 / np.sqrt(QUEUE_TC)
    trans = np.diff(special.ndtr((edges[None, :] - v[:, None] - mu) / sd), axis=1)
    lhs = np.r_[(trans.T - np.eye(states))[:-1], np.ones((1, states))]
    law = np.linalg.solve(lhs, np.r_[np.zeros(states - 1), 1.0])
    return v, law, trans


@lru_cache(maxsize=1)
def queue_cov(lags: int = 2048):
    """Return (mean, autocovariance at lags 0..lags - 1, in frames) of the unit backlog."""
    v, law, trans = queue_chain()
    mean = float(law @ v)
    g = v.copy()
    cov = np.empty(lags)
    for lag in range(lags):
        cov[lag] = law @ (v * g) - mean * mean
        g = trans @ g
    return mean, cov


def link_backlog(t, m: float, rng) -> np.ndarray:
    """Backlog (s) met by the samples at t: a Lindley walk on SLOT_S frames, from empty."""
    t = np.asarray(t, float)
    frame = np.floor((t - t[0]) / SLOT_S + 1e-9).astype(int)
    burn = 40 * QUEUE_TC
    x = rng.normal(-2 * m / QUEUE_TC, 2 * m / np.sqrt(QUEUE_TC), frame[-1] + 1 + burn)
    s = np.cumsum(x)
    v = s - np.minimum.accumulate(np.minimum(s, 0.0))
    return v[burn + frame]


def link_stamps(t, m: float, rng) -> np.ndarray:
    """Arrival stamps t + V(t) - E V, no closer than PACKET_S apart (a drained queue)."""
    t = np.asarray(t, float)
    a = t + link_backlog(t, m, rng) - m * queue_cov()[0]
    k = np.arange(t.size) * PACKET_S
    return np.maximum.accumulate(a - k) + k


@lru_cache(maxsize=1)
def _link_table():
    _, cov = queue_cov()
    size = 2 ** 17
    row = np.zeros(size)
    row[:cov.size] = cov
    row[size - cov.size + 1:] = cov[1:][::-1]
    psd = np.real(np.fft.fft(row)) * SLOT_S
    f = np.fft.fftfreq(size, SLOT_S)
    order = np.argsort(f)
    return f[order], psd[order]


def link_psd(f, m: float) -> np.ndarray:
    """Two-sided PSD (s^2/Hz) of the backlog m (the unit chain's, times m^2), per frame."""
    grid, psd = _link_table()
    return m * m * np.interp(np.asarray(f, float), grid, psd)


def crosstalk_error(phi, t, r: float, phase: float = 0.0) -> np.ndarray:
    """Angle error of atan2(sin u + r sin(2 pi PWM_HZ t + p), cos u) / L, u = L phi."""
    u = ENC_LINES * np.asarray(phi, float)
    s = np.sin(u) + r * np.sin(2 * np.pi * np.mod(PWM_HZ * np.asarray(t, float), 1.0) + phase)
    return np.angle(np.exp(1j * (np.arctan2(s, np.cos(u)) - u))) / ENC_LINES


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def isr(imu_t, gyro, enc_t, enc, stand, rng, c):
        return imu_t + backlog(stand(imu_t)[1], c), gyro, enc_t, enc

    def wavy(imu_t, gyro, enc_t, enc, stand, rng, c):
        return imu_t, gyro + waviness(G0 * np.sin(stand(imu_t)[0]), c), enc_t, enc

    def dac(imu_t, gyro, enc_t, enc, stand, rng, sigma_u):
        return imu_t, gyro + dac_error(gyro, sigma_u), enc_t, enc

    def bootstrap(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + droop(imu_t, stand(imu_t)[1], a), enc_t, enc

    def link(imu_t, gyro, enc_t, enc, stand, rng, m):
        return imu_t, gyro, link_stamps(enc_t, m, rng), enc

    def led(imu_t, gyro, enc_t, enc, stand, rng, r):
        err = crosstalk_error(stand(enc_t)[0], enc_t, r, rng.uniform(0, 2 * np.pi))
        return imu_t, gyro, enc_t, enc + err

    return {
        'time_delay': (isr, [{'c': 5e-3}, {'c': 2e-2}, {'c': 8.58e-4}]),
        'g_sensitivity': (wavy, [{'c': 1e-3}, {'c': 5e-3}, {'c': 1.495e-4}]),
        'scale_factor_nonlinearity': (dac, [{'sigma_u': 0.03}, {'sigma_u': 0.1},
                                            {'sigma_u': 0.00298}]),
        'scale_factor_asymmetry': (bootstrap, [{'a': 5e-3}, {'a': 2e-2}, {'a': 3.14e-4}]),
        'timestamp_jitter': (link, [{'m': 1e-4}, {'m': 3e-4}, {'m': 1.81e-5}]),
        'encoder_cyclic_error': (led, [{'r': 3e-3}, {'r': 2e-2}, {'r': 4.0e-4}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    s_n = n_arw * np.sqrt(rate_hz)
    n = int(duration * rate_hz)
    if name == 'g_sensitivity':
        def err(t):
            return waviness(G0 * np.sin(amp * np.sin(w * t)), p['c'])
        return float(period_lines(err, w) / s)
    if name == 'scale_factor_asymmetry':
        def err(t):
            tt = np.r_[t, t + 2 * np.pi / w]                    # a second period: t_r known
            return droop(tt, amp * w * np.cos(w * tt), p['a'])[t.size:]
        return float(period_lines(err, w) / s)
    if name == 'scale_factor_nonlinearity':
        return float(noise_lines(lambda v: dac_error(v, p['sigma_u']), amp * w, s_n) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: link_psd(f, p['m']), amp * w, w / (2 * np.pi), n_arw,
                       floor, duration, rate_hz, 400001)
    t = np.arange(n) / rate_hz
    phi = amp * np.sin(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(crosstalk_error(phi, t, p['r']), t, phi), rate_hz,
                         n_arw, floor)
    rate = amp * w * np.cos(w * t)
    err = amp * w * np.cos(w * (t - backlog(rate, p['c']))) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
