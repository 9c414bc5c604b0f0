#!/usr/bin/env python3
"""
Motion detector of allan_node on the real static ADIS16405 records (false-alarm check).

Runs ``MotionDetector`` with the node's defaults over both 2.8 h records in the node's chunk
size (0.1 s) and prints every flagged event, plus, as the peer in the same run, the same records
with a synthetic knock (0.2 g damped 15 Hz on accel_x, 0.05 rad/s on gyro_x) added at
t = 5000 s, which must be found.

    python bench/bench_node_motion_real.py
"""
from pathlib import Path
import sys

from gyro_char.io import read_imu
from gyro_char.live.motion_detect import MotionDetector
from gyro_char.records import IMU_CHANNELS
import numpy as np

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'adis16405'


def run(t: np.ndarray, x: np.ndarray, dt: float) -> MotionDetector:
    det = MotionDetector(dt)
    step = max(1, int(round(0.1 / dt)))
    for i in range(0, t.size, step):
        det.add(t[i:i + step], x[i:i + step])
    return det


def main() -> int:
    for k in (1, 2):
        rec = read_imu(str(DATA / f'adis16405_static_{k}.csv.gz'), quiet=True)
        t = rec.t
        x = np.column_stack([rec.channels[c] for c in IMU_CHANNELS])
        dt = rec.dt
        det = run(t, x, dt)
        events = [(round(e.start_s, 2), round(e.end_s, 2), IMU_CHANNELS[e.channel],
                   round(e.peak_score, 2)) for e in det.events]
        print(f'record {k}: {t.size} samples, {det.blocks} blocks of {det.block_len}; '
              f'{det.event_count} events {events}')
        i0 = int(np.searchsorted(t, 5000.0))
        tau = np.arange(30) * dt
        knock = x.copy()
        knock[i0:i0 + 30, 3] += 2.0 * np.exp(-tau / 0.05) * np.sin(2 * np.pi * 15 * tau)
        knock[i0:i0 + 30, 0] += 0.05 * np.exp(-tau / 0.05) * np.sin(2 * np.pi * 15 * tau)
        found = [e for e in run(t, knock, dt).events if abs(e.start_s - 5000.0) < 1.0]
        print(f'record {k} + knock at 5000 s: found {bool(found)} '
              f'{[(round(e.start_s, 2), IMU_CHANNELS[e.channel]) for e in found]}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
