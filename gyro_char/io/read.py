"""
One entry point per stream kind, whatever the input format (docs/design.md).

Dispatch by what ``path`` is: CSV(.gz) by suffix, otherwise a bag (ROS 2 directory, ``.mcap``
file, ROS 1 ``.bag``). Every result goes through ``sanitize`` so all commands see the same
hygiene and the same counted notes.
"""
from pathlib import Path
from typing import Optional, Union

from gyro_char.errors import InputError
from gyro_char.io.csv_io import is_csv, read_csv
from gyro_char.io.sanitize import sanitize
from gyro_char.records import ENCODER_CHANNEL, IMU_CHANNELS, Recording


def _check_exists(path: str) -> Path:
    p = Path(path)
    if not p.exists():
        raise InputError(f'{path}: no such file or directory')
    return p


def read_imu(path: str, topic: Optional[str] = None, quiet: bool = False) -> Recording:
    """Read IMU channels (those present) in SI; see ``gyro_char.io.read_imu``."""
    p = _check_exists(path)
    if is_csv(str(p)):
        rec = read_csv(str(p))
        present = {k: v for k, v in rec.channels.items() if k in IMU_CHANNELS}
        if not present:
            raise InputError(f'{path}: CSV has no gyro_* or accel_* column')
        rec = Recording(rec.t, present, source=rec.source, notes=rec.notes)
    else:
        from gyro_char.io.bag_read import read_imu_bag
        rec = read_imu_bag(p, topic=topic, quiet=quiet)
    return sanitize(rec)


def read_encoder(path: str, topic: Optional[str] = None,
                 joint: Union[str, int, None] = None, quiet: bool = False) -> Recording:
    """Read the encoder angle (rad), sanitised; see ``gyro_char.io.read_encoder``."""
    p = _check_exists(path)
    if is_csv(str(p)):
        rec = read_csv(str(p))
        if ENCODER_CHANNEL not in rec.channels:
            raise InputError(f'{path}: CSV has no encoder_rad or encoder_deg column')
        rec = Recording(rec.t, {ENCODER_CHANNEL: rec.channels[ENCODER_CHANNEL]},
                        source=rec.source, notes=rec.notes)
    else:
        from gyro_char.io.encoder_read import read_encoder_bag
        rec = read_encoder_bag(p, topic=topic, joint=joint, quiet=quiet)
    return sanitize(rec)
