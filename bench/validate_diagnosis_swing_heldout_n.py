"""
Held-out swing set N: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_m.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-M, and the kinds of departure
differ from shape to shape:

- time_delay: a motion-adaptive smoother: the IMU firmware smooths its rate output with a
  one-pole whose time constant falls as the motion grows, tau = tau0 / (1 + (y / 0.05 rad/s)^2)
  (y its own previous output, noise included): heavy smoothing, so a long lag, near rest and
  almost none at speed; on a swing the lag peaks at the turning points, where the rate
  changes fastest (a nonlinear, amplitude-dependent delay);
- g_sensitivity: sense-mass stiction: once |f_y| passes 2.5 m/s^2 the sense mass touches its
  anti-stiction bump and sticks until |f_y| falls below 1.0 m/s^2; while in contact the bias
  is c sign(f_y): a relay with hysteresis on the specific force (f_y = g sin(phi), 3.35 m/s^2
  at the swing's ends), pulses late in each half swing, off at small tilts;
- scale_factor_nonlinearity: a calibration table's residual: the factory corrected a cubic
  k3 w^3 by a look-up table with knots every 0.2 rad/s and linear interpolation between
  them (on the output value, noise included), so what is left is k3 (w^3 - L(w)), a train of
  parabolic arches, zero at every knot, growing with |w|;
- scale_factor_asymmetry: a leaky protection diode: a diode across one half of the torquer
  driver leaks with the Shockley law, its linear part absorbed by the calibration: c (e^(w /
  0.1 rad/s) - 1 - w / 0.1 rad/s) on the output value: one-sided, exponential, large for one
  direction only (all harmonics, even and odd);
- timestamp_jitter: CPU idle-state wake-up: the host stamps each encoder sample in an
  interrupt; when the core had entered its deep idle state the stamp is late by the exit
  latency L; the idle governor goes deep after a shallow wake-up more often (0.7) than after a
  deep one (0.2), so the late stamps alternate: a two-state Markov chain, correlation -0.5
  sample to sample, mean (a share 7 / 15) calibrated out: bimodal, blue (power near the
  encoder's Nyquist frequency);
- encoder_cyclic_error: a gear mesh: the encoder reads the stand through a spur-gear stage
  (30 teeth on the stand's gear), whose tooth profile errors add a transmission error
  a (sin(30 phi + 0.4) + 0.4 sin(60 phi + 2.1) + 0.15 sin(90 phi + 4.0)) to the angle: a
  non-sinusoidal error of 12 deg period (between a disk's per-revolution and per-line
  errors).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- adaptive smoother, gear mesh: matched detector on the noise-free angle residual (the
  smoother's periodic steady state on the true rate, integrated; the mesh error itself),
  offset, bias ramp and scale factor fitted out, against the gyro angle noise N^2 / (2 pi
  f)^2, the encoder's white floor and the preset's stamp jitter;
- stiction: the harmonics k = 1..60 of the relay's periodic steady state, in quadrature,
  against s (as set M's compensation);
- table residual, diode: lines k = 2..60 of the error averaged over the gyro's own noise
  (``noise_lines``), in quadrature, against s;
- idle wake-up: a quadratic detector on the angle error -phi_dot e(t), e's two-sided PSD
  v (1 - r^2) / (f_s |1 - r e^(-2 pi i f / f_s)|^2), v = L^2 p (1 - p), r = -0.5, shifted by
  +-1 / 5 s (as sets E and K-M).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: resting time constants of 1.1 ms (edge), 5 and 20 ms; stiction
offsets of 0.0053, 0.057 and 0.29 deg/s; cubics k3 of 0.036, 0.6 and 2 (rad/s)^-2 (0.7 %, 12 %
and 39 % of the peak rate before the table; residual arches up to 0.027, 0.45 and 1.5 deg/s);
diode leaks c of 4.6e-6, 1e-4 and 3e-4 rad/s (0.02, 0.44 and 1.3 deg/s at the peak rate);
exit latencies of 4.2, 25 and 80 us; mesh errors a of 1.7, 12 and 82 arcsec.
"""
from heldout_detect import encoder_floor, matched_z, noise_lines, stamp_z, swing_scales
import numpy as np
from validate_diagnosis_swing_heldout_m import fitted_residual

G0 = 9.80665
ADAPT_W = 0.05                          # rad/s: the rate that halves the smoothing time
STICK_ON, STICK_OFF = 2.5, 1.0          # m/s^2: contact above, release below |f_y|
KNOT = 0.2                              # rad/s: the table's knot spacing
DIODE_W = 0.1                           # rad/s: the leak's thermal-voltage scale
DEEP_AFTER = (0.7, 0.2)                 # P(deep | shallow before), P(deep | deep before)
TEETH = 30                              # teeth on the stand's gear
MESH = ((1.0, 0.4), (0.4, 2.1), (0.15, 4.0))  # mesh harmonics 1..3: relative size, phase


def adaptive(x: np.ndarray, tau0: float, rate_hz: float, start: float = None) -> np.ndarray:
    """One-pole of time tau0 / (1 + (y_(k-1) / ADAPT_W)^2), y_(-1) = ``start`` (x_0)."""
    out = np.empty(x.size)
    y = float(x[0]) if start is None else start
    for k, v in enumerate(np.asarray(x, float).tolist()):
        a = np.exp(-(1 + (y / ADAPT_W) ** 2) / (tau0 * rate_hz))
        y = a * y + (1 - a) * v
        out[k] = y
    return out


