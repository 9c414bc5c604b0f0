"""
``gyro-char fleet`` scaling: wall time with 1 and 2 local Dask workers, measured in one run.

Simulates ``--devices`` static records of ``--duration`` s (the bench simulator, all six IMU
channels at the preset's static rate, each written as a ROS 2 bag), then runs the fleet's allan
job on all of them with a LocalCluster of 1 worker and of 2 workers (fresh output directories,
so nothing comes from the resume cache; cluster start-up included). Prints both wall times and
their ratio, and the peak resident memory of each worker process against that of one
``gyro-char allan`` process on one of the records (a worker holds one recording at a time).

    python bench/bench_fleet.py [--devices 8] [--duration 3600] [--workers 1,2] [--repeat 1]
"""
import argparse
from collections import defaultdict
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

from gyro_char.fleet.run import FleetConfig, run_fleet
from gyro_char.io import write_bag
from gyro_char.sim.simulator import simulate_static

MB = 1024.0 ** 2


def make_fleet(folder: Path, devices: int, duration: float) -> int:
    """Write the simulated records (kept from an earlier run in ``folder``); return samples."""
    n = 0
    for i in range(devices):
        rec = simulate_static(duration=duration, seed=100 + i).imu
        n = rec.t.size
        if not (folder / f'imu{i:02d}' / 'metadata.yaml').is_file():
            write_bag(str(folder / f'imu{i:02d}'), rec)
    return n


def single_command_rss(record: Path, out: Path, boot: int) -> float:
    """Peak RSS (bytes) of one ``gyro-char allan`` process on one record (as it reports)."""
    code = ('import resource, sys; from gyro_char.cli import main; rc = main(sys.argv[1:]); '
            'print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, file=sys.stderr); '
            'sys.exit(rc)')
    run = subprocess.run([sys.executable, '-c', code, 'allan', str(record), '--out', str(out),
                          '--boot', str(boot), '--quiet'], check=True, text=True,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return float(run.stderr.strip().splitlines()[-1]) * 1024.0


def run_once(data: Path, out: Path, workers: int, boot: int) -> float:
    """Run the fleet on ``data`` with ``workers`` local workers; print and return its wall time."""
    cfg = FleetConfig(inputs=[str(data)], out=str(out), workers=workers, quiet=True,
                      job_options={'allan': f'--boot {boot}'})
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    rc = run_fleet(cfg)
    wall = time.perf_counter() - t0
    peaks, cpu, busy = defaultdict(float), 0.0, 0.0
    for entry in (out / '.fleet-cache').glob('*.json'):
        e = json.loads(entry.read_text())
        peaks[e['pid']] = max(peaks[e['pid']], e['peak_rss'])
        cpu, busy = cpu + e['cpu_seconds'], busy + e['seconds']
    print(f'{workers} worker(s): {wall:7.1f} s wall (exit {rc}); tasks: {busy:.1f} s wall, '
          f'{cpu:.1f} s CPU (CPU / wall {cpu / busy:.2f}: below 1 when the workers wait for a '
          f'core); load average before {load:.2f}')
    rss = ', '.join(f'{v / MB:.0f} MB' for v in sorted(peaks.values()))
    print(f'  peak RSS per worker: {rss}')
    return wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--devices', type=int, default=8)
    ap.add_argument('--duration', type=float, default=3600.0, help='seconds per record')
    ap.add_argument('--workers', default='1,2', help='worker counts to compare')
    ap.add_argument('--repeat', type=int, default=1,
                    help='runs per worker count, interleaved; the best wall time counts')
    ap.add_argument('--boot', type=int, default=100, help='allan --boot (the default 100)')
    ap.add_argument('--dir', default=None, help='working directory (default: a temporary one)')
    args = ap.parse_args()
    root = Path(args.dir or tempfile.mkdtemp(prefix='bench_fleet_'))
    data = root / 'data'
    data.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    n = make_fleet(data, args.devices, args.duration)
    print(f'{args.devices} records of {args.duration:g} s ({n} samples x 6 channels, '
          f'{n * 7 * 8 / MB:.0f} MB in memory each) written in '
          f'{time.perf_counter() - t0:.1f} s; {os.cpu_count()} cores')
    walls = defaultdict(list)
    for rep in range(args.repeat):
        for workers in [int(w) for w in args.workers.split(',')]:
            walls[workers].append(run_once(data, root / f'out_w{workers}_{rep}', workers,
                                           args.boot))
    single = single_command_rss(data / 'imu00', root / 'single', args.boot)
    print(f'one gyro-char allan process on one record: peak RSS {single / MB:.0f} MB')
    if 1 in walls and 2 in walls:
        print(f'speed-up 2 workers vs 1 (best of {args.repeat}): '
              f'x{min(walls[1]) / min(walls[2]):.2f}')
    print(f'outputs in {root}')


if __name__ == '__main__':
    main()
