"""
The swing Nyquist screen (``gyro_char.diagnosis.swing_nyquist``) over a harness's shape sets.

Records as ``validate_diagnosis_swing.py`` makes them (15 min, 1 kHz, adis16405 preset, 5 s
period; the same seeds), no diagnosis run: per record the screen's chi-square, p and flag.
Every set's shapes but an alternating one should pass unflagged, and so should clean runs
(``--clean N`` of them): the screen's false warnings. Usage::

    python bench/screen_nyquist.py                   # the development shapes
    python bench/screen_nyquist.py --held-out aj     # one held-out set
    python bench/screen_nyquist.py --held-out all --clean 20
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from gyro_char.diagnosis.swing_nyquist import record_screen  # noqa: E402

import validate_diagnosis_swing as harness  # noqa: E402


def screen(truth, seed, shape_set, duration) -> dict:
    """Return the screen of one harness record of ``truth`` ([(name, level)]) and ``seed``."""
    imu, enc = harness.make_record(truth, seed, duration=duration, shape_set=shape_set)
    return record_screen(imu, enc, 'x', harness.PERIOD)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[1])
    ap.add_argument('--held-out', default=None,
                    help="a held-out set's letter, or 'all' (default: the development shapes)")
    ap.add_argument('--seed', type=int, default=11)
    ap.add_argument('--clean', type=int, default=1, help='clean runs (seeds from --seed)')
    ap.add_argument('--duration', type=float, default=harness.DURATION)
    args = ap.parse_args(argv)
    letters = (harness.held_out_letters() if args.held_out == 'all'
               else [args.held_out] if args.held_out else [None])
    flagged, total = {}, {}
    for k in range(args.clean):
        s = screen([], args.seed + k, harness.SHAPES, args.duration)
        print(f'clean seed {args.seed + k}: chi2 {s["chi2"]:8.1f} p {s["p_value"]:.2e}'
              f'{"  FLAGGED" if s["flagged"] else ""}', flush=True)
        total['clean'] = total.get('clean', 0) + 1
        flagged['clean'] = flagged.get('clean', 0) + s['flagged']
    for letter in letters:
        shape_set = (harness.held_out_shapes(harness.RATE_HZ, letter) if letter
                     else harness.SHAPES)
        for name, (_, levels) in shape_set.items():
            for level in range(len(levels)):
                s = screen([(name, level)], args.seed, shape_set, args.duration)
                tag = f'{letter or "dev"} {name}/{harness.level_name(level)}'
                print(f'{tag:45s} chi2 {s["chi2"]:10.1f} p {s["p_value"]:.2e} rms '
                      f'{s["rms_rad_s"]:.2e}{"  FLAGGED" if s["flagged"] else ""}', flush=True)
                total[name] = total.get(name, 0) + 1
                flagged[name] = flagged.get(name, 0) + s['flagged']
    print('flagged / records:', ', '.join(f'{n} {flagged[n]}/{total[n]}' for n in total))
    return 0


if __name__ == '__main__':
    sys.exit(main())
