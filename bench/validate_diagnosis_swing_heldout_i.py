"""
Held-out swing set I: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_h.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-H, and the kinds of departure
differ from shape to shape:

- time_delay: an all-pass alignment: the IMU aligns its samples to the system sync with a
  first-order Thiran all-pass fractional delay, H(z) = (c + z^-1) / (1 + c z^-1), c = (1 - D)
  / (1 + D), D = d f_s: a delay of exactly d at low frequency and unit gain at every
  frequency, so the gyro's noise keeps its white spectrum (every earlier filter colours it);
- g_sensitivity: a settling g-coefficient: the suspension's g-sensitivity follows the package
  stress, which relaxes after power-on, g_y (1 + 2 e^(-t / 200 s)) f_y, f_y = g sin(phi),
  each run starting from power-on: linear in f, its coefficient three times larger at first;
- scale_factor_nonlinearity: full-scale clipping: a narrow-range gyro whose output saturates
  at +-S just below the swing's peak rate (output value, noise and bias included): flat tops,
  exact, a hard limit rather than a soft saturation;
- scale_factor_asymmetry: a late-onset asymmetry: the rebalance driver's two halves match at
  low current, but above |w| = 0.25 rad/s one half's gain departs, output w + a max(|w| -
  0.25 rad/s, 0) (output value): even, no kink at zero, one above the onset;
- timestamp_jitter: periodic jitter: mains ripple (50 Hz) on the reference of the encoder's
  stamping PLL moves every stamp by J sin(2 pi 50 Hz t + p): a deterministic sinusoidal stamp
  error at a frequency unrelated to the motion;
- encoder_cyclic_error: an interleaved graduation: the disk's 1250 lines were written in two
  passes, odd and even lines slightly offset, so the scale also carries a component of twice
  the line pitch; read through the head's quarter-pitch track offset it enters the sine track
  as e sin(u / 2 + p) and the cosine track as e sin(u / 2 + p + pi / 4) (u = L phi), and
  atan2 errs at half and 1.5 times the signal frequency: a sub-harmonic cyclic error, its
  period two lines.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- settling g: the fundamental 2 g J1(A) g_y times the run's mean coefficient 1 + 2 tau / T
  (1 - e^(-T / tau)), against s;
- clipping, late onset: the lines k >= 2 of the rate error at A w cos(wt) (k = 1 is a scale
  factor, k = 0 a bias), the error first averaged over the gyro's own noise (sd N sqrt(1 kHz),
  Gauss-Hermite), in quadrature, against s;
- all-pass, periodic jitter, graduation: matched detector on the noise-free angle
  residual (-phi_dot d; -phi_dot e; the graduation's error with offset and scale fitted out),
  against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's
  stamp jitter (as sets D-H).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to tens of times further in
z. Physical scale: delays of 0.188 (edge), 1 and 3 ms; g_y (settled) of 2.1e-5, 2e-4 and
5e-4 rad/s/(m/s^2) (0.012-0.28 deg/s/g); clipping at 26.8, 25 and 22 deg/s (the peak rate is
25.1 deg/s, the gyro's own noise 1 deg/s rms at 1 kHz); asymmetries a of 0.001, 0.01 and 0.04
(the gain departs by 0.1-4 %); ripple jitters J of 1.07, 5 and 20 us; half-pitch admixtures e
of 4.7e-4, 3e-3 and 1e-2 of the track amplitude.
"""
from heldout_detect import encoder_floor, matched_z, noise_lines, swing_scales
import numpy as np
from scipy import signal, special

G0 = 9.80665
SETTLE_EXCESS, SETTLE_TAU = 2.0, 200.0      # initial extra g-coefficient; its relaxation, s
ONSET = 0.25                                # rad/s: where the asymmetric gain sets in
MAINS_HZ = 50.0
TRACK_LINES = 1250                          # signal periods per turn of the encoder


def allpass(x: np.ndarray, d_samples: float) -> np.ndarray:
    """First-order Thiran all-pass of low-frequency delay ``d_samples``, started settled."""
    c = (1 - d_samples) / (1 + d_samples)
    b, a = [c, 1.0], [1.0, c]
    return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]


