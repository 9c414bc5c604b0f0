"""
Speed of ``gyro-char diagnose --kind swing`` on a whole 15-minute 1 kHz run, against its peers.

Every command runs as a child process (``gyro-char ... --quiet``), wall and CPU of the child
measured, everything included (start-up, read, fits, twins, plots, files), on ONE simulated run
(ADIS16405 preset, gyro and encoder at 1 kHz, 5 s period, a 0.2 ms stamp delay):

1. ``gyro-char swing REC --period 5`` (the peer the issue sets the budget against: <= 30 x);
2. ``gyro-char diagnose --kind swing REC`` with the defaults (pseudo-twins, whole run,
   8 baseline twins, 4 posterior-predictive twins);
3. the earlier twin path on the whole run (``--method twins --max-samples`` the run), stopped
   after ``--timeout`` seconds (reported as "> timeout" when it does not finish);
4. on the first 131 072 samples (the old default cut): ``--method twins`` and the default path.

    python bench/bench_diagnosis_swing_speed.py                 # 15 min at 1 kHz
    python bench/bench_diagnosis_swing_speed.py --duration 120  # a quick look
"""
import argparse
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_diagnosis_speed import child_cpu, timed  # noqa: E402

CUT = 2 ** 17


def timed_or_timeout(args, timeout: float) -> tuple:
    """Run ``timed`` with a time limit: (wall, cpu), or (None, None) after ``timeout`` s."""
    exe = os.path.join(os.path.dirname(sys.executable), 'gyro-char')
    cpu0, t0 = child_cpu(), time.perf_counter()
    try:
        proc = subprocess.run([exe] + list(args) + ['--quiet'], capture_output=True,
                              text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, None
    if proc.returncode != 0:
        raise SystemExit(f'gyro-char {" ".join(args)} failed:\n{proc.stderr}')
    return time.perf_counter() - t0, child_cpu() - cpu0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--duration', type=float, default=900.0, help='run length, s (900)')
    ap.add_argument('--rate', type=float, default=1000.0, help='gyro and encoder rate, Hz')
    ap.add_argument('--timeout', type=float, default=1800.0,
                    help='limit of the whole-run twin path, s (default 1800)')
    args = ap.parse_args(argv)
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        cfg = os.path.join(tmp, 'c.yaml')
        with open(cfg, 'w') as fh:
            fh.write(f'gyro: {{rate_hz: {args.rate}}}\nencoder: {{rate_hz: {args.rate}}}\n')
        out = os.path.join(tmp, 'sim')
        timed(['simulate', 'swing', '--out', out, '--duration', str(args.duration), '--config',
               cfg, '--seed', '7', '--effect', 'time_delay:delay_s=0.0002'])
        rec = os.path.join(out, 'recording.mcap')
        n = int(round(args.duration * args.rate))
        rows['swing'] = timed(['swing', rec, '--period', '5', '--out', os.path.join(tmp, 's')])
        rows['diagnose'] = timed(['diagnose', '--kind', 'swing', rec, '--period', '5',
                                  '--out', os.path.join(tmp, 'd')])
        rows['twins_whole'] = timed_or_timeout(
            ['diagnose', '--kind', 'swing', rec, '--period', '5', '--method', 'twins',
             '--max-samples', str(n), '--out', os.path.join(tmp, 'tw')], args.timeout)
        common = ['diagnose', '--kind', 'swing', rec, '--period', '5', '--check', '0',
                  '--max-samples', str(min(CUT, n))]
        rows['twins_cut'] = timed(common + ['--method', 'twins', '--out', os.path.join(tmp, 't')])
        rows['pseudo_cut'] = timed(common + ['--out', os.path.join(tmp, 'p')])
    for k, (wall, cpu) in rows.items():
        if wall is None:
            print(f'{k:12s} not finished after {args.timeout:.0f} s (stopped)')
        else:
            print(f'{k:12s} wall {wall:7.1f} s  cpu {cpu:7.1f} s')
    ratio = rows['diagnose'][0] / rows['swing'][0]
    print(f'diagnose --kind swing (whole {n} samples) / swing: {ratio:.1f} x wall, '
          f'{rows["diagnose"][1] / rows["swing"][1]:.1f} x cpu (target <= 30 x)')
    if rows['twins_whole'][0] is not None:
        print(f'twin path / default on the whole run: '
              f'{rows["twins_whole"][0] / rows["diagnose"][0]:.1f} x wall')
    print(f'twin path / default on the first {min(CUT, n)} samples: '
          f'{rows["twins_cut"][0] / rows["pseudo_cut"][0]:.1f} x wall, '
          f'{rows["twins_cut"][1] / rows["pseudo_cut"][1]:.1f} x cpu')
    return 0 if ratio <= 30.0 else 1


if __name__ == '__main__':
    sys.exit(main())
