"""
The input-health status a node publishes on /diagnostics, as a plain rclpy-free object.

A node lists what it watches (its ``StreamHealth`` objects and its own counters) and gets back
one (level, message, values) triple. Counters are judged by their growth since the last report,
so a status returns to OK once the input is clean again; ``reset`` forgets the last report.
"""
from typing import Any, Dict, Iterable, List, Optional, Tuple

from gyro_char.live.stream_health import StreamHealth

# DiagnosticStatus levels (the message's own byte values).
OK, WARN, ERROR = 0, 1, 2


class InputStatus:
    """Problems and values of one status report, with counters compared to the last report."""

    def __init__(self) -> None:
        self._last: Dict[str, Any] = {}
        self.problems: List[str] = []
        self.values: Dict[str, Any] = {}
        self.level = OK

    def reset(self) -> None:
        """Forget the last report (after a node's ``~/reset``)."""
        self._last = {}

    def begin(self) -> 'InputStatus':
        """Start a new report."""
        self.problems, self.values, self.level = [], {}, OK
        return self

    def streams(self, healths: Iterable[StreamHealth], now: float,
                stall_timeout_s: float) -> None:
        """Add each stream's counters and its problems since the last report."""
        for h in healths:
            self.problems += h.problems(now, stall_timeout_s, self._last.get(h.name))
            self._last[h.name] = h.as_dict()
            self.values.update(self._last[h.name])
        if self.problems:
            self.level = max(self.level, WARN)

    def grew(self, key: str, count: float) -> float:
        """Return how much counter ``key`` grew since the last report (and remember it)."""
        growth = count - self._last.get(key, 0)
        self._last[key] = count
        return growth

    def warn(self, problem: str) -> None:
        """Add a problem at WARN level."""
        self.problems.append(problem)
        self.level = max(self.level, WARN)

    def error(self, problem: Optional[str] = None) -> None:
        """Raise the level to ERROR (with an optional problem)."""
        if problem:
            self.problems.append(problem)
        self.level = ERROR

    def result(self) -> Tuple[int, str, Dict[str, Any]]:
        """Return (level, message, values) of this report."""
        return self.level, '; '.join(self.problems) if self.problems else 'ok', self.values
