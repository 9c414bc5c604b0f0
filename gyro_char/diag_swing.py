"""
The swing kind of the diagnosis: baseline fit, simulated twins, the problem for the engine.

Baseline = the paper's swing model fitted to the record: the 5-state Kalman estimates
(``swing_kf.estimate_swing``: scale-factor error, bias, drift, the gyro's white noise N and the
encoder's angle noise) put into the bench simulator (``bench_sim.simulate_swing``) with the
record's amplitude, period, rates and output step. Everything else is for the effects.
Observables: ``gyro_char.diag_swing_obs``; candidate effects' search spaces:
``gyro_char.diag_swing_spaces``.
"""
from dataclasses import dataclass, replace
from typing import Optional, Sequence

from gyro_char import bench_sim
from gyro_char.diag_static import output_step, twin_effects
from gyro_char.diag_swing_obs import layout, PSD_BINS, swing_observables, UNITS
from gyro_char.diag_swing_spaces import signs, swing_spaces
from gyro_char.diagnose import Problem
from gyro_char.recordings import ENCODER_CHANNEL, InputError, Recording
from gyro_char.sim_config import BenchConfig
from gyro_char.swing_kf import estimate_swing
import numpy as np

SWING_EFFECTS = ('time_delay', 'g_sensitivity', 'scale_factor_nonlinearity',
                 'scale_factor_asymmetry', 'encoder_cyclic_error', 'timestamp_jitter')
PRESET = 'adis16405'  # structure only: the fitted numbers override what matters


@dataclass
class SwingBaseline:
    """The paper's swing model fitted to one record (SI)."""

    period_s: float
    amplitude: float
    scale_factor_error: float
    bias: float
    drift: float
    N: float
    encoder_sigma: float
    lsb: float
    dt: float
    encoder_dt: float
    duration: float
    axis: str

    def to_json(self) -> dict:
        units = {'period_s': 's', 'amplitude': 'rad', 'scale_factor_error': '1',
                 'bias': 'rad/s', 'drift': 'rad/s^2', 'N': 'rad/s^0.5', 'encoder_sigma': 'rad',
                 'lsb': 'rad/s', 'dt': 's', 'encoder_dt': 's', 'duration': 's'}
        return {k: {'value': float(getattr(self, k)), 'unit': u} for k, u in units.items()}


def fit_baseline(imu: Recording, encoder: Recording, period_s: float,
                 axis: Optional[str] = None) -> SwingBaseline:
    run = estimate_swing(imu, encoder, period_s, axis)
    al = run.aligned
    # Mean sample intervals, not medians: a twin whose encoder and gyro rates differ by a
    # jitter-sized amount drifts through the interpolation phase and reshapes the residual PSD.
    dt = float((al.tau_gyro[-1] - al.tau_gyro[0]) / (al.tau_gyro.size - 1))
    lsb = output_step(al.rate_gyro)
    est = run.estimates
    # The filter's N covers the output rounding too (lsb^2 dt / 12); the twin adds it back.
    n2 = est.noise_gyro_arw ** 2 - lsb ** 2 * dt / 12.0
    return SwingBaseline(
        period_s=float(period_s), amplitude=float(est.amplitude_encoder.value),
        scale_factor_error=float(est.scale_factor_error.value), bias=float(est.bias.value),
        drift=float(est.bias_drift.value),
        N=float(np.sqrt(max(n2, 0.01 * est.noise_gyro_arw ** 2))),
        encoder_sigma=float(est.noise_encoder_rad), lsb=lsb, dt=dt,
        encoder_dt=float((al.tau_encoder[-1] - al.tau_encoder[0]) / (al.tau_encoder.size - 1)),
        duration=float(min(al.tau_gyro[-1], al.tau_encoder[-1])) + dt,
        axis=al.axis.replace('gyro_', ''))


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
        'noise': {ch: {'N': base.N, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}},
    })
    cfg.encoder.adc_noise = encoder_white_sigma(base, cfg)
    return cfg


def simulate_twin(base: SwingBaseline, effects: Sequence, seed: int):
    """IMU and encoder recordings of a twin: the baseline plus ``effects``."""
    run = bench_sim.simulate_swing(twin_config(base), duration=base.duration,
                                   seed=int(seed), effects=twin_effects(effects),
                                   channels=(f'gyro_{base.axis}',))
    return run.imu, run.encoder


