"""
Observables of a swing record for the diagnosis, computed identically on record and twins.

The gyro angle (trapezoid integral of the rate at its stamps) minus the least-squares fit of
``(1 + Δρ) · encoder angle + offset + bias · t + drift · t² / 2`` (encoder interpolated at the
gyro stamps), decomposed on the swing phase θ = ωt + ψ of the encoder's own sine fit:

- ``in_phase`` / ``quadrature``: the residual's sin θ / cos θ components (rad). A stamp delay
  d leaves -A ω d cos θ; a g-sensitivity g_y leaves -g_y g A / ω cos θ - the same shape on one
  period and amplitude, hence the ambiguity the engine reports for that pair;
- ``harmonic_2f`` / ``harmonic_3f``: sin and cos of 2θ and 3θ (scale-factor asymmetry and the
  quadratic term give 2f, the cubic term 3f);
- ``residual_psd``: log10 Welch PSD of the residual's rate (its difference over dt) in log bins
  from 1 Hz to 1/8 of the sample rate (stamp jitter, encoder interpolation error, smoothing).

Whole-record components rather than per-window ones: a constant effect's z grows with the
record length instead of being spread over windows; the twins' repeats give the scatter.
"""
from typing import List

from gyro_char.swing_align import integrate
import numpy as np
from scipy import signal

PSD_BINS = 10


def _solve(cols: List[np.ndarray], y: np.ndarray) -> np.ndarray:
    # Normal equations with einsum (a threaded BLAS lstsq is slow on a busy 2-core machine);
    # columns are scaled to unit rms so the 7x7 system stays well conditioned.
    a = np.array(cols)
    s = np.sqrt(np.einsum('ij,ij->i', a, a) / y.size)
    s[s == 0] = 1.0
    a = a / s[:, None]
    coef = np.linalg.solve(np.einsum('ik,jk->ij', a, a), np.einsum('ik,k->i', a, y))
    return coef / s


def layout(n_psd: int, dt: float, period_s: float) -> dict:
    """Per block, the (lo, hi) range (Hz) of every element."""
    f0 = 1.0 / period_s
    # Up to 1/8 of the sample rate: above it the residual is shaped by where the gyro stamps
    # fall between encoder samples (linear interpolation), which says nothing about the gyro.
    edges = np.geomspace(1.0, 0.125 / dt, PSD_BINS + 1)
    return {'in_phase': np.array([[f0, f0]]), 'quadrature': np.array([[f0, f0]]),
            'harmonic_2f': np.array([[2 * f0, 2 * f0]] * 2),
            'harmonic_3f': np.array([[3 * f0, 3 * f0]] * 2),
            'residual_psd': np.c_[edges[:-1], edges[1:]]}


UNITS = {'in_phase': 'Hz', 'quadrature': 'Hz', 'harmonic_2f': 'Hz', 'harmonic_3f': 'Hz',
         'residual_psd': 'Hz'}


def swing_observables(t_g: np.ndarray, rate: np.ndarray, t_e: np.ndarray, enc: np.ndarray,
                      period_s: float, ranges: dict) -> dict:
    """All swing blocks of one record (gyro rate rad/s at ``t_g``, encoder rad at ``t_e``)."""
    lo, hi = max(t_g[0], t_e[0]), min(t_g[-1], t_e[-1])
    m = (t_g >= lo) & (t_g <= hi)
    tau = t_g[m] - lo
    ang = integrate(tau, rate[m])
    e = np.interp(tau, t_e - lo, enc)
    w = 2.0 * np.pi / period_s
    s1, c1 = np.sin(w * tau), np.cos(w * tau)
    ts = tau / max(tau[-1], 1e-9)
    one = np.ones_like(tau)
    ce = _solve([s1, c1, one, ts, ts * ts], e)
    psi = float(np.arctan2(ce[1], ce[0]))
    line = [one, ts, ts * ts]
    k = _solve([e] + line, ang)
    r = ang - k[0] * e - (k[1] + k[2] * ts + k[3] * ts * ts)
    th = w * tau + psi
    cols = [np.sin(th), np.cos(th), np.sin(2 * th), np.cos(2 * th), np.sin(3 * th),
            np.cos(3 * th)]
    h = _solve(cols + line, r)
    dt = float(np.median(np.diff(tau)))
    f, p = signal.welch(np.diff(r) / dt, fs=1.0 / dt, nperseg=min(2048, r.size // 8))
    psd = np.array([np.mean(p[(f >= a) & (f < b)]) if np.any((f >= a) & (f < b))
                    else np.interp(0.5 * (a + b), f, p) for a, b in ranges['residual_psd']])
    return {'in_phase': h[0:1], 'quadrature': h[1:2], 'harmonic_2f': h[2:4],
            'harmonic_3f': h[4:6], 'residual_psd': np.log10(np.maximum(psd, 1e-300))}
