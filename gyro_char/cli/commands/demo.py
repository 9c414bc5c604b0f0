"""
``gyro-char demo``: the whole chain on the simulated bench, no hardware needed.

Simulates a 15 min swing-stand run and a 3 h static record of the MEMS preset (the paper's test
lengths), writes both as ROS 2 bags, processes them with the offline commands (``gyro-char
swing`` and ``gyro-char allan``, the very code a user runs on a real bag) and prints the paper's
Table 1 (scale-factor error, bias, bias drift) and Table 2 (N, B) beside the truth. ``--live``
also replays a swing run through the live nodes on a loopback ROS graph.
"""
import contextlib
import importlib
import io
import json
from pathlib import Path
import sys
import time

from gyro_char.cli import add_common
from gyro_char.errors import InputError
from gyro_char.records import GYRO_CHANNELS
from gyro_char.units import DEG

# The paper's measured means and 1 sigma (docs/method.md), printed for orientation.
PAPER_TABLE1 = {
    'adis16405': {'x': (-0.09, 1.00, -0.58, 0.17, -4.14, 11.67),
                  'y': (0.21, 0.82, -0.04, 0.10, 11.90, 26.61),
                  'z': (-0.28, 0.91, 0.11, 0.02, 0.03, 8.40)},
    'vg910': {a: (1.85, 0.43, -0.04, 0.04, -1.86, 4.49) for a in 'xyz'},
}
PAPER_TABLE2 = {
    'adis16405': {'gyro_x': (1.890, 0.041, 36.950, 3.824), 'gyro_y': (1.648, 0.005, 31.058, 1.409),
                  'gyro_z': (1.463, 0.029, 30.724, 8.008)},
    'vg910': {c: (0.005, 0.001, None, None) for c in GYRO_CHANNELS},
}


def register(subparsers) -> None:
    p = subparsers.add_parser('demo', help='the whole chain on the simulated bench',
                              description=__doc__.strip().splitlines()[0])
    p.add_argument('--preset', default='adis16405', help='adis16405 (default) or vg910')
    p.add_argument('--config', metavar='YAML', help='overrides of the preset')
    p.add_argument('--seed', type=int, default=0)
    p.add_argument('--swing-duration', type=float, default=900.0, metavar='S')
    p.add_argument('--static-duration', type=float, default=10800.0, metavar='S')
    p.add_argument('--no-static', action='store_true',
                   help='swing part only (no static record, no Table 2)')
    p.add_argument('--effect', action='append', default=[], metavar='NAME[:k=v,...]',
                   help='add an unmodelled effect to both simulated runs')
    p.add_argument('--live', action='store_true',
                   help='also run bench_sim_node -> swing_kf_node on a loopback ROS graph')
    p.add_argument('--live-duration', type=float, default=60.0, metavar='S',
                   help='simulated swing seconds replayed through swing_kf_node')
    p.add_argument('--live-rate-factor', type=float, default=1.0, metavar='X',
                   help='swing replay speed (1 = real time, the rate the nodes are built '
                        'for; faster replays may drop samples on a loaded machine)')
    p.add_argument('--live-static-duration', type=float, default=300.0, metavar='S',
                   help='simulated static seconds replayed through allan_node (at 5x)')
    add_common(p, default_out='out/demo')
    p.set_defaults(func=run)


class _Steps:
    """Numbered step messages on stderr (the long steps show their own progress bars)."""

    def __init__(self, total: int, quiet: bool) -> None:
        self.total, self.k, self.quiet, self.t0 = total, 0, quiet, time.monotonic()

    def __call__(self, text: str) -> None:
        self.k += 1
        if not self.quiet:
            print(f'[{self.k}/{self.total} {time.monotonic() - self.t0:5.1f} s] {text}',
                  file=sys.stderr, flush=True)


def _command(argv, log) -> dict:
    """Run a gyro-char subcommand in-process exactly as the CLI would; its output to ``log``."""
    from gyro_char.cli import build_parser
    args = build_parser().parse_args(argv)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = args.func(args)
    log.write(f'$ gyro-char {" ".join(argv)}\n{buf.getvalue()}\n')
    if code:
        raise InputError(f'gyro-char {argv[0]} failed with exit code {code}')
    return vars(args)


def _has_command(name: str) -> bool:
    try:
        importlib.import_module(f'gyro_char.cli.commands.{name}')
    except ModuleNotFoundError:
        return False
    return True


