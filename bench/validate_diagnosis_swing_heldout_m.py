"""
Held-out swing set M: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_l.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-L, and the kinds of departure
differ from shape to shape:

- time_delay: a FIFO race: the host driver reads the IMU's FIFO by DMA and, whenever its read
  loses the race with the sensor's write (a share p of the reads, independently), it takes the
  sample four slots older: y_k = x_(k - 4 B_k), B_k Bernoulli(p): a random delay of 0 or 4
  samples, 4 p on average (the values are the gyro's own, repeated, never mixed);
- g_sensitivity: a coarse compensation: the IMU's on-chip g-compensation subtracts g_y times
  the accelerometer word cut to its top bits (steps of 0.1 g), so what is left is g_y (f_y -
  D round(f_y / D)), f_y = g sin(phi), D = 0.98 m/s^2: a zero-mean sawtooth in f_y, no net
  g-sensitivity, six jumps every half swing;
- scale_factor_nonlinearity: torquer hysteresis: the torquer magnet's magnetisation follows the
  rebalance current (the true rate; the loop's noise enters after it) through a play of half
  width h = 0.12 rad/s (pinned domain walls) and the scale factor follows the magnetisation:
  error e P_h(w): rate-independent memory, a loop, flat stretches after every reversal;
- scale_factor_asymmetry: a chopped driver: the rebalance driver's two halves are swapped
  every half chop period (1.3 s, unsynchronised with the swing) to cancel their mismatch, but
  the chopper's duty is 55/45, so the catalogue's a |w| (true rate) is multiplied by a +-1
  square wave: the 2f line moved to sidebands of the chop harmonics, a tenth of it left at 2f;
- timestamp_jitter: a time-sync servo: the host's clock is disciplined by a daemon that
  measures its offset every 2 s (Gaussian measurement noise sd sigma) and slews the clock to it
  by the next measurement: the encoder stamps' error is piecewise linear between independent
  Gaussian nodes 2 s apart, random phase: slow, continuous, two-sided PSD sigma^2 S
  sinc^4(f S);
- encoder_cyclic_error: a two-LED read head: the sine and cosine tracks are lit by separate
  LEDs whose outputs wander independently (thermal, a unit first-order Markov process of 30 s),
  so the tracks' amplitude ratio is 1 + gamma u(t) about the calibrated balance, and the atan2
  interpolation errs by ~ gamma u sin(2 L phi) / (2 L) on 3000 lines: a cyclic error at twice
  the line rate whose size and sign wander at random, zero on average.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- compensation: the harmonics k = 1..60 of the residual bias along the swing, in quadrature,
  against s (as set L's preload); hysteresis: the lines k = 2..60 of e P_h(A w cos wt) in its
  periodic steady state, in quadrature, against s;
- FIFO race, chopped driver: matched detector on the noise-free angle residual (the integrated
  mean rate error, p (w_(k-4) - w_k) for the race, a |w| c(t) for the chopper, chop phase 0),
  offset, bias ramp and scale factor fitted out, against the gyro angle noise N^2 / (2 pi f)^2,
  the encoder's white floor and the preset's stamp jitter;
- time-sync servo: a quadratic detector on the angle error -phi_dot e(t), PSD shifted by
  +-1 / 5 s (as sets E, K and L);
- two-LED head: e = u c(t), c = gamma sin(2 U) / (2 L) periodic with the swing (U = L (phi +
  mount)), so e's PSD is a comb of Lorentzians |C_k|^2 S_u(f - k / 5 s), each narrower than the
  comb's spacing: the quadratic detector z^2 = (T tau / 2) sum_k (|C_k|^2 / S_n(k / 5 s))^2
  (int S_u^2 df = tau for a unit first-order process), S_n as above.
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: lost races in 4.7 % (edge), 25 % and 75 % of the reads (mean
delays 0.19, 1 and 3 ms); raw g_y of 2.7e-4, 2e-3 and 5e-3 rad/s/(m/s^2) (0.15-2.8 deg/s/g)
compensated to a sawtooth of 0.0076, 0.056 and 0.14 deg/s peak; magnetisation gains of 0.26 %,
2 % and 6 % (loop widths 0.018-0.41 deg/s); driver mismatches a of 1.7e-4, 2e-3 and 6e-3;
servo node noise of 0.59, 2 and 5 ms sd (NTP on a LAN); LED ratio wander of 0.32 %, 1 % and
3 % sd (cyclic error 0.11-1.0 arcsec peak on the 432 arcsec pitch).
"""
from heldout_detect import encoder_floor, matched_z, stamp_z, swing_scales
import numpy as np
from scipy import signal

