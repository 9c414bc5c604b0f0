"""
A live static record: stamped IMU chunks in, Allan variance of everything so far out.

The stamp rules are those of the batch path (``gyro_char.allan.compute``), applied as the data
arrive, over the streaming ``AllanAccumulator``:

- dt is the median interval of the first ``probe`` samples (or ``1 / rate_hz`` when given).
- A step longer than ``gap_factor`` dt (missing samples, a dropped NaN row, a node restart)
  closes the current contiguous segment; its sums are pooled with the next segments' (sum of
  sums, sum of counts), so no second difference ever spans a gap.
- A chunk whose median interval is off dt by more than ``rate_tolerance`` (the sensor changed
  its rate) is not accumulated: it is counted and reported, and the Allan variance keeps the
  data at the original rate. ``reset()`` starts over (at the new rate).
- Rows with NaN/Inf and stamps that do not advance past the last one are dropped and counted.

Samples are staged and fed to the accumulator ``feed_chunk`` at a time, because each
``AllanAccumulator.add`` costs O(m_max) whatever the chunk size. A ``MotionDetector`` watches
the same samples. Memory is bounded: the accumulator's tail (2 m_max + 1 rows), the pooled sums
(K x channels), the staged chunk and the detector's short history. A long-running process
should call ``return_freed_memory()`` once (the node does) so that the accumulator's tail-sized
temporaries do not stay resident between adds.
"""
import ctypes
import ctypes.util
import math
from typing import Any, Dict, List, Optional, Sequence

from gyro_char.allan.compute import GAP_FACTOR, RATE_CHANGE_TOL
from gyro_char.allan.edf import add_confidence, alpha_from_slope
from gyro_char.allan.kernel import AllanResult, AllanSums, pool
from gyro_char.allan.stream import AllanAccumulator
from gyro_char.errors import InputError
from gyro_char.live.motion_detect import MotionDetector
from gyro_char.records import IMU_CHANNELS
import numpy as np

STATE_VERSION = 1
COUNTERS = ('non_finite', 'stale', 'gaps', 'off_rate_samples', 'off_rate_chunks',
            'short_steps', 'segments')

M_TRIM_THRESHOLD = -1  # glibc mallopt parameters (malloc.h)
M_MMAP_THRESHOLD = -3


def return_freed_memory(threshold: int = 1 << 20) -> bool:
    """
    Make the C allocator give large freed buffers back to the OS (glibc; no-op elsewhere).

    Each ``AllanAccumulator.add`` allocates and frees temporaries the size of its tail (2 m_max
    x channels float64: 25 MB at m_max 2^18 x 6). glibc raises its mmap threshold when the
    first such buffer is freed, so later ones come from the heap, whose high-water mark stays
    resident: about 75 MB that is used only during an add. A fixed ``threshold`` for mmap and
    for trimming keeps every large temporary an mmap, unmapped when freed (the cost: page
    faults on each add, ~20 % of the feed time at 1 kHz, still hundreds of times real time).
    Returns whether both settings were applied.
    """
    name = ctypes.util.find_library('c')
    try:
        mallopt = ctypes.CDLL(name).mallopt
    except (OSError, AttributeError, TypeError):
        return False
    return (mallopt(M_MMAP_THRESHOLD, int(threshold)) == 1
            and mallopt(M_TRIM_THRESHOLD, int(threshold)) == 1)


