"""
The swing twins' runs of the stand alone, and the gyro white noise a candidate's twin restores.

The baseline's N is pinned on the record's residual PSD (``swing_calibrate.calibrate_n``), so
it holds whatever the record's effects did to that PSD: a gyro lag's colouring took some of
it, a full-scale limit held the output still for part of the time, a rate-dependent noise
added its own. A twin applying such a candidate starts from N² times the gain that undoes
this (``twin_noise_gain``), or it counts the effect's share of the noise twice.
"""
from dataclasses import replace
from typing import List, Sequence

from gyro_char.diagnosis.swing_baseline import SwingBaseline
from gyro_char.diagnosis.swing_obs import layout
from gyro_char.diagnosis.swing_rate_noise import rate_noise_gain
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
import numpy as np

SPAN_S = 60.0           # span of the noise-free effect runs (whole periods, at least 8)


def clean_config(cfg: BenchConfig) -> BenchConfig:
    """
    ``cfg`` with every noise and quantization off: the stand's motion only.

    The sampling jitter of the instants stays (values and stamps agree, so it adds no error,
    but it spreads where the gyro stamps fall between encoder samples, which sets how much of
    an encoder stamp error the interpolation passes on).
    """
    g = replace(cfg.gyro, output_step=0.0, misalignment_noise=0.0)
    e = replace(cfg.encoder, adc_noise=0.0, level_step=0.0, word_step=0.0)
    st = replace(cfg.stand, amplitude_noise=0.0, drift_rate_noise=0.0)
    noise = {ch: dict.fromkeys(v, 0.0) for ch, v in cfg.noise.items()}
    return replace(cfg, gyro=g, encoder=e, stand=st, noise=noise)


def noise_config(cfg: BenchConfig) -> BenchConfig:
    """``clean_config`` with the gyro's noise terms kept: the motion and the gyro noise."""
    return replace(clean_config(cfg), noise=cfg.noise)


def lag_gain(lag_s: float, dt: float, period_s: float) -> float:
    """
    Return the gyro noise power a lag candidate's twin restores: 1 / median |H|² of the bins.

    The baseline's N is pinned on the record's residual PSD by the median bin ratio against a
    WHITE twin (``swing_calibrate.calibrate_n``); a record whose gyro has the one-pole H reads
    N² times that median of |H|², so a twin that applies H must start from N² over it
    (measured: a 5 ms lag left the twins' low PSD bins 17 % short without this).
    """
    if not lag_s:
        return 1.0
    a = lag_s / (lag_s + dt)
    f = np.sqrt(np.prod(layout(0, dt, period_s)['residual_psd'], axis=1))
    h2 = (1 - a) ** 2 / (1 - 2 * a * np.cos(2 * np.pi * f * dt) + a * a)
    return float(1.0 / np.median(h2))


def limits_of(effects: Sequence[dict]) -> List[dict]:
    """Return the effects (simulator specs) that hold a full-scale limit (``range_rads``)."""
    return [fx for fx in effects if fx['params'].get('range_rads', 0)]


def limit_gain(cfg: BenchConfig, limits: list, axis: str, duration: float) -> float:
    """
    Return the gyro noise power a limit candidate's twin restores: 1 / the time it is free.

    Where the output sits at its limit its noise is gone, so the baseline's N, pinned on the
    clipped record's residual PSD, is the sensor's times the root of the share of time the
    output moves; a twin that applies the limit must start from N² over that share, or it
    cuts the noise twice (measured: 13 % of the time at the limit on held-out set I's
    strong clip). The share from a noise-free run of ``limits`` over ``duration``.
    """
    run = simulator.simulate_swing(clean_config(cfg), seed=0, duration=duration,
                                   effects=limits, channels=(f'gyro_{axis}',))
    x = run.imu.channels[f'gyro_{axis}']
    p = limits[0]['params']
    hi = float(p['range_rads'])
    lo = float(p.get('range_low_rads', 0.0)) or hi
    held = (x >= hi * (1 - 1e-9)) | (x <= -lo * (1 - 1e-9))
    return float(1.0 / max(1.0 - held.mean(), 0.1))


def span(base: SwingBaseline) -> float:
    """Duration of the noise-free effect runs: whole periods, >= ``SPAN_S`` and 8 periods."""
    k = int(np.ceil(max(SPAN_S, 8.0 * base.period_s) / base.period_s))
    return float(min(k * base.period_s + 2.0 * base.dt, base.duration))


def twin_noise_gain(cfg: BenchConfig, base: SwingBaseline, effects: Sequence[dict]) -> float:
    """
    Return the gyro white power a twin of ``effects`` (simulator specs) starts from, over N².

    The product of the gyro lags' ``lag_gain``, the full-scale limit's ``limit_gain`` (read
    off a noise-free run of ``cfg``) and the rate noise's ``rate_noise_gain``.
    """
    gain = rate_noise_gain(effects, base)
    for fx in effects:
        if fx['name'] == 'time_delay':
            gain *= lag_gain(float(fx['params'].get('lag_s', 0.0)), base.dt, base.period_s)
    limits = limits_of(effects)
    if limits:
        gain *= limit_gain(cfg, limits, base.axis, span(base))
    return gain
