"""
The ``diagnose`` job: where the sim-to-real gap lies and what explains it.

Fits the paper's baseline model to each gyro channel of the input record(s), compares them with
the model on a battery of observables - for static records their closed-form expectations over
the whole record, checked by simulated twins (``diagnose_static``); for swing records
pseudo-twins over the whole run (``diagnosis.swing_expect``) - ranks the catalogue effects and
adds them greedily
(``gyro_char.diagnosis.engine``). Writes ``diagnosis.json`` (docs/design.md: the channel
with the largest baseline gap at the top level, every channel under the extra ``per_channel``
field) and ``diagnosis_<channel>.png`` in ``--out``. ``--holdout INPUT`` re-measures, on a
record the fit never saw, the gap of the baseline and of the baseline + the selected effects
with their parameters fixed (only the baseline's white-noise level is refitted).
``--kind swing`` diagnoses one or several swing records of one gyro (IMU + encoder each;
``--period`` once for all, once per record, or the encoder's dominant period) against twins of
the paper's swing model (``gyro_char.diagnosis.swing``): the effect parameters and the gyro's one
scale-factor error are shared by the records, bias, drift and noise stay per record; the extra
field ``per_record`` lists each record's own Kalman scale-factor estimate against its amplitude
and period. ``--holdout`` then re-measures a withheld swing record with the effect parameters
and the pooled scale factor frozen (its bias, drift and noise levels refitted).
``gyro-char diagnose`` and ``gyro-char fleet --kind diagnose`` (one record a device) both run
it; the job returns the tidy gaps of each channel.
"""
import json
import os
from typing import List, Optional

from gyro_char.errors import InputError
from gyro_char.io import read_imu
from gyro_char.jobs.base import Console, measurement
from gyro_char.jobs.diagnose_static import (
    add_static_options, check_repeats, posterior_predictive, run_static)
from gyro_char.records import GYRO_CHANNELS
import numpy as np

# The tidy quantities of a diagnosis (all dimensionless gaps and counts).
QUANTITIES = {'baseline_gap': '1', 'final_gap': '1', 'null_gap_q95': '1',
              'effects_selected': '1'}

# ``--method twins`` on swing records simulates every candidate in full: cut to this unless
# --max-samples says otherwise (the default pseudo-twin path takes the whole record).
SWING_TWINS_MAX_SAMPLES = 2 ** 17


def add_options(p, require: bool = True) -> None:
    """
    Add the options of ``gyro-char diagnose`` but INPUT, ``--out`` and ``--quiet``.

    ``require=False`` lets ``--kind`` default to ``static`` (the fleet's one static record a
    device).
    """
    p.add_argument('--kind', choices=('static', 'swing'), required=require, default='static')
    p.add_argument('--channels', default=None,
                   help='comma-separated gyro channels (default: every gyro channel present)')
    p.add_argument('--holdout', default=None, metavar='INPUT',
                   help='record withheld from the fit, to check the selected model on')
    p.add_argument('--repeats', type=int, default=None,
                   help='simulated twins: of the baseline, for the null level (static, '
                        'closed forms; default 32), or per model (swing, static --method '
                        'twins; default 8)')
    p.add_argument('--max-samples', type=int, default=None,
                   help='analyse the first N samples of each record (default: the whole '
                        'record; swing --method twins: 131072)')
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--topic', default=None, help='sensor_msgs/Imu topic (bags)')
    p.add_argument('--period', default=None, metavar='SECONDS[,SECONDS...]',
                   help='swing: the swing period, once for all records or comma-separated '
                        'once per record (default: the dominant period of the encoder of each '
                        'record)')
    p.add_argument('--axis', default=None,
                   help='swing: gyro axis along the swing axis (default: the one that swings)')
    p.add_argument('--encoder-topic', default=None,
                   help='swing: sensor_msgs/JointState topic of the stand encoder (bags)')
    add_static_options(p)


def recording_args(path: str) -> dict:
    """Return the INPUT arguments of the command for one recording."""
    return {'inputs': [path]}


def _channels(recs, wanted):
    present = [c for c in GYRO_CHANNELS if all(c in r.channels for r in recs)]
    if wanted:
        chosen = [c.strip() for c in wanted.split(',') if c.strip()]
        bad = [c for c in chosen if c not in present]
        if bad:
            raise InputError(f'channel(s) {bad} not in every input; present: {present}')
        return chosen
    if not present:
        raise InputError('no gyro channel present in every input')
    return present


