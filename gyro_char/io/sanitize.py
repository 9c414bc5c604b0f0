"""
Stamp and value hygiene shared by every command, each treatment counted in ``Recording.notes``.

What is done: out-of-order stamps are sorted, repeated stamps keep their first sample, rows with a
NaN/Inf stamp or value are dropped. What is only reported: long gaps, a sample-rate change
mid-record, gyro rates that look like deg/s and accelerations that look like g. Nothing is
resampled or filled: what a gap means is the estimator's call (see ``segments``).
"""
from typing import List, Tuple

from gyro_char.errors import InputError
from gyro_char.records import DEFAULT_GAP_FACTOR, GYRO_CHANNELS, Recording
import numpy as np

# |rate| this large (about 2000 deg/s) is beyond nearly every MEMS and optical gyro's range, so a
# record reaching it is more likely deg/s written into a rad/s field
DEG_S_SUSPECT_RAD_S = 35.0
# a block's median interval differing by this fraction from the record's counts as a rate change
RATE_CHANGE_TOL = 0.1
RATE_BLOCKS = 20


def sanitize(rec: Recording, max_gap_factor: float = DEFAULT_GAP_FACTOR) -> Recording:
    """Return a cleaned copy of ``rec`` with counted treatments appended to its notes."""
    src = rec.source or 'recording'
    notes = list(rec.notes)
    t = rec.t
    names = list(rec.channels)
    values = [rec.channels[k] for k in names]
    if t.size == 0:
        raise InputError(f'{src}: no samples')
    # a finite sum proves every term finite: the per-sample mask is built only when needed
    if not all(np.isfinite(np.sum(x)) for x in [t] + values):
        finite = np.isfinite(t)
        for v in values:
            finite &= np.isfinite(v)
        bad = int(t.size - np.count_nonzero(finite))
        if bad:
            notes.append(f'{bad} sample(s) with NaN/Inf stamp or value dropped')
            t = t[finite]
            values = [v[finite] for v in values]
    if t.size == 0:
        raise InputError(f'{src}: every sample has a NaN/Inf stamp or value')
    dt = np.diff(t)
    backwards = int(np.count_nonzero(dt < 0))
    if backwards:
        order = np.argsort(t, kind='stable')
        t = t[order]
        values = [v[order] for v in values]
        notes.append(f'{backwards} out-of-order stamp(s): samples sorted by stamp')
        dt = np.diff(t)
    repeated = dt == 0
    dups = int(np.count_nonzero(repeated))
    if dups:
        keep = np.ones(t.size, dtype=bool)
        keep[1:] = ~repeated
        notes.append(f'{dups} sample(s) with a repeated stamp dropped (first kept)')
        t = t[keep]
        values = [v[keep] for v in values]
        dt = np.diff(t)
    out = Recording(t, dict(zip(names, values)), source=rec.source, notes=notes)
    if t.size > 2:
        _report_timing(out, dt, max_gap_factor)
    _report_units(out)
    return out


def _report_timing(rec: Recording, dt: np.ndarray, max_gap_factor: float) -> None:
    step = float(np.median(dt))
    gaps = dt > max_gap_factor * step
    n_gaps = int(np.count_nonzero(gaps))
    if n_gaps:
        rec.notes.append(
            f'{n_gaps} gap(s) longer than {max_gap_factor:g} x the median interval '
            f'({step:.6g} s), {float(np.sum(dt[gaps])):.6g} s in total, longest '
            f'{float(np.max(dt[gaps])):.6g} s; not filled')
    if dt.size >= 4 * RATE_BLOCKS:
        blocks = np.array_split(dt[~gaps], RATE_BLOCKS)
        med = np.array([np.median(b) for b in blocks if b.size])
        off = np.abs(med / step - 1.0) > RATE_CHANGE_TOL
        if np.any(off):
            rec.notes.append(
                f'sample rate changes within the record: block median intervals range '
                f'{med.min():.6g}..{med.max():.6g} s (overall {step:.6g} s)')


def _report_units(rec: Recording) -> None:
    for name in GYRO_CHANNELS:
        v = rec.channels.get(name)
        # the max first: the percentile (a partition) is only needed when the max is large
        if v is None or not v.size or max(float(v.max()), -float(v.min())) <= DEG_S_SUSPECT_RAD_S:
            continue
        if float(np.percentile(np.abs(v), 99.9)) > DEG_S_SUSPECT_RAD_S:
            rec.notes.append(
                f'warning: {name} reaches {float(np.max(np.abs(v))):.4g} rad/s: looks like deg/s '
                f'in a rad/s field (values kept as given)')
    accel = [rec.channels.get(f'accel_{a}') for a in 'xyz']
    if all(a is not None and a.size for a in accel):
        step = max(1, accel[0].size // 100_000)  # a heuristic: a subsample is plenty
        g = float(np.median(np.hypot(np.hypot(accel[0][::step], accel[1][::step]),
                                     accel[2][::step])))
        if 0.5 < g < 2.0:
            rec.notes.append(f'warning: median |accel| is {g:.4g} m/s^2: looks like g in a m/s^2 '
                             f'field (values kept as given)')


def segments(rec: Recording, max_gap_factor: float = DEFAULT_GAP_FACTOR
             ) -> List[Tuple[int, int]]:
    """
    Return contiguous runs as ``[(start, stop), ...]`` index slices (stop exclusive).

    A run ends where the interval exceeds ``max_gap_factor`` x the median interval.
    """
    n = len(rec)
    if n < 3:
        return [(0, n)] if n else []
    dt = np.diff(rec.t)
    cuts = np.flatnonzero(dt > max_gap_factor * float(np.median(dt))) + 1
    bounds = np.concatenate(([0], cuts, [n]))
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]
