"""
Bring the IMU and encoder streams of a swing run onto one time base, or refuse with a reason.

The two streams keep their own stamps (each filter runs at its own samples; no resampling of the
data that is filtered). What aligns them is one reference epoch ``t_ref`` (the start of the
overlapping window) at which both filters' states are expressed, so that w0 and wdot0 of the two
filters refer to the same instant, and a common window, so both see the same stretch of the run.
The gyro angle is integrated (trapezoid rule) at the gyro's own stamps over that window.
"""
from dataclasses import dataclass, field
from typing import Dict, List, Optional

from gyro_char.errors import InputError
from gyro_char.records import ENCODER_CHANNEL, GYRO_CHANNELS, Recording
from gyro_char.swing.batch import GAP_RELEASE_FACTOR
import numpy as np

MIN_PERIODS = 3.0           # refuse records with fewer swing periods than this
ENCODER_GAP_PERIODS = 0.25  # an encoder gap longer than this fraction of T leaves the swing unseen
PERIOD_TOLERANCE = 0.02     # warn when the dominant period differs from T by more than this
MIN_AXIS_RATIO = 0.5        # gyro swing amplitude / encoder's below this: wrong axis
FFT_MAX_POINTS = 1 << 16  # plenty for swing periods >= 0.01 s over 15 min


@dataclass
class AlignedSwing:
    """Both streams on a common window; stamps as tau = t - t_ref (s)."""

    t_ref: float
    axis: str
    period_s: float
    tau_encoder: np.ndarray
    angle_encoder: np.ndarray
    tau_gyro: np.ndarray
    rate_gyro: np.ndarray
    angle_gyro: np.ndarray
    dominant_period_s: float
    axis_ratios: Dict[str, float]
    notes: List[str] = field(default_factory=list)


def integrate(tau: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """Angle from rate samples at their own stamps (trapezoid rule), 0 at the first sample."""
    out = np.zeros_like(rate)
    np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(tau), out=out[1:])
    return out


def trapezoid_gain(dt: np.ndarray, period_s: float) -> float:
    """
    Gain of trapezoid integration of point rate samples on a sinusoid of period T.

    Per step h the trapezoid increment of cos is (x / tan x) times the exact one, x = pi h / T
    (about 1 - (2 pi h / T)^2 / 12: 3.3 ppm at h = 5 ms, T = 5 s), which would otherwise read as
    a scale-factor error; the mean over the steps is exact for uniform steps and second order
    in the jitter otherwise.
    """
    x = np.pi * np.asarray(dt, dtype=np.float64) / period_s
    if x.size == 0:
        return 1.0
    small = np.abs(x) < 1e-4
    g = np.where(small, 1.0 - x * x / 3.0, x / np.tan(np.where(small, 1.0, x)))
    return float(g.mean())


def check_stamps(t: np.ndarray, values: np.ndarray, what: str) -> None:
    """Refuse NaN/inf and stamps that are not strictly increasing, with counts."""
    if t.size < 2:
        raise InputError(f'{what}: fewer than 2 samples')
    bad = ~np.isfinite(values) | ~np.isfinite(t)
    if bad.any():
        first = t[np.argmax(bad)]
        raise InputError(f'{what}: {int(bad.sum())} NaN/inf samples (first at t={first:.6f} s);'
                         ' remove or repair them before the swing fit')
    d = np.diff(t)
    dup, back = int((d == 0).sum()), int((d < 0).sum())
    if dup or back:
        raise InputError(f'{what}: stamps not strictly increasing ({dup} duplicated, {back} out'
                         ' of order); sort and de-duplicate the stream')


def _check_gaps(tau: np.ndarray, limit: float, what: str, why: str) -> None:
    d = np.diff(tau)
    i = int(np.argmax(d))
    if d[i] > limit:
        raise InputError(f'{what}: gap of {d[i]:.3f} s after t_ref+{tau[i]:.3f} s (limit '
                         f'{limit:.3f} s): {why}')


