"""
The one in-memory record type shared by every source and estimator.

A ``Recording`` is one sampled stream: float64 stamps in seconds and named float64 channels in
SI units (``gyro_x`` rad/s, ``accel_x`` m/s^2, ``encoder`` rad). A swing run is two recordings
(IMU and encoder) because the two streams have their own stamps; the core aligns them.
"""
from dataclasses import dataclass, field
from typing import Dict, List

from gyro_char.errors import InputError
import numpy as np

GYRO_CHANNELS = ('gyro_x', 'gyro_y', 'gyro_z')
ACCEL_CHANNELS = ('accel_x', 'accel_y', 'accel_z')
IMU_CHANNELS = GYRO_CHANNELS + ACCEL_CHANNELS
ENCODER_CHANNEL = 'encoder'
# A step longer than this many median intervals is a gap (see gyro_char.io.sanitize.segments).
DEFAULT_GAP_FACTOR = 5.0


@dataclass
class Recording:
    """One stream: stamps ``t`` (s, float64) and SI channels of the same length."""

    t: np.ndarray
    channels: Dict[str, np.ndarray]
    source: str = ''
    # Human-readable, counted treatments applied on the way in (e.g. '3 duplicate stamps
    # dropped'); printed to the user so that nothing is changed silently.
    notes: List[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        self.channels = {k: np.asarray(v, dtype=np.float64) for k, v in self.channels.items()}
        for name, values in self.channels.items():
            if values.shape != self.t.shape:
                raise InputError(
                    f'channel {name!r} has {values.size} samples but there are '
                    f'{self.t.size} stamps')

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if self.t.size > 1 else 0.0

    @property
    def dt(self) -> float:
        """Median sample interval in seconds."""
        if self.t.size < 2:
            raise InputError(f'{self.source or "recording"}: fewer than 2 samples')
        return float(np.median(np.diff(self.t)))
