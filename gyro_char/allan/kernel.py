"""
Fully overlapping Allan variance of rate samples on the paper's log-spaced tau grid.

For rate samples y_1..y_L at interval dt the phase (angle) is x_0 = 0,
x_j = dt * sum_{i<=j} (y_i - mean(y)) (mean removed before the cumulative sum so that the
phase stays small on multi-hour records), and for tau = m dt

    sigma^2(tau) = S(m) / (2 tau^2 (L + 1 - 2m)),  S(m) = sum_j (x_{j+2m} - 2 x_{j+m} + x_j)^2

which is docs/method.md's formula with the inner sums of angle increments written as phase
differences. ``S(m)`` and the term count are kept separately (``AllanSums``) so that records
with gaps (pooled over contiguous segments) and the streaming accumulator produce the same
result type as the batch path.

The kernel is compiled (numba, fused subtract/square/sum) and tiled: all m are summed over
one cache-sized block of the phase before the next block; channels run in threads. If numba
is missing, a numpy path gives the same numbers about 10x slower.
"""
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
import os
from typing import Dict, List, Optional, Sequence, Tuple

from gyro_char.errors import InputError
import numpy as np

try:  # numba: ~10x faster fused kernel; optional so that the core still runs without it.
    import numba
except ImportError:  # pragma: no cover - exercised only where numba is absent
    numba = None

POINTS_PER_OCTAVE = 10  # the paper's 2^(0.1 k)
TILE = 4096  # phase points per tile of the compiled kernel (32 KB per stream)
PARALLEL_MIN = 200_000  # samples per channel above which channels are summed in threads


