"""
``gyro-char diagnose`` of this checkout against an earlier commit, on the same simulated runs.

Both codes run as child processes (the earlier one from a temporary ``git worktree``, first
on ``sys.path``), wall and CPU of the child measured, best of ``--repeats``; the peer
``gyro-char swing`` / ``allan`` on the same run is timed beside them. Also says whether the
two ``diagnosis.json`` agree (every float within 1e-6 relative, same selection).

    python bench/bench_diagnosis_ab.py --old 9c1cc80                  # swing 15 min, 1 kHz
    python bench/bench_diagnosis_ab.py --old 9c1cc80 --kind static    # static 2 h, 100 Hz
"""
import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_diagnosis_speed import child_cpu  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def run(root: str, args: list) -> tuple:
    """Run ``gyro-char ARGS`` with the package at ``root``; return (wall s, cpu s)."""
    code = (f'import sys; sys.path.insert(0, {root!r}); from gyro_char.cli import main; '
            'sys.exit(main(sys.argv[1:]))')
    cpu0, t0 = child_cpu(), time.perf_counter()
    subprocess.run([sys.executable, '-c', code] + args + ['--quiet'], check=True,
                   capture_output=True)
    return time.perf_counter() - t0, child_cpu() - cpu0


def same(a, b) -> bool:
    """Whether two JSON values agree: floats within 1e-6 relative, paths aside."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(
            k == 'source' or same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float):
        return abs(a - b) <= 1e-6 * max(abs(a), abs(b), 1e-12)
    return a == b


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--old', required=True, help='the earlier commit (any git revision)')
    ap.add_argument('--kind', choices=('swing', 'static'), default='swing')
    ap.add_argument('--repeats', type=int, default=2)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        old = os.path.join(tmp, 'old')
        subprocess.run(['git', '-C', str(ROOT), 'worktree', 'add', '-q', '--detach', old,
                        args.old], check=True)
        try:
            rows = compare(str(ROOT), old, tmp, args)
        finally:
            subprocess.run(['git', '-C', str(ROOT), 'worktree', 'remove', '--force', old],
                           check=False)
    best = {k: min(v) for k, v in rows.items() if k != 'same'}
    for k, (wall, cpu) in best.items():
        print(f'{k:6s} wall {wall:7.1f} s  cpu {cpu:7.1f} s')
    (ow, oc), (nw, nc), pw = best['old'], best['new'], best['peer'][0]
    print(f'old / new: {ow / nw:.2f} x wall, {oc / nc:.2f} x cpu; '
          f'new / peer {nw / pw:.1f} x wall (old {ow / pw:.1f} x)')
    print('diagnosis.json the same:', rows['same'])
    return 0 if rows['same'] else 1


def compare(new: str, old: str, tmp: str, args) -> dict:
    """Simulate the run, time peer, old and new; return their (wall, cpu) lists and 'same'."""
    sim = os.path.join(tmp, 'sim')
    if args.kind == 'swing':
        cfg = os.path.join(tmp, 'c.yaml')
        with open(cfg, 'w') as fh:
            fh.write('gyro: {rate_hz: 1000.0}\nencoder: {rate_hz: 1000.0}\n')
        run(new, ['simulate', 'swing', '--out', sim, '--duration', '900', '--config', cfg,
                  '--seed', '3', '--effect', 'time_delay:delay_s=0.0002'])
        rec = os.path.join(sim, 'recording.mcap')
        peer = ['swing', rec, '--period', '5']
        diag = ['diagnose', '--kind', 'swing', rec, '--period', '5']
    else:
        run(new, ['simulate', 'static', '--out', sim, '--duration', '7200', '--seed', '3',
                  '--effect', 'gauss_markov:sigma=0.001,tau_s=60'])
        rec = os.path.join(sim, 'recording.mcap')
        peer = ['allan', rec]
        diag = ['diagnose', '--kind', 'static', rec, '--channels', 'gyro_x']
    rows = {'peer': [], 'old': [], 'new': []}
    for _ in range(args.repeats):
        rows['peer'].append(run(new, peer + ['--out', os.path.join(tmp, 'peer')]))
        for name, root in (('old', old), ('new', new)):
            rows[name].append(run(root, diag + ['--out', os.path.join(tmp, name)]))
    a, b = (json.loads(Path(tmp, n, 'diagnosis.json').read_text()) for n in ('old', 'new'))
    rows['same'] = same(a, b)
    return rows


if __name__ == '__main__':
    sys.exit(main())
