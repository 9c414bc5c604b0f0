"""
Swing-stand calibration (docs/method.md section 1): the 5-state Kalman filter and its estimates.

Two implementations of the same filter:

- ``SwingKalman``: the paper's recursive filter, one predict/update per sample with Phi built
  from each actual dt_i, on filterpy's ``KalmanFilter`` (Joseph-form update). It is the reference
  the fast path is tested against; live use goes through ``swing_online.SwingOnline``, which
  folds chunks through the fast kernel because a Python predict/update per sample costs tens of
  microseconds (see ``bench/bench_swing_kf.py``).
- ``swing_batch``: a square-root information form of the same filter (exact for this model,
  see its module doc), vectorised over samples: the offline path.

``estimate_swing`` is the offline entry point: align the streams, run both filters, combine.
"""
from dataclasses import dataclass, field
from typing import List, Optional

from filterpy.kalman import KalmanFilter
from gyro_char.records import Recording
from gyro_char.swing import batch as swing_batch
from gyro_char.swing.align import align, AlignedSwing, trapezoid_gain
from gyro_char.swing.model import (combine, FilterResult, GYRO_ANCHOR_S, H, PRIOR_SD,
                                   SwingEstimates, SwingNoise, transition)
import numpy as np


class SwingKalman:
    """
    The per-sample recursive filter for one stream (``kind`` 'encoder' or 'gyro').

    ``noise`` is sigma_enc (rad) for the encoder, N (rad/sqrt(s)) for the gyro; see
    ``swing_model`` for the Q and R they define. Stamps are tau = t - t_ref (s).
    """

    def __init__(self, kind: str, period_s: float, noise: float) -> None:
        self.kind, self.period_s, self.noise = kind, float(period_s), float(noise)
        self.kf = KalmanFilter(dim_x=5, dim_z=1)
        self.kf.x = np.zeros((5, 1))
        self.kf.P = np.diag(PRIOR_SD ** 2)
        self.kf.H = H.copy()
        self.tau = 0.0
        self.count = 0
        self._q = np.zeros((5, 5))

    def step(self, tau: float, z: float) -> None:
        dt = tau - self.tau
        self.kf.F = transition(dt, self.period_s)
        n2 = self.noise ** 2
        gyro = self.kind == swing_batch.GYRO
        self._q[2, 2] = n2 * dt if (gyro and self.count > 0) else 0.0
        self.kf.predict(Q=self._q)
        if gyro:
            r = n2 * GYRO_ANCHOR_S if self.count == 0 else 0.0
        else:
            r = n2
        self.kf.update(np.array([[z]]), R=r)
        self.tau = tau
        self.count += 1

    def run(self, tau: np.ndarray, z: np.ndarray) -> 'SwingKalman':
        for ti, zi in zip(tau, z):
            self.step(float(ti), float(zi))
        return self

    def result(self) -> FilterResult:
        return FilterResult(x=self.kf.x[:, 0].copy(), P=self.kf.P.copy(), tau=self.tau,
                            samples=self.count, noise=self.noise, noise_estimated=False)


@dataclass
class SwingRun:
    """Everything an offline run produces: estimates, the aligned data, convergence history."""

    estimates: SwingEstimates
    aligned: AlignedSwing
    encoder: FilterResult
    gyro: FilterResult
    history: List[SwingEstimates] = field(default_factory=list)
    history_tau: np.ndarray = field(default_factory=lambda: np.zeros(0))


def estimate_swing(imu: Recording, encoder: Optional[Recording], period_s: float,
                   axis: Optional[str] = None, noise: Optional[SwingNoise] = None,
                   checkpoints: int = 0) -> SwingRun:
    """
    Offline swing calibration of one gyro axis against the stand encoder.

    ``noise`` None (or None fields) means noise levels estimated from each filter's residuals.
    ``checkpoints`` > 0 also returns the estimates' history at that many points (for plots).
    Raises ``InputError`` with a one-line reason on unusable input.
    """
    noise = noise or SwingNoise()
    al = align(imu, encoder, period_s, axis)
    enc, h_enc = swing_batch.run(swing_batch.ENCODER, al.tau_encoder, al.angle_encoder,
                                 period_s, noise.encoder_sigma, checkpoints)
    gyr, h_gyr = swing_batch.run(swing_batch.GYRO, al.tau_gyro, al.angle_gyro, period_s,
                                 noise.gyro_arw, checkpoints)
    notes = list(imu.notes) + list(encoder.notes) + al.notes
    for what, res in (('encoder', enc), ('gyro', gyr)):
        if res.noise_estimated:
            unit = 'rad' if what == 'encoder' else 'rad/sqrt(s)'
            notes.append(f'{what} noise estimated from the fit residuals: {res.noise:.3g} {unit}')
    steps = np.diff(al.tau_gyro)  # released gaps (swing_batch) take no part in the gain
    gain = trapezoid_gain(steps[steps <= swing_batch.GAP_RELEASE_FACTOR * np.median(steps)],
                          period_s)
    notes.append(f'gyro amplitude divided by the trapezoid-integration gain at the period, '
                 f'{gain:.9f}')
    est = combine(enc, gyr, period_s, notes, gyro_gain=gain)
    history = [combine(e, g, period_s, gyro_gain=gain) for e, g in zip(h_enc, h_gyr)]
    h_tau = np.array([max(e.tau, g.tau) for e, g in zip(h_enc, h_gyr)])
    return SwingRun(est, al, enc, gyr, history, h_tau)
