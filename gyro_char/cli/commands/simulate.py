"""
``gyro-char simulate {static,swing}``: a simulated bench record as a real ROS 2 bag + truth.json.

Writes, in ``--out``: ``recording.mcap`` (a ROS 2 mcap bag file: sensor_msgs/Imu on
``/imu/data_raw``, and for swing runs sensor_msgs/JointState on ``/stand/joint_states``; with
``--storage sqlite3`` a bag directory ``recording/`` instead) and ``truth.json`` (docs/design.md,
output contracts). The same arguments and ``--seed`` reproduce the record bit for bit.
"""
import json
import os
from pathlib import Path
import shutil
import tempfile

from gyro_char.cli import add_common
from gyro_char.errors import InputError
from gyro_char.io import write_bag
from gyro_char.records import Recording


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'simulate', help='simulated static or swing-stand record (ROS 2 bag + truth.json)',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('kind', choices=('static', 'swing'), nargs='?')
    p.add_argument('--config', metavar='YAML', help='overrides of the preset (see README)')
    p.add_argument('--preset', default=None, help='adis16405 (default) or vg910')
    p.add_argument('--seed', type=int, default=0, metavar='N')
    p.add_argument('--duration', type=float, default=None, metavar='S',
                   help='record length (default: 900 s swing, 10800 s static)')
    p.add_argument('--effect', action='append', default=[], metavar='NAME[:k=v,...]',
                   help='add an unmodelled effect (repeatable); --list-effects shows them')
    p.add_argument('--list-effects', action='store_true', help='print the catalogue and exit')
    p.add_argument('--storage', choices=('mcap', 'sqlite3'), default='mcap')
    p.add_argument('--overwrite', action='store_true', help='replace an existing record')
    add_common(p, default_out='out/simulate')
    p.set_defaults(func=run)


def list_effects() -> str:
    from gyro_char.sim.effects import catalogue
    lines = []
    for item in catalogue():
        lines.append(f'{item["name"]}: {item["summary"]}')
        for key, spec in item['params'].items():
            lines.append(f'    {key} = {spec["default"]:g} {spec["unit"]}  ({spec["doc"]})')
    return '\n'.join(lines)


def shift_to_positive(imu: Recording, encoder) -> float:
    """Shift both streams by the same whole seconds if an effect made a stamp negative."""
    first = min([imu.t[0]] + ([encoder.t[0]] if encoder is not None else []))
    if first >= 0:
        return 0.0
    shift = float(int(-first) + 1)
    imu.t = imu.t + shift
    if encoder is not None:
        encoder.t = encoder.t + shift
    return shift


def write_record(out: str, run, storage: str = 'mcap', quiet: bool = True,
                 overwrite: bool = False) -> str:
    """Write ``run`` (a SimRun) as a bag and truth.json in ``out``; return the bag path."""
    os.makedirs(out, exist_ok=True)
    target = Path(out) / ('recording.mcap' if storage == 'mcap' else 'recording')
    if target.exists():
        if not overwrite:
            raise InputError(f'{target} exists already; not overwriting (use --overwrite)')
        if target.is_dir():
            shutil.rmtree(target)
        else:
            target.unlink()
    shift = shift_to_positive(run.imu, run.encoder)
    if storage == 'mcap':
        with tempfile.TemporaryDirectory(dir=out) as tmp:
            bag = Path(tmp) / 'recording'
            write_bag(str(bag), run.imu, run.encoder, storage='mcap', quiet=quiet)
            shutil.move(str(bag / 'recording.mcap'), target)
    else:
        write_bag(str(target), run.imu, run.encoder, storage='sqlite3', quiet=quiet)
    with open(Path(out) / 'truth.json', 'w', encoding='utf-8') as fh:
        json.dump(run.truth, fh, indent=2)
    if shift:
        print(f'note: stamps shifted by +{shift:g} s so that none is negative')
    return str(target)


def run(args) -> int:
    from gyro_char.sim.config import load
    from gyro_char.sim.effects import build_effects
    from gyro_char.sim.simulator import simulate_static, simulate_swing

    if args.list_effects:
        print(list_effects())
        return 0
    if args.kind is None:
        raise InputError('say which record to simulate: static or swing')
    cfg = load(args.config, args.preset)
    effects = build_effects(args.effect)
    if args.kind == 'swing':
        duration = 900.0 if args.duration is None else args.duration
        sim = simulate_swing(cfg, duration=duration, seed=args.seed, effects=effects,
                             quiet=args.quiet)
    else:
        duration = 10800.0 if args.duration is None else args.duration
        sim = simulate_static(cfg, duration=duration, seed=args.seed, effects=effects,
                              quiet=args.quiet)
    path = write_record(args.out, sim, args.storage, quiet=args.quiet,
                        overwrite=args.overwrite)
    n_enc = len(sim.encoder) if sim.encoder is not None else 0
    print(f'{args.kind} run, preset {cfg.preset}, seed {args.seed}, {duration:g} s: '
          f'{len(sim.imu)} Imu' + (f' + {n_enc} JointState' if n_enc else '') + ' messages')
    print(f'wrote {path} and {os.path.join(args.out, "truth.json")}')
    return 0
