"""
Held-out swing set AG: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_af.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-R, AE and AF, and the kinds of
departure differ from shape to shape:

- time_delay: an adaptive playout buffer: the IMU's samples reach the host over a link whose
  transport latencies ell_k scatter (exponential, mean m), and the host publishes and stamps
  each out of a jitter buffer sized to the worst recent latency, D_k = max(D_(k-1) exp(-dt /
  BUFFER_S), ell_k) (``playout``; BUFFER_S = 2 s, run in for 10 releases), the values
  untouched: a latency with memory and an extreme-value law, jumping up to each new worst case
  (about 3 times a second) and decaying between them; mean d = 6.23 m at 1 kHz
  (``playout_gain``), sd 0.18 d, correlated over ~0.35 s, peaks of 2.5-3 d in a run;
- g_sensitivity: an over-smoothed compensation: the IMU cancels its gyro's g-sensitivity g_y
  f_y (f_y = g sin(phi)) with its accelerometer, exactly at rest, but through a one-pole
  smoothing of ACC_TAU = 0.8 s (set against vibration), so g_y (f_y - LP(f_y)) is left
  (``smoothed_residual``, started settled): a high-passed g-sensitivity, none for a steady
  tilt, i w tau / (1 + i w tau) of the raw one at the swing's frequency: its parts in phase
  with the tilt and 90 deg ahead of it are 0.5 and 0.5 of the raw one at the 5 s period, 0.8
  and 0.4 at 2.5 s, 0.2 and 0.4 at 10 s: set by the swing period;
- scale_factor_nonlinearity: a random-telegraph trap: one charge trap in the rebalance
  driver's current-setting transistor lowers the gain by e while it is occupied, its capture
  and emission rates following the current (the true rate; the loop's noise after it),
  TRAP_HZ exp(+-x), x = (|w| - TRAP_HALF) / TRAP_W (20 Hz, 0.25 and 0.1 rad/s), a two-state
  chain from sample to sample (``trap_states``), out = x - e s_k w: mostly empty at rest (0.75 %
  occupied), mostly full at the peak rate (97.6 %), switching at random near 0.25 rad/s: a
  smooth odd gain step in the mean (lines at 3f, 5f, ...) with a rate-dependent telegraph
  noise about it;
- scale_factor_asymmetry: a cracked rail strand: the IMU takes a split supply through the
  stand's cable, whose negative rail has a cracked strand that opens while the cable is bent
  past a tilt PHI_CRACK = 6 deg; the rail then sags under the negative driver half's load and
  that half reads low by 2 a: out = x + 2 a |w| while w < 0 and phi > PHI_CRACK (true rate and
  angle), untouched elsewhere: a one-sided gain set by the position, on the descent from the
  positive turning point to 6 deg only (20.1 % of the time at 20 deg; never under 6 deg);
- timestamp_jitter: interpolated stamps: the encoder's DAQ starts each conversion after an
  aperture delay that scatters (white, Gaussian, sd sigma, its mean calibrated out), captures
  the true instant of every ANCHOR = 32nd conversion in hardware, and the driver interpolates
  the stamps linearly in between (``anchored_errors``): the stamp error is 0 at the captures
  and (1 - w) j_a + w j_b - j_k between them (w the share of the way), of variance sigma^2 (1
  + (1 - w)^2 + w^2): a cyclostationary Gaussian error pinned to zero every 32 samples, the
  captures' scatter spread over their neighbours (stamps kept in order);
- encoder_cyclic_error: a learning read head: the head's interpolation ASIC adapts its track
  offsets and its amplitude and phase balance from the tracks as they sweep, starting from its
  stored defaults at power-on, each loop by a fixed share per signal period travelled, so its
  error a (exp(-n / 3e4) sin(u + 0.4) + 0.7 exp(-n / 9e4) sin(2 u + 1.7)), u = 1500 phi, n the
  signal periods travelled since the run's start (``learned_error``), falls through the run as
  fast as the swing travels (333 periods a swing at 20 deg; at 900 s 14 % and 51 % of it left
  at the 5 s period, 1.8 % and 26 % at 2.5 s; at rest none is learnt).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- playout buffer: the matched detector on the noise-free angle residual of the mean latency
  d, rate(t - d) - rate(t) integrated, offset, bias ramp and scale factor fitted out, against
  the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's stamp
  jitter (as sets M-R, AE and AF); the latency's random part not counted;
- smoothed compensation: the matched detector in the rate domain (AF's ``rate_z``, bias and
  scale factor fitted out, against the gyro's white rate noise);
- telegraph trap: the lines k = 2..60 of the mean error -e P_k w_k along the swing (P from the
  chain's master equation, ``trap_mean``) against s; the telegraph's random part not counted;
- cracked strand: the lines k = 2..60 of the periodic error (``period_lines``) against s;
- interpolated stamps: the stamp error read through the swing's rate (``stamp_z``, as sets E,
  K-R, AE and AF), its time-averaged two-sided PSD from ``anchored_acv`` (the
  cyclostationarity not counted);
- learning head: the matched detector on the noise-free angle residual, as the buffer's.
Edges solve z = 4 at the 5 s period, weak and strong z = 25 and 100 (``levels``, 3 digits; at
2.5 s the edges' z are: buffer 4x, strand 2x, stamps 2x, compensation 1.6x, head 0.98x, trap
0.82x). Physical scale: mean latencies d of 0.188 (edge), 1.18 and 4.7 ms (transport latencies
of mean 30, 189 and 754 us); raw g_y of 6.12e-5, 3.83e-4 and 1.53e-3 rad/s/(m/s^2) (0.034,
0.21 and 0.86 deg/s/g); trap gain steps e of 0.113 %, 0.70 % and 2.8 %; strand gain drops 2 a
of 0.081 %, 0.51 % and 2.0 %; aperture jitters sigma of 2.97, 7.42 and 14.8 us (beside the
preset's own 20 us: a quadratic detector on 900 000 samples sees a few per cent of variance);
power-on head errors a of 0.043, 0.27 and 1.08 arcsec on the 864 arcsec pitch.
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, period_lines, print_levels
from heldout_detect import solved_levels, stamp_z, step_of, swing_scales

import numpy as np

from scipy import signal

from validate_diagnosis_swing_heldout_af import increasing, rate_z

from validate_diagnosis_swing_heldout_m import fitted_residual

from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
BUFFER_S, BUFFER_BURN = 2.0, 10.0       # s: the playout buffer's release; burn-in in releases
ACC_TAU = 0.8                           # s: the compensating accelerometer's smoothing
TRAP_HZ, TRAP_HALF, TRAP_W = 20.0, 0.25, 0.1   # Hz, rad/s, rad/s: the trap's rates (doc)
PHI_CRACK = np.deg2rad(6.0)             # rad: the tilt past which the cracked strand opens
ANCHOR = 32                             # conversions from one captured stamp to the next
LEARN_LINES = 1500                      # the adaptive head's lines a turn
LEARN = ((1, 1.0, 0.4, 3.0e4), (2, 0.7, 1.7, 9.0e4))   # (k, amplitude, phase, N_k periods)
KEY = {'time_delay': 'd', 'g_sensitivity': 'gy', 'scale_factor_nonlinearity': 'e',
       'scale_factor_asymmetry': 'a', 'timestamp_jitter': 'sigma', 'encoder_cyclic_error': 'a'}
TARGETS = (25.0, 100.0, 4.0)            # z of the weak, strong and edge levels
GUESS = {'time_delay': 1e-3, 'g_sensitivity': 1e-4, 'scale_factor_nonlinearity': 1e-2,
         'scale_factor_asymmetry': 1e-3, 'timestamp_jitter': 1e-5, 'encoder_cyclic_error': 1e-6}


def playout(ell, step: float) -> np.ndarray:
    """Return the playout delays D_k = max(D_(k-1) exp(-step / BUFFER_S), ell_k), D_(-1) = 0."""
    r = np.arange(np.size(ell)) * (step / BUFFER_S)
    with np.errstate(divide='ignore'):
        return np.exp(np.maximum.accumulate(np.log(np.asarray(ell, float)) + r) - r)


@lru_cache(maxsize=8)
def playout_gain(step: float) -> float:
    """
    Return E[D] / m in the steady state, the latencies exponential of mean m.

    P(D <= x m) = prod_(j >= 0) (1 - exp(-x e^(j r))), r = step / BUFFER_S: on the grid x_i =
    x_0 e^(i r) its log is a reverse cumulative sum; E[D] / m = int (1 - P) dx.
    """
    r = step / BUFFER_S
    x = 1e-6 * np.exp(np.arange(int(np.log(60.0 / 1e-6) / r) + 1) * r)
    logp = np.cumsum(np.log1p(-np.exp(-x))[::-1])[::-1]
    return float(x[0] + np.trapezoid(-np.expm1(logp), x))


def playout_stamps(t, d: float, rng) -> np.ndarray:
    """Return the stamps t + D, the buffer run in for BUFFER_BURN releases, mean latency d."""
    t = np.asarray(t, float)
    if not d:
        return t.copy()
    step = step_of(t)
    burn = int(BUFFER_BURN * BUFFER_S / step)
    ell = rng.exponential(d / playout_gain(step), t.size + burn)
    return increasing(t + playout(ell, step)[burn:], step)


def smoothed_residual(t, f, gy: float) -> np.ndarray:
    """Return gy (f - LP(f)), LP the one-pole ACC_TAU (exact steps) started settled on f[0]."""
    f = np.asarray(f, float)
    a = float(np.exp(-step_of(t) / ACC_TAU))
    return gy * (f - signal.lfilter([1.0 - a], [1.0, -a], f, zi=[a * f[0]])[0])


def trap_rates(w, step: float):
    """Return the per-sample capture and emission probabilities of the trap at the rates w."""
    x = (np.abs(np.asarray(w, float)) - TRAP_HALF) / TRAP_W
    return -np.expm1(-TRAP_HZ * step * np.exp(x)), -np.expm1(-TRAP_HZ * step * np.exp(-x))


def trap_states(w, step: float, u) -> np.ndarray:
    """
    Return the trap's occupancy along the rates ``w``, driven by the uniform draws ``u``.

    s_0 = u_0 < c_0 / (c_0 + e_0) (the chain's stationary share); then s_k = u_k < c_k if the
    trap was empty, s_k = u_k >= e_k if it was occupied (c, e from ``trap_rates``).
    """
    up, down = trap_rates(w, step)
    cand = (np.flatnonzero(u < up), np.flatnonzero(u < down))
    state = first = bool(u[0] < up[0] / (up[0] + down[0]))
    flips, k = [], 0
    while True:
        arr = cand[state]
        i = int(np.searchsorted(arr, k, side='right'))
        if i == arr.size:
            break
        k = int(arr[i])
        flips.append(k)
        state = not state
    toggles = np.zeros(np.size(w), int)
    toggles[flips] = 1
    toggles[0] += first
    return np.cumsum(toggles) % 2 == 1


def trap_mean(w, step: float, periods: int = 3) -> np.ndarray:
    """Return the trap's mean occupancy along a periodic ``w`` (master equation, last period)."""
    up, down = trap_rates(w, step)
    p, out = up[0] / (up[0] + down[0]), np.empty(np.size(w))
    for _ in range(periods):
        for k, (c, e) in enumerate(zip(up.tolist(), down.tolist())):
            p = p * (1.0 - e) + (1.0 - p) * c
            out[k] = p
    return out


def crack_error(phi, w, a: float) -> np.ndarray:
    """Return 2 a |w| while w < 0 and phi > PHI_CRACK (the negative half read low), else 0."""
    return np.where((np.asarray(w) < 0) & (np.asarray(phi) > PHI_CRACK), -2.0 * a * w, 0.0)


def anchored_errors(n: int, sigma: float, rng) -> np.ndarray:
    """Return n stamp errors interp_k - j_k: aperture jitter j (sd sigma), anchors every ANCHOR."""
    blocks = max(-(-(n - 1) // ANCHOR), 1)
    j = sigma * rng.standard_normal(blocks * ANCHOR + 1)
    k = np.arange(n)
    a, w = k // ANCHOR, (k % ANCHOR) / ANCHOR
    return (1.0 - w) * j[ANCHOR * a] + w * j[ANCHOR * (a + 1)] - j[:n]


def anchored_stamps(t, sigma: float, rng) -> np.ndarray:
    """Return the stamps t + ``anchored_errors`` (kept in order)."""
    t = np.asarray(t, float)
    if not sigma:
        return t.copy()
    return increasing(t + anchored_errors(t.size, sigma, rng), step_of(t))


@lru_cache(maxsize=1)
def anchored_acv() -> np.ndarray:
    """Return the time-averaged autocovariance of ``anchored_errors`` (sigma 1) at 0..2 ANCHOR."""
    p, n = ANCHOR, 5 * ANCHOR
    k = np.arange(n)
    c = np.zeros((n, n + 1))
    c[k, k] -= 1.0
    c[k, p * (k // p)] += 1.0 - (k % p) / p
    c[k, p * (k // p + 1)] += (k % p) / p
    cov, mid = c @ c.T, np.arange(2 * p, 3 * p)
    return np.array([cov[mid, mid + lag].mean() for lag in range(2 * p + 1)])


def anchored_psd(f, sigma: float, fs: float) -> np.ndarray:
    """Return the two-sided time-averaged PSD (s^2/Hz) of ``anchored_errors`` at ``f``."""
    r, x = anchored_acv(), 2 * np.pi * np.asarray(f, float) / fs
    return sigma ** 2 / fs * (r[0] + 2 * sum(r[k] * np.cos(k * x) for k in range(1, r.size)))


def learned_error(phi, a: float) -> np.ndarray:
    """Return a sum_k r_k exp(-n / N_k) sin(k u + p_k), u = LEARN_LINES phi, n = sum|du| / 2 pi."""
    u = LEARN_LINES * np.asarray(phi, float)
    n = np.r_[0.0, np.cumsum(np.abs(np.diff(u)))] / (2 * np.pi)
    return a * sum(r * np.exp(-n / big) * np.sin(k * u + p) for k, r, p, big in LEARN)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def buffered(imu_t, gyro, enc_t, enc, stand, rng, d):
        return playout_stamps(imu_t, d, rng), gyro, enc_t, enc

    def smoothed(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + smoothed_residual(imu_t, G0 * np.sin(stand(imu_t)[0]), gy), enc_t, enc

    def trapped(imu_t, gyro, enc_t, enc, stand, rng, e):
        if not e:
            return imu_t, gyro, enc_t, enc
        w = stand(imu_t)[1]
        return imu_t, gyro - e * trap_states(w, step_of(imu_t), rng.random(w.size)) * w, enc_t, enc

    def cracked(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + crack_error(*stand(imu_t), a), enc_t, enc

    def anchored(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, anchored_stamps(enc_t, sigma, rng), enc

    def learning(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + learned_error(stand(enc_t)[0], a)

    return {
        'time_delay': (buffered, [{'d': 1.18e-3}, {'d': 4.7e-3}, {'d': 1.88e-4}]),
        'g_sensitivity': (smoothed, [{'gy': 3.83e-4}, {'gy': 1.53e-3}, {'gy': 6.12e-5}]),
        'scale_factor_nonlinearity': (trapped, [{'e': 7.04e-3}, {'e': 0.0282}, {'e': 1.13e-3}]),
        'scale_factor_asymmetry': (cracked, [{'a': 2.54e-3}, {'a': 0.0102}, {'a': 4.07e-4}]),
        'timestamp_jitter': (anchored, [{'sigma': 7.42e-6}, {'sigma': 1.48e-5},
                                        {'sigma': 2.97e-6}]),
        'encoder_cyclic_error': (learning, [{'a': 1.31e-6}, {'a': 5.25e-6}, {'a': 2.1e-7}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'scale_factor_nonlinearity':
        rate = amp * w * np.cos(w * np.arange(int(round(period_s * rate_hz))) / rate_hz)
        c = np.fft.rfft(-p['e'] * trap_mean(rate, 1.0 / rate_hz) * rate) / rate.size
        return float(2 * np.linalg.norm(c[2:61]) / s)
    if name == 'scale_factor_asymmetry':
        def err(u):
            return crack_error(amp * np.sin(w * u), amp * w * np.cos(w * u), p['a'])
        return float(period_lines(err, w, 2) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: anchored_psd(f, p['sigma'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(learned_error(phi, p['a']), t, phi), rate_hz, n_arw,
                         floor)
    if name == 'g_sensitivity':
        return rate_z(smoothed_residual(t, G0 * np.sin(phi), p['gy']), rate, n_arw, rate_hz)
    err = amp * w * np.cos(w * (t - p['d'])) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)


def levels(names=None, digits: int = 3) -> dict:
    """Return ``{name: [weak, strong, edge]}`` solved for z = TARGETS, to ``digits`` digits."""
    return solved_levels(detectability, KEY, GUESS, TARGETS, names,
                         slope={'timestamp_jitter': 2.0}, steps=20, digits=digits)


if __name__ == '__main__':
    print_levels(levels(), detectability, periods=(5.0,))
