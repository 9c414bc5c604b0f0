"""
The swing baseline's calibration against the record, and the error it leaves.

The Kalman filter's white-noise levels lump together what the twins separate (the encoder's
stamp jitter with its angle noise, the output rounding with the gyro's N); ``calibrate_encoder``
and ``calibrate_n`` re-pin them on the record where one term dominates. What those estimates
cannot pin - their own sampling error - goes into every twin (``calibration_shifts``).
"""
from dataclasses import replace
from typing import Callable, Dict, List, Sequence, Tuple

from gyro_char.diagnosis.swing_baseline import SwingBaseline
from gyro_char.diagnosis.swing_obs import unlocked_psd
from gyro_char.diagnosis.swing_residuals import solve_columns
from gyro_char.diagnosis.swing_twin import (
    encoder_white_sigma, record_observables, record_residuals, simulate_twin, twin_config)
from gyro_char.records import ENCODER_CHANNEL, Recording
import numpy as np


def calibrate_n(base: SwingBaseline, imu: Recording, encoder: Recording, ranges: dict,
                seeds: Sequence[int] = (901, 902, 903)) -> SwingBaseline:
    """
    Rescale N so that the twins' residual PSD in the gyro band matches the record's.

    The gyro filter's N is estimated from the angle residuals, which also carry the stand's
    and the encoder's noise; the residual rate's PSD from 1 Hz to 1/8 of the sample rate
    (where the gyro's white noise dominates) pins it. All the bins, not the lower half: on a
    whole 15-min 1 kHz run the upper bins are the precise ones (a few hundred Welch
    frequencies each), and the lower half's few, noisy ratios left N ~1 % high there, which
    read as a -3 to -7 sigma deficit of the record in the upper bins and as a lag-1 increment
    correlation 9 sigma off on clean runs. The median of the bins' record / twin ratios, not
    a ratio of band means, and on the residual rate less its part locked to the swing phase
    (``unlocked_psd``): a strong odd nonlinearity puts its 5f, 7f... lines into the lowest
    bins (measured: N 300x too high from a band mean on the tanh-saturation runs), and a
    dead band's sharp turning points into every bin (measured: N 10-14 % high from the
    median on a lock-in record before the phase mean came out). The median's standard error
    is kept as ``n_log_sd``.
    """
    def psd(rec_imu, rec_enc):
        return unlocked_psd(record_residuals(rec_imu, rec_enc, base), ranges)

    sims = np.array([psd(*simulate_twin(base, [], s)) for s in seeds])
    q = np.log(psd(imu, encoder) / sims.mean(axis=0))
    if not np.all(np.isfinite(q)):
        return base
    return replace(base, N=base.N * float(np.exp(0.5 * np.median(q))),
                   n_log_sd=median_ratio_error(sims))


def median_ratio_error(sims: np.ndarray) -> float:
    """
    Return the standard error of ``calibrate_n``'s log N from the calibration twins' own spread.

    Each twin plays the record against the mean of the others; the spread of those log
    median ratios, scaled from S - 1 to S twins in the mean, is the record's. Not the bins'
    scatter about their median: the bins differ in shape as well as by chance, and that
    spread read 0.6 % on clean 15-min 1 kHz runs whose N came out within 0.05 %.
    """
    s = len(sims)
    if s < 3:
        return 0.0
    loo = [float(np.median(np.log(sims[k] / np.delete(sims, k, axis=0).mean(axis=0))))
           for k in range(s)]
    var = float(np.var(loo, ddof=1)) * (1.0 + 1.0 / s) / (1.0 + 1.0 / (s - 1))
    return 0.5 * float(np.sqrt(var)) if np.isfinite(var) else 0.0


TURNING_COS = 0.05  # |cos θ| below this: within ~3° of phase of a turning point
CALIBRATION_STREAM = 0xCA1  # the random stream of the twins' calibration errors
ENCODER_PASSES = 3          # at most, each from the level the last one found
NEAR = 0.25                 # twins within this share of the record's power: no further pass


def turning_power(encoder: Recording, period_s: float) -> Tuple[float, float]:
    """
    Return the encoder's white angle noise power at the swing's turning points and its error.

    The mean square of the increments of the encoder's residual from its sine + trend fit,
    halved, over consecutive samples where the swing rate is under 5 % of its peak (rad²).
    Whatever scales with the rate (a stamp error reads as rate x error) vanishes there; white
    angle noise (ADC, quantization, the stand's amplitude noise) does not. The standard error
    is the ratio estimator's over the turning-point visits (batch means: increments within a
    visit are correlated, visits are not). NaN for both when too few increments qualify.
    """
    t = encoder.t - encoder.t[0]
    e = encoder.channels[ENCODER_CHANNEL]
    w = 2.0 * np.pi / period_s
    ts = t / max(t[-1], 1e-9)
    a = [np.sin(w * t), np.cos(w * t), np.ones_like(t), ts, ts * ts]
    coef = solve_columns(a, e)
    r = e - coef @ np.array(a)
    slow = np.abs(np.cos(w * t + np.arctan2(coef[1], coef[0]))) < TURNING_COS
    idx = np.flatnonzero(slow[1:] & slow[:-1])
    if idx.size < 16:
        return float('nan'), float('nan')
    d2 = np.diff(r)[idx] ** 2
    visit = np.concatenate([[0], np.cumsum(np.diff(idx) > 1)])
    sums, counts = np.bincount(visit, weights=d2), np.bincount(visit).astype(float)
    power = float(sums.sum() / counts.sum())
    se = float(np.sqrt(np.sum((sums - power * counts) ** 2)) / counts.sum()) \
        if counts.size >= 2 else float('nan')
    return power / 2.0, se / 2.0


