"""
The residual streams of a swing record, and the least squares they come from.

The gyro angle (trapezoid integral of the rate at its stamps) minus the least-squares fit of
``(1 + Δρ) · encoder angle + offset + bias · t + drift · t² / 2`` (encoder interpolated at the
gyro stamps), on the gyro stamps and, the same fit, on the encoder stamps (gyro angle
interpolated there), with the swing phase θ = ωt + ψ of the encoder's own sine fit
(``swing_obs`` decomposes them into the observables). A ``Residuals`` also keeps what its
geometry alone fixes (normal matrices, bin indices: ``Residuals.memo``), since the diagnosis
decomposes many streams on one geometry, the twin runs with and without an effect.
"""
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Tuple

from gyro_char.swing.align import integrate
import numpy as np


def column_normal(a: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Return the columns' rms scales and the normal matrix of the scaled columns (rows of a)."""
    s = np.sqrt(np.einsum('ij,ij->i', a, a) / a.shape[1])
    s[s == 0] = 1.0
    return s, np.einsum('ik,jk->ij', a, a) / np.outer(s, s)


def solve_columns(cols: List[np.ndarray], y: np.ndarray,
                  normal: Optional[Tuple[np.ndarray, np.ndarray]] = None) -> np.ndarray:
    """
    Return the least-squares coefficients of ``y`` on the columns ``cols`` (a few, long).

    Normal equations with einsum (a threaded BLAS lstsq is slow on a busy 2-core machine);
    columns are scaled to unit rms so that the small system stays well conditioned.
    ``normal``: ``column_normal`` of the columns, when several ``y`` share them.
    """
    a = np.array(cols)
    s, g = column_normal(a) if normal is None else normal
    return np.linalg.solve(g, np.einsum('ik,k->i', a, y) / s) / s


@dataclass
class Residuals:
    """
    The residual streams of one record and the swing geometry they are decomposed on.

    ``r`` at the gyro stamps (``idx_g``: their sample numbers in the input), ``r_e`` at the
    encoder stamps (``idx_e``); ``th`` / ``th_e`` the swing phase there, ``ts`` the normalised
    time of the trend columns, ``phi`` the encoder angle. ``memo``: what the geometry (or the
    run's own streams) alone fixes, filled on first use (``geometry``).
    """

    r: np.ndarray
    idx_g: np.ndarray
    th: np.ndarray
    ts: np.ndarray
    dt: float
    r_e: np.ndarray
    idx_e: np.ndarray
    th_e: np.ndarray
    phi: np.ndarray
    dt_e: float
    peak_rate: float
    memo: dict = field(default_factory=dict, repr=False, compare=False)

    def take(self, keep_g: np.ndarray, keep_e: np.ndarray) -> 'Residuals':
        """Return the geometry restricted to the gyro and encoder samples ``keep_g``/``keep_e``."""
        return Residuals(self.r[keep_g], self.idx_g[keep_g], self.th[keep_g], self.ts[keep_g],
                         self.dt, self.r_e[keep_e], self.idx_e[keep_e], self.th_e[keep_e],
                         self.phi[keep_e], self.dt_e, self.peak_rate)

    def geometry(self, name: str, make: Callable):
        """Return ``make()``, computed once: it must depend on this run alone, not the caller."""
        if name not in self.memo:
            self.memo[name] = make()
        return self.memo[name]


def common_samples(a: np.ndarray, b: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Positions in ``a`` and in ``b`` (sorted unique sample numbers) of the numbers in both."""
    if a.size == b.size and np.array_equal(a, b):
        pos = np.arange(a.size)
        return pos, pos
    return np.intersect1d(a, b, assume_unique=True, return_indices=True)[1:]


def residuals(t_g: np.ndarray, rate: np.ndarray, t_e: np.ndarray, enc: np.ndarray,
              period_s: float) -> Residuals:
    """Return the residual streams of a record (gyro rad/s at ``t_g``, encoder rad at ``t_e``)."""
    lo, hi = max(t_g[0], t_e[0]), min(t_g[-1], t_e[-1])
    m = (t_g >= lo) & (t_g <= hi)
    tau = t_g[m] - lo
    ang = integrate(tau, rate[m])
    e = np.interp(tau, t_e - lo, enc)
    w = 2.0 * np.pi / period_s
    span = max(tau[-1], 1e-9)
    ts = tau / span
    one = np.ones_like(tau)
    ce = solve_columns([np.sin(w * tau), np.cos(w * tau), one, ts, ts * ts], e)
    psi = float(np.arctan2(ce[1], ce[0]))
    k = solve_columns([e, one, ts, ts * ts], ang)
    r = ang - k[0] * e - (k[1] + k[2] * ts + k[3] * ts * ts)
    # The same fit on the encoder stamps inside the gyro span.
    me = (t_e >= lo + tau[0]) & (t_e <= lo + tau[-1])
    tau_e, phi = t_e[me] - lo, enc[me]
    tse = tau_e / span
    r_e = np.interp(tau_e, tau, ang) - k[0] * phi - (k[1] + k[2] * tse + k[3] * tse * tse)
    th_e = w * tau_e + psi
    return Residuals(r, np.flatnonzero(m), w * tau + psi, ts, float(np.median(np.diff(tau))),
                     r_e, np.flatnonzero(me), th_e, phi,
                     max(float(np.median(np.diff(tau_e))), 1e-9),
                     w * float(np.hypot(ce[0], ce[1])))
