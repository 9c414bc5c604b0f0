#!/usr/bin/env python3
"""
Bench simulator speed, against a peer measured in the same run.

Targets (issue 5): a 15 min, 1 kHz swing run (gyro axis + encoder, the swing filter's Monte Carlo
unit) well under 1 s; a 3 h, 333 Hz, 6-channel static record well under a minute, bag included.
Peer: allantools' Kasdin flicker generator (``allantools.Noise``, the usual way to synthesise
1/f noise in Python) for one channel of the same length - our whole chain includes a 1/f term
per channel, so the ratio says what the rest of the chain costs relative to that one step.

    python bench/bench_sim.py [--quick]
"""
import argparse
import tempfile
import time

import allantools
from gyro_char.cli.commands.simulate import write_record
from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_static, simulate_swing
from timing import best_of


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--quick', action='store_true', help='shorter records (smoke run)')
    args = ap.parse_args()
    scale = 0.1 if args.quick else 1.0
    cfg = load()
    swing_s, static_s = 900.0 * scale, 10800.0 * scale
    n_swing = int(swing_s * cfg.gyro.rate_hz)
    n_static = int(static_s * cfg.gyro.static_rate_hz)

    def peer(n):
        noise = allantools.Noise(n, qd=1.0, b=-1)
        noise.generateNoise()
        return noise.time_series

    def swing_gyro_x():
        return simulate_swing(cfg, duration=swing_s, seed=1, channels=['gyro_x'])

    t_swing, _ = best_of(swing_gyro_x, 3)
    t_peer_swing, _ = best_of(lambda: peer(n_swing), 3)
    print(f'swing {swing_s:g} s @ {cfg.gyro.rate_hz:g} Hz (gyro_x + encoder, {n_swing} + '
          f'{n_swing} samples): {t_swing:.3f} s; allantools 1/f alone: {t_peer_swing:.3f} s; '
          f'ratio {t_peer_swing / t_swing:.2f}x')
    t_all, _ = best_of(lambda: simulate_swing(cfg, duration=swing_s, seed=1), 1)
    print(f'swing, all 6 IMU channels: {t_all:.3f} s')
    t0 = time.perf_counter()
    run = simulate_static(cfg, duration=static_s, seed=1)
    t_static = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        write_record(tmp, run)
        t_bag = time.perf_counter() - t0
    t_peer_static = best_of(lambda: peer(n_static), 1)[0] * 6
    print(f'static {static_s:g} s @ {cfg.gyro.static_rate_hz:.4g} Hz x 6 channels '
          f'({n_static} samples): simulate {t_static:.2f} s + mcap bag {t_bag:.2f} s = '
          f'{t_static + t_bag:.2f} s; allantools 1/f for 6 channels alone: '
          f'{t_peer_static:.2f} s; ratio {t_peer_static / t_static:.2f}x')


if __name__ == '__main__':
    main()
