"""
A screen of the gyro rate at its Nyquist frequency, locked to the swing: what no block sees.

Every swing observable reads the trapezoid-integrated gyro angle, whose gain at the gyro's
Nyquist frequency is zero ((x_k + x_(k+1)) / 2 of an alternating sequence cancels). An error
that alternates sign from sample to sample with a size that follows the swing (the residue of
a chopped or ping-pong front end, the skew of two time-interleaved converters) thus leaves
the angle, the swing calibration and the gap untouched, while a user who filters or
integrates the rates otherwise gets it. The screen shifts the rate's Nyquist band to 0 Hz,
y_k = (-1)^k (x_k - (x_(k-1) + x_(k+1)) / 2) / 2 (unit gain at Nyquist, the smooth swing rate
out), fits y on the swing's shapes 1, cos θ, sin θ, cos 2θ, sin 2θ (a size following w², |w|
or w projects onto them), and scores the fit against the residual's own level at 0 Hz (block
means): chi-square on 5 degrees of freedom for white or coloured noise alike. Not a catalogue
effect and not in the gap: a warning.
"""
from typing import Optional

from gyro_char.diagnosis.swing_baseline import sample_numbers
from gyro_char.diagnosis.swing_residuals import residuals
from gyro_char.records import ENCODER_CHANNEL, Recording
import numpy as np
from scipy import stats

DOF = 5
P_FLAG = 1e-3            # p-value below which the screen warns
BLOCK = 1024             # samples a block of the noise level's estimate
MIN_BLOCKS = 8


def demodulated(t: np.ndarray, rate: np.ndarray):
    """
    Return (kept, y): the rate's Nyquist band shifted to 0 Hz (module doc).

    Only where both neighbours are one nominal step away (``swing_baseline.sample_numbers``:
    a lost sample does not flip the parity; a stamp that jumps late with none lost reads as a
    loss and flips it from there on, which costs the screen power, not a false warning);
    ``kept`` indexes the samples of ``rate`` that y stands for.
    """
    k = sample_numbers(t).astype(np.int64)
    x = np.asarray(rate, float)
    mid = np.flatnonzero((np.diff(k)[:-1] == 1) & (np.diff(k)[1:] == 1)) + 1
    y = 0.5 * (x[mid] - 0.5 * (x[mid - 1] + x[mid + 1]))
    return mid, np.where(k[mid] % 2 == 0, y, -y)


def columns(th: np.ndarray) -> np.ndarray:
    """Return the swing shapes the demodulated rate is fitted on (rows)."""
    return np.array([np.ones_like(th), np.cos(th), np.sin(th), np.cos(2 * th), np.sin(2 * th)])


def nyquist_screen(t: np.ndarray, rate: np.ndarray, th: np.ndarray) -> dict:
    """
    Return the screen of gyro rates ``rate`` (rad/s) at stamps ``t``, swing phase ``th``.

    ``tested`` False (with ``reason``) on too short or non-finite input; else ``chi2``,
    ``dof``, ``p_value``, ``flagged`` (p < ``P_FLAG``), ``rms_rad_s`` (the fitted component's
    rms) and ``noise_rad_s`` (the rate noise's rms at Nyquist, per sample).
    """
    t, rate, th = (np.asarray(a, float) for a in (t, rate, th))
    if not (np.all(np.isfinite(rate)) and np.all(np.isfinite(t))):
        return {'tested': False, 'reason': 'non-finite gyro samples'}
    mid, y = demodulated(t, rate) if t.size >= 3 else (np.array([], int), np.array([]))
    blocks = y.size // BLOCK
    if blocks < MIN_BLOCKS:
        return {'tested': False,
                'reason': f'{y.size} usable samples, need {MIN_BLOCKS * BLOCK}'}
    x = columns(th[mid])
    gram = x @ x.T
    coef = np.linalg.solve(gram, x @ y)
    fitted = coef @ x
    e = (y - fitted)[:blocks * BLOCK].reshape(blocks, BLOCK).mean(axis=1)
    s0 = max(BLOCK * float(np.mean(e * e)), 1e-300)
    chi2 = float(coef @ gram @ coef / s0)
    p = float(stats.chi2.sf(chi2, DOF))
    return {'tested': True, 'chi2': chi2, 'dof': DOF, 'p_value': p, 'flagged': p < P_FLAG,
            'rms_rad_s': float(np.sqrt(np.mean(fitted * fitted))),
            'noise_rad_s': float(np.sqrt(s0))}


def record_screen(imu: Recording, encoder: Recording, axis: str, period_s: float) -> dict:
    """Return the screen of a swing record's gyro ``axis`` (swing phase from its encoder)."""
    rate = imu.channels[f'gyro_{axis}']
    res = residuals(imu.t, rate, encoder.t, encoder.channels[ENCODER_CHANNEL], period_s)
    return nyquist_screen(imu.t[res.idx_g], rate[res.idx_g], res.th)


def screen_warning(label: str, screen: dict) -> Optional[str]:
    """Return the warning of a flagged screen of the run ``label`` ('record 1'), else None."""
    if not screen.get('flagged'):
        return None
    return (f'{label}: the gyro rate carries a component at its Nyquist frequency '
            f'locked to the swing (rms {screen["rms_rad_s"]:.3g} rad/s, chi2 '
            f'{screen["chi2"]:.1f} on {screen["dof"]} dof, p {screen["p_value"]:.1e}): an error '
            'alternating sample by sample (a chopped, ping-pong or time-interleaved front end). '
            'The integrated angle, hence the calibration and the gap, cannot see it; no '
            'catalogue effect models it; see "per_record" rate_nyquist')