G0 = 9.80665
STALE = 4                               # samples: how much older a lost race's read is
COMP_STEP = 0.1 * G0                    # m/s^2: the compensation's accelerometer step
PLAY = 0.12                             # rad/s: the magnetisation's play half width
CHOP_S, DUTY = 1.3, 0.55                # s: chop period; share of it with the halves direct
SYNC_S = 2.0                            # s between the servo's offset measurements
LINES, MOUNT = 3000, np.deg2rad(37.0)   # scale lines; where the swing sits on the scale
LED_TC = 30.0                           # s: the LEDs' wander


def race(x: np.ndarray, stale: np.ndarray) -> np.ndarray:
    """Return x_(k - STALE) where ``stale`` (x_0 held before the start), x_k elsewhere."""
    old = np.r_[np.full(STALE, x[0]), x[:-STALE]]
    return np.where(stale, old, x)


def comp_residual(f_y, gy: float) -> np.ndarray:
    """Left after compensating with the coarse word: gy (f_y - D round(f_y / D))."""
    f_y = np.asarray(f_y, float)
    return gy * (f_y - COMP_STEP * np.round(f_y / COMP_STEP))


def play(w: np.ndarray, h: float = PLAY, start: float = 0.0) -> np.ndarray:
    """Play (backlash) operator of half width h: p_k = min(max(p_(k-1), w_k - h), w_k + h)."""
    out = np.empty(w.size)
    p = start
    for k, v in enumerate(np.asarray(w, float).tolist()):
        p = min(max(p, v - h), v + h)
        out[k] = p
    return out


def chopper(t, phase: float = 0.0) -> np.ndarray:
    """+1 for the first DUTY of each CHOP_S period (halves direct), -1 for the rest (swapped)."""
    return np.where(np.mod(np.asarray(t, float) + phase, CHOP_S) < DUTY * CHOP_S, 1.0, -1.0)


def servo(t, sigma: float, rng) -> np.ndarray:
    """Piecewise-linear error between N(0, sigma^2) nodes SYNC_S apart, random phase."""
    t = np.asarray(t, float)
    t0 = t[0] - rng.uniform(0, SYNC_S)
    nodes = t0 + SYNC_S * np.arange(int((t[-1] - t0) / SYNC_S) + 2)
    return np.interp(t, nodes, sigma * rng.standard_normal(nodes.size))


def servo_psd(f, sigma: float) -> np.ndarray:
    """Two-sided PSD sigma^2 S sinc^4(f S) of ``servo`` (its phase averaged)."""
    return sigma ** 2 * SYNC_S * np.sinc(np.asarray(f, float) * SYNC_S) ** 4


def ratio_error(phi, g) -> np.ndarray:
    """Read minus true angle when the sine track's amplitude is (1 + g) times the cosine's."""
    u = LINES * (np.asarray(phi, float) + MOUNT)
    return np.angle(np.exp(1j * (np.arctan2((1 + g) * np.sin(u), np.cos(u)) - u))) / LINES


def led_wander(n: int, rate_hz: float, rng) -> np.ndarray:
    """Unit-variance first-order Markov process of LED_TC on a grid of ``rate_hz`` (stationary)."""
    c = np.exp(-1.0 / (LED_TC * rate_hz))
    w = rng.standard_normal(n) * np.sqrt(1 - c * c)
    return signal.lfilter([1.0], [1.0, -c], w, zi=[c * rng.standard_normal()])[0]


