"""
A screen of a swing run's IMU stamps for host stalls: gaps whose samples come late, not lost.

A host that stamps each IMU sample when it reads it, and now and then stalls (a garbage
collection, a disk write-back, a busy executor), leaves a pattern in the stamps: a gap, then
the samples the sensor produced meanwhile stamped in a burst as the reader catches up, none
lost. Numbered as kept (``swing_baseline.stamp_grid``), every stamp lies on the sample
grid or late of it, and how late is the latency. Across each burst the gyro angle integrated
on those stamps is off by the rate change times the latency, a step the swing filter then
reads as noise: on a 15-min 1 kHz run, stalls every 4 s of 64 and 128 ms (mean) raised
its white-noise estimate 1.23 and 2.5 times. The screen reports it beside the gap, as the
Nyquist and waveform screens do; a run it flags is calibrated on its samples' own instants
(``destalled``) and offered the stall form of the delay (``with_stall_form``: the twins'
stamps carry the record's own latency trace, ``stall_latency`` laid on the twin by
``twin_latency``, times a fitted gain). A run whose gaps are losses (the stamps resume on
the grid) is not flagged.
"""
from dataclasses import replace
from typing import List, Optional, Sequence, Tuple

from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.swing_baseline import stamp_grid, SwingBaseline
from gyro_char.records import Recording
from gyro_char.swing.batch import GAP_RELEASE_FACTOR
import numpy as np

LATE_STEPS = 0.5        # a stamp this many intervals after its grid instant is late
MIN_SAMPLES = 64
STALL_GAIN = (0.05, 3.0)   # the stall form's gain searched
JITTER_MADS = 6.0     # a latency this many MADs of the stamps' latencies up: a backlog


def stall_screen(t: np.ndarray) -> dict:
    """
    Return the stall screen of IMU stamps ``t`` (s).

    ``tested`` False (with ``reason``) on too few or non-finite stamps; else ``gaps`` (steps
    longer than the filter's release limit), ``samples_lost`` (the gaps' samples the stamps
    say were dropped), ``stalls`` (runs of late stamps), ``late_share``, ``mean_latency_s``
    (over the whole run), ``max_latency_s`` and ``flagged`` (gaps whose samples came late).
    """
    return _screen(t)[0]


def _screen(t: np.ndarray) -> Tuple[dict, Optional[np.ndarray]]:
    """Return the stall screen of ``t`` and each stamp's latency off its grid (None: untested)."""
    t = np.asarray(t, dtype=np.float64)
    if t.size < MIN_SAMPLES or not np.all(np.isfinite(t)):
        return {'tested': False,
                'reason': f'{t.size} stamps, need {MIN_SAMPLES} finite ones'}, None
    d = np.diff(t)
    med = float(np.median(d))
    if not med > 0:
        return {'tested': False, 'reason': 'the stamps do not advance'}, None
    gaps = int(np.count_nonzero(d > GAP_RELEASE_FACTOR * med))
    k, dt, g0 = _grid(t)
    lost = int(round(k[-1])) - (t.size - 1)
    latency = t - g0 - dt * k
    late = latency > LATE_STEPS * dt
    stalls = int(np.count_nonzero(np.diff(late.astype(np.int8), prepend=0) == 1))
    return {'tested': True, 'gaps': gaps, 'samples_lost': lost, 'stalls': stalls,
            'late_share': float(late.mean()),
            'mean_latency_s': float(np.mean(np.where(late, latency, 0.0))),
            'max_latency_s': float(max(latency.max(), 0.0)),
            'flagged': bool(gaps and not lost and stalls)}, latency


def _grid(t: np.ndarray) -> Tuple[np.ndarray, float, float]:
    """Return the stamps' sample numbers, interval and grid origin (the median departure)."""
    k, dt = stamp_grid(t)
    return k, dt, float(np.median(t - dt * k))


