"""
The one in-memory record type shared by every source and estimator.

A ``Recording`` is one sampled stream: float64 stamps in seconds and named float64 channels in
SI units (``gyro_x`` rad/s, ``accel_x`` m/s^2, ``encoder`` rad). A swing run is two recordings
(IMU and encoder) because the two streams have their own stamps; the core aligns them.
"""
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple, Union

import numpy as np

GYRO_CHANNELS = ('gyro_x', 'gyro_y', 'gyro_z')
ACCEL_CHANNELS = ('accel_x', 'accel_y', 'accel_z')
IMU_CHANNELS = GYRO_CHANNELS + ACCEL_CHANNELS
ENCODER_CHANNEL = 'encoder'
# A step longer than this many median intervals is a gap (see ingest.sanitize.segments).
DEFAULT_GAP_FACTOR = 5.0


class InputError(ValueError):
    """Bad or unusable input; the CLI turns it into a one-line message and exit code 2."""


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


# --- reading and writing (implemented in gyro_char.ingest; imported lazily to avoid a cycle) ---

def read_imu(path: str, topic: Optional[str] = None, quiet: bool = False) -> Recording:
    """
    Read IMU samples (``gyro_*`` rad/s, ``accel_*`` m/s^2, those present) from any input.

    ``path`` is a ROS 2 bag directory (sqlite3 or mcap), a ``.mcap`` file, a ROS 1 ``.bag`` or a
    CSV(.gz) as in DESIGN.md section 3. Stamps are ``header.stamp`` (bags) or ``t_s`` (CSV),
    sanitised (``gyro_char.ingest.sanitize``) with every treatment counted in ``notes``.
    """
    from gyro_char.ingest.read import read_imu as _read_imu
    return _read_imu(path, topic=topic, quiet=quiet)


def read_encoder(path: str, topic: Optional[str] = None,
                 joint: Union[str, int, None] = None, quiet: bool = False) -> Recording:
    """
    Read the stand's encoder angle (channel ``encoder``, rad) from any input.

    Bags: ``sensor_msgs/JointState`` (joint by name or index, default the first) or
    ``geometry_msgs/Vector3Stamped`` (x). CSV: column ``encoder_rad`` or ``encoder_deg``.
    """
    from gyro_char.ingest.read import read_encoder as _read_encoder
    return _read_encoder(path, topic=topic, joint=joint, quiet=quiet)


def write_bag(path: str, imu: Recording, encoder: Optional[Recording] = None, *,
              storage: str = 'mcap', imu_topic: str = '/imu/data_raw',
              encoder_topic: str = '/stand/joint_states', joint_name: str = 'stand_joint',
              frame_id: str = 'imu_link', quiet: bool = True) -> None:
    """Write a ROS 2 bag directory (``storage`` 'mcap' or 'sqlite3'): Imu and JointState."""
    from gyro_char.ingest.bag_write import write_bag as _write_bag
    _write_bag(path, imu, encoder, storage=storage, imu_topic=imu_topic,
               encoder_topic=encoder_topic, joint_name=joint_name, frame_id=frame_id,
               quiet=quiet)


def segments(rec: Recording, max_gap_factor: float = DEFAULT_GAP_FACTOR) -> List[Tuple[int, int]]:
    """Return the contiguous runs of ``rec`` as ``[(start, stop), ...]`` index slices."""
    from gyro_char.ingest.sanitize import segments as _segments
    return _segments(rec, max_gap_factor)
