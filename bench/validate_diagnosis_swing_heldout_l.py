"""
Held-out swing set L: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_k.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-K, and the kinds of departure
differ from shape to shape:

- time_delay: an over-eager predictor: the IMU firmware extrapolates every rate value ``lead``
  ahead from its slope over the last 10 samples, x_k + lead (x_k - x_(k-10)) / (10 dt), to
  hide a latency the host already removes: the gyro LEADS the motion (a negative delay), and
  its fast noise is lifted ((1 + q)^2 + q^2 in variance, q = lead / 10 dt), DC gain 1;
- g_sensitivity: a preloaded suspension: the proof mass rests against a spring preloaded to
  1.2 m/s^2 and only deflects beyond it, bias g_y sign(f_y) max(|f_y| - 1.2 m/s^2, 0), f_y =
  g sin(phi): a dead zone, none at small tilts, odd lines of the swing;
- scale_factor_nonlinearity: a two-range blend: the IMU crossfades (smoothstep) from its
  low-range channel to a high-range one as the low-range reading's magnitude goes from 0.15 to
  0.30 rad/s; the high-range channel's gain is off by ``gain`` and it carries its own white
  noise (as large as the gyro's): a gain change and a noise change with the rate, the weight
  set by the noisy reading;
- scale_factor_asymmetry: push-pull bandwidth mismatch: the rebalance driver's two halves
  settle tau slower and faster than the compensated mean, so the output is w - tau d|w|/dt
  (the slope over the driver's 10-sample settling window, output value, noise included): no
  static gain asymmetry at all, a 2f line in quadrature with that of a |w|;
- timestamp_jitter: a host de-jitter filter: the encoder samples arrive with exponential
  latencies (mean m) and the host stamps each with the mean latency of the last 32 arrivals:
  what is left is a running mean, Gaussian-like, skew 2 / sqrt(32), triangular
  autocorrelation over 32 ms, variance m^2 / 32;
- encoder_cyclic_error: a warming read head: the head's LED warms after power-on and the sine
  track's DC offset grows as o (1 - e^(-t / 240 s)) (of the track amplitude), so the atan2
  interpolation errs by up to asin(o) / L (L = 1800 lines) at the line period: a cyclic error
  whose size grows through the run (each run starting at power-on).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- preload: the harmonics k = 1..60 of the bias along the swing, in quadrature, against s;
- blend, push-pull: the lines k >= 2 of the rate error at A w cos(wt), in quadrature, against
  s: the blend gain w E[s(|w + n|)] (Gauss-Hermite over the gyro's own noise; its extra noise
  has no mean), the mismatch -tau times the 10-sample slope of E|w + n| line by line;
- predictor, warming head: matched detector on the noise-free angle residual (the integrated
  rate error of the predicted motion; the head's error with offset and scale fitted out)
  against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's
  stamp jitter;
- de-jitter: a quadratic detector on the angle error -phi_dot e(t), e of two-sided PSD m^2 /
  f_s |D_32(f)|^2 (the running mean's response), shifted by +-1 / 5 s, z = sqrt(T / 2 int
  (S_r / S_n)^2 df) (as sets E and K).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: leads of 0.19 (edge), 1 and 4 ms; g_y of 5.4e-5, 3e-4 and 1e-3
rad/s/(m/s^2) beyond a 0.12 g preload (0.030-0.56 deg/s/g); high-range gain errors of 0.11 %,
1 % and 4 % (crossfade 8.6-17.2 deg/s against the swing's 25.1 deg/s peak); driver
mismatches of 0.19, 2 and 6 ms; mean latencies of 93, 300 and 800 us (residual sd 16, 53 and
141 us); LED offsets of 0.044 %, 0.3 % and 1 % of the track (0.05, 0.34 and 1.15 arcsec peak
on the 720 arcsec pitch).
"""
from gyro_char.sim.config import BenchConfig
from heldout_detect import encoder_floor, matched_z, noise_mean, stamp_z, swing_scales
import numpy as np

G0 = 9.80665
SLOPE_SAMPLES = 10                      # the slope baseline (predictor, driver), samples
PRELOAD = 1.2                           # m/s^2: the suspension's preload
BLEND = (0.15, 0.30)                    # rad/s: the crossfade from the low to the high range
DEJITTER = 32                           # arrivals in the host's sliding mean
LINES, MOUNT = 1800, np.deg2rad(61.0)   # scale lines; where the swing sits on the scale
LED_S = 240.0                           # s: the read head's LED warm-up


def predictor(x: np.ndarray, lead: float, rate_hz: float) -> np.ndarray:
    """Return x_k + lead (x_k - x_(k-M)) / (M dt): ``lead`` s ahead (x held before 0)."""
    m = SLOPE_SAMPLES
    past = np.r_[np.full(m, x[0]), x[:-m]]
    return x + lead * (x - past) * rate_hz / m


def preloaded(f_y, gy: float) -> np.ndarray:
    """Bias gy sign(f_y) max(|f_y| - PRELOAD, 0): no deflection below the preload."""
    f_y = np.asarray(f_y, float)
    return gy * np.sign(f_y) * np.maximum(np.abs(f_y) - PRELOAD, 0.0)


def blend_weight(v) -> np.ndarray:
    """Smoothstep 3 u^2 - 2 u^3 of the low-range reading's magnitude across BLEND."""
    u = np.clip((np.abs(v) - BLEND[0]) / (BLEND[1] - BLEND[0]), 0.0, 1.0)
    return u * u * (3 - 2 * u)