def _dt(rec) -> float:
    dt = rec.dt
    d = rec.t[1:] - rec.t[:-1]
    if abs(d.max() - dt) > 0.1 * dt or abs(d.min() - dt) > 0.1 * dt:
        raise InputError(f'{rec.source}: sample interval varies by more than 10 % '
                         f'({d.min():.6g}..{d.max():.6g} s); the static diagnosis needs '
                         'uniform sampling')
    return dt


def default_repeats(kind: str, method: str) -> int:
    """Twins per model: many of the cheap baseline for the closed forms' null, else 8."""
    from gyro_char.diagnosis.static_expect import NULL_TWINS
    return NULL_TWINS if kind == 'static' and method == 'closed-form' else 8


def run(args, console: Optional[Console] = None) -> List[dict]:
    """Diagnose ``args.inputs``, write the files in ``args.out``; return the tidy gaps."""
    console = console or Console()
    if args.repeats is None:
        args.repeats = default_repeats(args.kind, getattr(args, 'method', 'closed-form'))
    if args.repeats < 4:
        raise InputError('--repeats must be >= 4 (the gap is judged against their scatter)')
    if args.kind == 'swing':
        return run_swing(args, console)
    recs = [read_imu(p, topic=args.topic, quiet=args.quiet) for p in args.inputs]
    dts = [_dt(r) for r in recs]
    if max(dts) - min(dts) > 1e-6 * max(dts):
        raise InputError(f'inputs have different sample intervals: {dts}')
    hold = read_imu(args.holdout, topic=args.topic, quiet=args.quiet) if args.holdout else None
    if hold is not None and abs(_dt(hold) - dts[0]) > 1e-6 * dts[0]:
        raise InputError('the holdout record has another sample interval')
    for r in recs + ([hold] if hold is not None else []):
        for note in r.notes:
            print(f'note: {r.source}: {note}', file=console.err)
    os.makedirs(args.out, exist_ok=True)
    channels = _channels(recs + ([hold] if hold is not None else []), args.channels)
    per = run_static(args, recs, dts, hold, channels,
                     emit=lambda ch, out: print(summary(ch, out), file=console.out))
    top = max(per, key=lambda c: per[c]['baseline_gap'])
    result = dict(per[top])
    result['per_channel'] = per
    with open(os.path.join(args.out, 'diagnosis.json'), 'w') as fh:
        json.dump(result, fh, indent=2)
    print(f'wrote {args.out}/diagnosis.json and {len(per)} plot(s)', file=console.out)
    return tidy(per)


def _swing_record(path, period, args, console: Console):
    """IMU, encoder and swing period of one swing input."""
    from gyro_char.io import read_encoder
    from gyro_char.swing.align import dominant_period

    imu = read_imu(path, topic=args.topic, quiet=args.quiet)
    enc = read_encoder(path, topic=args.encoder_topic, quiet=args.quiet)
    for r in (imu, enc):
        for note in r.notes:
            print(f'note: {r.source}: {note}', file=console.err)
    if period is None:
        if len(enc) < 16:
            raise InputError(f'{path}: no encoder samples to find the swing period from; '
                             'give --period')
        period = dominant_period(enc.t - enc.t[0], enc.channels['encoder'])
        print(f'note: {path}: swing period {period:.4g} s (dominant period of the encoder)',
              file=console.err)
    return imu, enc, float(period)


def _swing_periods(args) -> list:
    n = len(args.inputs)
    if args.period is None:
        return [None] * n
    try:
        periods = [float(v) for v in args.period.split(',') if v.strip()]
    except ValueError:
        raise InputError(f'--period: not a number or comma-separated numbers: '
                         f'{args.period!r}') from None
    if not periods or not all(0 < v < float('inf') for v in periods):
        raise InputError(f'--period must be positive seconds: {args.period!r}')
    if len(periods) == 1:
        return periods * n
    if len(periods) != n:
        raise InputError(f'--period takes one value for all records or one per record '
                         f'({n}); got {len(periods)}')
    return periods


