"""
Live swing calibration: feed IMU and encoder chunks as they arrive, ask for estimates any time.

The two streams arrive at their own rates and stamps; each is buffered and folded, in chunks,
through the same square-root information kernel as the offline path (``swing_batch``), so that
a 1 kHz IMU plus a 1 kHz encoder costs a few percent of a core instead of a Python
predict/update per sample. The gyro angle is integrated (trapezoid) at the gyro's own stamps
across chunk boundaries. Both filters share the reference epoch t_ref (by default the first
stamp seen on either stream), which is what aligns them (see ``swing_align``).

Samples that cannot be used are counted, never silently absorbed: non-finite values and stamps
that do not advance (duplicates, out of order) are dropped. A gyro gap longer than
``swing_batch.GAP_RELEASE_FACTOR`` reference intervals (3 or more samples lost) releases the
integrated angle's offset in the kernel (see ``swing_batch``: the motion in the gap is unknown),
is left out of the trapezoid gain, and is counted (``gaps_released``, ``notes``); shorter gaps
stay integrated.
"""
from typing import List, Optional, Tuple

from gyro_char.swing import batch as swing_batch
from gyro_char.swing.align import integrate, trapezoid_gain
from gyro_char.swing.model import combine, Estimate, FilterResult, SwingEstimates, SwingNoise
import numpy as np

FOLD_EVERY = 512  # buffered samples per stream before a fold (a QR of a (512+6) x 6 matrix)


class _Stream:
    """One input stream: its information factor, buffer and counters."""

    def __init__(self, kind: str, noise: Optional[float]) -> None:
        self.srif = swing_batch.Srif()
        self.state = swing_batch.StreamState(kind, noise)
        self.t: List[np.ndarray] = []
        self.y: List[np.ndarray] = []
        self.buffered = 0
        self.last_t = -np.inf
        self.rejected = 0