def settling(t: np.ndarray) -> np.ndarray:
    """Return the g-coefficient's factor 1 + 2 e^(-t / 200 s) after power-on."""
    return 1 + SETTLE_EXCESS * np.exp(-np.asarray(t) / SETTLE_TAU)


def late_onset(w, a: float) -> np.ndarray:
    """Asymmetric gain above the onset: a max(|w| - ONSET, 0)."""
    return a * np.maximum(np.abs(w) - ONSET, 0.0)


def mains_stamps(t: np.ndarray, amp: float, phase: float) -> np.ndarray:
    """Stamp error J sin(2 pi 50 Hz t + phase)."""
    return amp * np.sin(2 * np.pi * MAINS_HZ * t + phase)


def track_error(phi: np.ndarray, eps: float, p: float = 0.0) -> np.ndarray:
    """Angle error of atan2 of tracks carrying the half-pitch component (module docstring)."""
    u = TRACK_LINES * phi
    half = u / 2 + p
    read = np.arctan2(np.sin(u) + eps * np.sin(half), np.cos(u) + eps * np.sin(half + np.pi / 4))
    return np.angle(np.exp(1j * (read - u))) / TRACK_LINES


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def aligned(imu_t, gyro, enc_t, enc, stand, rng, delay):
        return imu_t, allpass(gyro, delay * rate_hz), enc_t, enc

    def settling_g(imu_t, gyro, enc_t, enc, stand, rng, gy):
        f_y = G0 * np.sin(stand(imu_t)[0])
        return imu_t, gyro + gy * settling(imu_t - imu_t[0]) * f_y, enc_t, enc

    def clipped(imu_t, gyro, enc_t, enc, stand, rng, full_scale):
        return imu_t, np.clip(gyro, -full_scale, full_scale), enc_t, enc

    def onset(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + late_onset(gyro, a), enc_t, enc

    def ripple(imu_t, gyro, enc_t, enc, stand, rng, amp):
        return imu_t, gyro, enc_t + mains_stamps(enc_t, amp, rng.uniform(0, 2 * np.pi)), enc

    def interleaved(imu_t, gyro, enc_t, enc, stand, rng, eps):
        return imu_t, gyro, enc_t, enc + track_error(enc, eps, rng.uniform(0, 2 * np.pi))

    deg = np.pi / 180
    return {
        'time_delay': (aligned, [{'delay': 1e-3}, {'delay': 3e-3}, {'delay': 1.88e-4}]),
        'g_sensitivity': (settling_g, [{'gy': 2e-4}, {'gy': 5e-4}, {'gy': 2.14e-5}]),
        'scale_factor_nonlinearity': (clipped, [{'full_scale': 25 * deg},
                                                {'full_scale': 22 * deg},
                                                {'full_scale': 26.81 * deg}]),
        'scale_factor_asymmetry': (onset, [{'a': 0.01}, {'a': 0.04}, {'a': 9.8e-4}]),
        'timestamp_jitter': (ripple, [{'amp': 5e-6}, {'amp': 2e-5}, {'amp': 1.07e-6}]),
        'encoder_cyclic_error': (interleaved, [{'eps': 3e-3}, {'eps': 1e-2},
                                               {'eps': 4.66e-4}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    s_n = n_arw * np.sqrt(rate_hz)
    p = params
    if name == 'g_sensitivity':
        mean = 1 + SETTLE_EXCESS * SETTLE_TAU / duration * (1 - np.exp(-duration / SETTLE_TAU))
        return float(2 * G0 * special.j1(amp) * p['gy'] * mean / s)
    if name == 'scale_factor_nonlinearity':
        fs = p['full_scale']
        return noise_lines(lambda v: np.clip(v, -fs, fs) - v, amp * w, s_n) / s
    if name == 'scale_factor_asymmetry':
        return noise_lines(lambda v: late_onset(v, p['a']), amp * w, s_n) / s
    floor = encoder_floor(enc, rate_hz)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        residual = -rate * p['delay']
    elif name == 'encoder_cyclic_error':
        residual = track_error(phi, p['eps'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    else:
        e = mains_stamps(t, p['amp'], 0.0)
        residual = -rate * (e - e.mean())
    return matched_z(residual, rate_hz, n_arw,
                     floor + (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz)
