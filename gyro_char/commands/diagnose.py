"""
``gyro-char diagnose --kind KIND INPUT...``: where the sim-to-real gap lies and what explains it.

Fits the paper's baseline model to each gyro channel of the input record(s), compares them with
repeated simulated twins on a battery of observables, ranks the catalogue effects and adds them
greedily (``gyro_char.diagnose``). Writes ``diagnosis.json`` (DESIGN.md section 4: the channel
with the largest baseline gap at the top level, every channel under the extra ``per_channel``
field) and ``diagnosis_<channel>.png`` in ``--out``. ``--holdout INPUT`` re-measures, on a
record the fit never saw, the gap of the baseline and of the baseline + the selected effects
with their parameters fixed (only the baseline's white-noise level is refitted).
``--kind swing`` diagnoses one swing record (IMU + encoder, ``--period`` or the encoder's
dominant period) against twins of the paper's swing model (``gyro_char.diag_swing``).
"""
import json
import os
import sys

from gyro_char.cli import add_common
from gyro_char.recordings import GYRO_CHANNELS, InputError, read_imu


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'diagnose', help='sim-to-real gap: where it lies, which unmodelled effects explain it',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('--kind', choices=('static', 'swing'), required=True)
    p.add_argument('inputs', metavar='INPUT', nargs='+',
                   help='bag directory, .mcap, ROS 1 .bag or CSV (same sensor, same rate)')
    p.add_argument('--channels', default=None,
                   help='comma-separated gyro channels (default: every gyro channel present)')
    p.add_argument('--holdout', default=None, metavar='INPUT',
                   help='record withheld from the fit, to check the selected model on')
    p.add_argument('--repeats', type=int, default=8,
                   help='simulated twins per model (the sim scatter; default 8)')
    p.add_argument('--max-samples', type=int, default=2 ** 17,
                   help='analyse the first N samples of each record (default 131072)')
    p.add_argument('--seed', type=int, default=1)
    p.add_argument('--topic', default=None, help='sensor_msgs/Imu topic (bags)')
    p.add_argument('--period', type=float, default=None, metavar='SECONDS',
                   help='swing: the swing period (default: the dominant period of the encoder)')
    p.add_argument('--axis', default=None,
                   help='swing: gyro axis along the swing axis (default: the one that swings)')
    p.add_argument('--encoder-topic', default=None,
                   help='swing: sensor_msgs/JointState topic of the stand encoder (bags)')
    add_common(p, default_out='diagnose_out')
    p.set_defaults(func=run)


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


def run(args) -> int:
    from gyro_char import diag_static, diagnose
    from gyro_char.report.diagnose import plot_diagnosis

    if args.repeats < 4:
        raise InputError('--repeats must be >= 4 (the gap is judged against their scatter)')
    if args.kind == 'swing':
        return run_swing(args)
    recs = [read_imu(p, topic=args.topic, quiet=args.quiet) for p in args.inputs]
    dts = [_dt(r) for r in recs]
    if max(dts) - min(dts) > 1e-6 * max(dts):
        raise InputError(f'inputs have different sample intervals: {dts}')
    hold = read_imu(args.holdout, topic=args.topic, quiet=args.quiet) if args.holdout else None
    if hold is not None and abs(_dt(hold) - dts[0]) > 1e-6 * dts[0]:
        raise InputError('the holdout record has another sample interval')
    for r in recs + ([hold] if hold is not None else []):
        for note in r.notes:
            print(f'note: {r.source}: {note}', file=sys.stderr)
    os.makedirs(args.out, exist_ok=True)
    per = {}
    for ch in _channels(recs + ([hold] if hold is not None else []), args.channels):
        problem = diag_static.static_problem([r.channels[ch] for r in recs], dts[0],
                                             channel=ch, max_samples=args.max_samples)
        diag = diagnose.run(problem, repeats=args.repeats, seed=args.seed, quiet=args.quiet)
        out = diag.to_json()
        out['channel'] = ch
        if hold is not None:
            out['holdout'] = holdout_check(diag, hold.channels[ch], dts[0], ch, args)
        png = os.path.join(args.out, f'diagnosis_{ch}.png')
        plot_diagnosis(diag, problem.ranges[0], png, title=f'{ch}: sim-to-real gap')
        per[ch] = out
        print(summary(ch, out))
    top = max(per, key=lambda c: per[c]['baseline_gap'])
    result = dict(per[top])
    result['per_channel'] = per
    with open(os.path.join(args.out, 'diagnosis.json'), 'w') as fh:
        json.dump(result, fh, indent=2)
    print(f'wrote {args.out}/diagnosis.json and {len(per)} plot(s)')
    return 0


