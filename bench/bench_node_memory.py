#!/usr/bin/env python3
"""
allan_node memory over a day: 24 h at 1 kHz x 6 channels through AllanLive, faster than real time.

Feeds ``AllanLive`` (the node's accumulation path: stamp checks, segments, motion detector,
``AllanAccumulator``) with synthetic white noise, with the node's default ``m_max`` and chunks
of ``--chunk-s`` seconds, after the node's allocator setting (``return_freed_memory``; pass
``--glibc-default`` to measure without it), and prints the process RSS every ``--report-h``
simulated hours. What is measured, separately:

- the numba compile (a one-off cost of the process): RSS after imports vs after the compile;
- the run: RSS growth over the post-compile baseline, at the end and after the first hour;
- the run's peak: the kernel's RSS high-water mark (VmHWM, reset after the compile through
  /proc/self/clear_refs) over the same baseline, i.e. including the transient working buffers
  of an ``add``.

Peers measured in the same run: the raw size of the data fed (what keeping the samples would
cost) and real time.

    python bench/bench_node_memory.py --hours 24 --rate 1000
"""
import argparse
import sys
import time

from gyro_char.live.allan_live import AllanLive, return_freed_memory
import numpy as np


def status_mb(key: str) -> float:
    with open('/proc/self/status') as f:
        for line in f:
            if line.startswith(key + ':'):
                return int(line.split()[1]) / 1024.0
    return float('nan')


def reset_peak() -> bool:
    try:
        with open('/proc/self/clear_refs', 'w') as f:
            f.write('5')  # resets VmHWM to the current RSS
        return True
    except OSError:
        return False


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--hours', type=float, default=24.0)
    ap.add_argument('--rate', type=float, default=1000.0)
    ap.add_argument('--m-max', type=int, default=2 ** 18, help="the node's default")
    ap.add_argument('--chunk-s', type=float, default=60.0)
    ap.add_argument('--report-h', type=float, default=2.0)
    ap.add_argument('--glibc-default', action='store_true',
                    help="skip the node's allocator setting (the behaviour before it)")
    args = ap.parse_args()
    applied = False if args.glibc_default else return_freed_memory()
    dt = 1.0 / args.rate
    chunk = int(round(args.chunk_s * args.rate))
    n_chunks = int(round(args.hours * 3600.0 / args.chunk_s))
    rss_import = status_mb('VmRSS')
    # Compile the numba kernel first: a one-off cost of the process, reported on its own.
    AllanLive(rate_hz=args.rate, m_max=64, feed_chunk=256).add(
        1.0 + np.arange(1000) * dt, np.random.default_rng(1).normal(size=(1000, 6)))
    live = AllanLive(rate_hz=args.rate, m_max=args.m_max, feed_chunk=chunk)
    rng = np.random.default_rng(0)
    base = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 9.81])
    rss0 = status_mb('VmRSS')
    peak_ok = reset_peak()
    start = time.monotonic()
    next_report = args.report_h
    rss_warm = None
    print(f'allocator setting (return_freed_memory) applied: {applied}')
    print(f'RSS after imports {rss_import:.1f} MB, after the numba compile {rss0:.1f} MB '
          f'(compile: {rss0 - rss_import:.1f} MB, not counted below); {n_chunks} chunks of '
          f'{chunk} samples', flush=True)
    for i in range(n_chunks):
        t = (i * chunk + np.arange(chunk)) * dt + 1.0
        live.add(t, base + rng.normal(0.0, 0.01, (chunk, 6)))
        hours = (i + 1) * args.chunk_s / 3600.0
        if rss_warm is None and hours >= 1.0:
            rss_warm = status_mb('VmRSS')  # tail full (2 m_max samples) and allocator warm
        if hours >= next_report - 1e-9 or i == n_chunks - 1:
            print(f'{hours:6.2f} h simulated: RSS {status_mb("VmRSS"):7.1f} MB, '
                  f'{time.monotonic() - start:7.1f} s wall', flush=True)
            next_report += args.report_h
    wall = time.monotonic() - start
    res = live.result()
    raw_mb = live.n_samples * 6 * 8 / 2 ** 20
    rss_end = status_mb('VmRSS')
    growth = rss_end - rss0
    peak = status_mb('VmHWM') - rss0 if peak_ok else float('nan')
    print(f'samples {live.n_samples} ({raw_mb:.0f} MB raw), tau_max {res.tau[-1]:.0f} s, '
          f'gaps {live.gaps}, motion events {live.motion.event_count}')
    print(f'RSS growth over the run {growth:.1f} MB (target < 100 MB), after the first hour '
          f'{rss_end - (rss_warm or rss0):.1f} MB; ratio growth / raw data {growth / raw_mb:.4f}')
    print(f'peak RSS during the run (VmHWM) {peak:.1f} MB over the post-compile baseline; '
          f'with the compile {rss_end - rss_import:.1f} MB end, '
          f'{peak + rss0 - rss_import:.1f} MB peak')
    print(f'speed: {args.hours * 3600.0 / wall:.0f}x real time ({wall:.0f} s wall)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
