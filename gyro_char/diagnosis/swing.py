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
from gyro_char.diagnosis.swing_baseline import fit_baseline, pooled_scale_factor, SwingBaseline
from gyro_char.diagnosis.swing_calibrate import (
    calibrate_encoder, calibrate_n, calibration_shifts, with_calibration_error)
from gyro_char.diagnosis.swing_expect import EffectParts
from gyro_char.diagnosis.swing_obs import layout, raw_parts, UNITS
from gyro_char.diagnosis.swing_pseudo import pseudo_twin
from gyro_char.diagnosis.swing_rate_noise import with_rate_noise
from gyro_char.diagnosis.swing_spaces import (
    probe_twins, signs, swing_spaces, unresolved_pairs, with_saturation, with_stamp_band,
    with_tables)
from gyro_char.diagnosis.swing_speed_gate import with_speed_gate
from gyro_char.diagnosis.swing_stalls import (
    destalled, stall_latency, twin_latency, with_stall_form)
from gyro_char.diagnosis.swing_twin import (
    record_observables, record_residuals, record_scale, simulate_twin, twin_config)
from gyro_char.diagnosis.twins import twin_effects
from gyro_char.errors import InputError
from gyro_char.records import ENCODER_CHANNEL, Recording
import numpy as np

SWING_EFFECTS = ('time_delay', 'g_sensitivity', 'scale_factor_nonlinearity',
                 'scale_factor_asymmetry', 'encoder_cyclic_error', 'timestamp_jitter')


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
        # A record whose stamps show host stalls is calibrated at its samples' own instants
        # (``swing_stalls``); its observables stay the record's.
        traces = [stall_latency(imu.t) for imu, _, _ in records]
        own = [destalled(imu, tr) for (imu, _, _), tr in zip(records, traces)]
        bases = [fit_baseline(i, e, p, axis) for i, (_, e, p) in zip(own, records)]
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
    reals = [record_observables(imu, enc, b, r)
             for (imu, enc, _), b, r in zip(records, bases, ranges)]
    if fitted:
        bases = [calibrate_n(calibrate_encoder(b, enc), imu, enc, r)
                 for b, imu, (_, enc, _), r in zip(bases, own, records, ranges)]
        bases = [b if tr is None else replace(b, stamp_latency=twin_latency(
            tr, imu.t, enc.t, enc.channels[ENCODER_CHANNEL], b.period_s,
            twin_config(b).stand.phase, b.gyro_start))
            for b, tr, (imu, enc, _) in zip(bases, traces, records)]
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
        o = record_observables(imu, enc, bases[i], ranges[i])
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

    # Every twin carries a draw of the baseline calibration's own error (``swing_calibrate``).
    shifts = [calibration_shifts(b, r) for b, r in zip(bases, ranges)]
    twin = with_calibration_error(sim, shifts)
    if method == 'expected':
        simulate = with_calibration_error(expected_twins(bases, ranges, len(records) > 1),
                                          shifts)
    else:
        simulate = twin
    # Search spaces scaled to the longest record (the others' bounds differ by the ratio of
    # their peak rates, well inside the spans' decades).
    longest = max(bases, key=lambda b: b.duration)
    spaces = [s for s in swing_spaces(longest) if s.name in names]
    probe = probe_twins(len(reals), simulate)
    spaces = with_tables(signs(spaces, reals, simulate, probe), bases, simulate, probe)
    spaces = with_speed_gate(with_stamp_band(spaces, reals, ranges, probe, bases), bases)
    crests = [(float(np.nanmax(imu.channels[ch])), -float(np.nanmin(imu.channels[ch])))
              for imu, _, _ in records]
    spaces = with_stall_form(with_rate_noise(with_saturation(spaces, crests, bases), bases),
                             bases)
    units = dict(UNITS, scale_factor_shift='rad/s')
    baseline = bases[0].to_json()
    if len(bases) > 1:
        sf, sf_sigma = pooled_scale_factor(bases)
        baseline['pooled_scale_factor_error'] = {'value': sf, 'sigma': sf_sigma, 'unit': '1'}
        baseline['records'] = [b.to_json() for b in bases]
    return Problem(kind='swing', reals=reals, simulate=simulate, spaces=spaces, ranges=ranges,
                   units=units, baseline=baseline, context=bases, twin=twin,
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
            raw = raw_parts(record_residuals(imu, enc, b), ranges[i])
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
