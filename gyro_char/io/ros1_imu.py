"""
Vectorised decoding of ROS 1 serialised ``sensor_msgs/Imu`` (little-endian, no alignment).

Layout: ``header.seq`` uint32 @0, ``stamp.secs`` @4 (read as int32, as rosbags does), ``nsecs`` @8,
``frame_id`` uint32 length L @12 and its bytes @16 (no terminator), then 37 packed float64
(orientation, covariances, angular_velocity @16+L+104, linear_acceleration @16+L+200); size
16 + L + 296. Payloads that do not fit exactly, or whose frame_id is not ASCII, are left to
rosbags' per-message path so both paths accept the same messages.
"""
from typing import Dict, Tuple

from gyro_char.io.cdr import (ascii_frames, gather, IMU_TAIL,
                              stamp_and_rates)
import numpy as np


def decode_imu_ros1(buf: np.ndarray, offsets: np.ndarray, sizes: np.ndarray
                    ) -> Tuple[np.ndarray, Dict[str, np.ndarray], np.ndarray]:
    """Return ``(t, channels, ok)`` as ``cdr.decode_imu`` does, for ROS 1 payloads."""
    offsets = np.asarray(offsets, dtype=np.int64)
    sizes = np.asarray(sizes, dtype=np.int64)
    n = offsets.size
    ok = (sizes >= 16 + IMU_TAIL) & (offsets >= 0) & (offsets + sizes <= buf.size)
    idx = np.flatnonzero(ok)
    off = offsets[idx]
    little = np.zeros(idx.size, dtype=bool)
    strlen = gather(buf, off + 12, 'u4', little).astype(np.int64)
    good = sizes[idx] == 16 + strlen + IMU_TAIL
    good &= ascii_frames(buf, off + 16, np.where(good, strlen, 0))
    idx, off, strlen, little = idx[good], off[good], strlen[good], little[good]
    ok[:] = False
    ok[idx] = True
    # secs read as int32, as rosbags reads it
    t, channels = stamp_and_rates(buf, n, idx, off, off + 16 + strlen, little)
    return t, channels, ok