def stiction(f_y, c: float) -> np.ndarray:
    """Return c sign(f_y) while stuck: on above STICK_ON in |f_y|, off below STICK_OFF."""
    f = np.abs(np.asarray(f_y, float))
    event = np.where(f > STICK_ON, 1, np.where(f < STICK_OFF, 0, -1))
    idx = np.where(event >= 0, np.arange(f.size), -1)
    last = np.maximum.accumulate(idx)
    stuck = np.where(last >= 0, event[np.maximum(last, 0)], 0)
    return c * np.sign(f_y) * stuck


def table_residual(x, k3: float) -> np.ndarray:
    """Return k3 (x^3 - L(x)), L the linear interpolation of x^3 between knots KNOT apart."""
    x = np.asarray(x, float)
    lo = KNOT * np.floor(x / KNOT)
    hi = lo + KNOT
    return k3 * (x ** 3 - (lo ** 3 + (x - lo) * (hi ** 3 - lo ** 3) / KNOT))


def diode(x, c: float) -> np.ndarray:
    """Leak c (e^(x / DIODE_W) - 1 - x / DIODE_W), its linear part calibrated out."""
    u = np.asarray(x, float) / DIODE_W
    return c * (np.expm1(u) - u)


def idle_states(n: int, rng) -> np.ndarray:
    """1 where the core woke from deep idle: a two-state chain with DEEP_AFTER probabilities."""
    u = rng.uniform(size=n)
    out = np.empty(n, int)
    s = int(u[0] < deep_share())
    for k, v in enumerate(u.tolist()):
        s = int(v < DEEP_AFTER[s]) if k else s
        out[k] = s
    return out


def deep_share() -> float:
    """Stationary share of deep wake-ups, b / (1 - a + b)."""
    b, a = DEEP_AFTER
    return b / (1 - a + b)


def wake_psd(f, latency: float, rate_hz: float) -> np.ndarray:
    """Two-sided PSD v (1 - r^2) / (f_s |1 - r e^(-2 pi i f / f_s)|^2) of the stamp error."""
    p, r = deep_share(), DEEP_AFTER[1] - DEEP_AFTER[0]
    v = latency ** 2 * p * (1 - p)
    z1 = np.exp(-2j * np.pi * np.asarray(f, float) / rate_hz)
    return v * (1 - r * r) / (rate_hz * np.abs(1 - r * z1) ** 2)


def mesh_error(phi, a: float) -> np.ndarray:
    """Transmission error a sum_h r_h sin(h TEETH phi + p_h) of the gear stage (rad)."""
    phi = np.asarray(phi, float)
    return a * sum(r * np.sin((h + 1) * TEETH * phi + p) for h, (r, p) in enumerate(MESH))


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def smooth(imu_t, gyro, enc_t, enc, stand, rng, tau0):
        return imu_t, adaptive(gyro, tau0, rate_hz), enc_t, enc

    def stick(imu_t, gyro, enc_t, enc, stand, rng, c):
        return imu_t, gyro + stiction(G0 * np.sin(stand(imu_t)[0]), c), enc_t, enc

    def table(imu_t, gyro, enc_t, enc, stand, rng, k3):
        return imu_t, gyro + table_residual(gyro, k3), enc_t, enc

    def leak(imu_t, gyro, enc_t, enc, stand, rng, c):
        return imu_t, gyro + diode(gyro, c), enc_t, enc

    def wake(imu_t, gyro, enc_t, enc, stand, rng, latency):
        late = latency * (idle_states(enc_t.size, rng) - deep_share())
        return imu_t, gyro, enc_t + late, enc

    def gear(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + mesh_error(enc, a)

    return {
        'time_delay': (smooth, [{'tau0': 5e-3}, {'tau0': 2e-2}, {'tau0': 1.1e-3}]),
        'g_sensitivity': (stick, [{'c': 1e-3}, {'c': 5e-3}, {'c': 9.2e-5}]),
        'scale_factor_nonlinearity': (table, [{'k3': 0.6}, {'k3': 2.0}, {'k3': 0.0361}]),
        'scale_factor_asymmetry': (leak, [{'c': 1e-4}, {'c': 3e-4}, {'c': 4.6e-6}]),
        'timestamp_jitter': (wake, [{'latency': 2.5e-5}, {'latency': 8e-5},
                                    {'latency': 4.24e-6}]),
        'encoder_cyclic_error': (gear, [{'a': 6e-5}, {'a': 4e-4}, {'a': 8.2e-6}]),
    }


def angle_residual(e: np.ndarray, t: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Angle error with offset, bias ramp and scale factor (phi) fitted out."""
    cols = np.c_[np.ones_like(t), t, phi]
    return e - cols @ np.linalg.lstsq(cols, e, rcond=None)[0]


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    th = np.arange(4096) * 2 * np.pi / 4096
    if name == 'g_sensitivity':
        f_y = G0 * np.sin(amp * np.sin(np.tile(th, 2)))
        err = stiction(f_y, p['c'])[th.size:]                        # the periodic state
        return float(2 * np.linalg.norm((np.fft.rfft(err) / th.size)[1:61]) / s)
    s_n = n_arw * np.sqrt(rate_hz)
    if name == 'scale_factor_nonlinearity':
        return float(noise_lines(lambda x: table_residual(x, p['k3']), amp * w, s_n) / s)
    if name == 'scale_factor_asymmetry':
        return float(noise_lines(lambda x: diode(x, p['c']), amp * w, s_n) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: wake_psd(f, p['latency'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi = amp * np.sin(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(mesh_error(phi, p['a']), t, phi), rate_hz, n_arw, floor)
    per = int(round(period_s * rate_hz))
    rate = amp * w * np.cos(w * t[:3 * per])
    err = (adaptive(rate, p['tau0'], rate_hz) - rate)[2 * per:]      # the periodic state
    err = np.resize(err, t.size)
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
