"""
``gyro-char swing INPUT --period SECONDS``: swing-stand calibration of one gyro axis.

Writes ``swing.json`` (docs/design.md) and ``swing.png`` in ``--out``; prints the estimates
in the field's units and every note (treatments of the input, warnings) on stderr.
"""
import json
import os
import sys

from gyro_char.cli import add_common
from gyro_char.errors import InputError
from gyro_char.io import read_encoder, read_imu


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'swing', help='scale-factor error, bias and bias drift from a swing-stand run',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('input', metavar='INPUT', help='bag directory, .mcap, ROS 1 .bag or CSV')
    p.add_argument('--period', type=float, required=True, metavar='SECONDS',
                   help='commanded swing period T')
    p.add_argument('--axis', choices=('x', 'y', 'z'),
                   help='gyro axis on the swing axis (default: the one that shows the swing)')
    p.add_argument('--imu-topic', default=None, help='sensor_msgs/Imu topic (bags)')
    p.add_argument('--encoder-topic', default=None, help='sensor_msgs/JointState topic (bags)')
    p.add_argument('--encoder-noise', type=float, default=None, metavar='RAD',
                   help='encoder white angle noise (default: estimated from the residuals)')
    p.add_argument('--gyro-arw', type=float, default=None, metavar='RAD_PER_SQRT_S',
                   help='gyro rate noise density N (default: estimated from the residuals)')
    add_common(p, default_out='swing_out')
    p.set_defaults(func=run)


def run(args) -> int:
    from gyro_char.report.swing_plot import plot_swing, table
    from gyro_char.swing.filter import estimate_swing
    from gyro_char.swing.model import SwingNoise

    imu = read_imu(args.input, topic=args.imu_topic, quiet=args.quiet)
    try:
        encoder = read_encoder(args.input, topic=args.encoder_topic, quiet=args.quiet)
    except InputError as exc:
        raise InputError(f'no encoder data: {exc}') from None
    noise = SwingNoise(args.encoder_noise, args.gyro_arw)
    result = estimate_swing(imu, encoder, args.period, axis=args.axis, noise=noise,
                            checkpoints=200)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, 'swing.json'), 'w') as fh:
        json.dump(result.estimates.to_json(), fh, indent=2)
    plot_swing(result, os.path.join(args.out, 'swing.png'))
    for note in result.estimates.notes:
        print(f'note: {note}', file=sys.stderr)
    print('\n'.join(table(result.estimates)))
    print(f'wrote {args.out}/swing.json, {args.out}/swing.png')
    return 0
