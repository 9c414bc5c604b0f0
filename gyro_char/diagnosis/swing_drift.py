"""
A screen of the swing residual's waveform along the run: an effect that does not hold still.

Every swing block reads the whole run at once and every catalogue effect is constant over it,
so an effect that changes along the run (a scale factor still warming up, a driver half that
forms with use, a delay that creeps) is fitted as its average and its change is left as a gap
that no candidate closes, or as noise. The screen splits the residual angle (gyro angle less
the whole-run fit of the encoder angle, ``swing_residuals``) into ``SEGMENTS`` equal spans and
fits on each the swing harmonics k = 1..``HARMONICS`` (cos kθ and sin kθ; sin θ included: the
scale factor fitted over the whole run leaves one that changes as a sin θ of changing sign),
a local quadratic (the bias's wander) and off-harmonic pairs at k ± 1/6 and k ± 1/3, which
carry the residual's noise alone. The spread of each harmonic's coefficients about their
mean, over the noise variance interpolated log-log between its off-lines, sums to a statistic
on 2 K (S - 1) degrees of freedom, referred to F(2 K (S - 1), the off-lines' count): the
noise level is itself estimated. A warning beside the gap, as the Nyquist screen is.
"""
from typing import Optional

from gyro_char.diagnosis.swing_residuals import Residuals, residuals, solve_columns
from gyro_char.records import ENCODER_CHANNEL, Recording
import numpy as np
from scipy import stats

SEGMENTS = 6
HARMONICS = 4
OFFSETS = (-1 / 3, -1 / 6, 1 / 6, 1 / 3)     # the off-lines, in harmonics of the swing
P_FLAG = 1e-3
MIN_PERIODS = 12         # swing periods a segment needs (off-lines 2 cycles apart in it)
DECIMATE_S = 0.01        # the residual averaged over blocks of this length first


def _blocks(x: np.ndarray, n: int) -> np.ndarray:
    """Return the means of consecutive blocks of ``n`` samples (the tail dropped)."""
    m = x.size // n
    return x[:m * n].reshape(m, n).mean(axis=1)


def segment_fit(r: np.ndarray, th: np.ndarray) -> tuple:
    """Return one segment's (line coefficients K x 2, off-line coefficients K x 4 x 2)."""
    u = np.linspace(-1.0, 1.0, r.size)
    cols = [np.ones_like(u), u, u * u]
    for k in range(1, HARMONICS + 1):
        for m in (k, *(k + o for o in OFFSETS)):
            cols += [np.cos(m * th), np.sin(m * th)]
    c = solve_columns(cols, r)[3:].reshape(HARMONICS, 1 + len(OFFSETS), 2)
    return c[:, 0, :], c[:, 1:, :]


def drift_screen(res: Residuals, period_s: float) -> dict:
    """
    Return the waveform screen of a run's residual streams ``res`` (module docstring).

    ``tested`` False (with ``reason``) when a segment would hold fewer than ``MIN_PERIODS``
    periods; else ``statistic``, ``dof``, ``noise_dof``, ``p_value``, ``flagged``
    (p < ``P_FLAG``), ``segments`` and per harmonic k its ``chi2`` and ``change_rad`` (the rms
    spread of its coefficients over the segments) beside ``noise_rad`` (one coefficient's
    noise sd).
    """
    span = float(res.ts.size * res.dt)
    if not np.all(np.isfinite(res.r)):
        return {'tested': False, 'reason': 'non-finite residual'}
    if span < SEGMENTS * MIN_PERIODS * period_s:
        return {'tested': False, 'reason': f'{span:.0f} s of run, need '
                                           f'{SEGMENTS * MIN_PERIODS * period_s:.0f} s'}
    n = max(1, int(round(DECIMATE_S / res.dt)))
    r, th = _blocks(res.r, n), _blocks(res.th, n)
    edges = np.linspace(0, r.size, SEGMENTS + 1).astype(int)
    fits = [segment_fit(r[a:b], th[a:b]) for a, b in zip(edges[:-1], edges[1:])]
    lines = np.array([f[0] for f in fits])              # S x K x 2
    off = np.array([f[1] for f in fits])                # S x K x 4 x 2
    k = np.arange(1, HARMONICS + 1, dtype=float)
    var_off = np.mean(off ** 2, axis=(0, 3))            # K x 4: noise variance per off-line
    freqs = k[:, None] + np.asarray(OFFSETS)[None, :]
    noise = np.empty(HARMONICS)
    for i in range(HARMONICS):
        slope, icpt = np.polyfit(np.log(freqs[i]), np.log(np.maximum(var_off[i], 1e-300)), 1)
        noise[i] = np.exp(icpt + slope * np.log(k[i]))
    dev = lines - lines.mean(axis=0)
    chi2 = np.sum(dev ** 2, axis=(0, 2)) / noise
    dof = 2 * HARMONICS * (SEGMENTS - 1)
    noise_dof = SEGMENTS * 2 * len(OFFSETS)
    statistic = float(chi2.sum())
    p = float(stats.f.sf(statistic / dof, dof, noise_dof))
    return {'tested': True, 'statistic': statistic, 'dof': dof, 'noise_dof': noise_dof,
            'p_value': p, 'flagged': p < P_FLAG, 'segments': SEGMENTS,
            'harmonics': [{'k': int(kk), 'chi2': float(c),
                           'change_rad': float(np.sqrt(np.mean(d ** 2))),
                           'noise_rad': float(np.sqrt(s))}
                          for kk, c, d, s in zip(k, chi2, dev.transpose(1, 0, 2), noise)]}


def record_drift(imu: Recording, encoder: Recording, axis: str, period_s: float) -> dict:
    """Return the waveform screen of a swing record's gyro ``axis`` against its encoder."""
    rate = imu.channels[f'gyro_{axis}']
    res = residuals(imu.t, rate, encoder.t, encoder.channels[ENCODER_CHANNEL], period_s)
    return drift_screen(res, period_s)


def drift_warning(label: str, screen: dict) -> Optional[str]:
    """Return the warning of a flagged screen of the run ``label`` ('record 1'), else None."""
    if not screen.get('flagged'):
        return None
    worst = max(screen['harmonics'], key=lambda h: h['chi2'])
    return (f"{label}: the swing residual's waveform changes along the run (harmonic "
            f'{worst["k"]} most, its coefficients spread {worst["change_rad"]:.3g} rad over '
            f'{screen["segments"]} segments against a noise of {worst["noise_rad"]:.3g} rad; '
            f'p {screen["p_value"]:.1e}): an effect that drifts (a scale factor or asymmetry '
            'still settling, a part that forms or wears with use, a creeping delay) or a stand '
            'whose swing changes. The gap and the named effects describe its average over '
            'the run; see "per_record" waveform_drift')