def _fit_amplitude(tau: np.ndarray, y: np.ndarray, period_s: float, poly: int):
    """Amplitude at the swing period of y (least squares with a trend) and the residual rms."""
    step = max(1, tau.size // 50_000)
    tt, yy = tau[::step], y[::step]
    a = 2 * np.pi * tt / period_s
    s = tt / max(tt[-1], 1e-9)
    cols = [np.cos(a), np.sin(a)] + [s ** k for k in range(poly + 1)]
    a = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(a, yy, rcond=None)
    return float(np.hypot(coef[0], coef[1])), float(np.std(yy - a @ coef))


def dominant_period(tau: np.ndarray, y: np.ndarray) -> float:
    """Period (s) of the strongest spectral line of y after removing a quadratic trend."""
    n = min(tau.size, FFT_MAX_POINTS)
    grid = np.linspace(tau[0], tau[-1], n)
    yy = np.interp(grid, tau, y)
    yy = yy - np.polyval(np.polyfit(grid - grid[0], yy, 2), grid - grid[0])
    spec = np.abs(np.fft.rfft(yy * np.hanning(n)))
    f = np.fft.rfftfreq(n, grid[1] - grid[0])
    spec[f < 1.5 / (grid[-1] - grid[0])] = 0.0
    k = int(np.argmax(spec))
    if 0 < k < spec.size - 1:  # parabolic interpolation of the log-peak
        lm, l0, lp = np.log(spec[k - 1:k + 2] + 1e-300)
        den = lm - 2 * l0 + lp
        k = k + (0.5 * (lm - lp) / den if den != 0 else 0.0)
    df = f[1] - f[0]
    return float(1.0 / (k * df)) if k > 0 else float('inf')


def align(imu: Recording, encoder: Optional[Recording], period_s: float,
          axis: Optional[str] = None) -> AlignedSwing:
    """Validate both streams, pick the gyro axis, trim to the overlap, integrate the gyro."""
    if not (np.isfinite(period_s) and period_s > 0):
        raise InputError(f'--period must be a positive number of seconds, got {period_s}')
    if encoder is None or ENCODER_CHANNEL not in encoder.channels or len(encoder) == 0:
        raise InputError('no encoder data: the swing fit needs the stand angle (encoder_rad/'
                         'encoder_deg column or a JointState topic)')
    present = [c for c in GYRO_CHANNELS if c in imu.channels]
    if not present or len(imu) == 0:
        raise InputError('no gyro data in the IMU input')
    if axis is not None:
        name = axis if axis.startswith('gyro_') else f'gyro_{axis}'
        if name not in imu.channels:
            raise InputError(f'--axis {axis}: no {name} channel (have {", ".join(present)})')
    t_e, y_e = encoder.t, encoder.channels[ENCODER_CHANNEL]
    check_stamps(t_e, y_e, 'encoder')
    for c in present:
        check_stamps(imu.t, imu.channels[c], c)
    lo, hi = max(t_e[0], imu.t[0]), min(t_e[-1], imu.t[-1])
    if hi <= lo:
        raise InputError(f'no time overlap: IMU covers {imu.t[0]:.3f}..{imu.t[-1]:.3f} s, '
                         f'encoder {t_e[0]:.3f}..{t_e[-1]:.3f} s (are both stamped by the same'
                         ' clock?)')
    if hi - lo < MIN_PERIODS * period_s:
        raise InputError(f'record too short: {hi - lo:.2f} s of overlapping data is '
                         f'{(hi - lo) / period_s:.1f} periods of {period_s:g} s; need at least '
                         f'{MIN_PERIODS:g}')
    notes = []
    me = (t_e >= lo) & (t_e <= hi)
    mg = (imu.t >= lo) & (imu.t <= hi)
    dropped = (me.size - me.sum(), mg.size - mg.sum())
    if any(dropped):
        notes.append(f'kept the overlap {lo:.3f}..{hi:.3f} s: dropped {dropped[0]} encoder and '
                     f'{dropped[1]} IMU samples outside it')
    tau_e, z_e = t_e[me] - lo, y_e[me]
    tau_g = imu.t[mg] - lo
    _check_gaps(tau_e, ENCODER_GAP_PERIODS * period_s, 'encoder',
                'the swing is not observed there; split the record')
    # Gyro gaps: the filter kernel releases the integrated angle's offset at each (swing_batch).
    steps = np.diff(tau_g)
    long_steps = steps[steps > GAP_RELEASE_FACTOR * float(np.median(steps))]
    if long_steps.size:
        notes.append(f'imu: {long_steps.size} gaps > {GAP_RELEASE_FACTOR:g} sample intervals '
                     f'(longest {long_steps.max():.3f} s) bridged by releasing the gyro angle '
                     'offset')

    dom = dominant_period(tau_e, z_e)
    if abs(dom / period_s - 1.0) > PERIOD_TOLERANCE:
        notes.append(f'WARNING: the dominant period of the encoder angle is {dom:.4g} s but the '
                     f'given period is {period_s:g} s; the estimates assume the latter')
    a_enc, rms = _fit_amplitude(tau_e, z_e, period_s, poly=2)
    if not a_enc > 3 * rms:
        raise InputError(f'the encoder shows no swing at the {period_s:g} s period (amplitude '
                         f'{a_enc:.3g} rad, residual rms {rms:.3g} rad; its dominant period is '
                         f'{dom:.4g} s)')
    rate_amp = 2 * np.pi / period_s * a_enc
    ratios = {c: _fit_amplitude(tau_g, imu.channels[c][mg], period_s, poly=0)[0] / rate_amp
              for c in present}
    best = max(ratios, key=ratios.get)
    if axis is None:
        name = best
        notes.append(f'gyro axis chosen automatically: {name} (swing amplitude ratios '
                     + ', '.join(f'{c} {r:.3f}' for c, r in ratios.items()) + ')')
    if ratios[name] < MIN_AXIS_RATIO:
        hint = f'; the swing shows on {best} (ratio {ratios[best]:.3f})' if best != name else ''
        raise InputError(f'no swing signal on {name}: its rate at the {period_s:g} s period is '
                         f'{ratios[name]:.3f} of the encoder swing rate (expected ~1){hint}')
    rate = imu.channels[name][mg]
    return AlignedSwing(t_ref=float(lo), axis=name, period_s=float(period_s),
                        tau_encoder=tau_e, angle_encoder=z_e, tau_gyro=tau_g, rate_gyro=rate,
                        angle_gyro=integrate(tau_g, rate), dominant_period_s=dom,
                        axis_ratios=ratios, notes=notes)