def m_grid(n: int, points_per_octave: int = POINTS_PER_OCTAVE,
           m_max: Optional[int] = None) -> np.ndarray:
    """
    Return the paper's averaging factors m_k = [2^(k/10)], duplicates collapsed, m <= n/2.

    ``n`` is the number of rate samples L; k = 0..NK with NK = 10 [log2(L/2)] (docs/method.md), and
    optionally m <= ``m_max``.
    """
    n = int(n)
    if n < 2:
        raise InputError(f'Allan variance needs at least 2 samples, got {n}')
    nk = points_per_octave * int(np.floor(np.log2(n / 2.0)))
    m = np.unique(np.floor(2.0 ** (np.arange(nk + 1) / points_per_octave)).astype(np.int64))
    m = m[m <= n // 2]
    if m_max is not None:
        m = m[m <= int(m_max)]
    return m


def tau_grid(dt: float, n: int, points_per_octave: int = POINTS_PER_OCTAVE,
             m_max: Optional[int] = None) -> np.ndarray:
    """Return the paper's tau grid tau_k = dt [2^(0.1 k)] in seconds (see ``m_grid``)."""
    return dt * m_grid(n, points_per_octave, m_max)


def taus_to_m(taus: Sequence[float], dt: float, n: int) -> np.ndarray:
    """
    Return averaging factors for a user tau list (s): rounded to multiples of dt, collapsed.

    Raises InputError when a tau is not positive or needs more samples than the record has
    (tau = m dt needs at least 2m samples).
    """
    taus = np.atleast_1d(np.asarray(taus, dtype=np.float64))
    if taus.size == 0 or not np.all(np.isfinite(taus)) or np.any(taus <= 0):
        raise InputError('tau values must be finite and > 0')
    m = np.unique(np.maximum(1, np.round(taus / dt)).astype(np.int64))
    too_long = m[2 * m > n]
    if too_long.size:
        raise InputError(
            f'too few samples for tau = {too_long[0] * dt:g} s: it needs at least '
            f'{2 * too_long[0]} samples at dt = {dt:g} s, the record has {n}')
    return m


def phase(rate: np.ndarray, dt: float) -> np.ndarray:
    """
    Return x_0 = 0, x_j = dt * cumsum(rate - mean) along axis 0 (length n + 1).

    Column-major (each channel's phase contiguous, as the kernel reads it); a column-major
    ``rate`` is read without strides.
    """
    rate = np.asarray(rate, dtype=np.float64)
    x = np.zeros((rate.shape[0] + 1,) + rate.shape[1:], order='F')
    if rate.ndim == 1:
        np.cumsum((rate - rate.mean()) * dt, out=x[1:])
        return x
    for c in range(rate.shape[1]):
        col = rate[:, c]
        np.cumsum((col - col.mean()) * dt, out=x[1:, c])
    return x


def _second_difference_sums_numpy(x: np.ndarray, m: np.ndarray) -> np.ndarray:
    out = np.empty(m.size)
    for j, mm in enumerate(m):
        nt = x.size - 2 * mm
        v = x[2 * mm:] - 2.0 * x[mm:mm + nt]
        v += x[:nt]
        out[j] = np.dot(v, v)
    return out


if numba is not None:
    @numba.njit(cache=True, fastmath=True, nogil=True)
    def _ssq(a, b, c):  # pragma: no cover - compiled
        s = 0.0
        for i in range(a.size):
            v = a[i] - 2.0 * b[i] + c[i]
            s += v * v
        return s

    @numba.njit(cache=True, nogil=True)
    def _second_difference_sums_numba(x, m):  # pragma: no cover - compiled
        # Tiled over j: every m is summed over one TILE of indices before moving on, so the
        # three streams x[j], x[j+m], x[j+2m] of a tile stay in L1/L2 across all m (for small
        # m they overlap) instead of streaming the whole phase from memory once per m: 1.5x.
        out = np.zeros(m.size)
        for j0 in range(0, x.size, TILE):
            for j in range(m.size):
                mm = m[j]
                j1 = min(j0 + TILE, x.size - 2 * mm)
                if j1 > j0:
                    # Separate views let LLVM vectorise the fused loop (no aliasing).
                    out[j] += _ssq(x[j0 + 2 * mm:j1 + 2 * mm], x[j0 + mm:j1 + mm], x[j0:j1])
        return out


def second_difference_sums(x: np.ndarray, m: np.ndarray, use_numba: bool = True) -> np.ndarray:
    """Return S(m) = sum_j (x_{j+2m} - 2 x_{j+m} + x_j)^2 for one phase series ``x``."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    m = np.ascontiguousarray(m, dtype=np.int64)
    if m.size and 2 * m.max() >= x.size:
        raise InputError(f'm = {m.max()} needs {2 * m.max() + 1} phase points, have {x.size}')
    if use_numba and numba is not None:
        return _second_difference_sums_numba(x, m)
    return _second_difference_sums_numpy(x, m)


@dataclass
class AllanSums:
    """
    Raw accumulated Allan sums; ``sums[k, c]`` is S(m_k) of channel c over ``counts[k]`` terms.

    ``n_samples`` is the number of rate samples that went in (over all segments).
    """

    dt: float
    m: np.ndarray
    sums: np.ndarray
    counts: np.ndarray
    channels: Tuple[str, ...]
    n_samples: int
    notes: List[str] = field(default_factory=list)

    def result(self) -> 'AllanResult':
        """Return the Allan variance for every m with at least one term."""
        ok = self.counts > 0
        m = self.m[ok]
        tau = m * self.dt
        avar = self.sums[ok] / (2.0 * (tau ** 2)[:, None] * self.counts[ok][:, None])
        return AllanResult(dt=self.dt, m=m, tau=tau, avar=avar, counts=self.counts[ok],
                           channels=self.channels, n_samples=self.n_samples,
                           notes=list(self.notes))


@dataclass
class AllanResult:
    """
    Overlapping Allan variance per tau (rows) and channel (columns), in (channel unit)^2.

    ``counts[k]`` is the number of overlapping terms at tau_k (L + 1 - 2m for one segment);
    ``edf`` / ``alpha`` (equivalent degrees of freedom and the power-law noise exponent used
    for it) are filled by ``gyro_char.allan.edf.add_confidence``.
    """

    dt: float
    m: np.ndarray
    tau: np.ndarray
    avar: np.ndarray
    counts: np.ndarray
    channels: Tuple[str, ...]
    n_samples: int
    notes: List[str] = field(default_factory=list)
    edf: Optional[np.ndarray] = None
    alpha: Optional[np.ndarray] = None
    adev_lo: Optional[np.ndarray] = None
    adev_hi: Optional[np.ndarray] = None
    # per channel, filled by ``gyro_char.allan.compute.compute``: the sensor filter for the
    # noise fit (``sensor_filter.FilterChoice``) and the spikes found (``spikes.SpikeReport``)
    sensor_filters: Optional[dict] = None
    spikes: Optional[dict] = None

    @property
    def adev(self) -> np.ndarray:
        return np.sqrt(self.avar)

    def channel(self, name: str) -> Dict[str, np.ndarray]:
        """Return tau, avar, adev, lo/hi and edf of one channel as 1-D arrays."""
        c = self.channels.index(name)
        out = {'tau': self.tau, 'avar': self.avar[:, c], 'adev': self.adev[:, c]}
        for key in ('edf', 'alpha', 'adev_lo', 'adev_hi'):
            value = getattr(self, key)
            out[key] = None if value is None else value[:, c]
        return out


def _as_2d(rate) -> Tuple[np.ndarray, bool]:
    rate = np.asarray(rate, dtype=np.float64)
    if rate.ndim not in (1, 2):
        raise InputError(f'rate must be 1-D or (n, channels), got shape {rate.shape}')
    if not np.all(np.isfinite(rate)):
        bad = int(np.count_nonzero(~np.isfinite(rate)))
        raise InputError(f'{bad} NaN/Inf rate samples: Allan variance needs finite data '
                         '(the reader must drop or repair them first)')
    return (rate[:, None], True) if rate.ndim == 1 else (rate, False)


def allan_sums(rate, dt: float, m: np.ndarray, channels: Optional[Sequence[str]] = None,
               use_numba: bool = True, x: Optional[np.ndarray] = None) -> AllanSums:
    """
    Accumulate S(m) and counts of a uniformly sampled, gap-free (n,) or (n, C) array.

    ``x``: ``phase(rate, dt)`` (2-D) if the caller already has it (it is not recomputed).
    """
    rate2, _ = _as_2d(rate)
    n, nc = rate2.shape
    if not dt > 0 or not np.isfinite(dt):
        raise InputError(f'sample interval must be > 0, got {dt}')
    m = np.asarray(m, dtype=np.int64)
    x = phase(rate2, dt) if x is None else x
    sums = np.zeros((m.size, nc))
    ok = 2 * m <= n
    workers = min(nc, os.cpu_count() or 1) if use_numba and numba is not None else 1
    if workers > 1 and n >= PARALLEL_MIN:
        # The compiled kernel releases the GIL: channels run on all cores (one column each).
        with ThreadPoolExecutor(workers) as pool_:
            cols = list(pool_.map(lambda c: second_difference_sums(x[:, c], m[ok]), range(nc)))
    else:
        cols = [second_difference_sums(x[:, c], m[ok], use_numba) for c in range(nc)]
    for c, col in enumerate(cols):
        sums[ok, c] = col
    counts = np.where(ok, n + 1 - 2 * m, 0).astype(np.int64)
    names = tuple(channels) if channels is not None else tuple(f'ch{c}' for c in range(nc))
    return AllanSums(dt=float(dt), m=m, sums=sums, counts=counts, channels=names, n_samples=n)


def pool(parts: Sequence[AllanSums]) -> AllanSums:
    """Pool the sums of several segments on the same m grid (gaps between them)."""
    first = parts[0]
    sums = sum(p.sums for p in parts)
    counts = sum(p.counts for p in parts)
    notes = [note for p in parts for note in p.notes]
    return AllanSums(dt=first.dt, m=first.m, sums=sums, counts=counts, channels=first.channels,
                     n_samples=sum(p.n_samples for p in parts), notes=notes)


def overlapping_avar(rate, dt: float, taus: Optional[Sequence[float]] = None,
                     m: Optional[Sequence[int]] = None, use_numba: bool = True
                     ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Return ``(taus, avar, counts)`` of (n,) or (n, C) uniformly sampled rate data.

    Grid: ``m`` (averaging factors) or ``taus`` (s, rounded to multiples of dt) or, by default,
    the paper's grid. ``avar`` has shape (K,) for 1-D input, (K, C) otherwise. Equal to
    ``allantools.oadev(rate, rate=1/dt, data_type='freq', taus=taus)[1] ** 2``.
    """
    rate2, one = _as_2d(rate)
    n = rate2.shape[0]
    if m is None:
        m = m_grid(n) if taus is None else taus_to_m(taus, dt, n)
    else:
        m = taus_to_m(np.asarray(m, dtype=np.float64) * dt, dt, n)
    res = allan_sums(rate2, dt, m, use_numba=use_numba).result()
    return res.tau, (res.avar[:, 0] if one else res.avar), res.counts
