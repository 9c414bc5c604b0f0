"""Wall-clock timing shared by the benchmarks: best of N runs (the least disturbed one)."""
import time
from typing import Any, Callable, Tuple


def best_of(fn: Callable[[], Any], repeat: int = 1) -> Tuple[float, Any]:
    """Run ``fn`` ``repeat`` times; return (the shortest wall time in s, the last result)."""
    best, out = float('inf'), None
    for _ in range(max(1, int(repeat))):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out