def _obs(imu: Recording, encoder: Recording, base: SwingBaseline, ranges: dict) -> dict:
    return swing_observables(imu.t, imu.channels[f'gyro_{base.axis}'], encoder.t,
                             encoder.channels[ENCODER_CHANNEL], base.period_s, ranges)


def _white(o: dict) -> float:
    return float(np.mean(10 ** o['residual_psd'][: PSD_BINS // 2]))


def encoder_white_sigma(base: SwingBaseline, cfg: BenchConfig) -> float:
    """
    Return the encoder ADC noise that gives the filter's encoder noise estimate in a twin.

    The estimate lumps the stand's white amplitude noise (seen as A_noise^2 / 2 on average
    over the swing) and both quantizations with the ADC noise; the twin adds those again.
    """
    st, en = cfg.stand, cfg.encoder
    other = st.amplitude_noise ** 2 / 2 + en.level_step ** 2 / 12 + en.word_step ** 2 / 12
    return float(np.sqrt(max(base.encoder_sigma ** 2 - other, 0.0)))


def calibrate_n(base: SwingBaseline, real: dict, ranges: dict,
                seeds: Sequence[int] = (901, 902, 903)) -> SwingBaseline:
    """
    Rescale N so that the twins' residual PSD in the gyro band matches the record's.

    The gyro filter's N is estimated from the angle residuals, which also carry the stand's
    and the encoder's noise; the white band of the residual rate (1 Hz to ~10 % of the sample
    rate, where the gyro's white noise dominates) pins it to about 1 %.
    """
    sims = [_white(_obs(*simulate_twin(base, [], s), base, ranges)) for s in seeds]
    return replace(base, N=base.N * float(np.sqrt(_white(real) / np.mean(sims))))


def swing_problem(imu: Recording, encoder: Recording, period_s: float, *,
                  axis: Optional[str] = None, max_samples: Optional[int] = None,
                  names: Sequence[str] = SWING_EFFECTS,
                  base: Optional[SwingBaseline] = None) -> Problem:
    """
    Build the diagnosis problem for one swing record (IMU + encoder).

    Records longer than ``max_samples`` gyro samples are cut to that span from the start of
    the overlap (twins are simulated at the same length).
    """
    if encoder is None or ENCODER_CHANNEL not in encoder.channels:
        raise InputError('the swing diagnosis needs the encoder angle of the stand')
    if max_samples and len(imu) > max_samples:
        t_end = imu.t[0] + (max_samples - 1) * float(np.median(np.diff(imu.t)))
        imu = Recording(imu.t[imu.t <= t_end],
                        {c: v[imu.t <= t_end] for c, v in imu.channels.items()},
                        imu.source, list(imu.notes))
        keep = encoder.t <= t_end
        encoder = Recording(encoder.t[keep], {ENCODER_CHANNEL: encoder.channels[
            ENCODER_CHANNEL][keep]}, encoder.source, list(encoder.notes))
    fitted = base is None
    if fitted:
        base = fit_baseline(imu, encoder, period_s, axis)
    ch = f'gyro_{base.axis}'
    if ch not in imu.channels:
        raise InputError(f'no {ch} channel in the IMU input')
    n_min = 8 * 256
    if len(imu) < n_min:
        raise InputError(f'swing record too short for the diagnosis: {len(imu)} samples '
                         f'(need >= {n_min})')
    ranges = layout(len(imu), base.dt, base.period_s)
    real = _obs(imu, encoder, base, ranges)
    if fitted:
        base = calibrate_n(base, real, ranges)

    def sim(effects: list, seed: int) -> dict:
        return _obs(*simulate_twin(base, effects, seed), base, ranges)

    spaces = [s for s in swing_spaces(base) if s.name in names]
    spaces = signs(spaces, [real], lambda i, fx, s: sim(fx, s))
    return Problem(kind='swing', reals=[real], simulate=lambda i, fx, s: sim(fx, s),
                   spaces=spaces, ranges=[ranges], units=dict(UNITS),
                   baseline=base.to_json(), context=base)
