"""
The swing kind of the diagnosis: baseline fit, simulated twins, the problem for the engine.

Baseline = the paper's swing model fitted to the record(s): the 5-state Kalman estimates
(``swing.filter.estimate_swing``: scale-factor error, bias, drift, the gyro's white noise N and the
encoder's angle noise) put into the bench simulator (``simulator.simulate_swing``) with each
record's amplitude, period, rates and output step, plus the gyro's bias instability and rate
random walk, which a swing record cannot pin (``swing_baseline.static_noise``). Everything else
is for the effects.
Observables: ``gyro_char.diagnosis.swing_obs``; candidate effects' search spaces:
``gyro_char.diagnosis.swing_spaces``.

Several records of the same gyro (other amplitudes and/or periods) are diagnosed together: the
paper's model has ONE scale-factor error per gyro, so every twin gets the inverse-variance mean
of the records' Kalman estimates, while bias, drift and noise levels stay per record; the effect
parameters are shared by all records (the engine pools the blocks). A scale factor that depends
on the rate (nonlinearity) then shows as a departure of the ``scale_factor_shift`` block - each
further record's least-squares scale factor minus the first record's - and the cos θ residual
of a delay (∝ A ω) and of a g-sensitivity (∝ g A / ω) no longer match on both periods.
"""
from dataclasses import replace
from typing import Optional, Sequence, Tuple

from gyro_char.diagnosis.engine import Problem
from gyro_char.diagnosis.swing_baseline import PRESET, static_noise, SwingBaseline
from gyro_char.diagnosis.swing_expect import EffectParts, lag_gain, pseudo_twin
from gyro_char.diagnosis.swing_obs import (
    layout, raw_parts, residuals, swing_observables, UNITS, unlocked_psd)
from gyro_char.diagnosis.swing_spaces import signs, swing_spaces, unresolved_pairs
from gyro_char.diagnosis.twins import output_step, twin_effects
from gyro_char.errors import InputError
from gyro_char.records import ENCODER_CHANNEL, Recording
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
from gyro_char.swing.align import integrate
from gyro_char.swing.filter import estimate_swing
import numpy as np

SWING_EFFECTS = ('time_delay', 'g_sensitivity', 'scale_factor_nonlinearity',
                 'scale_factor_asymmetry', 'encoder_cyclic_error', 'timestamp_jitter')


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
        record_scale_factor_error=float(est.scale_factor_error.value),
        record_scale_factor_sigma=float(est.scale_factor_error.sigma),
        drift=float(est.bias_drift.value),
        N=float(np.sqrt(max(n2, 0.01 * est.noise_gyro_arw ** 2))),
        encoder_sigma=float(est.noise_encoder_rad), lsb=lsb, dt=dt,
        encoder_dt=float((al.tau_encoder[-1] - al.tau_encoder[0]) / (al.tau_encoder.size - 1)),
        duration=float(min(al.tau_gyro[-1], al.tau_encoder[-1])) + dt,
        axis=al.axis.replace('gyro_', ''), gyro_start=stamp_offset(imu.t, encoder.t),
        **static_noise(al.axis))