def run(args) -> int:
    from gyro_char.sim.config import load
    from gyro_char.sim.effects import build_effects

    cfg = load(args.config, args.preset)
    effects = build_effects(args.effect)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    have_allan = _has_command('allan') and not args.no_static
    live_static = args.live and not args.no_static
    steps = _Steps(3 + int(not args.no_static) + int(have_allan) + int(args.live)
                   + int(live_static), args.quiet)
    missing = []
    static = noise = live = live_noise = None
    with open(out / 'demo.log', 'w', encoding='utf-8') as log:
        swing, estimates = _swing_part(cfg, args, effects, out, steps, log)
        if not args.no_static:
            static, noise = _static_part(cfg, args, effects, out, steps, log, have_allan)
            if not have_allan:
                missing.append('gyro-char allan (not in this build): Table 2 shows truth only')
        if args.live:
            steps(f'live: bench_sim_node -> swing_kf_node, {args.live_duration:g} s simulated')
            from gyro_char.cli.commands.demo_live import run_live
            live = run_live(cfg, args.seed, args.live_duration, args.effect, log,
                            rate_factor=args.live_rate_factor, config_file=args.config)
            if live.get('missing'):
                missing.append(live['missing'])
        if live_static:
            steps(f'live: bench_sim_node -> allan_node, {args.live_static_duration:g} s '
                  'static at 5x real time, then ~/compute')
            from gyro_char.cli.commands.demo_live import run_live_static
            live_noise = run_live_static(cfg, args.seed + 1, args.live_static_duration,
                                         args.effect, log, config_file=args.config)
            if live_noise.get('missing'):
                missing.append(live_noise['missing'])
                live_noise = None
        steps('tables')
    text = table1(cfg, estimates, swing.truth, swing.realized, live)
    if static is not None:
        text += [''] + table2(cfg, noise, static.truth, live_noise)
    if effects:
        text += ['', 'effects added to both runs: '
                 + ', '.join(f'{e.name} {e.params}' for e in effects)]
    if live and not live.get('missing'):
        sent = int(round(args.live_duration * cfg.gyro.rate_hz))
        got = min(live['samples_gyro'] or 0, live['samples_encoder'] or 0)
        text.append(f'live node: {args.live_duration:g} s replayed at '
                    f'{args.live_rate_factor:g}x real time over DDS (seed {args.seed}); the '
                    f'filter used {live["samples_gyro"]} gyro + {live["samples_encoder"]} '
                    f'encoder samples of {sent} each, converged {bool(live["converged"])}')
        if got < sent:
            text.append(f'warning: {sent - got} of the live samples '
                        f'({100 * (1 - got / sent):.2g} %) were '
                        'lost (best-effort transport on a loaded machine); a gyro angle '
                        'integrated across lost samples is wrong, so the live column is not '
                        'comparable - use a smaller --live-rate-factor')
    if live_noise:
        text.append(f'live allan_node: {args.live_static_duration:g} s static record replayed '
                    f'at 5x real time (seed {args.seed + 1}, a shorter record than the offline '
                    f'one, so B is poorly resolved); {live_noise["message"]}')
    text += [f'missing: {item}' for item in missing]
    plots = sorted(str(p) for p in out.glob('*/*.png'))
    text += ['', f'written in {out}: swing/ and static/ (recording.mcap, truth.json, '
             f'results), demo.log; plots: {", ".join(plots) or "none"}']
    (out / 'demo.txt').write_text('\n'.join(text) + '\n', encoding='utf-8')
    print('\n'.join(text))
    return 0


def _swing_part(cfg, args, effects, out, steps, log):
    from gyro_char.cli.commands.simulate import write_record
    from gyro_char.sim.simulator import simulate_swing
    steps(f'simulating a {args.swing_duration:g} s swing run ({cfg.preset}, '
          f'{cfg.gyro.rate_hz:g} Hz gyro + encoder)')
    swing = simulate_swing(cfg, duration=args.swing_duration, seed=args.seed,
                           effects=effects, quiet=args.quiet)
    bag = write_record(str(out / 'swing'), swing, quiet=args.quiet, overwrite=True)
    steps('gyro-char swing on the recorded bag (Kalman filters on encoder and gyro angle)')
    _command(['swing', bag, '--period', repr(cfg.stand.period_s), '--axis', cfg.gyro.axis,
              '--out', str(out / 'swing')] + (['--quiet'] if args.quiet else []), log)
    return swing, json.loads((out / 'swing' / 'swing.json').read_text())


def _static_part(cfg, args, effects, out, steps, log, have_allan):
    from gyro_char.cli.commands.simulate import write_record
    from gyro_char.sim.simulator import simulate_static
    steps(f'simulating a {args.static_duration:g} s static record '
          f'({cfg.gyro.static_rate_hz:g} Hz, 6 channels)')
    static = simulate_static(cfg, duration=args.static_duration, seed=args.seed + 1,
                             effects=effects, quiet=args.quiet)
    bag = write_record(str(out / 'static'), static, quiet=args.quiet, overwrite=True)
    if not have_allan:
        return static, None
    steps('gyro-char allan on the recorded bag (Allan variance + IEEE 952 fit)')
    # Table 2 is about the gyros (as the paper's); the accelerometer channels stay in the bag.
    _command(['allan', bag, '--channels', ','.join(GYRO_CHANNELS), '--out', str(out / 'static')]
             + (['--quiet'] if args.quiet else []), log)
    noise = json.loads((out / 'static' / 'noise.json').read_text())
    from gyro_char.report.sim_plot import plot_allan_vs_truth
    allan = json.loads((out / 'static' / 'allan.json').read_text())
    plot_allan_vs_truth(allan, static.truth, str(out / 'static' / 'allan_truth.png'), noise)
    return static, noise


