"""
From a sanitised ``Recording`` to Allan variances: the Allan-specific treatment of stamps.

The Allan variance assumes one sample per dt. After the ingest layer's sanitising (sorted,
de-duplicated, NaN rows dropped, all counted in ``notes``) this module decides:

- dt is the median stamp interval.
- An interval longer than 1.5 dt means missing samples (including rows the reader dropped):
  the record is split there into contiguous segments, S(m) and term counts are computed per
  segment and pooled (sum of sums / sum of counts), so no difference ever spans a gap; tau is
  limited to half the longest segment. Counted in the notes.
- Intervals shorter than 0.5 dt, or a sample rate that changes along the record (block medians
  differing by more than 2 %), are refused: resample first (never silently wrong).
- Smaller jitter is treated as stamp noise on a uniformly clocked sensor (the sample values are
  used at their index); its rms is noted when above 5 % of dt.
- A channel with no variation at all (constant signal) is refused: it has no noise to analyse.
- Impulsive outliers (spikes) are looked for on every channel and counted in a note with their
  share, largest size and the white noise they add to sigma^2 (``gyro_char.allan.spikes``);
  ``despike`` replaces them by their neighbours' mean (opt in, counted).
- The sensor's output filter for the noise fit (``gyro_char.allan.sensor_filter``: none, given,
  or ``auto``, estimated on the longest gap-free run) is resolved per channel and noted.
"""
from typing import List, Optional, Sequence, Tuple

from gyro_char.allan import spikes
from gyro_char.allan.edf import add_confidence, alpha_from_acf, alpha_from_slope
from gyro_char.allan.kernel import (allan_sums, AllanResult, m_grid, phase, POINTS_PER_OCTAVE,
                                    pool, taus_to_m)
from gyro_char.allan.sensor_filter import parse_spec, resolve
from gyro_char.errors import InputError
from gyro_char.records import ACCEL_CHANNELS, GYRO_CHANNELS, Recording
from gyro_char.units import RATE_UNITS, sensor_kind
import numpy as np

GAP_FACTOR = 1.5
SHORT_FACTOR = 0.5
RATE_CHANGE_TOL = 0.02
JITTER_NOTE = 0.05
MIN_SAMPLES = 16


