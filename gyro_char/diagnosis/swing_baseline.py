"""The paper's swing model fitted to one record: the baseline every swing twin starts from."""
from dataclasses import dataclass

from gyro_char.sim.config import BenchConfig
import numpy as np

PRESET = 'adis16405'  # the twins' structure: the fitted numbers override what matters


@dataclass
class SwingBaseline:
    """The paper's swing model fitted to one record (SI)."""

    period_s: float
    amplitude: float
    scale_factor_error: float
    bias: float
    drift: float
    N: float
    encoder_sigma: float
    lsb: float
    dt: float
    encoder_dt: float
    duration: float
    axis: str
    # This record's own Kalman estimate (``scale_factor_error`` is what the twin uses: the
    # gyro's one scale-factor error, pooled over the records diagnosed together).
    record_scale_factor_error: float = 0.0
    record_scale_factor_sigma: float = 0.0
    samples: int = 0                # gyro samples analysed (0: not set)
    gyro_start: float = 0.0         # gyro stamps' offset into the encoder interval, s
    # The gyro's static noise terms beyond the white N (IEEE bias instability and rate random
    # walk): a swing record does not pin them (``swing.static_noise``), the twin carries them.
    B: float = 0.0
    K: float = 0.0

    @property
    def peak_rate(self) -> float:
        return 2.0 * np.pi * self.amplitude / self.period_s

    def to_json(self) -> dict:
        units = {'period_s': 's', 'amplitude': 'rad', 'peak_rate': 'rad/s',
                 'scale_factor_error': '1', 'record_scale_factor_error': '1',
                 'record_scale_factor_sigma': '1', 'bias': 'rad/s', 'drift': 'rad/s^2',
                 'N': 'rad/s^0.5', 'B': 'rad/s', 'K': 'rad/s^1.5', 'encoder_sigma': 'rad',
                 'lsb': 'rad/s', 'dt': 's',
                 'encoder_dt': 's', 'duration': 's'}
        return {k: {'value': float(getattr(self, k)), 'unit': u} for k, u in units.items()}


def static_noise(channel: str, preset: str = PRESET) -> dict:
    """
    Return the gyro's bias instability B and rate random walk K for the twin: the preset's.

    The paper's swing model has white noise only, and a swing record cannot pin B and K: the
    residual fit takes out a bias and a drift, and what is left of a flicker and a random walk
    lies in the few lowest residual-PSD bins, below the swing frequency's neighbourhood where
    the harmonics sit. Left out, the twins missed that low-frequency power (a whole 15-min run
    read it as a misfit that timestamp_jitter soaked up: a false alarm). They are a static
    characterisation's numbers (``gyro-char allan`` on a static record of the same gyro), so
    the twin takes them from the configuration it is compared with, as it takes the encoder's
    level and word steps; a caller with measured values passes its own ``bases``.
    """
    terms = BenchConfig.from_preset(preset).noise.get(channel, {})
    return {'B': float(terms.get('B', 0.0)), 'K': float(terms.get('K', 0.0))}
