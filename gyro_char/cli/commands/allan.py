"""
``gyro-char allan INPUT``: Allan variance and IEEE 952 noise terms of a static record.

Writes in ``--out`` (docs/design.md): ``allan.json`` (tau, overlapping ADEV and its 68 %
interval per channel), ``noise.json`` (N, B, K, Q, R per channel, SI, with 68 % intervals and
``resolved``), ``imu.yaml`` (Kalibr noise model: worst axis, per-axis values too) and
``allan.png``. Prints the human table (deg/sqrt(h), deg/h, ...) and every note about the input.
"""
import os
import sys

from gyro_char.cli import add_common
from gyro_char.errors import InputError
from gyro_char.io import read_imu
from gyro_char.report.allan_outputs import write_outputs

DEFAULT_TOPIC = '/imu/data_raw'


def register(subparsers) -> None:
    p = subparsers.add_parser(
        'allan', help='Allan variance + IEEE 952 noise terms (N, B, K, Q, R) of a static record',
        description=__doc__.strip().splitlines()[0])
    p.add_argument('input', metavar='INPUT', help='bag directory, .mcap, ROS 1 .bag or CSV')
    p.add_argument('--topic', default=None, help='sensor_msgs/Imu topic (bags)')
    p.add_argument('--channels', default=None,
                   help='comma-separated, e.g. gyro_x,gyro_y (default: all IMU channels)')
    p.add_argument('--fit', choices=('l1', 'l1w', 'weighted'), default='l1',
                   help='l1: the log-domain L1 objective of the paper (robust where the '
                        'sensor departs from formula (4)); l1w: the same on log estimates '
                        'standardised by their EDF and median-unbiased (more accurate K); '
                        'weighted: EDF-weighted log least squares')
    p.add_argument('--tau-min', type=float, default=None, metavar='S',
                   help='fit only tau >= S (a workaround; --sensor-filter models the filter)')
    p.add_argument('--sensor-filter', default='none', metavar='SPEC',
                   help="the sensor's own output filter, modelled exactly in the white term: "
                        'none (default), auto[@RATE] (estimated from the record), '
                        'boxcar:TAPS[@RATE] or bartlett:TAPS[@RATE]; RATE = the internal rate, '
                        '8x (multiple of the output rate) or Hz (docs/cli.md)')
    p.add_argument('--markov', type=int, choices=(0, 1, 2), default=0,
                   help='up to this many IEEE 952 exponentially correlated (Markov) terms, '
                        'kept only where the term selection keeps them (default 0)')
    p.add_argument('--despike', action='store_true',
                   help='replace detected spikes (impulsive outliers) by the mean of their '
                        'neighbours; counted in a note (spikes are always detected and noted)')
    p.add_argument('--m-max', type=int, default=None,
                   help='largest averaging factor (default: half the record)')
    p.add_argument('--noise-id', choices=('acf', 'fit'), default='acf',
                   help='noise type for the EDF of the intervals: lag-1 autocorrelation, or '
                        'the dominant term of the fit')
    p.add_argument('--boot', type=int, default=100, help='bootstrap curves for the intervals')
    p.add_argument('--seed', type=int, default=0, help='bootstrap seed')
    add_common(p, default_out='allan_out')
    p.set_defaults(func=run)


def run(args) -> int:
    from gyro_char.allan.compute import compute
    from gyro_char.allan.edf import add_confidence, alpha_from_model
    from gyro_char.allan.fit import fit_result
    from gyro_char.allan.sensor_filter import parse_spec
    from gyro_char.report.allan_plot import table
    import numpy as np

    parse_spec(args.sensor_filter)  # a bad spec is a usage error before any reading
    rec = read_imu(args.input, topic=args.topic, quiet=args.quiet)
    channels = None
    if args.channels:
        channels = [c.strip() for c in args.channels.split(',') if c.strip()]
    res = compute(rec, channels=channels, m_max=args.m_max, sensor_filter=args.sensor_filter,
                  despike=args.despike)
    try:
        fits = fit_result(res, method=args.fit, tau_min=args.tau_min, n_boot=args.boot,
                          seed=args.seed, markov=args.markov)
    except ValueError as exc:
        raise InputError(f'cannot fit the noise model: {exc}') from None
    if args.noise_id == 'fit':
        alpha = np.stack([alpha_from_model(res.tau, fits[n].coeffs()) for n in res.channels],
                         axis=1)
        add_confidence(res, alpha)
    write_outputs(args.out, res, fits, args.topic or DEFAULT_TOPIC,
                  title=f'{os.path.basename(str(args.input))}: {res.n_samples} samples at '
                        f'{1.0 / res.dt:.6g} Hz, fit {args.fit}')
    for note in res.notes:
        print(f'note: {note}', file=sys.stderr)
    print('\n'.join(table(fits)))
    print(f'wrote {args.out}/allan.json, noise.json, imu.yaml, allan.png')
    return 0
