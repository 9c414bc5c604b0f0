"""
The swing screens beside the gap (Nyquist, waveform drift, IMU stalls) over a harness's shape sets.

Records as ``validate_diagnosis_swing.py`` makes them (15 min, 1 kHz, adis16405 preset, 5 s
period unless ``--period``; the same seeds), no diagnosis run: per record the screen's
statistic, p and flag. ``--screen nyquist`` (``gyro_char.diagnosis.swing_nyquist``): every
shape but an alternating one should pass; ``--screen drift`` (``swing_drift``): every shape
constant over the run should; ``--screen stalls`` (``swing_stalls``): every shape whose
stamps are not a stalling host's should (the statistic: the mean latency, s). Clean runs
(``--clean N``) give the false warnings. Usage::

    python bench/screen_swing.py                   # Nyquist, the development shapes
    python bench/screen_swing.py --held-out aj     # one held-out set
    python bench/screen_swing.py --held-out all --clean 20
    python bench/screen_swing.py --screen drift --clean 20 --held-out aj
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from gyro_char.diagnosis.swing_drift import record_drift  # noqa: E402
from gyro_char.diagnosis.swing_nyquist import record_screen  # noqa: E402
from gyro_char.diagnosis.swing_stalls import record_stalls  # noqa: E402

import validate_diagnosis_swing as harness  # noqa: E402

SCREENS = {'nyquist': (record_screen, 'chi2'), 'drift': (record_drift, 'statistic'),
           'stalls': (lambda imu, enc, axis, period: record_stalls(imu), 'mean_latency_s')}


def screen(truth, seed, shape_set, duration, kind='nyquist',
           period=harness.PERIOD) -> dict:
    """Return the screen of one harness record of ``truth`` ([(name, level)]) and ``seed``."""
    imu, enc = harness.make_record(truth, seed, period, duration=duration,
                                   shape_set=shape_set)
    return SCREENS[kind][0](imu, enc, 'x', period)


def line(s: dict, key: str) -> str:
    """Return one record's statistic, p and flag (or why it was not tested)."""
    if not s.get('tested', True):
        return f'not tested: {s["reason"]}'
    p = f' p {s["p_value"]:.2e}' if 'p_value' in s else ''
    return f'{key} {s[key]:10.4g}{p}{"  FLAGGED" if s["flagged"] else ""}'


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    ap.add_argument('--screen', choices=sorted(SCREENS), default='nyquist')
    ap.add_argument('--held-out', default=None,
                    help="a held-out set's letter, or 'all' (default: the development shapes)")
    ap.add_argument('--seed', type=int, default=11)
    ap.add_argument('--clean', type=int, default=1, help='clean runs (seeds from --seed)')
    ap.add_argument('--duration', type=float, default=harness.DURATION)
    ap.add_argument('--period', type=float, default=harness.PERIOD)
    args = ap.parse_args(argv)
    key = SCREENS[args.screen][1]
    letters = (harness.held_out_letters() if args.held_out == 'all'
               else [args.held_out] if args.held_out else [None])
    flagged, total = {}, {}

    def count(name, s):
        total[name] = total.get(name, 0) + 1
        flagged[name] = flagged.get(name, 0) + bool(s.get('flagged'))

    for k in range(args.clean):
        s = screen([], args.seed + k, harness.SHAPES, args.duration, args.screen, args.period)
        print(f'clean seed {args.seed + k}: {line(s, key)}', flush=True)
        count('clean', s)
    for letter in letters:
        shape_set = (harness.held_out_shapes(harness.RATE_HZ, letter) if letter
                     else harness.SHAPES)
        for name, (_, levels) in shape_set.items():
            for level in range(len(levels)):
                s = screen([(name, level)], args.seed, shape_set, args.duration, args.screen,
                           args.period)
                tag = f'{letter or "dev"} {name}/{harness.level_name(level)}'
                print(f'{tag:45s} {line(s, key)}', flush=True)
                count(name, s)
    print('flagged / records:', ', '.join(f'{n} {flagged[n]}/{total[n]}' for n in total))
    return 0


if __name__ == '__main__':
    sys.exit(main())