def stamp_offset(t_g: np.ndarray, t_e: np.ndarray, count: int = 4096) -> float:
    """
    Where the gyro stamps fall in the encoder's sample interval at the start of the overlap (s).

    The residual interpolates the encoder at the gyro stamps: how much of the encoder's
    white noise passes into it, and how it correlates from sample to sample, depend on that
    position (at one rate, a gyro stamp 0.2 intervals after each encoder sample smooths the
    encoder noise: measured lag-1 increment correlation z = 98 on a 15-min 1 kHz run against
    twins whose stamps coincided). The circular mean of the first ``count`` positions.
    """
    lo = max(t_g[0], t_e[0])
    te = t_e[t_e >= lo]
    tg = t_g[t_g >= lo][:count]
    if te.size < 2 or tg.size < 1:
        return 0.0
    # The mean interval over the whole record: a median of jittered intervals is off by
    # parts in 1e4, which over thousands of samples moves the phase by whole cycles.
    dte = float((te[-1] - te[0]) / (te.size - 1))
    j = np.arange(min(te.size, count))
    grid = float(np.mean(te[:j.size] - j * dte))     # the encoder's grid, not one stamp
    ph = np.exp(2j * np.pi * (tg - grid) / dte)
    return float(np.angle(np.mean(ph)) % (2.0 * np.pi) / (2.0 * np.pi) * dte)


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
    (``lag_s``) leaves the stamps alone and restores the noise the N calibration took for
    the lag's (``swing_expect.lag_gain``).
    """
    cfg = twin_config(base)
    ch = f'gyro_{base.axis}'
    for n, p in effects:
        if n == 'time_delay':
            cfg.noise[ch]['N'] *= np.sqrt(lag_gain(float(p.get('lag_s', 0.0)), base.dt,
                                                   base.period_s))
    cfg.gyro.start_s -= sum(float(p.get('delay_s', 0.0)) - float(p.get('lag_s', 0.0))
                            for n, p in effects if n == 'time_delay')
    run = simulator.simulate_swing(cfg, duration=base.duration,
                                   seed=int(seed), effects=twin_effects(effects),
                                   channels=(f'gyro_{base.axis}',))
    return run.imu, run.encoder


def _obs(imu: Recording, encoder: Recording, base: SwingBaseline, ranges: dict) -> dict:
    return swing_observables(imu.t, imu.channels[f'gyro_{base.axis}'], encoder.t,
                             encoder.channels[ENCODER_CHANNEL], base.period_s, ranges)


def _residuals(imu: Recording, encoder: Recording, base: SwingBaseline):
    return residuals(imu.t, imu.channels[f'gyro_{base.axis}'], encoder.t,
                     encoder.channels[ENCODER_CHANNEL], base.period_s)


def encoder_white_sigma(base: SwingBaseline, cfg: BenchConfig) -> float:
    """
    Return the encoder ADC noise that gives the filter's encoder noise estimate in a twin.

    The estimate lumps the stand's white amplitude noise (seen as A_noise^2 / 2 on average
    over the swing) and both quantizations with the ADC noise; the twin adds those again.
    """
    st, en = cfg.stand, cfg.encoder
    other = st.amplitude_noise ** 2 / 2 + en.level_step ** 2 / 12 + en.word_step ** 2 / 12
    return float(np.sqrt(max(base.encoder_sigma ** 2 - other, 0.0)))


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
    median on a lock-in record before the phase mean came out).
    """
    def psd(rec_imu, rec_enc):
        return unlocked_psd(_residuals(rec_imu, rec_enc, base), ranges)

    sims = [psd(*simulate_twin(base, [], s)) for s in seeds]
    ratio = float(np.median(psd(imu, encoder) / np.mean(sims, axis=0)))
    return replace(base, N=base.N * float(np.sqrt(ratio)))


TURNING_COS = 0.05  # |cos θ| below this: within ~3° of phase of a turning point


def turning_noise(encoder: Recording, period_s: float) -> float:
    """
    Return the encoder's white angle noise at the swing's turning points (rad).

    The mean square of the increments of the encoder's residual from its sine + trend fit,
    halved, over consecutive samples where the swing rate is under 5 % of its peak. Whatever
    scales with the rate (a stamp error reads as rate x error) vanishes there; white angle
    noise (ADC, quantization, the stand's amplitude noise) does not.
    """
    t = encoder.t - encoder.t[0]
    e = encoder.channels[ENCODER_CHANNEL]
    w = 2.0 * np.pi / period_s
    ts = t / max(t[-1], 1e-9)
    a = np.array([np.sin(w * t), np.cos(w * t), np.ones_like(t), ts, ts * ts])
    coef = np.linalg.solve(np.einsum('ik,jk->ij', a, a), np.einsum('ik,k->i', a, e))
    r = e - coef @ a
    slow = np.abs(np.cos(w * t + np.arctan2(coef[1], coef[0]))) < TURNING_COS
    pair = slow[1:] & slow[:-1]
    d = np.diff(r)[pair]
    return float(np.sqrt(np.mean(d * d) / 2.0)) if d.size >= 16 else float('nan')


