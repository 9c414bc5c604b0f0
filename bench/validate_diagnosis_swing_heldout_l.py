"""
Held-out swing set L: written blind, without running the diagnosis, run once at the end.

DOCSTRING
"""
from gyro_char.sim.config import BenchConfig
from heldout_detect import matched_z, noise_mean
import numpy as np

G0 = 9.80665
SLOPE_SAMPLES = 10                      # the slope baseline (predictor, driver), samples
PRELOAD = 1.2                           # m/s^2: the suspension's preload
BLEND = (0.15, 0.30)                    # rad/s: the crossfade from the low to the high range
DEJITTER = 32                           # arrivals in the host's sliding mean
LINES, MOUNT = 1800, np.deg2rad(61.0)   # scale lines; where the swing sits on the scale
LED_S = 240.0                           # s: the read head's LED warm-up


def predictor(x: np.ndarray, lead: float, rate_hz: float) -> np.ndarray:
    """x_k + lead (x_k - x_(k-M)) / (M dt): extrapolated ``lead`` s ahead (x held before 0)."""
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
    """x - tau d|x|/dt, the slope over the driver's SLOPE_SAMPLES settling window."""
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
    cfg = BenchConfig.from_preset('adis16405')
    n_arw, amp, enc = cfg.noise['gyro_x']['N'], cfg.stand.amplitude, cfg.encoder
    w = 2 * np.pi / period_s
    s = n_arw * np.sqrt(2 / duration)
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
    floor = (enc.adc_noise ** 2 + enc.level_step ** 2 / 12 + enc.word_step ** 2 / 12) / rate_hz
    floor += (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz
    if name == 'timestamp_jitter':
        f = np.linspace(-rate_hz / 2, rate_hz / 2, 400001)
        f0 = w / (2 * np.pi)
        s_r = (amp * w) ** 2 / 4 * (dejitter_psd(f - f0, p['mean'], rate_hz)
                                    + dejitter_psd(f + f0, p['mean'], rate_hz))
        s_g = n_arw ** 2 / np.maximum((2 * np.pi * f) ** 2, 1e-30) + floor
        return float(np.sqrt(duration / 2 * np.trapezoid((s_r / s_g) ** 2, f)))
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        residual = np.cumsum(predictor(rate, p['lead_s'], rate_hz) - rate) / rate_hz
        residual -= residual.mean()
    else:
        residual = offset_error(phi, led_offset(t, p['offset']))
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    return matched_z(residual, rate_hz, n_arw, floor)
