"""
The swing screens that run beside the gap, together: one call per record, one list of warnings.

Each screen looks at what the gap cannot see or no catalogue effect models: the rate at the
gyro's Nyquist frequency (``swing_nyquist``), a waveform that changes over the run
(``swing_drift``) and a host that stalls and stamps its backlog late (``swing_stalls``). The
diagnosis reports them per record and turns the flagged ones into
warnings.
"""
from typing import List

from gyro_char.diagnosis.swing_drift import drift_warning, record_drift
from gyro_char.diagnosis.swing_nyquist import record_screen, screen_warning
from gyro_char.diagnosis.swing_stalls import record_stalls, stall_warning
from gyro_char.records import Recording

__all__ = ['record_screens', 'screen_warnings']


def record_screens(imu: Recording, encoder: Recording, axis: str, period_s: float) -> dict:
    """Return the three screens of one swing record: rate_nyquist, waveform_drift, imu_stalls."""
    return {'rate_nyquist': record_screen(imu, encoder, axis, period_s),
            'waveform_drift': record_drift(imu, encoder, axis, period_s),
            'imu_stalls': record_stalls(imu)}


def screen_warnings(label: str, screens: dict) -> List[str]:
    """Return the warnings of the flagged screens of the run ``label`` ('record 1')."""
    found = (screen_warning(label, screens['rate_nyquist']),
             drift_warning(label, screens['waveform_drift']),
             stall_warning(label, screens['imu_stalls']))
    return [w for w in found if w]