def run_swing(args, console: Console) -> List[dict]:
    """``--kind swing``: swing records (IMU + encoder) of one gyro against their twins."""
    from dataclasses import replace

    from gyro_char.diagnosis import engine as diagnose, swing as diag_swing
    from gyro_char.diagnosis.swing_screens import record_screens, screen_warnings
    from gyro_char.report.diagnosis_plot import plot_diagnosis

    check = check_repeats(args)
    periods = _swing_periods(args)
    records = [_swing_record(p, per, args, console) for p, per in zip(args.inputs, periods)]
    hold = None
    if args.holdout:
        # A single --period is the stand's for every run; per-record periods leave the
        # held-out run's to its encoder.
        once = periods[0] if args.period and ',' not in args.period else None
        hold = _swing_record(args.holdout, once, args, console)
    problem = diag_swing.swing_records_problem(records, axis=args.axis,
                                               max_samples=swing_max_samples(args),
                                               method=swing_method(args))
    diag = diagnose.run(problem, repeats=args.repeats, seed=args.seed, quiet=args.quiet)
    out = diag.to_json()
    bases = problem.context
    ch = f'gyro_{bases[0].axis}'
    out['channel'] = ch
    out['method'] = swing_method(args)
    out['analysed'] = swing_analysed(args.inputs, bases)
    if swing_method(args) == 'expected' and check:
        out['posterior_predictive'] = posterior_predictive(problem, diag, check, args.seed)
    out['per_record'] = per_record(args.inputs, bases)
    screens = []
    for i, ((imu, enc, _), b, rec) in enumerate(zip(records, bases, out['per_record'])):
        rec.update(record_screens(imu, enc, b.axis, b.period_s))
        screens.append((f'record {i + 1}', rec))
    if hold is not None:
        out['holdout'] = swing_holdout_check(diag, hold, bases, args)
        screens.append(('held-out record', out['holdout']['record']))
    warnings = [w for label, rec in screens for w in screen_warnings(label, rec)]
    if warnings:
        out['warnings'] = out.get('warnings', []) + warnings
    os.makedirs(args.out, exist_ok=True)
    pngs = []
    for i, b in enumerate(bases):
        # One figure per record: the engine's plot shows its first record.
        view = replace(diag, reals=[diag.reals[i]], evaluations={
            k: replace(ev, stats=[ev.stats[i]]) for k, ev in diag.evaluations.items()})
        pngs.append(f'diagnosis_{ch}.png' if i == 0 else f'diagnosis_{ch}_record{i + 1}.png')
        plot_diagnosis(view, problem.ranges[i], os.path.join(args.out, pngs[-1]),
                       title=f'{ch}: swing sim-to-real gap, record {i + 1} (period '
                             f'{b.period_s:.4g} s, amplitude {b.amplitude:.3g} rad)')
    with open(os.path.join(args.out, 'diagnosis.json'), 'w') as fh:
        json.dump(out, fh, indent=2)
    print(summary(ch, out), file=console.out)
    print(f'wrote {args.out}/diagnosis.json and {", ".join(pngs)}', file=console.out)
    return tidy({ch: out})


def swing_method(args) -> str:
    """Return the swing problem's method: pseudo-twins ('expected', the default) or twins."""
    return 'twins' if getattr(args, 'method', 'closed-form') == 'twins' else 'expected'


def swing_max_samples(args):
    """Return the gyro samples to analyse per swing record (None: the whole record)."""
    if args.max_samples:
        return args.max_samples
    return SWING_TWINS_MAX_SAMPLES if swing_method(args) == 'twins' else None


def swing_analysed(sources, bases) -> dict:
    """Return the contract's ``analysed`` field of a swing diagnosis: gyro samples per record."""
    per = [{'source': str(s), 'samples': int(b.samples), 'duration_s': float(b.samples * b.dt)}
           for s, b in zip(sources, bases)]
    return {'samples': per[0]['samples'], 'duration_s': per[0]['duration_s'], 'records': per}


def per_record(sources, bases) -> list:
    """Each record's own Kalman scale-factor estimate against its amplitude and period."""
    return [{'source': str(src), 'period_s': b.period_s, 'amplitude_rad': b.amplitude,
             'peak_rate_rad_s': b.peak_rate,
             'kalman_scale_factor_error': b.record_scale_factor_error,
             'kalman_scale_factor_sigma': b.record_scale_factor_sigma,
             'twin_scale_factor_error': b.scale_factor_error}
            for src, b in zip(sources, bases)]


