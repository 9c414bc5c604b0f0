"""The paper's swing model fitted to one record: the baseline every swing twin starts from."""
from dataclasses import dataclass

import numpy as np


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

    @property
    def peak_rate(self) -> float:
        return 2.0 * np.pi * self.amplitude / self.period_s

    def to_json(self) -> dict:
        units = {'period_s': 's', 'amplitude': 'rad', 'peak_rate': 'rad/s',
                 'scale_factor_error': '1', 'record_scale_factor_error': '1',
                 'record_scale_factor_sigma': '1', 'bias': 'rad/s', 'drift': 'rad/s^2',
                 'N': 'rad/s^0.5', 'encoder_sigma': 'rad', 'lsb': 'rad/s', 'dt': 's',
                 'encoder_dt': 's', 'duration': 's'}
        return {k: {'value': float(getattr(self, k)), 'unit': u} for k, u in units.items()}
