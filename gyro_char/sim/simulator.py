"""
The paper's bench model (docs/method.md, "The paper's simulation model") plus composable effects.

``simulate_swing`` gives a swing-stand run (IMU and encoder streams), ``simulate_static`` a
static record; both return a ``SimRun`` whose ``truth`` is the ``truth.json`` dict of
docs/design.md. Same config + seed + effects -> identical output; each noise source has
its own seeded stream, so adding an effect leaves the baseline noise of a seed unchanged.

Gyro chain (per axis, at the internal rate, sample instants t~ with Gaussian jitter):

    omega = (1 + drho) cos(dtheta + ddtheta) phi_st'(t~) + w0H + wdot0H t~ + noise(N,B,K,Q,R)

then effects, the sensor's own processing, decimation to the output rate and output
quantization dH. The paper's white in-run bias instability ddw0H (one Gaussian draw per sample)
is the IEEE white term N of ``noise``: sigma = N / sqrt(dt) at the sensor's internal rate.
The paper's formula has no scale-factor error (only cos dtheta); a real gyro has one
(``gyro.scale_factor_error``). ``truth.swing.scale_factor_error`` is what the method measures:
(1 + drho) cos(dtheta) exp(-sigma_ddtheta^2 / 2) - 1 (the last factor is E[cos] of the white
misalignment instability). Static records use ``gyro.bias`` and the IEEE terms only:
``gyro.bias_drift`` is the swing-run drift (the paper's Table 1), a static ramp is the term R.

Truth N includes the output quantization's white contribution dH^2 dt / 12 (added in
quadrature) when the per-sample noise is at least half a step (so the error is white).
"""
from dataclasses import dataclass
from typing import Iterable, Optional, Sequence

from gyro_char.errors import InputError
from gyro_char.progress import progress
from gyro_char.records import (ACCEL_CHANNELS, ENCODER_CHANNEL, GYRO_CHANNELS, IMU_CHANNELS,
                               Recording)
from gyro_char.sim import noise_gen
from gyro_char.sim.chain import (encoder_reading, quantize, quantizer_mean_error, sample_times,
                                 specific_force, stand_angle_clean, stand_motion,
                                 stand_rate_clean)
from gyro_char.sim.config import AXES, BenchConfig, load
from gyro_char.sim.effects import build_effects, Effect, SimContext
import numpy as np


# A run holds ~25 float64 arrays of its length at peak (chain + FFT of the 1/f generator):
# 2e7 samples is ~4 GB, the most a run may take on a desktop.
MAX_SAMPLES = 20_000_000


@dataclass
class SimRun:
    """One simulated run: IMU stream, encoder stream (swing only) and the truth dict."""

    imu: Recording
    encoder: Optional[Recording]
    truth: dict
    # Swing runs: this run's own bias and drift (rad/s, rad/s^2) - the parameters plus the
    # least-squares line through the realized correlated noise (B, K, Q, R terms) of the swing
    # axis over the run. The white noise is what an estimator's sigma covers; the correlated
    # noise of one run is a real bias/drift of that run which truth.json's parameters omit.
    realized: Optional[dict] = None


def _config(config) -> BenchConfig:
    if config is None:
        return load()
    if isinstance(config, str):
        return load(preset_name=config)
    if not isinstance(config, BenchConfig):
        raise InputError(f'config must be a BenchConfig or a preset name, got {config!r}')
    return config


def _check_run(duration: float, seed: int, rate: float) -> int:
    if not np.isfinite(duration) or duration <= 0:
        raise InputError(f'duration must be > 0 s, got {duration}')
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise InputError(f'seed must be a non-negative integer, got {seed!r}')
    n = int(round(duration * rate))
    if n < 2:
        raise InputError(f'duration {duration} s gives fewer than 2 samples at {rate} Hz')
    if n > MAX_SAMPLES:
        raise InputError(f'{duration:g} s at {rate:g} Hz is {n} samples, more than one '
                         f'in-memory run holds ({MAX_SAMPLES}, ~200 bytes each); simulate '
                         'shorter runs')
    return n


def _select(channels: Optional[Iterable[str]]) -> tuple:
    if channels is None:
        return IMU_CHANNELS
    chosen = tuple(channels)
    bad = [c for c in chosen if c not in IMU_CHANNELS]
    if bad:
        raise InputError(f'unknown channel(s) {bad}; known: {", ".join(IMU_CHANNELS)}')
    return chosen