def calibrate_encoder(base: SwingBaseline, encoder: Recording,
                      seeds: Sequence[int] = (901, 902, 903)) -> SwingBaseline:
    """
    Re-pin the twin's encoder white noise on the record's turning points.

    The filter's encoder noise lumps in everything white in the encoder residual over the
    whole swing: an encoder stamp jitter (rate x error, 6 to 36 times the ADC noise in the
    validation's jitter cases) would otherwise be built into the baseline twin, and a jitter
    candidate could only add more. The twins' turning-point noise (``turning_noise``) is
    matched to the record's by moving the ADC noise (variances add).
    """
    real = turning_noise(encoder, base.period_s)
    if not np.isfinite(real):
        return base
    sims = [turning_noise(simulate_twin(base, [], s)[1], base.period_s) for s in seeds]
    adc = encoder_white_sigma(base, twin_config(base))
    other = base.encoder_sigma ** 2 - adc ** 2
    adc2 = max(adc ** 2 + real ** 2 - float(np.mean(np.square(sims))), 0.0)
    return replace(base, encoder_sigma=float(np.sqrt(adc2 + max(other, 0.0))))


def pooled_scale_factor(bases: Sequence[SwingBaseline]) -> Tuple[float, float]:
    """Inverse-variance mean of the records' Kalman scale-factor errors, and its sigma."""
    sf = np.array([b.record_scale_factor_error for b in bases])
    sig = np.array([b.record_scale_factor_sigma for b in bases])
    if np.any(sig <= 0) or not np.all(np.isfinite(sig)):
        return float(np.mean(sf)), float(np.std(sf) / np.sqrt(sf.size))
    w = 1.0 / sig ** 2
    return float(np.sum(w * sf) / np.sum(w)), float(1.0 / np.sqrt(np.sum(w)))


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
    a = np.array([e - e.mean(), np.ones_like(ts), ts - 0.5, ts * ts - 1.0 / 3.0])
    coef = np.linalg.solve(np.einsum('ik,jk->ij', a, a), np.einsum('ik,k->i', a, ang))
    return float(coef[0] - 1.0)


def _cut(imu: Recording, encoder: Recording, max_samples: Optional[int]):
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
    n_min = 8 * 256
    if len(imu) < n_min:
        raise InputError(f'swing record too short for the diagnosis: {len(imu)} samples '
                         f'(need >= {n_min})')
    return imu, encoder


def swing_problem(imu: Recording, encoder: Recording, period_s: float, *,
                  axis: Optional[str] = None, max_samples: Optional[int] = None,
                  names: Sequence[str] = SWING_EFFECTS,
                  base: Optional[SwingBaseline] = None) -> Problem:
    """Build the diagnosis problem for one swing record (see ``swing_records_problem``)."""
    return swing_records_problem([(imu, encoder, period_s)], axis=axis,
                                 max_samples=max_samples, names=names,
                                 bases=None if base is None else [base])