def run_swing(args) -> int:
    """``--kind swing``: one swing record (IMU + encoder) against its fitted twins."""
    from gyro_char import diag_swing, diagnose
    from gyro_char.recordings import read_encoder
    from gyro_char.report.diagnose import plot_diagnosis
    from gyro_char.swing_align import dominant_period

    if len(args.inputs) != 1 or args.holdout:
        raise InputError('--kind swing takes one record (IMU + encoder) and no --holdout')
    imu = read_imu(args.inputs[0], topic=args.topic, quiet=args.quiet)
    enc = read_encoder(args.inputs[0], topic=args.encoder_topic, quiet=args.quiet)
    for r in (imu, enc):
        for note in r.notes:
            print(f'note: {r.source}: {note}', file=sys.stderr)
    period = args.period
    if period is None:
        if len(enc) < 16:
            raise InputError('no encoder samples to find the swing period from; give --period')
        period = dominant_period(enc.t - enc.t[0], enc.channels['encoder'])
        print(f'note: swing period {period:.4g} s (dominant period of the encoder)',
              file=sys.stderr)
    problem = diag_swing.swing_problem(imu, enc, period, axis=args.axis,
                                       max_samples=args.max_samples)
    diag = diagnose.run(problem, repeats=args.repeats, seed=args.seed, quiet=args.quiet)
    out = diag.to_json()
    ch = f'gyro_{problem.context.axis}'
    out['channel'] = ch
    os.makedirs(args.out, exist_ok=True)
    plot_diagnosis(diag, problem.ranges[0], os.path.join(args.out, f'diagnosis_{ch}.png'),
                   title=f'{ch}: swing sim-to-real gap (period {period:.4g} s)')
    with open(os.path.join(args.out, 'diagnosis.json'), 'w') as fh:
        json.dump(out, fh, indent=2)
    print(summary(ch, out))
    print(f'wrote {args.out}/diagnosis.json and diagnosis_{ch}.png')
    return 0


def holdout_check(diag, x, dt, channel, args) -> dict:
    """Gap of the baseline and of the selected model on a record the fit never saw."""
    from gyro_char import diag_static
    from gyro_char.diag_fit import fit_effect, GapObjective

    problem = diag_static.static_problem([x], dt, channel=channel,
                                         max_samples=args.max_samples)
    seeds = [args.seed * 1000 + 500 + k for k in range(args.repeats)]
    objective = GapObjective(problem.reals, problem.simulate, seeds)
    effects = [(n, p) for n, p in diag.model if n != diag_static.NUISANCE]
    _, base = fit_effect(objective, [], problem.nuisance)
    objective.set_reference(base)
    _, final = fit_effect(objective, effects, problem.nuisance)
    return {'baseline_gap': base.gap, 'final_gap': final.gap,
            'effects': [{'name': n, 'params': p} for n, p in effects],
            'note': 'effect parameters fixed from the fit; only the baseline white-noise '
                    'level is refitted on this record'}


def summary(channel: str, out: dict) -> str:
    lines = [f'{channel}: baseline gap {out["baseline_gap"]:.2f} (sim vs itself: '
             f'{out["null_gap"]["mean"]:.2f}, 95 % {out["null_gap"]["q95"]:.2f})']
    for w in out['where'][:4]:
        lines.append(f'  gap in {w["observable"]} over {w["range"][0]:.4g}-{w["range"][1]:.4g} '
                     f'{w["range_unit"]}: {w["excess"]:+.1f} sigma')
    for s in out['steps']:
        lines.append(f'  + {s["effect"]} {s["params"]} -> gap {s["gap_after"]:.2f}')
    for a in out['ambiguous']:
        lines.append(f'  ambiguous: {" / ".join(a["effects"])}; separating run: '
                     f'{a["separating_run"]}')
    if 'holdout' in out:
        h = out['holdout']
        lines.append(f'  held-out record: baseline gap {h["baseline_gap"]:.2f} -> '
                     f'{h["final_gap"]:.2f} with the selected effects')
    return '\n'.join(lines)
