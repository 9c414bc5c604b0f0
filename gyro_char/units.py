"""
Units: degree and g constants, SI unit strings of the noise terms, human units of tables.

Inside the package everything is SI (rad, rad/s, m/s^2, s); tables for people use the field's
units (deg/sqrt(h), deg/h, ug). ``HUMAN_UNITS[kind][term] = (factor, unit)`` with
human value = SI value / factor.
"""
import numpy as np

# SI unit strings (noise.json) and the human units of the table.
SI_UNITS = {
    'gyro': {'N': 'rad/s^0.5', 'B': 'rad/s', 'K': 'rad/s^1.5', 'Q': 'rad', 'R': 'rad/s^2'},
    'accel': {'N': 'm/s^1.5', 'B': 'm/s^2', 'K': 'm/s^2.5', 'Q': 'm/s', 'R': 'm/s^3'},
}
RATE_UNITS = {'gyro': 'rad/s', 'accel': 'm/s^2'}
DEG = np.pi / 180.0
G0 = 9.80665
# (factor, unit): human value = SI value / factor.
HUMAN_UNITS = {
    'gyro': {'N': (DEG / 60.0, 'deg/h^0.5'), 'B': (DEG / 3600.0, 'deg/h'),
             'K': (DEG / 3600.0 / 60.0, 'deg/h^1.5'), 'Q': (DEG / 3600.0, 'arcsec'),
             'R': (DEG / 3600.0 ** 2, 'deg/h^2')},
    'accel': {'N': (1.0 / 60.0, 'm/s/h^0.5'), 'B': (G0 * 1e-6, 'ug'),
              'K': (G0 * 1e-6 / 60.0, 'ug/h^0.5'), 'Q': (1.0, 'm/s'),
              'R': (G0 * 1e-6, 'ug/s')},
}


def sensor_kind(channel: str) -> str:
    """Return ``'gyro'`` or ``'accel'`` from a channel name like ``gyro_x``."""
    kind = channel.split('_', 1)[0]
    if kind not in SI_UNITS:
        raise ValueError(f'channel {channel!r} is neither gyro_* nor accel_*')
    return kind


def to_human(term: str, kind: str, value: float) -> float:
    """Convert an SI coefficient to the human unit of ``HUMAN_UNITS``."""
    return value / HUMAN_UNITS[kind][term][0]
