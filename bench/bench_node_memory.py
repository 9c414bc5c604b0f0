#!/usr/bin/env python3
"""
allan_node memory over a day: 24 h at 1 kHz x 6 channels through AllanLive, faster than real time.

Feeds ``AllanLive`` (the node's accumulation path: stamp checks, segments, motion detector,
``AllanAccumulator``) with synthetic white noise, with the node's default ``m_max`` and chunks
of ``--chunk-s`` seconds, and prints the process RSS every ``--report-h`` simulated hours. The
peers measured in the same run: the raw size of the data fed (what keeping the samples would
cost) and real time.

    python bench/bench_node_memory.py --hours 24 --rate 1000
"""
import argparse
import sys
import time

from gyro_char.allan_live import AllanLive
import numpy as np


def rss_mb() -> float:
    with open('/proc/self/status') as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    return float('nan')


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--hours', type=float, default=24.0)
    ap.add_argument('--rate', type=float, default=1000.0)
    ap.add_argument('--m-max', type=int, default=2 ** 18, help="the node's default")
    ap.add_argument('--chunk-s', type=float, default=60.0)
    ap.add_argument('--report-h', type=float, default=2.0)
    args = ap.parse_args()
    dt = 1.0 / args.rate
    chunk = int(round(args.chunk_s * args.rate))
    n_chunks = int(round(args.hours * 3600.0 / args.chunk_s))
    rss_import = rss_mb()
    # Compile the numba kernel first: a one-off cost of the process, not of the run.
    AllanLive(rate_hz=args.rate, m_max=64, feed_chunk=256).add(
        1.0 + np.arange(1000) * dt, np.random.default_rng(1).normal(size=(1000, 6)))
    live = AllanLive(rate_hz=args.rate, m_max=args.m_max, feed_chunk=chunk)
    rng = np.random.default_rng(0)
    base = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 9.81])
    rss0 = rss_mb()
    start = time.monotonic()
    next_report = args.report_h
    rss_warm = None
    print(f'RSS after imports {rss_import:.1f} MB, after the numba compile {rss0:.1f} MB; '
          f'{n_chunks} chunks of {chunk} samples', flush=True)
    for i in range(n_chunks):
        t = (i * chunk + np.arange(chunk)) * dt + 1.0
        live.add(t, base + rng.normal(0.0, 0.01, (chunk, 6)))
        hours = (i + 1) * args.chunk_s / 3600.0
        if rss_warm is None and hours >= 1.0:
            rss_warm = rss_mb()  # tail full (2 m_max samples) and allocator warm
        if hours >= next_report - 1e-9 or i == n_chunks - 1:
            print(f'{hours:6.2f} h simulated: RSS {rss_mb():7.1f} MB, '
                  f'{time.monotonic() - start:7.1f} s wall', flush=True)
            next_report += args.report_h
    wall = time.monotonic() - start
    res = live.result()
    raw_mb = live.n_samples * 6 * 8 / 2 ** 20
    growth = rss_mb() - rss0
    print(f'samples {live.n_samples} ({raw_mb:.0f} MB raw), tau_max {res.tau[-1]:.0f} s, '
          f'gaps {live.gaps}, motion events {live.motion.event_count}')
    print(f'RSS growth over the run {growth:.1f} MB (target < 100 MB), after the first hour '
          f'{rss_mb() - (rss_warm or rss0):.1f} MB; ratio growth / raw data '
          f'{growth / raw_mb:.4f}')
    print(f'speed: {args.hours * 3600.0 / wall:.0f}x real time ({wall:.0f} s wall)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
