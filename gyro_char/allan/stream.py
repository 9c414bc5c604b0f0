"""
Streaming overlapping Allan variance: chunks in, memory bounded by ``m_max``, batch-equal sums.

Which tau it covers: the paper's grid m_k = [2^(k/10)] (or the given ``m``) up to ``m_max``,
tau = m dt, and at ``result()`` time only those with at least one term (2m <= samples so far).
For every covered tau the accumulator holds exactly the batch sum
S(m) = sum_j (x_{j+2m} - 2 x_{j+m} + x_j)^2 over ALL overlapping terms and the same term count,
so ``result()`` equals ``gyro_char.allan.kernel.overlapping_avar`` on the concatenated samples (to
rounding: about 1e-12 relative, the sums are added in a different order).

How: the phase x (angle, cumulative sum of rate times dt) of the last 2 m_max samples is kept
per channel. Each new sample j closes the term (j - 2m, j - m, j) for every m, so a chunk of k
samples is processed as one vectorised pass per m over [kept tail, new phase]. The kept tail is
re-based after each chunk (a common constant, which second differences ignore) so the stored
phase stays small however long the run. Instead of the batch's global mean (unknown while
streaming) the first chunk's mean is removed from the rate; again second differences are
unchanged, only rounding differs. Memory: (2 m_max + 1 + chunk) x channels floats plus the
(K x channels) sums; a state dict of plain numpy arrays checkpoints it (np.savez) and
``from_state`` restores it bit for bit.
"""
from typing import Dict, Optional, Sequence

from gyro_char.allan.edf import add_confidence, alpha_from_slope
from gyro_char.allan.kernel import (AllanResult, AllanSums, m_grid, POINTS_PER_OCTAVE,
                                    second_difference_sums)
from gyro_char.errors import InputError
import numpy as np

STATE_VERSION = 1


class AllanAccumulator:
    """Accumulate overlapping Allan sums of (k, n_channels) rate chunks at a fixed ``dt``."""

    def __init__(self, dt: float, n_channels: int, m_max: int = 2 ** 16,
                 points_per_octave: int = POINTS_PER_OCTAVE,
                 channels: Optional[Sequence[str]] = None, m: Optional[Sequence[int]] = None):
        if not (np.isfinite(dt) and dt > 0):
            raise InputError(f'dt must be > 0, got {dt}')
        if int(m_max) < 1 or int(n_channels) < 1:
            raise InputError('m_max and n_channels must be >= 1')
        self.dt = float(dt)
        self.n_channels = int(n_channels)
        self.m_max = int(m_max)
        grid = (m_grid(2 * self.m_max, points_per_octave, self.m_max) if m is None
                else np.unique(np.asarray(m, dtype=np.int64)))
        if grid.size == 0 or grid.min() < 1 or grid.max() > self.m_max:
            raise InputError(f'averaging factors must be within 1..m_max={self.m_max}')
        self.m = grid
        self.channels = (tuple(channels) if channels is not None
                         else tuple(f'ch{c}' for c in range(self.n_channels)))
        if len(self.channels) != self.n_channels:
            raise InputError('channels must have n_channels names')
        self.sums = np.zeros((self.m.size, self.n_channels))
        self.counts = np.zeros(self.m.size, dtype=np.int64)
        self.n_samples = 0
        self.offset = np.full(self.n_channels, np.nan)  # rate offset, set by the first chunk
        self.tail = np.zeros((1, self.n_channels))      # phase of the last <= 2 m_max + 1 pts

    def add(self, chunk) -> None:
        """Add ``chunk`` of shape (k, n_channels) (or (k,) for one channel) of rate samples."""
        chunk = np.asarray(chunk, dtype=np.float64)
        if chunk.ndim == 1 and self.n_channels == 1:
            chunk = chunk[:, None]
        if chunk.ndim != 2 or chunk.shape[1] != self.n_channels:
            raise InputError(f'chunk must be (k, {self.n_channels}), got {chunk.shape}')
        if chunk.shape[0] == 0:
            return
        if not np.all(np.isfinite(chunk)):
            raise InputError('NaN/Inf in the rate chunk: drop or repair samples first (a '
                             'dropped sample is a gap: reset the accumulator)')
        if np.isnan(self.offset[0]):
            self.offset = chunk.mean(axis=0)
        new = self.tail[-1] + np.cumsum((chunk - self.offset) * self.dt, axis=0)
        full = np.concatenate([self.tail, new])
        n_tail = self.tail.shape[0]
        for c in range(self.n_channels):
            col = np.ascontiguousarray(full[:, c])
            for k, mm in enumerate(self.m):
                start = max(0, n_tail - 2 * int(mm))
                if full.shape[0] - start > 2 * mm:
                    self.sums[k, c] += second_difference_sums(col[start:], self.m[k:k + 1])[0]
        ends = np.arange(n_tail, full.shape[0])[None, :]
        self.counts += np.count_nonzero(ends >= 2 * self.m[:, None], axis=1)
        keep = full[-(2 * self.m_max + 1):]
        self.tail = keep - keep[-1]  # re-base: a common constant, invisible to the sums
        self.n_samples += chunk.shape[0]

    def sums_view(self) -> AllanSums:
        """Return the accumulated sums as ``AllanSums`` (same type as the batch path)."""
        return AllanSums(dt=self.dt, m=self.m.copy(), sums=self.sums.copy(),
                         counts=self.counts.copy(), channels=self.channels,
                         n_samples=self.n_samples)

    def result(self, confidence: bool = True) -> AllanResult:
        """
        Return the Allan variance for every covered tau (see module docstring).

        With ``confidence`` the 68 % intervals use Greenhall's EDF with the noise type taken
        from the local log-log slope of the curve (the raw samples are gone by then).
        """
        if not np.any(self.counts):
            raise InputError(f'too few samples for any tau: {self.n_samples} so far')
        res = self.sums_view().result()
        if confidence:
            add_confidence(res, alpha_from_slope(res.tau, res.avar))
        return res

    def state_dict(self) -> Dict[str, np.ndarray]:
        """Return the full state as plain numpy arrays (``np.savez``-able, no pickle)."""
        return {'version': np.array(STATE_VERSION), 'dt': np.array(self.dt),
                'm_max': np.array(self.m_max), 'm': self.m.copy(), 'sums': self.sums.copy(),
                'counts': self.counts.copy(), 'n_samples': np.array(self.n_samples),
                'offset': self.offset.copy(), 'tail': self.tail.copy(),
                'channels': np.array(self.channels, dtype=str)}

    @classmethod
    def from_state(cls, state) -> 'AllanAccumulator':
        """Rebuild from ``state_dict()`` output (or an ``np.load`` of its ``np.savez``)."""
        if int(state['version']) != STATE_VERSION:
            raise InputError(f'Allan state version {int(state["version"])} is not supported')
        channels = [str(c) for c in np.asarray(state['channels'])]
        acc = cls(float(state['dt']), len(channels), int(state['m_max']), channels=channels,
                  m=np.asarray(state['m']))
        acc.sums = np.array(state['sums'], dtype=np.float64)
        acc.counts = np.array(state['counts'], dtype=np.int64)
        acc.n_samples = int(state['n_samples'])
        acc.offset = np.array(state['offset'], dtype=np.float64)
        acc.tail = np.array(state['tail'], dtype=np.float64)
        if acc.sums.shape != (acc.m.size, acc.n_channels) or acc.tail.shape[1] != acc.n_channels:
            raise InputError('Allan state arrays have inconsistent shapes')
        return acc