def stall_latency(t: np.ndarray) -> Optional[np.ndarray]:
    """
    Return each stamp's latency off the sample grid where the screen flags stalls, else None.

    The latency counts only where a stamp stands above the grid by more than the stamps' own
    jitter (JITTER_MADS median absolute departures of the latencies), so that a trace carried
    into a twin's stamps holds the stalls' backlogs down to their last microseconds and not
    the record's white stamp jitter, which the twin draws for itself. None too where the
    stamps moved back by it would not be in order: a latency that is not a backlog drained
    behind a stall (set AG's playout buffer at its strong level: 44 stamps out of order).
    """
    screen, latency = _screen(t)
    if not screen.get('flagged'):
        return None
    floor = JITTER_MADS * float(np.median(np.abs(latency)))
    latency = np.where(latency > floor, latency, 0.0)
    return latency if np.all(np.diff(np.asarray(t, dtype=np.float64) - latency) > 0) else None


def destalled(imu: Recording, latency: Optional[np.ndarray]) -> Recording:
    """Return ``imu`` with each stamp moved back by its latency (the samples' own instants)."""
    if latency is None:
        return imu
    return Recording(imu.t - latency, imu.channels, imu.source, list(imu.notes))


def twin_latency(latency: np.ndarray, imu_t: np.ndarray, enc_t: np.ndarray,
                 angle: np.ndarray, period_s: float, twin_phase: float,
                 gyro_start: float) -> np.ndarray:
    """
    Return the record's latency trace laid on a twin's samples, at the same swing phase.

    A stall's error is the rate at its instant times the latency, so the trace goes where the
    twin's stand is at the phase the record's was: the record's phase at the start of the
    overlap from a least-squares sine on the encoder angle (at the period the twins use),
    the twin's own (``twin_phase``) at its time 0, the shift taken within half a period and
    rounded to whole samples. Samples of the twin the record has no trace for get none.
    """
    _, dt, g0 = _grid(imu_t)
    t_ov = max(float(imu_t[0]), float(enc_t[0]))
    w = 2.0 * np.pi / period_s
    u = enc_t - t_ov
    a = np.column_stack([np.sin(w * u), np.cos(w * u), np.ones_like(u)])
    c = np.linalg.lstsq(a, angle, rcond=None)[0]
    shift = ((float(np.arctan2(c[1], c[0])) - twin_phase) / w + 0.5 * period_s) % period_s \
        - 0.5 * period_s
    m = int(round((t_ov + gyro_start - shift - g0) / dt))
    out = np.zeros(latency.size)
    lo, hi = max(0, -m), min(latency.size, latency.size - m)
    if hi > lo:
        out[lo:hi] = latency[lo + m:hi + m]
    return out


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
            'burst is off by the rate change times the latency; the run was calibrated at '
            "its samples' own instants and offered the delay's stall form (time_delay "
            "stall_gain: the twins' stamps carry this latency). Stamp the samples at the "
            'sensor or in the driver; see "per_record" imu_stalls')


def with_stall_form(spaces: List[EffectSpace],
                    bases: Sequence[SwingBaseline]) -> List[EffectSpace]:
    """
    Give the delay a stall form where a record carries a latency trace (its screen flagged).

    The form's stamps carry ``stall_gain`` times the record's trace and no constant delay;
    1 is a host that stamps on read and stalls, the samples taken on time; searched from a
    twentieth to three times (a trace read off jittered stamps, a gain near 1 either way).
    """
    if not any(b.stamp_latency is not None for b in bases):
        return spaces
    out = []
    for sp in spaces:
        if sp.name == 'time_delay':
            form = EffectSpace('time_delay', [Param('stall_gain', *STALL_GAIN, init=1.0)],
                               fixed={'delay_s': 0.0, 'lag_s': 0.0})
            sp = replace(sp, alternatives=tuple(sp.alternatives) + (form,))
        out.append(sp)
    return out
