"""
Held-out swing set F: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_e.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-E, and the kinds of departure
differ from shape to shape:

- time_delay: the ENCODER late, dispersively: its sine-cosine tracks reach the interpolator
  through an RC anti-alias filter (tracks digitised by a DAQ), each lagging by arctan(2 pi f_s
  tau) at the signal frequency f_s = L |phi_dot| / 2 pi (L = 2048), so the interpolated angle
  lags the stand by arctan(L phi_dot tau) / L: by tau at low rate, less towards the peak rate
  (L A w tau = 1.8 at the strong tau, 5 s period) (catalogue stamps / gyro lag; dev Lagrange;
  B one-pole; C integrate-dump; D FIR; E isolator: all the gyro late, by a constant delay);
- g_sensitivity: a lever arm: the IMU sits ARM = 0.6 m below the swing axis (a pendulum
  stand), so the specific force it feels is f_y = g sin(phi) + r phi_ddot, f_z = g cos(phi) +
  r phi_dot^2, and a linear g-sensitivity g_y f_y + g_z (f_z - g) (g_y = g_z) also sees the
  swing's own tangential and centripetal accelerations: the in-phase term is cut by r w^2 / g
  (10 % at 5 s, 39 % at 2.5 s) and the 2f line gains g_z r A^2 w^2 / 2 (catalogue, dev: on
  the axis; B f_y f_z; C relaxation; D play; E bilinear: all of the gravity term alone);
- scale_factor_nonlinearity: integral nonlinearity of the rate converter: a periodic ripple
  e0 sin(2 pi w / 0.25 rad/s + 0.6) over the code range (a segmented converter's repeating
  pattern, 14.3 deg/s long), on the gyro's output value (noise and bias included): an
  oscillating transfer error whose lines at k f go as J_k(2 pi A w / 0.25 rad/s) (catalogue
  polynomial; dev tanh; B knee; C range switch; D lock-in; E lagged cubic: none oscillating);
- scale_factor_asymmetry: a warming asymmetry: the catalogue's a |w|, but its coefficient
  settles after power-on from 4 a to a with a 240 s time constant (the torquer driver's two
  halves warming unequally), each run starting from power-on: non-stationary, its 2f line
  shrinks through the run (catalogue constant; dev, B smoothed; C offset; D Schmitt; E
  after-effect: all stationary);
- timestamp_jitter: an ASCII protocol: the encoder sends its angle as text in degrees ("%.4f")
  and the host stamps each message when its last character arrives; a negative angle has one
  more character (its sign), |angle| >= 10 deg one more digit, so the latency is 0, 1 or 2
  character times, its mean calibrated out: a data-dependent, angle-locked stamp error
  (catalogue Gaussian; dev uniform; B Gauss-Markov; C heavy-tailed; D sync sawtooth; E
  packets: none depending on the data);
- encoder_cyclic_error: a dirty scale: a spot (oil, dust) at 8 deg on a 2500-line scale
  attenuates track A by up to ``depth`` (Gaussian in angle, sd 1.1 deg), and the atan2
  interpolation errs by ~-(d / 2) sin(2 L phi) / L there only: an interpolation error confined
  to the arc of the swing that passes the spot (catalogue, dev, B: uniform line harmonics; C
  triangle; D per-revolution; E random per line).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- track filter: the fundamental of the angle error arctan(L A w tau cos(wt)) / L, by
  quadrature, against s / w;
- lever arm: the fundamental of g_y (g sin(A sin wt) - r w^2 A sin wt), 2 g J1(A) - r w^2 A
  times g_y, against s (g_z's 2f line, g_z (2 g J2(A) + r A^2 w^2 / 2), not counted);
- INL: the lines k >= 2 of the rate error (k = 1 is a scale factor), a_k = 2 e0 |J_k(2 pi A w
  / P)| (times |sin 0.6| for even k, |cos 0.6| for odd k), summed in quadrature (a matched
  detector), times the dithering by the gyro's own noise, exp(-2 pi^2 s_n^2 / P^2) = 0.91
  (s_n = N sqrt(1 kHz)), against s; the preset bias shifts the ripple's phase by 0.25 rad, not
  counted;
- warming asymmetry: the 2f line of the run's mean a(t) |w|: a (1 + 3 tau_w / T (1 -
  e^(-T / tau_w))) 4 A w / (3 pi) = 1.78 a 4 A w / (3 pi), against s;
- ASCII stamps, dirty scale: matched detector on the noise-free angle residual (-phi_dot
  (e - mean e) for the stamps; the spot's error with offset and scale fitted out for the
  scale), against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the
  preset's stamp jitter (as sets D and E).
Edges are at z ~ 4 at the 5 s period (at 2.5 s: track filter 3.9x, asymmetry 2x, stamps 2.3x,
INL 1x, dirty scale 0.75x, lever arm 0.67x); weak and strong are 3-47x further in z. Physical
scale: RC cut-offs 840 Hz (edge), 265 Hz, 80 Hz (strong); g 3.4e-5 to 5e-4 rad/s/(m/s^2)
(0.019-0.28 deg/s/g); INL ripples of 0.0068-0.11 deg/s (11-190 ppm of the +-300 deg/s span);
settled asymmetries 0.03-0.6 %; character times of 1.8 Mbaud (edge), 460.8 kbaud (weak) and
115.2 kbaud (strong) links; spot depths 0.18 %, 1.5 %, 8 %.
"""
from heldout_detect import encoder_floor, fourier, matched_z, swing_scales
import numpy as np
from scipy import special

