"""
Motion detection during a record that is supposed to be static (someone bumps the table).

The stream is cut into blocks of ``block_s`` seconds. For each block and channel two statistics
are compared with a reference learnt from the record itself (so that the detector needs no
sensor datasheet and copes with correlated, non-white sensor noise):

- the block variance against the reference variance (a bump or a vibration adds energy), and
- the block mean against the median of the recent clean block means, in units of the typical
  block-to-block scatter of the means (a tilt or a rotation shifts the mean).

The references are medians over the first ``warmup_blocks`` blocks and then follow clean blocks
slowly, so that a slow thermal change of the noise is not taken for motion. Consecutive motion
blocks form one event.
"""
from collections import deque
from dataclasses import dataclass
from typing import Dict, List, Optional

from gyro_char.robust import robust_sd
import numpy as np


@dataclass
class MotionEvent:
    """One stretch of consecutive motion blocks (stamps in s)."""

    start_s: float
    end_s: float
    peak_score: float
    channel: int


class MotionDetector:
    """Block-wise motion detector over ``n_channels`` columns of samples."""

    def __init__(self, dt: float, n_channels: int = 6, block_s: float = 0.5,
                 variance_ratio: float = 4.0, mean_sigmas: float = 10.0,
                 warmup_blocks: int = 40, history_blocks: int = 64,
                 min_block_samples: int = 20) -> None:
        if not dt > 0:
            raise ValueError(f'sample interval must be > 0 s, got {dt}')
        self.dt = float(dt)
        self.n_channels = int(n_channels)
        self.block_len = max(int(round(block_s / dt)), int(min_block_samples))
        self.variance_ratio = float(variance_ratio)
        self.mean_sigmas = float(mean_sigmas)
        self.warmup_blocks = int(warmup_blocks)
        self.history_blocks = int(history_blocks)
        self.reset()

    def reset(self) -> None:
        """Forget the references, events and any partial block."""
        self._carry_t = np.zeros(0)
        self._carry_x = np.zeros((0, self.n_channels))
        self._warm_means: List[np.ndarray] = []
        self._warm_vars: List[np.ndarray] = []
        self._recent = deque(maxlen=self.history_blocks)
        self.ref_var: Optional[np.ndarray] = None
        self.mean_scatter: Optional[np.ndarray] = None
        self.events: List[MotionEvent] = []
        self.event_count = 0
        self.motion_time_s = 0.0
        self.blocks = 0
        self._open: Optional[MotionEvent] = None

    @property
    def ready(self) -> bool:
        """Whether the references are learnt (before that nothing can be flagged)."""
        return self.ref_var is not None

    def break_stream(self) -> None:
        """Drop a partial block (call at a stamp gap so that no block spans it)."""
        self._carry_t = np.zeros(0)
        self._carry_x = np.zeros((0, self.n_channels))

    def add(self, t: np.ndarray, x: np.ndarray) -> List[MotionEvent]:
        """Feed samples (stamps ``t`` (k,), values ``x`` (k, n_channels)); return new events."""
        t = np.concatenate([self._carry_t, np.asarray(t, dtype=np.float64)])
        x = np.concatenate([self._carry_x, np.asarray(x, dtype=np.float64)])
        nb = t.size // self.block_len
        used = nb * self.block_len
        self._carry_t, self._carry_x = t[used:], x[used:]
        if nb == 0:
            return []
        xb = x[:used].reshape(nb, self.block_len, self.n_channels)
        tb = t[:used].reshape(nb, self.block_len)
        means = xb.mean(axis=1)
        variances = xb.var(axis=1, ddof=1)
        new = []
        for i in range(nb):
            event = self._block(tb[i, 0], tb[i, -1], means[i], variances[i])
            if event is not None:
                new.append(event)
        return new

    def _block(self, t0: float, t1: float, mean: np.ndarray,
               var: np.ndarray) -> Optional[MotionEvent]:
        self.blocks += 1
        if self.ref_var is None:
            self._warm_means.append(mean)
            self._warm_vars.append(var)
            self._recent.append(mean)
            if len(self._warm_vars) >= self.warmup_blocks:
                self._learn()
            return None
        tiny = np.finfo(float).tiny
        var_score = var / np.maximum(self.ref_var, tiny) / self.variance_ratio
        centre = np.median(np.asarray(self._recent), axis=0)
        mean_score = np.abs(mean - centre) / np.maximum(self.mean_scatter, tiny) / self.mean_sigmas
        score = np.maximum(var_score, mean_score)
        channel = int(np.argmax(score))
        peak = float(score[channel])
        if peak <= 1.0:
            # Clean block: follow slow changes of the noise level.
            self.ref_var = 0.99 * self.ref_var + 0.01 * var
            self._recent.append(mean)
            self._open = None
            return None
        self.motion_time_s += t1 - t0 + self.dt
        if self._open is None:
            self._open = MotionEvent(float(t0), float(t1), peak, channel)
            self.event_count += 1
            self.events.append(self._open)
            del self.events[:-100]  # keep the latest events only: bounded memory
            return self._open
        self._open.end_s = float(t1)
        if peak > self._open.peak_score:
            self._open.peak_score, self._open.channel = peak, channel
        return None

    def _learn(self) -> None:
        means = np.asarray(self._warm_means)
        self.ref_var = np.median(np.asarray(self._warm_vars), axis=0)
        steps = np.diff(means, axis=0)
        # Consecutive means differ by sqrt(2) times the scatter of one mean.
        self.mean_scatter = robust_sd(steps, axis=0) / np.sqrt(2.0)
        floor = np.sqrt(self.ref_var / self.block_len)
        # Quantized sensors can give a zero MAD; never go below the white-noise scatter / 4.
        self.mean_scatter = np.maximum(self.mean_scatter, 0.25 * floor)
        self._warm_means, self._warm_vars = [], []

    @property
    def in_motion(self) -> bool:
        """Whether the latest block was flagged."""
        return self._open is not None

    def summary(self) -> Dict[str, float]:
        """Counters for diagnostics (SI units in the keys)."""
        out = {'motion_events': self.event_count, 'motion_time_s': float(self.motion_time_s),
               'motion_in_progress': int(self.in_motion)}
        if self.events:
            last = self.events[-1]
            out['motion_last_start_s'] = float(last.start_s)
            out['motion_last_end_s'] = float(last.end_s)
            out['motion_last_peak_score'] = float(last.peak_score)
        return out

    def state_dict(self) -> Dict[str, np.ndarray]:
        """Learnt references and counters as plain arrays (for ``np.savez`` checkpoints)."""
        state = {'event_count': np.array(self.event_count),
                 'motion_time_s': np.array(self.motion_time_s),
                 'blocks': np.array(self.blocks)}
        if self.ready:
            state['ref_var'] = self.ref_var
            state['mean_scatter'] = self.mean_scatter
            state['recent'] = np.asarray(self._recent)
        return state

    def load_state(self, state: Dict[str, np.ndarray]) -> None:
        """Restore what ``state_dict`` saved (the partial block is lost: at most one block)."""
        self.reset()
        self.event_count = int(state['event_count'])
        self.motion_time_s = float(state['motion_time_s'])
        self.blocks = int(state['blocks'])
        if 'ref_var' in state:
            self.ref_var = np.asarray(state['ref_var'], dtype=np.float64)
            self.mean_scatter = np.asarray(state['mean_scatter'], dtype=np.float64)
            self._recent.extend(np.asarray(state['recent'], dtype=np.float64))