def swing_records_problem(records: Sequence[Tuple[Recording, Recording, float]], *,
                          axis: Optional[str] = None, max_samples: Optional[int] = None,
                          names: Sequence[str] = SWING_EFFECTS,
                          bases: Optional[Sequence[SwingBaseline]] = None,
                          scale_factor: Optional[float] = None,
                          method: str = 'expected') -> Problem:
    """
    Build the diagnosis problem for swing records (IMU, encoder, period) of one gyro.

    Records longer than ``max_samples`` gyro samples are cut to that span from the start of
    the overlap (twins are simulated at the same length). ``bases`` (fitted elsewhere) are used
    as given; otherwise each record's baseline is fitted and every twin gets the pooled
    scale-factor error (``scale_factor`` when given, e.g. a held-out check's frozen value).
    ``problem.context`` is the list of the records' baselines (``samples``: gyro samples used).
    ``method='expected'`` scores candidates on pseudo-twins (``swing_expect``: the baseline
    twins' noise part, simulated once per seed, plus the effect's noise-free part);
    ``'twins'`` simulates every twin of every candidate in full (``problem.twin`` always does).
    """
    if method not in ('expected', 'twins'):
        raise InputError(f'unknown swing method {method!r}: expected or twins')
    records = [(*_cut(i, e, max_samples), float(p)) for i, e, p in records]
    fitted = bases is None
    if fitted:
        bases = [fit_baseline(i, e, p, axis) for i, e, p in records]
        sf = pooled_scale_factor(bases)[0] if scale_factor is None else float(scale_factor)
        bases = [replace(b, scale_factor_error=sf) for b in bases]
    bases = [replace(b, samples=len(imu)) for b, (imu, _, _) in zip(bases, records)]
    if len({b.axis for b in bases}) > 1:
        raise InputError(f'the records swing different gyro axes: {[b.axis for b in bases]}; '
                         'give --axis')
    ch = f'gyro_{bases[0].axis}'
    for imu, _, _ in records:
        if ch not in imu.channels:
            raise InputError(f'no {ch} channel in the IMU input {imu.source}')
    ranges = [layout(len(imu), b.dt, b.period_s) for (imu, _, _), b in zip(records, bases)]
    reals = [_obs(imu, enc, b, r) for (imu, enc, _), b, r in zip(records, bases, ranges)]
    if fitted:
        bases = [calibrate_n(calibrate_encoder(b, enc), imu, enc, r)
                 for b, (imu, enc, _), r in zip(bases, records, ranges)]
    # The rate dependence of the scale factor: each further record's scale against the first's.
    scales = [record_scale(imu, enc, b.axis) for (imu, enc, _), b in zip(records, bases)]
    for i in range(1, len(records)):
        reals[i]['scale_factor_shift'] = np.array([scales[i] - scales[0]])
        ranges[i]['scale_factor_shift'] = np.array([[bases[0].peak_rate, bases[i].peak_rate]])
    first_scale = {}  # (effects, seed) -> scale of the first record's twin

    def sim(i: int, effects: list, seed: int) -> dict:
        # Record 0 keeps the seed (a single-record diagnosis is unchanged); the others are
        # offset so that no two records share a noise realisation.
        imu, enc = simulate_twin(bases[i], effects, seed + 7919 * i)
        o = _obs(imu, enc, bases[i], ranges[i])
        key = (repr(effects), seed)
        if i == 0 and len(records) > 1:
            if len(first_scale) > 512:
                first_scale.clear()
            first_scale[key] = record_scale(imu, enc, bases[0].axis)
        elif i > 0:
            if key not in first_scale:
                first_scale[key] = record_scale(*simulate_twin(bases[0], effects, seed),
                                                bases[0].axis)
            o['scale_factor_shift'] = np.array([record_scale(imu, enc, bases[i].axis)
                                                - first_scale[key]])
        return o

    if method == 'expected':
        simulate = expected_twins(bases, ranges, len(records) > 1)
    else:
        simulate = sim
    # Search spaces scaled to the longest record (the others' bounds differ by the ratio of
    # their peak rates, well inside the spans' decades).
    longest = max(bases, key=lambda b: b.duration)
    spaces = [s for s in swing_spaces(longest) if s.name in names]
    spaces = signs(spaces, reals, simulate)
    units = dict(UNITS, scale_factor_shift='rad/s')
    baseline = bases[0].to_json()
    if len(bases) > 1:
        sf, sf_sigma = pooled_scale_factor(bases)
        baseline['pooled_scale_factor_error'] = {'value': sf, 'sigma': sf_sigma, 'unit': '1'}
        baseline['records'] = [b.to_json() for b in bases]
    return Problem(kind='swing', reals=reals, simulate=simulate, spaces=spaces, ranges=ranges,
                   units=units, baseline=baseline, context=bases, twin=sim,
                   unresolved=unresolved_pairs(bases))


def expected_twins(bases: Sequence[SwingBaseline], ranges: Sequence[dict], shift: bool):
    """
    Return ``simulate(record, effects, seed)`` on pseudo-twins (``swing_expect``).

    The noise part of record i and seed s is the full baseline twin of the twin path's seed,
    simulated on first use; with ``shift`` (several records) each further record gets the
    ``scale_factor_shift`` block against the first record's pseudo-twin of the same seed.
    """
    parts = EffectParts(bases, ranges, twin_config, record_scale)
    noise = {}

    def noise_of(i: int, seed: int) -> dict:
        if (i, seed) not in noise:
            b = bases[i]
            imu, enc = simulate_twin(b, [], seed + 7919 * i)
            raw = raw_parts(_residuals(imu, enc, b), ranges[i])
            raw['scale'] = record_scale(imu, enc, b.axis) if shift else 0.0
            noise[(i, seed)] = raw
        return noise[(i, seed)]

    def simulate(i: int, effects: list, seed: int) -> dict:
        fx = twin_effects(effects)
        o, s = pseudo_twin(noise_of(i, seed), parts.part(i, fx))
        if i > 0:
            s0 = pseudo_twin(noise_of(0, seed), parts.part(0, fx))[1]
            o['scale_factor_shift'] = np.array([s - s0])
        return o
    return simulate