G0 = 9.80665
SIGNAL_LINES = 2048           # sine-cosine signal periods per turn of the encoder (time_delay)
ARM = 0.6                     # m, the IMU below the swing axis (g_sensitivity)
INL_PERIOD, INL_PHASE = 0.25, 0.6     # rad/s, rad: the converter's INL ripple
WARM_TAU, WARM_EXCESS = 240.0, 3.0    # s; the asymmetry starts at (1 + WARM_EXCESS) a
CHAR_DIGITS = 10.0            # deg: one more character at |angle| >= 10 deg (and for a sign)
SPOT_LINES = 2500             # lines of the contaminated encoder scale
SPOT_AT, SPOT_WIDTH = 0.14, 0.02      # rad: the spot's centre and its Gaussian width


def track_lag(rate: np.ndarray, tau: float) -> np.ndarray:
    """Angle error of a sine-cosine read-out whose tracks pass an RC of ``tau`` (quasi-static)."""
    return -np.arctan(SIGNAL_LINES * rate * tau) / SIGNAL_LINES


def specific_force(stand, t: np.ndarray):
    """(f_y, f_z) at the IMU, ARM below the axis: gravity, r phi_ddot and r phi_dot^2."""
    phi, rate = stand(t)
    acc = np.gradient(rate, t)
    return G0 * np.sin(phi) + ARM * acc, G0 * np.cos(phi) + ARM * rate * rate


def inl(w: np.ndarray, e0: float) -> np.ndarray:
    """Integral nonlinearity of the rate converter at the rate ``w``: a periodic ripple."""
    return e0 * np.sin(2 * np.pi * w / INL_PERIOD + INL_PHASE)


def warm(t: np.ndarray) -> np.ndarray:
    """Asymmetry relative to its settled value, ``t`` s after power-on."""
    return 1.0 + WARM_EXCESS * np.exp(-t / WARM_TAU)


def extra_chars(angle: np.ndarray) -> np.ndarray:
    """Characters the ASCII message of ``angle`` (rad, sent in deg) has beyond the shortest."""
    deg = np.degrees(angle)
    return (deg < 0).astype(float) + (np.abs(deg) >= CHAR_DIGITS)


