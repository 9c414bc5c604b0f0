"""
The swing twins: the bench simulator configured as a fitted baseline, and what is read off a run.

A twin is the paper's swing model at the baseline's numbers plus candidate effects; a run
(record or twin) is read through ``record_residuals`` / ``record_observables`` (the residual
streams of ``swing_residuals``, observables of ``swing_obs``) and ``record_scale`` (its
least-squares scale).
"""
from typing import Sequence

from gyro_char.diagnosis.swing_baseline import PRESET, SwingBaseline
from gyro_char.diagnosis.swing_gains import twin_noise_gain
from gyro_char.diagnosis.swing_obs import swing_observables
from gyro_char.diagnosis.swing_residuals import residuals, solve_columns
from gyro_char.diagnosis.twins import twin_effects
from gyro_char.records import ENCODER_CHANNEL, Recording
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
from gyro_char.swing.align import integrate
import numpy as np


def twin_config(base: SwingBaseline) -> BenchConfig:
    """Return the bench simulator's config for a twin: the paper's swing model only."""
    a = base.axis
    ch = f'gyro_{a}'
    # Stand: the record's amplitude and period; encoder: its rate and white noise (the
    # preset's level/word steps kept: a record does not reveal them below its noise).
    cfg = BenchConfig.from_preset(PRESET, {
        'stand': {'amplitude': base.amplitude, 'period_s': base.period_s},
        'encoder': {'rate_hz': 1.0 / base.encoder_dt},
        'gyro': {'rate_hz': 1.0 / base.dt, 'axis': a, 'output_step': base.lsb,
                 'quantizer': 'round', 'misalignment': 0.0,
                 'scale_factor_error': {a: base.scale_factor_error},
                 'bias': {a: base.bias}, 'bias_drift': {a: base.drift}},
        'noise': {ch: {'N': base.N, 'B': base.B, 'K': base.K, 'Q': 0.0, 'R': 0.0}},
    })
    cfg.encoder.adc_noise = encoder_white_sigma(base, cfg)
    cfg.gyro.start_s = base.gyro_start
    return cfg


def simulate_twin(base: SwingBaseline, effects: Sequence, seed: int):
    """
    IMU and encoder recordings of a twin: the baseline plus ``effects``.

    A stamp delay candidate starts the gyro's instants that much earlier, so that its stamps
    fall where the record's do (``stamp_offset`` measured them delay included); a gyro lag
    (``lag_s``) leaves the stamps alone; a lag, a full-scale limit and a rate-dependent
    noise set the twin's gyro white noise (``swing_gains.twin_noise_gain``).
    """
    cfg = twin_config(base)
    specs = twin_effects(effects)
    # The gain is read off noise-free runs of this config (its noise set to zero there).
    cfg.noise[f'gyro_{base.axis}']['N'] *= np.sqrt(twin_noise_gain(cfg, base, specs))
    cfg.gyro.start_s -= sum(float(p.get('delay_s', 0.0)) - float(p.get('lag_s', 0.0))
                            for n, p in effects if n == 'time_delay')
    run = simulator.simulate_swing(cfg, duration=base.duration,
                                   seed=int(seed), effects=specs,
                                   channels=(f'gyro_{base.axis}',),
                                   stamp_latency=base.stall_trace)
    return run.imu, run.encoder


def encoder_white_sigma(base: SwingBaseline, cfg: BenchConfig) -> float:
    """
    Return the encoder ADC noise that gives the filter's encoder noise estimate in a twin.

    The estimate lumps the stand's white amplitude noise (seen as A_noise^2 / 2 on average
    over the swing) and both quantizations with the ADC noise; the twin adds those again.
    """
    st, en = cfg.stand, cfg.encoder
    other = st.amplitude_noise ** 2 / 2 + en.level_step ** 2 / 12 + en.word_step ** 2 / 12
    return float(np.sqrt(max(base.encoder_sigma ** 2 - other, 0.0)))


def record_observables(imu: Recording, encoder: Recording, base: SwingBaseline,
                       ranges: dict) -> dict:
    """Return the observables (``swing_obs``) of a run of the baseline's axis and period."""
    return swing_observables(imu.t, imu.channels[f'gyro_{base.axis}'], encoder.t,
                             encoder.channels[ENCODER_CHANNEL], base.period_s, ranges)


def record_residuals(imu: Recording, encoder: Recording, base: SwingBaseline):
    """Return the residual streams (``swing_residuals.Residuals``) of a run."""
    return residuals(imu.t, imu.channels[f'gyro_{base.axis}'], encoder.t,
                     encoder.channels[ENCODER_CHANNEL], base.period_s)


def record_scale(imu: Recording, encoder: Recording, axis: str) -> float:
    """
    Least-squares scale of the gyro angle on the encoder angle (plus a quadratic trend), - 1.

    The scale the observables' residual fit removes; across records of one gyro it moves only
    with what the paper's model lacks (a rate-dependent scale factor).
    """
    t_g, t_e = imu.t, encoder.t
    lo, hi = max(t_g[0], t_e[0]), min(t_g[-1], t_e[-1])
    m = (t_g >= lo) & (t_g <= hi)
    tau = t_g[m] - lo
    ang = integrate(tau, imu.channels[f'gyro_{axis}'][m])
    e = np.interp(tau, t_e - lo, encoder.channels[ENCODER_CHANNEL])
    ts = tau / max(tau[-1], 1e-9)
    coef = solve_columns([e - e.mean(), np.ones_like(ts), ts - 0.5, ts * ts - 1.0 / 3.0], ang)
    return float(coef[0] - 1.0)
