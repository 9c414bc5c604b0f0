"""
Health of one live sample stream: what was refused, what looked wrong, what is late.

Two layers, so that the per-message cost stays O(1):

- ``StreamHealth.admit`` runs once per message (a few comparisons) and refuses messages that
  cannot be used at all: zero stamps, stamps that go backwards or repeat, a wrong frame, and
  floods (more messages per wall-clock second than ``max_rate_hz``).
- ``StreamHealth.observe_chunk`` runs on the node's processing timer with numpy arrays of the
  admitted stamps: it counts non-finite values, gaps (a step longer than ``gap_factor`` nominal
  intervals) and sustained rate changes, and tracks the stamp-to-receive-time offset that
  ``stream_skew_s`` compares between two streams.

Nothing here raises on bad input: every refusal is counted and the counters are reported
(``as_dict``) in the node's diagnostics.
"""
import math
from typing import Dict, List, Optional

import numpy as np

ACCEPT = 0
DROP = 1
# The stream's stamps jumped back and stayed back (a publisher restarted, a bag looped): the
# message is accepted and the consumer must treat it as the start of a new segment.
RESTART = 2


class StreamHealth:
    """Admission checks and counters for one stream of stamped samples."""

    def __init__(self, name: str, frame_id: str = '', max_rate_hz: float = 0.0,
                 gap_factor: float = 3.0, rate_tolerance: float = 0.1,
                 restart_after: int = 200, rate_window: int = 200) -> None:
        self.name = name
        self.frame_id = frame_id
        self.max_rate_hz = max_rate_hz
        self.gap_factor = gap_factor
        self.rate_tolerance = rate_tolerance
        self.restart_after = restart_after
        self.rate_window = rate_window
        self.reset()

    def reset(self) -> None:
        """Forget everything (counters, nominal rate, last stamp)."""
        self.received = 0
        self.accepted = 0
        self.zero_stamp = 0
        self.backwards = 0
        self.duplicate = 0
        self.wrong_frame = 0
        self.flood_dropped = 0
        self.non_finite = 0
        self.gaps = 0
        self.gap_time_s = 0.0
        self.restarts = 0
        self.rate_changes = 0
        self.last_stamp = -math.inf
        self.last_receive = None
        self.dt_nominal: Optional[float] = None
        self.dt_recent: Optional[float] = None
        self.offset_s: Optional[float] = None
        self._backwards_run = 0
        self._window_start = -math.inf
        self._window_count = 0
        self._pending_dt = []
        self._pending_n = 0
        self._off_rate = 0

    # -- per message -------------------------------------------------------------------------

    def admit(self, stamp: float, receive_time: float, frame_id: str = '') -> int:
        """
        Decide for one message: ``ACCEPT``, ``DROP`` or ``RESTART`` (accept, new segment).

        ``receive_time`` is the local wall clock (s) when the message arrived; it drives the
        flood limit and the stall check.
        """
        self.received += 1
        self.last_receive = receive_time
        if self.max_rate_hz > 0.0:
            if receive_time - self._window_start >= 1.0:
                self._window_start = receive_time
                self._window_count = 0
            self._window_count += 1
            if self._window_count > self.max_rate_hz:
                self.flood_dropped += 1
                return DROP
        if self.frame_id and frame_id != self.frame_id:
            self.wrong_frame += 1
            return DROP
        if stamp <= 0.0 or stamp != stamp:
            self.zero_stamp += 1
            return DROP
        if stamp <= self.last_stamp:
            if stamp == self.last_stamp:
                self.duplicate += 1
                return DROP
            self.backwards += 1
            self._backwards_run += 1
            if self._backwards_run < self.restart_after:
                return DROP
            # Consistently behind for restart_after messages: the source restarted. This one
            # is accepted, so it is not a dropped backwards stamp.
            self.backwards -= 1
            self.restarts += 1
            self._backwards_run = 0
            self.last_stamp = stamp
            self.accepted += 1
            return RESTART
        self._backwards_run = 0
        self.last_stamp = stamp
        self.accepted += 1
        return ACCEPT

    # -- per chunk ---------------------------------------------------------------------------

    def count_non_finite(self, n: int) -> None:
        """Count samples the consumer dropped because a value was NaN or infinite."""
        self.non_finite += int(n)

    def observe_chunk(self, t: np.ndarray, receive: Optional[np.ndarray] = None,
                      previous_stamp: Optional[float] = None) -> np.ndarray:
        """
        Check one chunk of admitted stamps; return the indices ``i`` where a gap ends.

        A gap ends at ``t[i]`` when ``t[i] - t[i-1]`` (or ``t[0] - previous_stamp``) exceeds
        ``gap_factor`` nominal intervals. The nominal interval is the median of the first
        ``rate_window`` intervals; a new rate is adopted (and counted in ``rate_changes``) after
        ``rate_window`` intervals in a row whose median differs by more than
        ``rate_tolerance`` (relative).
        """
        t = np.asarray(t, dtype=np.float64)
        if receive is not None and t.size:
            off = float(np.median(np.asarray(receive) - t))
            self.offset_s = off if self.offset_s is None else 0.8 * self.offset_s + 0.2 * off
        if t.size == 0:
            return np.zeros(0, dtype=np.intp)
        if previous_stamp is not None and math.isfinite(previous_stamp):
            steps = np.diff(t, prepend=previous_stamp)
            offset = 0
        else:
            steps = np.diff(t)
            offset = 1
        gap_idx = np.zeros(0, dtype=np.intp)
        if self.dt_nominal is not None and steps.size:
            is_gap = steps > self.gap_factor * self.dt_nominal
            gap_idx = np.flatnonzero(is_gap) + offset
            self.gaps += int(gap_idx.size)
            self.gap_time_s += float(np.sum(steps[is_gap]))
            self._collect_rate(steps[~is_gap])
        else:
            self._collect_rate(steps)
        return gap_idx

    def _collect_rate(self, steps: np.ndarray) -> None:
        steps = steps[steps > 0]
        if steps.size == 0:
            return
        self._pending_dt.append(steps)
        self._pending_n += steps.size
        if self._pending_n < self.rate_window:
            return
        dt = float(np.median(np.concatenate(self._pending_dt)))
        self._pending_dt, self._pending_n = [], 0
        self.dt_recent = dt
        if self.dt_nominal is None:
            self.dt_nominal = dt
            return
        if abs(dt - self.dt_nominal) > self.rate_tolerance * self.dt_nominal:
            self._off_rate += 1
            # Two windows in a row off the nominal rate: the sensor really changed its rate.
            if self._off_rate >= 2:
                self.rate_changes += 1
                self.dt_nominal = dt
                self._off_rate = 0
        else:
            self._off_rate = 0

    # -- status ------------------------------------------------------------------------------

    def rate_changed_since(self, count: int) -> bool:
        """Return True when ``rate_changes`` grew past ``count`` (a snapshot taken earlier)."""
        return self.rate_changes > count

    def stalled(self, now: float, timeout_s: float) -> bool:
        """Return True when the stream delivered before but nothing for ``timeout_s`` seconds."""
        return self.last_receive is not None and now - self.last_receive > timeout_s

    @property
    def dropped(self) -> int:
        """All messages refused by ``admit`` or later for a non-finite value."""
        return self.received - self.accepted + self.non_finite

    def as_dict(self) -> Dict[str, float]:
        """Counters for diagnostics; keys carry the unit where there is one."""
        p = self.name + '_'
        out = {
            p + 'received': self.received,
            p + 'accepted': self.accepted - self.non_finite,
            p + 'dropped_zero_stamp': self.zero_stamp,
            p + 'dropped_backwards': self.backwards,
            p + 'dropped_duplicate': self.duplicate,
            p + 'dropped_wrong_frame': self.wrong_frame,
            p + 'dropped_flood': self.flood_dropped,
            p + 'dropped_non_finite': self.non_finite,
            p + 'stamp_restarts': self.restarts,
            p + 'gaps': self.gaps,
            p + 'gap_time_s': self.gap_time_s,
            p + 'rate_changes': self.rate_changes,
        }
        if self.dt_nominal:
            out[p + 'rate_hz'] = 1.0 / self.dt_nominal
        return out

    def problems(self, now: float, stall_timeout_s: float,
                 previous: Optional[Dict[str, float]] = None) -> List[str]:
        """
        List the problems in words (empty when healthy).

        With ``previous`` (an earlier ``as_dict()``), only counters that grew since then are
        reported, so that a diagnostics status returns to OK once the input is clean again.
        """
        now_counts = self.as_dict()
        p = self.name + '_'

        def grew(key: str) -> float:
            before = previous.get(p + key, 0) if previous else 0
            return now_counts[p + key] - before

        out = []
        if self.last_receive is None:
            out.append(f'no {self.name} data yet')
        elif self.stalled(now, stall_timeout_s):
            out.append(f'{self.name} stalled for {now - self.last_receive:.1f} s')
        labels = [
            ('dropped_backwards', 'stamps went backwards'),
            ('dropped_duplicate', 'repeated stamps'),
            ('dropped_zero_stamp', 'zero stamps'),
            ('dropped_wrong_frame', f'messages from a frame other than {self.frame_id!r}'),
            ('dropped_flood', f'dropped in floods (> {self.max_rate_hz:g}/s)'),
            ('dropped_non_finite', 'non-finite samples'),
            ('gaps', 'stamp gaps'),
            ('rate_changes', 'rate changes'),
            ('stamp_restarts', 'stamp restarts'),
        ]
        for key, label in labels:
            n = grew(key)
            if n:
                out.append(f'{self.name}: {int(n)} {label}')
        return out


def stream_skew_s(a: StreamHealth, b: StreamHealth) -> Optional[float]:
    """
    Return how far apart two streams are in time (s), or None before both have data.

    Each stream's offset is the smoothed median of (receive time - header stamp). If both are
    stamped on one clock with similar latency the difference is ~0; a constant difference means
    the stamps come from different clocks, a growing one that the clocks drift apart. Either way
    the core cannot align them.
    """
    if a.offset_s is None or b.offset_s is None:
        return None
    return a.offset_s - b.offset_s
