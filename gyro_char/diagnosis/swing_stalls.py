"""
A screen of a swing run's IMU stamps for host stalls: gaps whose samples come late, not lost.

A host that stamps each IMU sample when it reads it, and now and then stalls (a garbage
collection, a disk write-back, a busy executor), leaves a pattern in the stamps: a gap, then
the samples the sensor produced meanwhile stamped in a burst as the reader catches up, none
lost. Numbered as kept (``swing_baseline.stamp_grid``), every stamp lies on the sample
grid or late of it, and how late is the latency. Across each burst the gyro angle integrated
on those stamps is off by the rate change times the latency, a step the swing filter then
reads as noise: on a 15-min 1 kHz run, stalls every 4 s of 64 and 128 ms (mean) raised
its white-noise estimate 1.23 and 2.5 times. No catalogue effect makes it (the stamp
jitter candidates are Gaussian and move the stamps both ways), so the screen reports it
beside the gap, as the Nyquist and waveform screens do. A run whose gaps are losses (the
stamps resume on the grid) is not flagged.
"""
from typing import Optional

from gyro_char.diagnosis.swing_baseline import stamp_grid
from gyro_char.records import Recording
from gyro_char.swing.batch import GAP_RELEASE_FACTOR
import numpy as np

LATE_STEPS = 0.5        # a stamp this many intervals after its grid instant is late
MIN_SAMPLES = 64


def stall_screen(t: np.ndarray) -> dict:
    """
    Return the stall screen of IMU stamps ``t`` (s).

    ``tested`` False (with ``reason``) on too few or non-finite stamps; else ``gaps`` (steps
    longer than the filter's release limit), ``samples_lost`` (the gaps' samples the stamps
    say were dropped), ``stalls`` (runs of late stamps), ``late_share``, ``mean_latency_s``
    (over the whole run), ``max_latency_s`` and ``flagged`` (gaps whose samples came late).
    """
    t = np.asarray(t, dtype=np.float64)
    if t.size < MIN_SAMPLES or not np.all(np.isfinite(t)):
        return {'tested': False,
                'reason': f'{t.size} stamps, need {MIN_SAMPLES} finite ones'}
    d = np.diff(t)
    med = float(np.median(d))
    if not med > 0:
        return {'tested': False, 'reason': 'the stamps do not advance'}
    gaps = int(np.count_nonzero(d > GAP_RELEASE_FACTOR * med))
    k, dt = stamp_grid(t)
    lost = int(round(k[-1])) - (t.size - 1)
    res = t - dt * k
    latency = res - float(np.median(res))
    late = latency > LATE_STEPS * dt
    stalls = int(np.count_nonzero(np.diff(late.astype(np.int8), prepend=0) == 1))
    return {'tested': True, 'gaps': gaps, 'samples_lost': lost, 'stalls': stalls,
            'late_share': float(late.mean()),
            'mean_latency_s': float(np.mean(np.where(late, latency, 0.0))),
            'max_latency_s': float(max(latency.max(), 0.0)),
            'flagged': bool(gaps and not lost and stalls)}


def record_stalls(imu: Recording) -> dict:
    """Return the stall screen of a swing record's IMU stamps."""
    return stall_screen(imu.t)


def stall_warning(label: str, screen: dict) -> Optional[str]:
    """Return the warning of a flagged screen of the run ``label`` ('record 1'), else None."""
    if not screen.get('flagged'):
        return None
    return (f'{label}: the IMU stamps show {screen["stalls"]} stalls ({screen["gaps"]} gaps, '
            f'each followed by the samples produced meanwhile stamped late in a burst, none '
            f'lost; {100.0 * screen["late_share"]:.2g} % of the samples late, by '
            f'{screen["mean_latency_s"]:.3g} s on average over the run and up to '
            f'{screen["max_latency_s"]:.3g} s): a host that stamps samples when it reads '
            'them and stalls: a delay that varies along the run. The gyro angle across each '
            'burst is off by the rate change times the latency; no catalogue effect models '
            'it, so the effect named for the gap may stand in for it (stamp the samples at '
            'the sensor or in the driver); see "per_record" imu_stalls')