def uniform_segments(t: np.ndarray, source: str = 'recording'
                     ) -> Tuple[float, List[Tuple[int, int]], List[str]]:
    """Return (dt, [(start, stop), ...], notes) per the rules of this module's docstring."""
    t = np.asarray(t, dtype=np.float64)
    if t.size < MIN_SAMPLES:
        raise InputError(f'{source}: {t.size} samples; the Allan variance needs at least '
                         f'{MIN_SAMPLES}')
    step = np.diff(t)
    if np.any(step <= 0) or not np.all(np.isfinite(step)):
        raise InputError(f'{source}: stamps are not strictly increasing')
    dt = float(np.median(step))
    notes = []
    short = int(np.count_nonzero(step < SHORT_FACTOR * dt))
    if short:
        raise InputError(
            f'{source}: {short} stamp interval(s) shorter than half the median {dt:.6g} s: '
            'the samples are not uniformly spaced; resample to a uniform rate first')
    gap = step > GAP_FACTOR * dt
    blocks = np.array_split(step[~gap], 20) if step.size >= 200 else [step[~gap]]
    med = np.array([np.median(b) for b in blocks if b.size])
    if np.any(np.abs(med / dt - 1.0) > RATE_CHANGE_TOL):
        raise InputError(
            f'{source}: the sample interval changes along the record (block medians '
            f'{med.min():.6g}..{med.max():.6g} s); resample to one uniform rate first')
    jitter = float(np.sqrt(np.mean((step[~gap] / dt - 1.0) ** 2)))
    if jitter > JITTER_NOTE:
        notes.append(f'allan: stamp jitter {100 * jitter:.3g} % rms of dt; samples treated as '
                     'uniformly clocked at the median interval')
    cuts = np.flatnonzero(gap) + 1
    bounds = np.concatenate(([0], cuts, [t.size]))
    segs = [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
    if cuts.size:
        missing = int(np.sum(np.round(step[gap] / dt) - 1))
        notes.append(f'allan: {cuts.size} gap(s) (about {missing} missing samples): sums '
                     f'pooled over {len(segs)} contiguous segments, longest '
                     f'{max(b - a for a, b in segs)} samples')
    return dt, segs, notes


def default_channels(rec: Recording) -> List[str]:
    """Return the IMU channels present in ``rec`` (gyro first)."""
    return [c for c in GYRO_CHANNELS + ACCEL_CHANNELS if c in rec.channels]


def screen(data: np.ndarray, names: Sequence[str], dt: float, longest: Tuple[int, int],
           sensor_filter='none', despike: bool = False) -> Tuple[dict, dict, List[str]]:
    """
    Find each channel's spikes (removed in place with ``despike``) and its sensor filter.

    Return ({channel: FilterChoice}, {channel: SpikeReport}, notes). The filter (``none``,
    given, or ``auto``: estimated on the longest gap-free run) is for the noise fit.
    """
    spec = parse_spec(sensor_filter)
    a, b = longest
    filters, reports, notes = {}, {}, []
    for c, name in enumerate(names):
        rep = spikes.detect(data[:, c], dt)
        if rep.count and despike:
            data[:, c] = spikes.remove(data[:, c], rep.index)
            rep.removed = True
        if rep.count:
            notes.append(spikes.note(name, rep, RATE_UNITS[sensor_kind(name)]))
        reports[name] = rep
        choice = resolve(spec, data[a:b, c], dt)
        if choice.note:
            notes.append(f'allan: {name}: sensor filter {choice.note}')
        filters[name] = choice
    return filters, reports, notes


def compute(rec: Recording, channels: Optional[Sequence[str]] = None,
            taus: Optional[Sequence[float]] = None, m_max: Optional[int] = None,
            points_per_octave: int = POINTS_PER_OCTAVE, sensor_filter='none',
            despike: bool = False) -> AllanResult:
    """
    Return the overlapping Allan variance of ``rec`` with 68 % intervals.

    Noise type for the EDF: lag-1 ACF where the m-averaged series has >= 30 points, the local
    log-log slope of the curve beyond.

    Grid: the paper's (optionally capped at ``m_max``) or the user's ``taus`` (s). Spikes are
    always looked for and noted; ``despike`` replaces them. ``sensor_filter`` (a spec of
    ``gyro_char.allan.sensor_filter``) is resolved per channel for the noise fit.
    """
    source = rec.source or 'recording'
    names = list(channels) if channels else default_channels(rec)
    if not names:
        raise InputError(f'{source}: no gyro_* or accel_* channels')
    missing = [c for c in names if c not in rec.channels]
    if missing:
        raise InputError(f'{source}: no channel(s) {missing}; present: {sorted(rec.channels)}')
    dt, segs, notes = uniform_segments(rec.t, source)
    data = np.empty((rec.t.size, len(names)), order='F')  # channels contiguous, as the kernel
    for c, name in enumerate(names):
        data[:, c] = rec.channels[name]
    if not np.all(np.isfinite(data)):
        raise InputError(f'{source}: NaN/Inf samples reached the Allan variance')
    const = [c for c, col in zip(names, data.T) if np.ptp(col) == 0.0]
    if const:
        raise InputError(f'{source}: channel(s) {const} are constant: no noise to analyse '
                         '(choose others with --channels)')
    longest = max(b - a for a, b in segs)
    if longest < MIN_SAMPLES:
        raise InputError(f'{source}: longest gap-free run is {longest} samples; the Allan '
                         f'variance needs at least {MIN_SAMPLES}')
    m = (m_grid(longest, points_per_octave, m_max) if taus is None
         else taus_to_m(taus, dt, longest))
    a, b = max(segs, key=lambda s: s[1] - s[0])
    filters, reports, screen_notes = screen(data, names, dt, (a, b), sensor_filter, despike)
    x_long = phase(data[a:b], dt)  # shared by the sums and the noise identification
    parts = [allan_sums(data[s0:s1], dt, m, names, x=x_long if (s0, s1) == (a, b) else None)
             for s0, s1 in segs if s1 - s0 >= 2]
    sums = pool(parts)
    sums.notes = list(rec.notes) + notes + screen_notes
    res = sums.result()
    res.sensor_filters, res.spikes = filters, reports
    alpha = alpha_from_acf(data[a:b], res.m, beyond=alpha_from_slope(res.tau, res.avar),
                           csum=x_long)
    return add_confidence(res, alpha)
