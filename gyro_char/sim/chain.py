"""
Elements of the paper's bench model (docs/method.md, "The paper's simulation model"), vectorised.

Each function is one element of the chain, tested against its closed form in
``test/test_sim_chain.py``: quantizers, jittered sampling instants, the stand's angle and rate,
the encoder's reading, the gravity seen by a sensor on a tilting stand.
"""
from typing import Tuple

from gyro_char.sim.config import EncoderConfig, StandConfig
import numpy as np


G0 = 9.80665
# Sampling jitter is clipped at this fraction of the sample interval so that the sample
# instants stay strictly increasing (at the presets' 10-20 us over >= 1 ms it never binds).
JITTER_CLIP = 0.45


def quantize(x: np.ndarray, step: float, mode: str = 'round') -> np.ndarray:
    """
    Quantize to multiples of ``step`` (0: unchanged).

    ``'floor'`` is the paper's integer part [x/step]*step (error uniform on (-step, 0], mean
    -step/2); ``'round'`` is round-to-nearest (error uniform on [-step/2, step/2), mean 0). Both
    have error variance step^2/12 when the input spreads over many steps.
    """
    if not step:
        return x
    if mode == 'floor':
        return np.floor(x / step) * step
    if mode == 'round':
        return np.round(x / step) * step
    raise ValueError(f'unknown quantizer {mode!r}')


def quantizer_mean_error(step: float, mode: str) -> float:
    """Mean error of ``quantize`` on an input spread over many steps: -step/2 or 0."""
    return -0.5 * step if mode == 'floor' else 0.0


def sample_times(n: int, dt: float, jitter_s: float, rng: np.random.Generator,
                 start: float = 0.0) -> np.ndarray:
    """Nominal instants start + k dt plus Gaussian jitter (sigma ``jitter_s``, clipped)."""
    t = start + dt * np.arange(n, dtype=np.float64)
    if jitter_s > 0:
        lim = JITTER_CLIP * dt
        t += np.clip(jitter_s * rng.standard_normal(n), -lim, lim)
        # Never before the start: stamps of a run stay >= start (ROS times are unsigned).
        t[0] = max(t[0], start)
    return t


def stand_motion(cfg: StandConfig, t: np.ndarray,
                 rng: np.random.Generator) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return the stand's angle, rate and angular acceleration at the instants ``t``.

    phi(t) = (A + dA) sin(2 pi t / T + psi0) + phi0 + (w0 + dw0) t + wdot0 t^2 / 2, with dA, dw0
    white: one independent Gaussian draw per sample instant (the paper's "system noises"; two
    streams sampling the stand at different instants see independent draws). The rate is the
    analytic derivative with the same draws; acceleration without them.
    """
    n = t.size
    w = 2.0 * np.pi / cfg.period_s
    amp = np.full(n, cfg.amplitude)
    if cfg.amplitude_noise > 0:
        amp += cfg.amplitude_noise * rng.standard_normal(n)
    w0 = np.full(n, cfg.drift_rate)
    if cfg.drift_rate_noise > 0:
        w0 += cfg.drift_rate_noise * rng.standard_normal(n)
    arg = w * t + cfg.phase
    s, c = np.sin(arg), np.cos(arg)
    angle = amp * s + cfg.offset + w0 * t + 0.5 * cfg.drift_accel * t * t
    rate = amp * w * c + w0 + cfg.drift_accel * t
    accel = -cfg.amplitude * w * w * s + cfg.drift_accel
    return angle, rate, accel


def stand_angle_clean(cfg: StandConfig, t: np.ndarray) -> np.ndarray:
    """Return the stand angle without the system noises (for effects and tests)."""
    w = 2.0 * np.pi / cfg.period_s
    return (cfg.amplitude * np.sin(w * t + cfg.phase) + cfg.offset + cfg.drift_rate * t
            + 0.5 * cfg.drift_accel * t * t)


def stand_rate_clean(cfg: StandConfig, t: np.ndarray) -> np.ndarray:
    """Return the stand rate without the system noises (the derivative of the clean angle)."""
    w = 2.0 * np.pi / cfg.period_s
    return cfg.amplitude * w * np.cos(w * t + cfg.phase) + cfg.drift_rate + cfg.drift_accel * t


def encoder_reading(cfg: EncoderConfig, angle: np.ndarray,
                    rng: np.random.Generator) -> np.ndarray:
    """phi_enc = [([phi / d1] d1 + dd1) / d2] d2 with [.] the integer part (floor)."""
    reading = quantize(angle, cfg.level_step, 'floor')
    if cfg.adc_noise > 0:
        reading = reading + cfg.adc_noise * rng.standard_normal(angle.size)
    return quantize(reading, cfg.word_step, 'floor')


def specific_force(axis: int, angle: np.ndarray) -> np.ndarray:
    """
    Return the specific force (3 x n, m/s^2) on a sensor tilted about one of its axes.

    The sensor frame is z-up at angle 0 and is tilted by ``angle`` about its axis ``axis``
    (0, 1, 2); the specific force is the reaction to gravity, R^T (0, 0, g).

    The sensor is assumed on the swing axis (no centripetal or tangential term).
    """
    f = np.zeros((3, angle.size))
    if axis == 2 or not angle.any():        # about the vertical, or a static record
        f[2] = G0
        return f
    s, c = G0 * np.sin(angle), G0 * np.cos(angle)
    if axis == 0:
        f[1], f[2] = s, c
    else:
        f[0], f[2] = -s, c
    return f