class AllanLive:
    """Segmented streaming Allan variance of ``channels`` with stamp checks and motion."""

    def __init__(self, channels: Sequence[str] = IMU_CHANNELS, rate_hz: float = 0.0,
                 m_max: int = 2 ** 18, feed_chunk: int = 2000, gap_factor: float = GAP_FACTOR,
                 rate_tolerance: float = RATE_CHANGE_TOL, probe: int = 200,
                 motion: Optional[Dict[str, Any]] = None) -> None:
        self.channels = tuple(channels)
        self.rate_hz = float(rate_hz)
        self.m_max = int(m_max)
        self.feed_chunk = int(feed_chunk)
        self.gap_factor = float(gap_factor)
        self.rate_tolerance = float(rate_tolerance)
        self.probe = int(probe)
        self.motion_args = dict(motion or {})
        self.reset()

    def reset(self) -> None:
        """Forget all data, counters and the sample interval."""
        self.dt: Optional[float] = 1.0 / self.rate_hz if self.rate_hz > 0 else None
        self.acc: Optional[AllanAccumulator] = None
        self.pooled: Optional[AllanSums] = None
        self.motion: Optional[MotionDetector] = None
        self.last_t = -math.inf
        self.first_t = math.nan
        self.gap_time_s = 0.0
        self.off_rate_hz = math.nan
        for name in COUNTERS:
            setattr(self, name, 0)
        self._staged_t: List[np.ndarray] = []
        self._staged_x: List[np.ndarray] = []
        self._staged = 0
        self._probe_t: List[np.ndarray] = []
        self._probe_x: List[np.ndarray] = []
        if self.dt is not None:
            self._start_motion()

    def _start_motion(self) -> None:
        self.motion = MotionDetector(self.dt, n_channels=len(self.channels), **self.motion_args)

    # -- input ---------------------------------------------------------------------------------

    def add(self, t, x) -> None:
        """Add stamps ``t`` (k,) in s and samples ``x`` (k, channels) in SI units."""
        t = np.asarray(t, dtype=np.float64).ravel()
        x = np.asarray(x, dtype=np.float64).reshape(t.size, len(self.channels))
        ok = np.isfinite(x).all(axis=1) & np.isfinite(t)
        self.non_finite += int(t.size - np.count_nonzero(ok))
        t, x = t[ok], x[ok]
        prev = np.maximum.accumulate(np.concatenate([[self.last_t], t]))[:-1]
        fresh = t > prev
        self.stale += int(t.size - np.count_nonzero(fresh))
        t, x = t[fresh], x[fresh]
        if t.size == 0:
            return
        if self.dt is None:
            self._probe_t.append(t)
            self._probe_x.append(x)
            self.last_t = float(t[-1])
            if sum(p.size for p in self._probe_t) <= self.probe:
                return
            t, x = np.concatenate(self._probe_t), np.concatenate(self._probe_x)
            self._probe_t, self._probe_x = [], []
            self.dt = float(np.median(np.diff(t)))
            self._start_motion()
            self.last_t = -math.inf
        self._ingest(t, x)

    def _ingest(self, t: np.ndarray, x: np.ndarray) -> None:
        dt = self.dt
        first = math.isinf(self.last_t)
        steps = np.diff(t, prepend=t[0] - dt if first else self.last_t)
        if math.isnan(self.first_t):
            self.first_t = float(t[0])
        inner = steps[1:]
        if inner.size >= 5:
            med = float(np.median(inner))
            if abs(med / dt - 1.0) > self.rate_tolerance:
                self.off_rate_samples += int(t.size)
                self.off_rate_chunks += 1
                self.off_rate_hz = 1.0 / med
                self._close_segment()
                self.last_t = float(t[-1])
                return
        self.short_steps += int(np.count_nonzero(steps < 0.5 * dt))
        cuts = np.flatnonzero(steps > self.gap_factor * dt)
        bounds = np.unique(np.concatenate([[0], cuts, [t.size]]))
        for a, b in zip(bounds[:-1], bounds[1:]):
            if a in cuts:
                self.gaps += 1
                self.gap_time_s += float(steps[a] - dt)
                self._close_segment()
                self.motion.break_stream()
            if b > a:
                self._stage(t[a:b], x[a:b])
        self.last_t = float(t[-1])
        if self._staged >= self.feed_chunk:
            self.flush()

    def _stage(self, t: np.ndarray, x: np.ndarray) -> None:
        self._staged_t.append(t)
        self._staged_x.append(x)
        self._staged += t.size
        self.motion.add(t, x)

    def flush(self) -> None:
        """Feed the staged samples to the accumulator (done automatically every chunk)."""
        if not self._staged:
            return
        x = np.concatenate(self._staged_x)
        self._staged_t, self._staged_x, self._staged = [], [], 0
        if self.acc is None:
            self.acc = AllanAccumulator(self.dt, len(self.channels), self.m_max,
                                        channels=self.channels)
            self.segments += 1
        self.acc.add(x)

    def restart_stamps(self) -> None:
        """Start a new segment whose stamps may lie before the last ones (a source restart)."""
        self._close_segment()
        if self.motion is not None:
            self.motion.break_stream()
        self.last_t = -math.inf

    def _close_segment(self) -> None:
        self.flush()
        if self.acc is not None:
            part = self.acc.sums_view()
            self.pooled = part if self.pooled is None else pool([self.pooled, part])
            self.acc = None

    # -- output --------------------------------------------------------------------------------

    @property
    def n_samples(self) -> int:
        """Return the number of samples accumulated so far (including staged ones)."""
        done = (self.pooled.n_samples if self.pooled is not None else 0) + \
            (self.acc.n_samples if self.acc is not None else 0)
        return int(done + self._staged)

    def sums(self) -> Optional[AllanSums]:
        """Return the pooled sums of every segment so far (None before any data)."""
        self.flush()
        parts = [p for p in (self.pooled, self.acc.sums_view() if self.acc else None) if p]
        return pool(parts) if parts else None

    def result(self) -> AllanResult:
        """Return the Allan variance with 68 % intervals (``InputError`` until a tau has terms)."""
        sums = self.sums()
        if sums is None or not np.any(sums.counts):
            raise InputError(f'too few samples for any tau: {self.n_samples} so far')
        res = sums.result()
        res.notes = self.notes()
        return add_confidence(res, alpha_from_slope(res.tau, res.avar))

    def notes(self) -> List[str]:
        """List the counted treatments in words."""
        out = []
        if self.gaps:
            out.append(f'{self.gaps} stamp gaps ({self.gap_time_s:.6g} s missing): sums pooled '
                       f'over {self.segments} contiguous segments')
        if self.off_rate_samples:
            out.append(f'{self.off_rate_samples} samples at {self.off_rate_hz:.6g} Hz instead of '
                       f'{1.0 / self.dt:.6g} Hz not accumulated (reset to restart at the new '
                       'rate)')
        if self.non_finite:
            out.append(f'{self.non_finite} NaN/Inf samples dropped (each starts a new segment)')
        if self.stale:
            out.append(f'{self.stale} samples with stamps not after the previous one dropped')
        return out

    def summary(self) -> Dict[str, Any]:
        """Return the counters for diagnostics (SI units in the keys)."""
        out: Dict[str, Any] = {'samples': self.n_samples, 'segments': self.segments,
                               'gaps': self.gaps, 'gap_time_s': self.gap_time_s,
                               'dropped_non_finite': self.non_finite,
                               'dropped_stale': self.stale,
                               'off_rate_samples': self.off_rate_samples,
                               'short_steps': self.short_steps}
        if self.dt is not None:
            out['rate_hz'] = 1.0 / self.dt
            out['duration_s'] = self.n_samples * self.dt
        if self.off_rate_samples:
            out['off_rate_hz'] = self.off_rate_hz
        if math.isfinite(self.last_t):
            out['last_stamp_s'] = self.last_t
        if self.motion is not None:
            out.update(self.motion.summary())
        return out

    # -- checkpoints ---------------------------------------------------------------------------

    def state_dict(self) -> Dict[str, Any]:
        """Return what is needed to resume, as plain arrays (staged samples flushed first)."""
        self.flush()
        state: Dict[str, Any] = {
            'version': STATE_VERSION, 'channels': np.array(self.channels, dtype=str),
            'dt': np.nan if self.dt is None else self.dt, 'last_t': self.last_t,
            'first_t': self.first_t, 'gap_time_s': self.gap_time_s,
            'off_rate_hz': self.off_rate_hz, 'm_max': self.m_max}
        for name in COUNTERS:
            state[name] = getattr(self, name)
        if self.acc is not None:
            state['acc'] = self.acc.state_dict()
        if self.pooled is not None:
            state['pooled'] = {'m': self.pooled.m, 'sums': self.pooled.sums,
                               'counts': self.pooled.counts,
                               'n_samples': self.pooled.n_samples}
        if self.motion is not None:
            state['motion'] = self.motion.state_dict()
        return state

    def load_state(self, state: Dict[str, Any]) -> None:
        """Resume from ``state_dict()`` output; ``InputError`` if it belongs to another set-up."""
        if int(state['version']) != STATE_VERSION:
            raise InputError(f'live Allan state version {int(state["version"])} unsupported')
        channels = tuple(str(c) for c in np.asarray(state['channels']))
        if channels != self.channels or int(state['m_max']) != self.m_max:
            raise InputError(f'checkpoint is for channels {channels}, m_max '
                             f'{int(state["m_max"])}; this node has {self.channels}, '
                             f'm_max {self.m_max}')
        self.reset()
        dt = float(state['dt'])
        self.dt = None if math.isnan(dt) else dt
        if self.rate_hz > 0 and self.dt is not None and \
                abs(self.dt * self.rate_hz - 1.0) > self.rate_tolerance:
            raise InputError(f'checkpoint is at {1.0 / self.dt:.6g} Hz, not {self.rate_hz:g} Hz')
        self.last_t = float(state['last_t'])
        self.first_t = float(state['first_t'])
        self.gap_time_s = float(state['gap_time_s'])
        self.off_rate_hz = float(state['off_rate_hz'])
        for name in COUNTERS:
            setattr(self, name, int(state[name]))
        if 'acc' in state:
            self.acc = AllanAccumulator.from_state(state['acc'])
        if 'pooled' in state:
            p = state['pooled']
            self.pooled = AllanSums(dt=self.dt, m=np.asarray(p['m']), sums=np.asarray(p['sums']),
                                    counts=np.asarray(p['counts']), channels=self.channels,
                                    n_samples=int(p['n_samples']))
        if self.dt is not None:
            self._start_motion()
            if 'motion' in state:
                self.motion.load_state(state['motion'])
