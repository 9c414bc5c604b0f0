"""
The narrow-line scan's false alarms on clean records and its reach on weak steady lines.

Clean records are the validation harness's (white noise at the ADIS16405's level, a bias,
the 0.05 deg/s output step); the lines are pure tones of a given share of the white noise's
per-sample sd at a fixed frequency, random phase. Printed: how many clean records report a
line (family-wise p below the report level) and the quantiles of their smallest p; per line
level, how many records report it at its frequency, and the gap's tone-block element there
against the clean record's (what the coarse bins see).

    python bench/narrow_lines_check.py --clean 60 --lines 20 --duration 7200
"""
import argparse

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.narrow_lines import line_scan, narrow_lines, REPORT_P
import numpy as np
import validate_diagnosis as vd


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--clean', type=int, default=60, help='clean records (seeds 200..)')
    ap.add_argument('--lines', type=int, default=20, help='records per line level')
    ap.add_argument('--duration', type=float, default=7200.0, help='record length, s')
    ap.add_argument('--freq', type=float, default=13.3, help='line frequency, Hz')
    ap.add_argument('--levels', type=float, nargs='+', default=[0.01, 0.015, 0.02],
                    help="line amplitudes in units of the white noise's per-sample sd")
    args = ap.parse_args(argv)
    n = int(round(args.duration / vd.DT))
    layout = obs.static_layout(n, vd.DT)
    band = int(args.freq // (0.5 / vd.DT / len(layout.ranges['tone'])))
    ps, alarms = [], 0
    for s in range(args.clean):
        x = vd.make_record([], n, 200 + s)
        scan = line_scan(x, vd.DT)
        ps.append(float(scan['p'].min()))
        alarms += bool(narrow_lines(x, vd.DT)['lines'])
    q = np.quantile(ps, [0.05, 0.5, 0.95])
    print(f'clean: {alarms}/{args.clean} report a line (p < {REPORT_P:g}); smallest p per '
          f'record: 5 % {q[0]:.3g}, median {q[1]:.3g}, 95 % {q[2]:.3g}; below 0.1: '
          f'{sum(p < 0.1 for p in ps)} (uniform: {0.1 * args.clean:.0f})')
    for level in args.levels:
        hits, tone_rise = 0, []
        for s in range(args.lines):
            rng = np.random.default_rng(500 + s)
            x = vd.clean(n, rng)
            t = np.arange(n) * vd.DT
            y = x + level * vd.SIG * np.sin(2 * np.pi * args.freq * t + rng.uniform(0, 6.3))
            x, y = (np.round(v / vd.LSB) * vd.LSB for v in (x, y))
            found = narrow_lines(y, vd.DT)['lines']
            hits += any(abs(d['frequency_hz'] - args.freq) < 0.01 for d in found)
            tone_rise.append(obs.static_observables(y, layout)['tone'][band]
                             - obs.static_observables(x, layout)['tone'][band])
        print(f'line {level:g} sd at {args.freq:g} Hz: found in {hits}/{args.lines}; the tone '
              f'block element rises by {np.mean(tone_rise):.3f} +- {np.std(tone_rise):.3f} '
              '(log10)')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
