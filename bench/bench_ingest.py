"""
Ingest speed: the vectorised raw-CDR reader against plain rosbags, in the same run.

Writes a bag of N sensor_msgs/Imu messages (default 3.6 M: 3 h at 333 Hz) with
``gyro_char.recordings.write_bag`` into a temporary directory (never the repository), for sqlite3
and mcap storage, then measures messages/s of

- the fast path (``read_imu_bag``: stamps + 6 channels, not yet sanitised), whole bag;
- rosbags per-message (``AnyReader.messages`` + ``deserialize`` + ``msg_adapters.imu_sample``),
  timed on the first ``--subset`` messages and extrapolated (stated in the output);

checks that both give the same stamps and values bit for bit on that subset, and prints the ratio
of wall-clock rates and of CPU-time rates (the box is shared: CPU time is the steadier figure).
Usage: ``python bench/bench_ingest.py [--n 3600000] [--subset 300000] [--keep DIR]``.
"""
import argparse
from itertools import islice
from pathlib import Path
import shutil
import sys
import tempfile
import time

from gyro_char.ingest.bag_read import read_imu_bag
from gyro_char.ingest.bag_write import typestore
from gyro_char.ingest.sanitize import sanitize
from gyro_char.recordings import IMU_CHANNELS, Recording, write_bag
from msg_adapters import imu_sample
import numpy as np
from rosbags.highlevel import AnyReader


def make_recording(n: int, rate: float = 333.0, seed: int = 1) -> Recording:
    rng = np.random.default_rng(seed)
    t = 1.7e9 + np.arange(n) / rate + rng.uniform(0, 2e-5, n)
    scale = {'gyro': 1e-3, 'accel': 1e-2}
    ch = {k: rng.normal(scale=scale[k.split('_')[0]], size=n) for k in IMU_CHANNELS}
    ch['accel_z'] += 9.80665
    return Recording(t, ch)


def rosbags_per_message(path: Path, count: int):
    """Return (wall s, CPU s, stamps, 6 x values) for the first ``count`` messages via rosbags."""
    start, cpu = time.perf_counter(), time.process_time()
    ts, rows = [], []
    with AnyReader([path], default_typestore=typestore()) as reader:
        for conn, _, raw in islice(reader.messages(), count):
            stamp, six = imu_sample(reader.deserialize(raw, conn.msgtype))
            ts.append(stamp)
            rows.append(six)
    return (time.perf_counter() - start, time.process_time() - cpu, np.array(ts),
            np.array(rows))


def bench(n: int, subset: int, workdir: Path) -> bool:
    rec = make_recording(n)
    ok = True
    print(f'{n} sensor_msgs/Imu messages, bags in {workdir}')
    for storage in ('sqlite3', 'mcap'):
        path = workdir / f'bag_{storage}'
        t0 = time.perf_counter()
        write_bag(str(path), rec, storage=storage)
        t_write = time.perf_counter() - t0
        size = sum(f.stat().st_size for f in path.iterdir())
        t0, c0 = time.perf_counter(), time.process_time()
        fast = read_imu_bag(path, quiet=True)
        t_fast, c_fast = time.perf_counter() - t0, time.process_time() - c0
        t0 = time.perf_counter()
        sanitize(fast)
        t_san = time.perf_counter() - t0
        m = min(subset, n)
        t_slow, c_slow, ts, rows = rosbags_per_message(path, m)
        same = (np.array_equal(ts.view(np.int64), fast.t[:m].view(np.int64)) and all(
            np.array_equal(rows[:, i].view(np.int64), fast.channels[k][:m].view(np.int64))
            for i, k in enumerate(IMU_CHANNELS)))
        ok &= same and len(fast) == n
        fast_rate, slow_rate = n / t_fast, m / t_slow
        print(f'[{storage}] write {t_write:.2f} s ({size / 1e6:.0f} MB) | fast read '
              f'{t_fast:.2f} s = {fast_rate / 1e6:.2f} M msg/s (+ sanitize {t_san:.2f} s) | '
              f'rosbags '
              f'per-message {slow_rate / 1e6:.3f} M msg/s (timed on the first {m} messages, '
              f'extrapolated to {n / slow_rate:.1f} s for all) | speed-up '
              f'{fast_rate / slow_rate:.1f}x wall, {(n / c_fast) / (m / c_slow):.1f}x CPU time '
              f'({c_fast:.2f} s CPU for all vs {c_slow:.2f} s for {m}) | bit-for-bit equal on '
              f'those {m}: {same}')
        shutil.rmtree(path)
    return ok


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--n', type=int, default=3_600_000,
                        help='messages (default 3 h x 333 Hz)')
    parser.add_argument('--subset', type=int, default=300_000,
                        help='messages timed through rosbags per-message deserialization')
    parser.add_argument('--keep', default=None, help='work in this directory (not deleted)')
    args = parser.parse_args(argv)
    if args.keep:
        Path(args.keep).mkdir(parents=True, exist_ok=True)
        return 0 if bench(args.n, args.subset, Path(args.keep)) else 1
    with tempfile.TemporaryDirectory(prefix='bench_ingest_') as tmp:
        return 0 if bench(args.n, args.subset, Path(tmp)) else 1


if __name__ == '__main__':
    sys.exit(main())