def spot(phi: np.ndarray, depth: float) -> np.ndarray:
    """Interpolation error where a spot attenuates track A by ``depth`` (Gaussian in angle)."""
    d = depth * np.exp(-0.5 * ((phi - SPOT_AT) / SPOT_WIDTH) ** 2)
    u = SPOT_LINES * phi
    return (np.arctan2((1 - d) * np.sin(u), np.cos(u)) - np.arctan2(np.sin(u), np.cos(u))) \
        / SPOT_LINES


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def track_filter(imu_t, gyro, enc_t, enc, stand, rng, tau):
        return imu_t, gyro, enc_t, enc + track_lag(stand(enc_t)[1], tau)

    def lever_arm(imu_t, gyro, enc_t, enc, stand, rng, gy, gz):
        f_y, f_z = specific_force(stand, imu_t)
        return imu_t, gyro + gy * f_y + gz * (f_z - G0), enc_t, enc

    def converter_inl(imu_t, gyro, enc_t, enc, stand, rng, e0):
        return imu_t, gyro + inl(gyro, e0), enc_t, enc

    def warming_asymmetry(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + a * warm(imu_t - imu_t[0]) * np.abs(stand(imu_t)[1]), enc_t, enc

    def ascii_stamps(imu_t, gyro, enc_t, enc, stand, rng, char):
        e = char * extra_chars(enc)
        return imu_t, gyro, enc_t + e - e.mean(), enc

    def dirty_scale(imu_t, gyro, enc_t, enc, stand, rng, depth):
        return imu_t, gyro, enc_t, enc + spot(enc, depth)

    return {
        'time_delay': (track_filter, [{'tau': 6e-4}, {'tau': 2e-3}, {'tau': 1.9e-4}]),
        'g_sensitivity': (lever_arm, [{'gy': 1.5e-4, 'gz': 1.5e-4}, {'gy': 5e-4, 'gz': 5e-4},
                                      {'gy': 3.41e-5, 'gz': 3.41e-5}]),
        'scale_factor_nonlinearity': (converter_inl, [{'e0': 5e-4}, {'e0': 2e-3},
                                                      {'e0': 1.18e-4}]),
        'scale_factor_asymmetry': (warming_asymmetry, [{'a': 2e-3}, {'a': 6e-3},
                                                       {'a': 3.13e-4}]),
        'timestamp_jitter': (ascii_stamps, [{'char': 2.17e-5}, {'char': 8.68e-5},
                                            {'char': 5.56e-6}]),
        'encoder_cyclic_error': (dirty_scale, [{'depth': 0.015}, {'depth': 0.08},
                                               {'depth': 0.00176}]),
    }


def inl_lines(e0: float, amp: float, kmax: int = 60) -> np.ndarray:
    """Harmonics k = 2..kmax of the INL ripple at the rate amp cos(theta) (Jacobi-Anger)."""
    x = 2 * np.pi * amp / INL_PERIOD
    k = np.arange(2, kmax + 1)
    phase = np.where(k % 2 == 0, np.sin(INL_PHASE), np.cos(INL_PHASE))
    return 2 * e0 * np.abs(special.jv(k, x) * phase)


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'time_delay':
        return fourier(lambda r, th: track_lag(r, p['tau']), amp * w, 1) / (s / w)
    if name == 'g_sensitivity':
        def f_y(r, th):
            return p['gy'] * (G0 * np.sin(amp * np.sin(th)) - ARM * w * w * amp * np.sin(th))
        return fourier(f_y, amp * w, 1) / s
    if name == 'scale_factor_nonlinearity':
        dither = np.exp(-2 * (np.pi * n_arw * np.sqrt(rate_hz) / INL_PERIOD) ** 2)
        return float(np.linalg.norm(inl_lines(p['e0'], amp * w)) * dither / s)
    if name == 'scale_factor_asymmetry':
        mean = 1 + WARM_EXCESS * WARM_TAU / duration * (1 - np.exp(-duration / WARM_TAU))
        return p['a'] * mean * 4 * amp * w / (3 * np.pi) / s
    floor = encoder_floor(enc, rate_hz)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi = amp * np.sin(w * t)
    if name == 'encoder_cyclic_error':
        residual = spot(phi, p['depth'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    else:
        e = p['char'] * extra_chars(phi)
        residual = -amp * w * np.cos(w * t) * (e - e.mean())
    return matched_z(residual, rate_hz, n_arw,
                     floor + (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz)
