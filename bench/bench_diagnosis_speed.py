"""
Speed of ``gyro-char diagnose --kind static`` on whole records, against its peers in one run.

Every command runs as a child process (``gyro-char ... --quiet``), wall and CPU (user + system
of the child) measured, everything included (start-up, read, fit, twins, plots, files):

1. ``gyro-char allan REC`` (the peer the issue sets the budget against: diagnose <= 30 x);
2. ``gyro-char diagnose --kind static REC`` with the defaults (closed forms, whole record,
   every gyro channel, 8 baseline twins, 4 posterior-predictive twins);
3. on the first ``--short`` samples of one channel: the earlier twin-based path
   (``--method twins``: every candidate scored on simulated twins) and the closed-form path,
   the same record and options.

    python bench/bench_diagnosis_speed.py            # the real ADIS16405 session 1 (2.8 h)
    python bench/bench_diagnosis_speed.py --quick    # a simulated 20 min record (the test)
"""
import argparse
import os
from pathlib import Path
import resource
import shutil
import subprocess
import sys
import tempfile
import time

REAL = (Path(__file__).resolve().parents[1].parent / 'shared' / 'data' / 'adis16405'
        / 'adis16405_static_1.csv.gz')


def child_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def timed(args) -> tuple:
    """Run ``gyro-char ARGS`` in a child process; return (wall s, cpu s)."""
    exe = shutil.which('gyro-char') or os.path.join(os.path.dirname(sys.executable),
                                                    'gyro-char')
    cpu0, t0 = child_cpu(), time.perf_counter()
    proc = subprocess.run([exe] + list(args) + ['--quiet'], capture_output=True, text=True)
    wall, cpu = time.perf_counter() - t0, child_cpu() - cpu0
    if proc.returncode != 0:
        raise SystemExit(f'gyro-char {" ".join(args)} failed:\n{proc.stderr}')
    return wall, cpu


def simulated_record(directory: str, duration: float) -> str:
    """Simulate a static record (ADIS16405 preset, smoothing filter on) as a bag."""
    out = os.path.join(directory, 'sim')
    timed(['simulate', 'static', '--out', out, '--duration', str(duration), '--seed', '7',
           '--effect', 'internal_lowpass:taps=7,stages=2,decimation=8'])
    return os.path.join(out, 'recording.mcap')


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--record', default=str(REAL), help='static record (default: session 1)')
    ap.add_argument('--short', type=int, default=16384,
                    help='samples of the shorter record both paths run on (default 16384)')
    ap.add_argument('--quick', action='store_true',
                    help='a simulated 20 min record and a 4096-sample short record')
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        record, short = args.record, args.short
        if args.quick:
            record, short = simulated_record(tmp, 1200.0), 4096
        elif not os.path.exists(record):
            raise SystemExit(f'no record at {record}')
        rows = {}
        rows['allan'] = timed(['allan', record, '--out', os.path.join(tmp, 'a')])
        rows['diagnose'] = timed(['diagnose', '--kind', 'static', record,
                                  '--out', os.path.join(tmp, 'd')])
        common = ['diagnose', '--kind', 'static', record, '--channels', 'gyro_x',
                  '--max-samples', str(short), '--check', '0']
        rows['twins_short'] = timed(common + ['--method', 'twins',
                                              '--out', os.path.join(tmp, 't')])
        rows['closed_short'] = timed(common + ['--out', os.path.join(tmp, 'c')])
    for k, (wall, cpu) in rows.items():
        print(f'{k:14s} wall {wall:7.1f} s  cpu {cpu:7.1f} s')
    ratio = rows['diagnose'][0] / rows['allan'][0]
    print(f'diagnose (whole record, all gyro channels) / allan: {ratio:.1f} x wall, '
          f'{rows["diagnose"][1] / rows["allan"][1]:.1f} x cpu (target <= 30 x)')
    print(f'twin-based / closed-form on the first {short} samples of gyro_x: '
          f'{rows["twins_short"][0] / rows["closed_short"][0]:.1f} x wall, '
          f'{rows["twins_short"][1] / rows["closed_short"][1]:.1f} x cpu')
    return 0 if ratio <= 30.0 else 1


if __name__ == '__main__':
    sys.exit(main())