def simulate_swing(config=None, *, duration: float = 900.0, seed: int = 0,
                   effects: Sequence = (), channels: Optional[Iterable[str]] = None,
                   quiet: bool = True, stamp_latency=None) -> SimRun:
    """
    Simulate a swing-stand run: IMU at ``gyro.rate_hz``, encoder at ``encoder.rate_hz``.

    ``channels`` limits the IMU channels generated (e.g. ``('gyro_x',)`` for fast Monte Carlo
    runs); the default is all six. ``stamp_latency`` (s, one value an IMU sample) is the
    host latency trace a ``time_delay`` with ``stall_gain`` puts into the stamps.
    """
    cfg = _config(config)
    fx = build_effects(effects)
    n = _check_run(duration, seed, cfg.gyro.rate_hz)
    ctx = SimContext(config=cfg, kind='swing', seed=int(seed), dt=1.0 / cfg.gyro.rate_hz,
                     axis=AXES.index(cfg.gyro.axis))
    if stamp_latency is not None:
        ctx.extras['stamp_latency'] = stamp_latency
    ctx.stand_angle = lambda t: stand_angle_clean(cfg.stand, t)
    ctx.stand_rate = lambda t: stand_rate_clean(cfg.stand, t)
    imu, truth_channels = _imu_chain(cfg, ctx, fx, n, _select(channels), quiet)

    ne = int(round(duration * cfg.encoder.rate_hz))
    te = sample_times(ne, 1.0 / cfg.encoder.rate_hz, cfg.encoder.jitter_s,
                      ctx.rng('jitter:encoder'))
    angle, _, _ = stand_motion(cfg.stand, te, ctx.rng('stand:encoder'))
    for effect in fx:
        angle = effect.encoder_angle(ctx, te, angle)
    reading = encoder_reading(cfg.encoder, angle, ctx.rng('encoder:adc'))
    stamps = te
    for effect in fx:
        stamps = effect.encoder_stamps(ctx, stamps)
    encoder = Recording(stamps, {ENCODER_CHANNEL: reading}, source='bench_sim:encoder')

    g = cfg.gyro
    a = g.axis
    sigma = g.misalignment_noise
    truth = _truth('swing', cfg, seed, fx, truth_channels)
    truth['swing'] = {
        'scale_factor_error': float((1.0 + g.scale_factor_error[a]) * np.cos(g.misalignment)
                                    * np.exp(-0.5 * sigma * sigma) - 1.0),
        'bias': float(g.bias[a] + quantizer_mean_error(g.output_step, g.quantizer)),
        'bias_drift': float(g.bias_drift[a]),
        'period_s': float(cfg.stand.period_s),
        'amplitude': float(cfg.stand.amplitude),
    }
    for effect in fx:
        effect.update_truth(ctx, truth)
    realized = {'bias': truth['swing']['bias'], 'bias_drift': truth['swing']['bias_drift']}
    part = ctx.extras.get('colored_axis_noise')
    if part is not None:
        t = ctx.t - ctx.t.mean()
        slope = float(np.dot(t, part - part.mean()) / np.dot(t, t))
        realized['bias'] += float(part.mean() - slope * ctx.t.mean())
        realized['bias_drift'] += slope
    return SimRun(imu=imu, encoder=encoder, truth=truth, realized=realized)


def simulate_static(config=None, *, duration: float = 3 * 3600.0, seed: int = 0,
                    effects: Sequence = (), channels: Optional[Iterable[str]] = None,
                    quiet: bool = True) -> SimRun:
    """Simulate a static record at ``gyro.static_rate_hz`` (sensor level, at rest, z up)."""
    cfg = _config(config)
    fx = build_effects(effects)
    n = _check_run(duration, seed, cfg.gyro.static_rate_hz)
    ctx = SimContext(config=cfg, kind='static', seed=int(seed),
                     dt=1.0 / cfg.gyro.static_rate_hz, axis=AXES.index(cfg.gyro.axis))
    imu, truth_channels = _imu_chain(cfg, ctx, fx, n, _select(channels), quiet)
    truth = _truth('static', cfg, seed, fx, truth_channels)
    for effect in fx:
        effect.update_truth(ctx, truth)
    return SimRun(imu=imu, encoder=None, truth=truth)