def calibrate_encoder(base: SwingBaseline, encoder: Recording,
                      seeds: Sequence[int] = (901, 902, 903)) -> SwingBaseline:
    """
    Re-pin the twin's encoder white noise on the record's turning points.

    The filter's encoder noise lumps in everything white in the encoder residual over the
    whole swing: an encoder stamp jitter (rate x error, 6 to 36 times the ADC noise in the
    validation's jitter cases) would otherwise be built into the baseline twin, and a jitter
    candidate could only add more. The twins' turning-point power (``turning_power``) is
    matched to the record's by moving the ADC noise (variances add), again from the level
    found while the twins were far off: their power's sampling error (1 %) is a share of
    their own level, and from a filter estimate lumping in milliseconds of stamp error (100
    times the ADC noise) one step left the level at that noise (4 times the record's). The
    match's error (the record's and the twins' sampling error) is kept as
    ``encoder_power_sd``.
    """
    real, se = turning_power(encoder, base.period_s)
    if not np.isfinite(real):
        return base
    adc = encoder_white_sigma(base, twin_config(base))
    other = max(base.encoder_sigma ** 2 - adc ** 2, 0.0)
    for _ in range(ENCODER_PASSES):
        sim = float(np.mean([turning_power(simulate_twin(base, [], s)[1], base.period_s)[0]
                             for s in seeds]))
        adc2 = max(adc ** 2 + real - sim, 0.0)
        base = replace(base, encoder_sigma=float(np.sqrt(adc2 + other)))
        adc = float(np.sqrt(adc2))
        if abs(sim - real) <= NEAR * real:
            break
    sd = se * np.sqrt(1.0 + 1.0 / len(seeds)) if np.isfinite(se) else 0.0
    return replace(base, encoder_power_sd=float(sd))


def calibration_shifts(base: SwingBaseline, ranges: dict,
                       seed: int = 905) -> List[Dict[str, np.ndarray]]:
    """
    Return how far one standard error of each calibrated level moves each observable.

    The residual's increment correlation is set by the ratio of the encoder's white angle
    noise to the gyro's: on a clean 15-min 1 kHz run, 1 % of encoder noise moves its lag-1
    value by 3.5 times its scatter and 1 % of N by 4 times, and the turning points pin the
    encoder's noise to about 1 %. So a twin at the calibrated levels misses the record by
    several sigma that no twin scatter covers (3 of 9 clean runs scored above the null's 95 %
    point, one named a jitter). One shift per level (the encoder's white power, then log N),
    each from two twins of one seed (common random numbers: only that noise's size
    differs), central difference over +-1 standard error.
    """
    power = base.encoder_sigma ** 2
    levels = []
    if base.encoder_power_sd > 0 and power > 0:
        h = min(base.encoder_power_sd, 0.5 * power)
        levels.append(([replace(base, encoder_sigma=float(np.sqrt(power + k * h)))
                        for k in (-1.0, 1.0)], base.encoder_power_sd / h))
    if base.n_log_sd > 0:
        h = min(base.n_log_sd, 0.5)
        levels.append(([replace(base, N=base.N * float(np.exp(k * h))) for k in (-1.0, 1.0)],
                       base.n_log_sd / h))
    shifts = []
    for (lo, hi), gain in levels:
        o_lo = record_observables(*simulate_twin(lo, [], seed), lo, ranges)
        o_hi = record_observables(*simulate_twin(hi, [], seed), hi, ranges)
        shifts.append({b: (o_hi[b] - o_lo[b]) * (0.5 * gain) for b in o_hi})
    return shifts


def with_calibration_error(simulate: Callable, shifts: Sequence[List[Dict[str, np.ndarray]]]):
    """
    Return ``simulate(i, effects, seed)`` whose twin carries a calibration error of its own.

    The record was scored against twins at its calibrated levels, which are off by the
    calibration's error; each twin gets one draw of that error per level (seeded by the
    twin's seed and record, so every candidate model sees the same draws), applied through
    the linear shifts of ``calibration_shifts``. The twins' scatter and the null then hold
    what the record's score holds: a parametric bootstrap of the calibration, linearized.
    """
    def sim(i: int, effects: list, seed: int) -> dict:
        o = simulate(i, effects, seed)
        if not shifts[i]:
            return o
        rng = np.random.default_rng([int(seed), i, CALIBRATION_STREAM])
        o = dict(o)
        for s in shifts[i]:
            eps = float(rng.standard_normal())
            for b, v in s.items():
                if b in o:
                    o[b] = o[b] + eps * v
        return o
    return sim