def swing_holdout_check(diag, hold, bases, args) -> dict:
    """
    Gap of the baseline and of the selected model on a swing record the fit never saw.

    The effect parameters and the pooled scale-factor error are frozen; the record's own bias,
    drift, noise levels, amplitude and period are refitted (they change from run to run).
    """
    from gyro_char.diagnosis import gap as diag_gap, swing as diag_swing
    from gyro_char.diagnosis.engine import excess_gap
    from gyro_char.diagnosis.fit import GapObjective
    from gyro_char.diagnosis.swing_screens import record_screens

    imu, enc, period = hold
    problem = diag_swing.swing_records_problem(
        [(imu, enc, period)], axis=bases[0].axis, max_samples=swing_max_samples(args),
        scale_factor=bases[0].scale_factor_error, method=swing_method(args))
    seeds = [args.seed * 1000 + 500 + k for k in range(args.repeats)]
    objective = GapObjective(problem.reals, problem.simulate, seeds)
    base = objective.evaluate([])
    objective.set_reference(base)
    final = objective.evaluate(list(diag.model))
    null = diag_gap.null_gaps(base.stats)
    b = problem.context[0]
    return {'baseline_gap': base.gap, 'final_gap': final.gap,
            'null_gap_q95': float(np.quantile(null, 0.95)),
            'baseline_excess': excess_gap(base.gap, null),
            'final_excess': excess_gap(final.gap, null),
            'effects': [{'name': n, 'params': p} for n, p in diag.model],
            'record': {'period_s': b.period_s, 'amplitude_rad': b.amplitude,
                       'kalman_scale_factor_error': b.record_scale_factor_error,
                       **record_screens(imu, enc, b.axis, b.period_s)},
            'note': 'effect parameters and the pooled scale-factor error fixed from the fit; '
                    'bias, drift and noise levels of the record are refitted'}


def summary(channel: str, out: dict) -> str:
    lines = [f'{channel}: baseline gap {out["baseline_gap"]:.2f} (sim vs itself: '
             f'{out["null_gap"]["mean"]:.2f}, 95 % {out["null_gap"]["q95"]:.2f})']
    lines.append(f'  verdict: {out["verdict"]["code"]}: {out["verdict"]["text"]}')
    for w in out['where'][:4]:
        lines.append(f'  gap in {w["observable"]} over {w["range"][0]:.4g}-{w["range"][1]:.4g} '
                     f'{w["range_unit"]}: {w["excess"]:+.1f} sigma')
    for s in out['steps']:
        lines.append(f'  + {s["effect"]} {s["params"]} -> gap {s["gap_after"]:.2f}')
    for a in out['ambiguous']:
        lines.append(f'  ambiguous: {" / ".join(a["effects"])}; separating run: '
                     f'{a["separating_run"]}')
    lines.extend(f'  WARNING: {w}' for w in out.get('warnings', []))
    for i, r in enumerate(out.get('per_record', [])):
        lines.append(f'  record {i + 1}: period {r["period_s"]:.4g} s, amplitude '
                     f'{r["amplitude_rad"]:.4g} rad, peak rate {r["peak_rate_rad_s"]:.4g} rad/s: '
                     f'Kalman scale-factor error {r["kalman_scale_factor_error"]:+.3e} '
                     f'+- {r["kalman_scale_factor_sigma"]:.1e}')
    if 'holdout' in out:
        h = out['holdout']
        lines.append(f'  held-out record: baseline gap {h["baseline_gap"]:.2f} -> '
                     f'{h["final_gap"]:.2f} with the selected effects')
    return '\n'.join(lines)


def tidy(per_channel: dict) -> List[dict]:
    """Tidy rows of a diagnosis: each channel's gaps; verdict and effects in the message."""
    rows = []
    for ch, out in per_channel.items():
        chosen = ', '.join(out['selected_effects']) or 'none'
        rows += [measurement(ch, 'baseline_gap', out['baseline_gap'], '1'),
                 measurement(ch, 'final_gap', out['final_gap'], '1',
                             message=f'verdict: {out["verdict"]["code"]}; '
                                     f'selected effects: {chosen}'),
                 measurement(ch, 'null_gap_q95', out['null_gap']['q95'], '1'),
                 measurement(ch, 'effects_selected', len(out['selected_effects']), '1')]
    return rows