def blend_mean_error(w, gain: float, s_n: float) -> np.ndarray:
    """E[y - w] over the gyro noise: gain w E[s(|w + n|)] (the weight sees the noise)."""
    w = np.asarray(w, float)
    return gain * w * noise_mean(blend_weight, w, s_n)


def push_pull(x: np.ndarray, tau: float, rate_hz: float) -> np.ndarray:
    """Return x - tau d|x|/dt, the slope over the driver's SLOPE_SAMPLES settling window."""
    m, mag = SLOPE_SAMPLES, np.abs(x)
    return x - tau * (mag - np.r_[np.full(m, mag[0]), mag[:-m]]) * rate_hz / m


def dejitter(n: int, mean: float, rng) -> np.ndarray:
    """Sliding mean of the last DEJITTER exponential arrival latencies, less its mean."""
    lat = rng.exponential(mean, n + DEJITTER - 1)
    return np.convolve(lat, np.full(DEJITTER, 1 / DEJITTER), 'valid') - mean


def dejitter_psd(f, mean: float, rate_hz: float) -> np.ndarray:
    """Two-sided PSD: mean^2 / f_s |D_M(f)|^2, D_M the M-point mean's response."""
    x = np.pi * np.asarray(f, float) / rate_hz
    num = np.sin(DEJITTER * x)
    den = DEJITTER * np.sin(x)
    gain = np.where(np.abs(den) < 1e-12, 1.0, num / np.where(den == 0, 1.0, den))
    return mean ** 2 / rate_hz * gain ** 2


def led_offset(t, offset: float) -> np.ndarray:
    """Sine-track offset (of the track amplitude) as the LED warms: offset (1 - e^(-t / LED_S))."""
    return offset * (1 - np.exp(-np.asarray(t, float) / LED_S))


def offset_error(phi, o) -> np.ndarray:
    """Read minus true angle when the sine track carries offset ``o``: atan2 on the scale."""
    u = LINES * (np.asarray(phi, float) + MOUNT)
    return np.angle(np.exp(1j * (np.arctan2(np.sin(u) + o, np.cos(u)) - u))) / LINES


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    s_n = BenchConfig.from_preset('adis16405').noise['gyro_x']['N'] * np.sqrt(rate_hz)

    def lead(imu_t, gyro, enc_t, enc, stand, rng, lead_s):
        return imu_t, predictor(gyro, lead_s, rate_hz), enc_t, enc

    def preload(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + preloaded(G0 * np.sin(stand(imu_t)[0]), gy), enc_t, enc

    def two_range(imu_t, gyro, enc_t, enc, stand, rng, gain):
        extra = gain * stand(imu_t)[1] + s_n * rng.standard_normal(gyro.size)
        return imu_t, gyro + blend_weight(gyro) * extra, enc_t, enc

    def halves(imu_t, gyro, enc_t, enc, stand, rng, tau):
        return imu_t, push_pull(gyro, tau, rate_hz), enc_t, enc

    def host(imu_t, gyro, enc_t, enc, stand, rng, mean):
        return imu_t, gyro, enc_t + dejitter(enc_t.size, mean, rng), enc

    def led(imu_t, gyro, enc_t, enc, stand, rng, offset):
        return imu_t, gyro, enc_t, enc + offset_error(enc, led_offset(enc_t - enc_t[0], offset))

    return {
        'time_delay': (lead, [{'lead_s': 1e-3}, {'lead_s': 4e-3}, {'lead_s': 1.88e-4}]),
        'g_sensitivity': (preload, [{'gy': 3e-4}, {'gy': 1e-3}, {'gy': 5.4e-5}]),
        'scale_factor_nonlinearity': (two_range, [{'gain': 0.01}, {'gain': 0.04},
                                                  {'gain': 1.12e-3}]),
        'scale_factor_asymmetry': (halves, [{'tau': 2e-3}, {'tau': 6e-3}, {'tau': 1.94e-4}]),
        'timestamp_jitter': (host, [{'mean': 3e-4}, {'mean': 8e-4}, {'mean': 9.3e-5}]),
        'encoder_cyclic_error': (led, [{'offset': 3e-3}, {'offset': 0.01}, {'offset': 4.43e-4}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    s_n = n_arw * np.sqrt(rate_hz)
    p = params
    th = np.arange(4096) * 2 * np.pi / 4096
    if name == 'g_sensitivity':
        c = np.fft.rfft(preloaded(G0 * np.sin(amp * np.sin(th)), p['gy']))[1:61] / th.size
        return float(2 * np.linalg.norm(c) / s)
    if name in ('scale_factor_nonlinearity', 'scale_factor_asymmetry'):
        rate = amp * w * np.cos(th)
        if name == 'scale_factor_nonlinearity':
            err = np.fft.rfft(blend_mean_error(rate, p['gain'], s_n)) / th.size
        else:
            k = np.arange(th.size // 2 + 1)
            m = SLOPE_SAMPLES
            diff = (1 - np.exp(-1j * k * w * m / rate_hz)) * rate_hz / m
            err = -p['tau'] * diff * np.fft.rfft(noise_mean(np.abs, rate, s_n)) / th.size
        return float(2 * np.linalg.norm(err[2:61]) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: dejitter_psd(f, p['mean'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        residual = np.cumsum(predictor(rate, p['lead_s'], rate_hz) - rate) / rate_hz
        residual -= residual.mean()
    else:
        residual = offset_error(phi, led_offset(t, p['offset']))
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    return matched_z(residual, rate_hz, n_arw, floor)