def _imu_chain(cfg: BenchConfig, ctx: SimContext, fx: Sequence[Effect], n: int,
               channels: tuple, quiet: bool = True):
    """Run the gyro and accelerometer chain; return the IMU Recording and truth channels."""
    ctx.oversample = max([1] + [int(e.oversample(ctx)) for e in fx])
    d = ctx.oversample
    dti = ctx.dt_internal
    ni = n * d
    if ni > MAX_SAMPLES:
        raise InputError(f'{n} output samples x {d} internal samples each is more than one '
                         f'in-memory run holds ({MAX_SAMPLES}); simulate shorter runs')
    g = cfg.gyro
    t = sample_times(ni, dti, g.jitter_s, ctx.rng('jitter:gyro'),
                     start=g.start_s if ctx.kind == 'swing' else 0.0)
    ctx.t = t
    ctx.t_out = t[d - 1::d]
    true_rate = np.zeros((3, ni))
    if ctx.kind == 'swing':
        angle, rate, _ = stand_motion(cfg.stand, t, ctx.rng('stand:gyro'))
        true_rate[ctx.axis] = rate
    else:
        angle = np.zeros(ni)
    ctx.angle = angle
    ctx.true_rate = true_rate
    ctx.specific_force = specific_force(ctx.axis, angle)

    gyro = np.empty((3, ni))
    for i, ax in enumerate(AXES):
        gyro[i] = g.bias[ax]
        if ctx.kind == 'swing':
            gyro[i] += g.bias_drift[ax] * t
    if ctx.kind == 'swing':
        mis = np.full(ni, g.misalignment)
        if g.misalignment_noise > 0:
            mis += g.misalignment_noise * ctx.rng('gyro:misalignment').standard_normal(ni)
        gyro[ctx.axis] += (1.0 + g.scale_factor_error[g.axis]) * np.cos(mis) \
            * true_rate[ctx.axis]
    accel = ctx.specific_force.copy()
    for i, ax in enumerate(AXES):
        accel[i] += cfg.accel.bias[ax]
    bar = progress(IMU_CHANNELS, desc=f'simulating {ctx.kind} noise', quiet=quiet,
                   unit='channel')
    for i, name in enumerate(bar):
        if name not in channels:
            continue
        terms = cfg.channel_terms(name)
        if not any(terms.values()):
            continue
        # White part, then the correlated terms, from one stream (the draws come in the same
        # order as one generate() call); the correlated part of the swing axis is kept to
        # state this run's own bias and drift (SimRun.realized).
        rng = ctx.rng(f'noise:{name}')
        noise = noise_gen.generate(ni, dti, N=terms['N'], rng=rng) if terms['N'] else 0.0
        colored = {k: v for k, v in terms.items() if k != 'N' and v}
        if colored:
            part = noise_gen.generate(ni, dti, rng=rng, **colored)
            noise = noise + part
            if i == ctx.axis:
                ctx.extras['colored_axis_noise'] = part
        if i < 3:
            gyro[i] += noise
        else:
            accel[i - 3] += noise

    for effect in fx:
        gyro, accel = effect.sensor(ctx, gyro, accel)
    for effect in fx:
        gyro, accel = effect.internal(ctx, gyro, accel)
    if d > 1:
        gyro, accel = gyro[:, d - 1::d], accel[:, d - 1::d]
    for effect in sorted(fx, key=lambda e: e.output_stage):
        gyro, accel = effect.output(ctx, gyro, accel)
    gyro = quantize(gyro, g.output_step, g.quantizer)
    accel = quantize(accel, cfg.accel.output_step, 'round')
    stamps = ctx.t_out
    for effect in fx:
        stamps = effect.stamps(ctx, stamps)
    if np.any(np.diff(stamps) <= 0):
        raise InputError('the effects made the IMU stamps non-increasing; reduce the '
                         'timestamp jitter')
    data = {}
    for i, name in enumerate(IMU_CHANNELS):
        if name in channels:
            data[name] = gyro[i] if i < 3 else accel[i - 3]
    imu = Recording(stamps, data, source=f'bench_sim:{ctx.kind}')
    truth_channels = {name: _truth_terms(cfg, name, ctx.dt) for name in channels}
    return imu, truth_channels


def _truth_terms(cfg: BenchConfig, name: str, dt: float) -> dict:
    terms = cfg.channel_terms(name)
    step = cfg.gyro.output_step if name in GYRO_CHANNELS else cfg.accel.output_step
    if step and name in GYRO_CHANNELS + ACCEL_CHANNELS:
        white_sigma = terms['N'] / np.sqrt(dt)
        if white_sigma >= 0.5 * step:
            terms['N'] = float(np.hypot(terms['N'], step * np.sqrt(dt / 12.0)))
    return {k: float(v) for k, v in terms.items()}


def _truth(kind: str, cfg: BenchConfig, seed: int, fx: Sequence[Effect],
           channels: dict) -> dict:
    return {'kind': kind, 'channels': channels, 'effects': [e.describe() for e in fx],
            'preset': cfg.preset, 'seed': int(seed)}