class SwingOnline:
    """
    Recursive (chunk-wise) swing filter pair for one gyro axis against the stand encoder.

    ``add_imu(t, rate)`` takes stamps (s) and the chosen axis' rate (rad/s);
    ``add_encoder(t, angle)`` stamps and angles (rad). ``estimates()`` returns the paper's
    (1)-(3) with 1-sigma (NaN until both streams have data). ``reset()`` starts over.
    """

    def __init__(self, period_s: float, noise: Optional[SwingNoise] = None,
                 t_ref: Optional[float] = None) -> None:
        if not (np.isfinite(period_s) and period_s > 0):
            raise ValueError(f'period_s must be positive, got {period_s}')
        self.period_s = float(period_s)
        self.noise = noise or SwingNoise()
        self._t_ref_given = t_ref
        self.reset()

    def reset(self) -> None:
        self.t_ref = self._t_ref_given
        self._enc = _Stream(swing_batch.ENCODER, self.noise.encoder_sigma)
        self._gyr = _Stream(swing_batch.GYRO, self.noise.gyro_arw)
        self._gyro_last: Optional[Tuple[float, float, float]] = None  # tau, rate, angle
        self._gain_sum = 0.0
        self._gain_steps = 0

    # -- input ---------------------------------------------------------------------------------
    def _accept(self, s: _Stream, t: np.ndarray, y: np.ndarray) -> None:
        t = np.asarray(t, dtype=np.float64).ravel()
        y = np.asarray(y, dtype=np.float64).ravel()
        if t.shape != y.shape:
            raise ValueError(f'{t.size} stamps but {y.size} values')
        ok = np.isfinite(t) & np.isfinite(y)
        # Keep only stamps that advance past everything accepted so far.
        run_max = np.maximum.accumulate(np.where(ok, t, -np.inf))
        prev_max = np.concatenate([[s.last_t], run_max[:-1]])
        prev_max = np.maximum(prev_max, s.last_t)
        ok &= t > prev_max
        s.rejected += int(t.size - ok.sum())
        if not ok.any():
            return
        if self.t_ref is None:
            self.t_ref = float(t[ok][0])
        s.t.append(t[ok])
        s.y.append(y[ok])
        s.buffered += int(ok.sum())
        s.last_t = float(t[ok][-1])
        if s.buffered >= FOLD_EVERY:
            self._fold(s)

    def add_imu(self, t: np.ndarray, rate: np.ndarray) -> None:
        self._accept(self._gyr, t, rate)

    def add_encoder(self, t: np.ndarray, angle: np.ndarray) -> None:
        self._accept(self._enc, t, angle)

    # -- processing ----------------------------------------------------------------------------
    def _fold(self, s: _Stream) -> None:
        if not s.buffered:
            return
        tau = np.concatenate(s.t) - self.t_ref
        y = np.concatenate(s.y)
        s.t, s.y, s.buffered = [], [], 0
        if s is self._gyr:
            y = self._integrate(tau, y)
        swing_batch.fold(s.srif, s.state, tau, y, self.period_s)

    def _integrate(self, tau: np.ndarray, rate: np.ndarray) -> np.ndarray:
        """Trapezoid angle continuing from the previous chunk's last sample."""
        if self._gyro_last is None:
            p_tau, p_rate, p_angle = tau[0], rate[0], 0.0
        else:
            p_tau, p_rate, p_angle = self._gyro_last
        tt = np.concatenate([[p_tau], tau])
        rr = np.concatenate([[p_rate], rate])
        dt = np.diff(tt)
        angle = p_angle + integrate(tt, rr)[1:]
        steps = dt if self._gyro_last is not None else dt[1:]
        # Released gaps carry no increment, so they take no part in the integration's gain.
        # (The last steps.size flags, by index: a first chunk of one sample has no step, and
        # [-0:] would be all of them.)
        gaps = swing_batch.gap_steps(self._gyr.state, tau)
        steps = steps[~gaps[gaps.size - steps.size:]]
        if steps.size:
            self._gain_sum += trapezoid_gain(steps, self.period_s) * steps.size
            self._gain_steps += steps.size
        self._gyro_last = (float(tau[-1]), float(rate[-1]), float(angle[-1]))
        return angle

    def flush(self) -> None:
        """Fold whatever is buffered (``estimates`` does this)."""
        self._fold(self._enc)
        self._fold(self._gyr)

    # -- output --------------------------------------------------------------------------------
    def states(self) -> Tuple[Optional[FilterResult], Optional[FilterResult]]:
        """Each filter's state and covariance at its last sample (None before 2 samples)."""
        self.flush()
        out = []
        for s in (self._enc, self._gyr):
            out.append(swing_batch.result(s.srif, s.state, self.period_s)
                       if s.state.count >= 2 else None)
        return out[0], out[1]

    def notes(self) -> List[str]:
        notes = []
        for name, s in (('encoder', self._enc), ('imu', self._gyr)):
            if s.rejected:
                notes.append(f'{name}: {s.rejected} samples dropped (NaN or stamps not advancing)')
        if self.gaps_released:
            notes.append(f'imu: {self.gaps_released} gaps > {swing_batch.GAP_RELEASE_FACTOR:g} '
                         'sample intervals bridged by releasing the gyro angle offset')
        return notes

    def estimates(self) -> SwingEstimates:
        enc, gyr = self.states()
        if enc is None or gyr is None:
            nan = float('nan')
            e = Estimate(nan, nan, 'rad')
            return SwingEstimates(
                Estimate(nan, nan, '1'), Estimate(nan, nan, 'rad/s'),
                Estimate(nan, nan, 'rad/s^2'), e, e, self.period_s,
                self._enc.state.count, self._gyr.state.count, False, notes=self.notes())
        gain = self._gain_sum / self._gain_steps if self._gain_steps else 1.0
        return combine(enc, gyr, self.period_s, self.notes(), gyro_gain=gain)

    @property
    def gaps_released(self) -> int:
        """Count the gyro gaps bridged so far by releasing the angle offset (folded samples)."""
        return self._gyr.state.gaps

    @property
    def rejected(self) -> Tuple[int, int]:
        """Count the samples dropped so far: (encoder, imu)."""
        return self._enc.rejected, self._gyr.rejected