def fitted_residual(err: np.ndarray, t: np.ndarray, phi: np.ndarray,
                    rate_hz: float) -> np.ndarray:
    """Integrated rate error with offset, bias ramp and scale factor (phi) fitted out."""
    angle = np.cumsum(err) / rate_hz
    cols = np.c_[np.ones_like(t), t, phi]
    return angle - cols @ np.linalg.lstsq(cols, angle, rcond=None)[0]


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def fifo(imu_t, gyro, enc_t, enc, stand, rng, p):
        return imu_t, race(gyro, rng.uniform(size=gyro.size) < p), enc_t, enc

    def comp(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + comp_residual(G0 * np.sin(stand(imu_t)[0]), gy), enc_t, enc

    def magnet(imu_t, gyro, enc_t, enc, stand, rng, e):
        w = stand(imu_t)[1]
        return imu_t, gyro + e * play(w, PLAY, w[0]), enc_t, enc

    def chop(imu_t, gyro, enc_t, enc, stand, rng, a):
        err = a * np.abs(stand(imu_t)[1]) * chopper(imu_t, rng.uniform(0, CHOP_S))
        return imu_t, gyro + err, enc_t, enc

    def sync(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, enc_t + servo(enc_t, sigma, rng), enc

    def leds(imu_t, gyro, enc_t, enc, stand, rng, gamma):
        g = gamma * led_wander(enc_t.size, rate_hz, rng)
        return imu_t, gyro, enc_t, enc + ratio_error(enc, g)

    return {
        'time_delay': (fifo, [{'p': 0.25}, {'p': 0.75}, {'p': 0.047}]),
        'g_sensitivity': (comp, [{'gy': 2e-3}, {'gy': 5e-3}, {'gy': 2.72e-4}]),
        'scale_factor_nonlinearity': (magnet, [{'e': 0.02}, {'e': 0.06}, {'e': 2.63e-3}]),
        'scale_factor_asymmetry': (chop, [{'a': 2e-3}, {'a': 6e-3}, {'a': 1.66e-4}]),
        'timestamp_jitter': (sync, [{'sigma': 2e-3}, {'sigma': 5e-3}, {'sigma': 5.87e-4}]),
        'encoder_cyclic_error': (leds, [{'gamma': 0.01}, {'gamma': 0.03}, {'gamma': 3.2e-3}]),
    }


def led_z(gamma: float, amp: float, w: float, n_arw: float, floor: float, duration: float,
          rate_hz: float) -> float:
    """Quadratic z of the wandering ratio's error: (T tau / 2) sum_k (|C_k|^2 / S_n)^2."""
    m = 1 << 17
    th = np.arange(m) * 2 * np.pi / m
    c = gamma * np.sin(2 * LINES * (amp * np.sin(th) + MOUNT)) / (2 * LINES)
    ck = np.fft.fft(c) / m
    f = np.fft.fftfreq(m, 1.0 / m) * w / (2 * np.pi)          # harmonic k at k / period
    keep = (np.abs(f) > 0) & (np.abs(f) < rate_hz / 2)
    s_n = n_arw ** 2 / (2 * np.pi * f[keep]) ** 2 + floor
    return float(np.sqrt(duration * LED_TC / 2 * np.sum((np.abs(ck[keep]) ** 2 / s_n) ** 2)))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    th = np.arange(4096) * 2 * np.pi / 4096
    if name == 'g_sensitivity':
        c = np.fft.rfft(comp_residual(G0 * np.sin(amp * np.sin(th)), p['gy']))[1:61] / th.size
        return float(2 * np.linalg.norm(c) / s)
    if name == 'scale_factor_nonlinearity':
        rate = np.tile(amp * w * np.cos(th), 2)
        err = p['e'] * play(rate, PLAY, rate[0])[th.size:]           # the periodic state
        return float(2 * np.linalg.norm((np.fft.rfft(err) / th.size)[2:61]) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: servo_psd(f, p['sigma']), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    if name == 'encoder_cyclic_error':
        return led_z(p['gamma'], amp, w, n_arw, floor, duration, rate_hz)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        err = p['p'] * (race(rate, np.ones(rate.size, bool)) - rate)
    else:
        err = p['a'] * np.abs(rate) * chopper(t)
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