def table1(cfg, est: dict, truth: dict, realized: dict, live=None) -> list:
    """
    Paper's Table 1 layout: estimate +- filter sigma beside the truth.

    Two truths: the parameters (truth.json) and this run's own bias and drift, which include
    the run's realized flicker / rate random walk (``SimRun.realized``); the last column is the
    estimate's error against the latter in filter sigmas.
    """
    t = dict(truth['swing'])
    run = {**t, **(realized or {})}
    paper = PAPER_TABLE1.get(cfg.preset, {}).get(cfg.gyro.axis)
    rows = [('scale-factor error, %', 'scale_factor_error', 100.0, 0),
            ('bias, deg/s', 'bias', 1.0 / DEG, 2),
            ('bias drift, 1e-5 deg/s^2', 'bias_drift', 1e5 / DEG, 4)]
    head = (f'Table 1. Swing-stand calibration, {cfg.preset} gyro_{cfg.gyro.axis}, '
            f'T = {cfg.stand.period_s:g} s, A = {cfg.stand.amplitude / DEG:g} deg, '
            f'seed {truth["seed"]}')
    lines = [head, f'{"":26s}{"estimate":>10s}{"1 sigma":>9s}{"truth":>10s}{"this run":>10s}'
             f'{"err/sigma":>10s}' + ('  live node' if live else '')
             + ('   paper (mean, 1 sigma)' if paper else '')]
    for label, key, scale, pcol in rows:
        e = est[key]
        value, sigma = e['value'] * scale, e['sigma'] * scale
        true, this = t[key] * scale, run[key] * scale
        z = (value - this) / sigma if sigma else float('nan')
        line = f'{label:26s}{value:10.5g}{sigma:9.2g}{true:10.5g}{this:10.5g}{z:10.1f}'
        if live:
            lv = live.get(key)
            line += f'{lv * scale:11.5g}' if lv is not None else f'{"-":>11s}'
        if paper:
            line += f'   {paper[pcol]:+.2f} ({paper[pcol + 1]:.2f})'
        lines.append(line)
    lines.append('truth: the simulator parameters; this run: plus the least-squares line '
                 'through the flicker (B) and rate random walk (K) of this very run - what an '
                 'ideal estimator of the model of the paper would find; err/sigma is against '
                 'it.')
    return lines


def table2(cfg, noise, truth: dict, live=None) -> list:
    """Paper's Table 2 layout: N deg/sqrt(h) and B deg/h per gyro axis beside the truth."""
    arw, dph = 60.0 / DEG, 3600.0 / DEG
    paper = PAPER_TABLE2.get(cfg.preset, {})
    lines = [f'Table 2. Allan-variance noise terms, {cfg.preset}, static record, seed '
             f'{truth["seed"]}',
             f'{"":8s}{"N est":>9s}{"68% interval":>18s}{"N truth":>9s}{"B est":>9s}'
             f'{"68% interval":>18s}{"B truth":>9s}' + ('  live N / B' if live else '')
             + '   paper N / B (mean)']
    for ch in GYRO_CHANNELS:
        tr = truth['channels'].get(ch)
        if tr is None:
            continue
        cells = []
        for term, scale in (('N', arw), ('B', dph)):
            item = (noise or {}).get('channels', {}).get(ch, {}).get(term)
            if item is None:
                cells += ['-', '-']
                continue
            ci = item.get('ci68')
            flag = '' if item.get('resolved', True) else '<'
            cells += [f'{flag}{item["value"] * scale:.3f}',
                      f'[{ci[0] * scale:.3f}, {ci[1] * scale:.3f}]' if ci else '-']
        p = paper.get(ch)
        ptxt = f'{p[0]:.3f} / {p[2]:.2f}' if p and p[2] is not None else (
            f'{p[0]:.3f} / -' if p else '-')
        line = (f'{ch:8s}{cells[0]:>9s}{cells[1]:>18s}{tr["N"] * arw:9.3f}{cells[2]:>9s}'
                f'{cells[3]:>18s}{tr["B"] * dph:9.2f}')
        if live:
            line += f'  {_live_terms(live, ch, arw, dph):>11s}'
        lines.append(line + f'   {ptxt}')
    lines.append('N in deg/sqrt(h), B in deg/h (IEEE coefficient: the Allan floor is 0.664 B); '
                 '<x: not resolved by the record, x is an upper bound.')
    return lines


def _live_terms(live: dict, ch: str, arw: float, dph: float) -> str:
    values = live.get('channels', {}).get(ch, {})
    out = []
    for key, scale in (('N_rad_sqrt_s', arw), ('B_rad_s', dph)):
        term = key[0]
        if key not in values:
            out.append('-')
            continue
        text = f'{values[key] * scale:.3g}'
        out.append(text if values.get(f'{term}_resolved', 1) else '<' + text)
    return ' / '.join(out)
