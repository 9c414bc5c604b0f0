"""
The ``swing`` job: swing-stand calibration of one gyro axis from one run.

Writes ``swing.json`` (docs/design.md) and ``swing.png`` in ``args.out``; prints the estimates
in the field's units and every note (treatments of the input, warnings) on the note stream.
``gyro-char swing`` and ``gyro-char fleet --kind swing`` both run it.
"""
import json
import os
from typing import List, Optional

from gyro_char.errors import InputError
from gyro_char.io import read_encoder, read_imu
from gyro_char.jobs.base import Console, measurement

# swing.json's estimates and their SI units (docs/design.md section 4).
QUANTITIES = {'scale_factor_error': '1', 'bias': 'rad/s', 'bias_drift': 'rad/s^2',
              'amplitude_encoder': 'rad', 'amplitude_gyro': 'rad', 'period_s': 's'}


def add_options(p, require: bool = True) -> None:
    """
    Add the options of ``gyro-char swing`` but INPUT, ``--out`` and ``--quiet``.

    ``require=False`` leaves ``--period`` optional (the fleet may take it from a manifest).
    """
    p.add_argument('--period', type=float, required=require, metavar='SECONDS',
                   help='commanded swing period T')
    p.add_argument('--axis', choices=('x', 'y', 'z'),
                   help='gyro axis on the swing axis (default: the one that shows the swing)')
    p.add_argument('--imu-topic', default=None, help='sensor_msgs/Imu topic (bags)')
    p.add_argument('--encoder-topic', default=None, help='sensor_msgs/JointState topic (bags)')
    p.add_argument('--encoder-noise', type=float, default=None, metavar='RAD',
                   help='encoder white angle noise (default: estimated from the residuals)')
    p.add_argument('--gyro-arw', type=float, default=None, metavar='RAD_PER_SQRT_S',
                   help='gyro rate noise density N (default: estimated from the residuals)')


def recording_args(path: str) -> dict:
    """Return the INPUT argument of the command for one recording."""
    return {'input': path}


def run(args, console: Optional[Console] = None) -> List[dict]:
    """Calibrate from ``args.input``, write the files in ``args.out``; return the tidy rows."""
    from gyro_char.report.swing_plot import plot_swing, table
    from gyro_char.swing.filter import estimate_swing
    from gyro_char.swing.model import SwingNoise

    console = console or Console()
    if args.period is None:
        raise InputError("no swing period: give --period (fleet: the manifest's period_s "
                         'or --swing-options="--period S")')
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
        print(f'note: {note}', file=console.err)
    print('\n'.join(table(result.estimates)), file=console.out)
    print(f'wrote {args.out}/swing.json, {args.out}/swing.png', file=console.out)
    return tidy(result.estimates.to_json(), result.aligned.axis)


def tidy(swing: dict, channel: str) -> List[dict]:
    """Tidy rows of swing.json: each estimate with value -+ sigma as its 68 % interval."""
    rows = []
    for name, item in swing.items():
        if isinstance(item, dict) and 'value' in item:
            v, s = item['value'], item['sigma']
            rows.append(measurement(channel, name, v, item['unit'], v - s, v + s))
    rows.append(measurement(channel, 'period_s', swing['period_s'], 's'))
    return rows
