#!/usr/bin/env python3
"""
Feed the nodes over DDS from the bench simulator (a publisher process for tests and benches).

    python bench/bench_node_feed.py swing --duration 30 --speed 2 --summary out.json
    python bench/bench_node_feed.py static --duration 60 --speed 10 --summary out.json

Publishes ``imu/data_raw`` (sensor_msgs/Imu) and, for swing runs, ``stand/joint_states``
(sensor_msgs/JointState, joint ``swing``) with sensor-data QoS, stamped ``--epoch`` + simulated
time, paced at ``--speed`` times real time in bursts of ``--burst-ms`` of simulated time. Waits
for ``--subscribers`` matched subscriptions first, so that nothing is published into the void.
Writes a JSON summary (messages sent per topic, the simulator's truth, the epoch) to
``--summary``. ``--synthetic`` skips the simulator and sends a known ramp (for throughput runs,
where generating the data must not load the machine during the measurement).
"""
import argparse
import json
import math
import sys
import time

from gyro_char.sim.simulator import simulate_static, simulate_swing
from msg_adapters import fill_imu, to_stamp
import numpy as np
import rclpy
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Imu, JointState

GYRO = ('gyro_x', 'gyro_y', 'gyro_z')
ACCEL = ('accel_x', 'accel_y', 'accel_z')


def make_streams(args) -> tuple:
    """Return (imu t, imu (n, 6), encoder t or None, encoder angle or None, truth)."""
    if args.synthetic:
        n = int(round(args.duration * args.rate_hz))
        t = np.arange(n) / args.rate_hz
        imu = np.zeros((n, 6))
        imu[:, 0] = 0.2 * np.sin(2 * np.pi * t / 5.0)
        imu[:, 5] = 9.81
        angle = -0.2 * 5.0 / (2 * np.pi) * np.cos(2 * np.pi * t / 5.0)
        return t, imu, t, angle, {}
    if args.kind == 'swing':
        run = simulate_swing(duration=args.duration, seed=args.seed)
    else:
        run = simulate_static(duration=args.duration, seed=args.seed)
    imu = np.column_stack([run.imu.channels[c] for c in GYRO + ACCEL])
    if run.encoder is None:
        return run.imu.t, imu, None, None, run.truth
    return run.imu.t, imu, run.encoder.t, run.encoder.channels['encoder'], run.truth


def wait_for_subscribers(node, pubs, count: int, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if all(p.get_subscription_count() >= count for p in pubs):
            return True
        time.sleep(0.05)
    return False


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('kind', choices=('swing', 'static'))
    ap.add_argument('--duration', type=float, default=30.0, help='simulated seconds')
    ap.add_argument('--speed', type=float, default=1.0, help='times real time')
    ap.add_argument('--seed', type=int, default=1)
    ap.add_argument('--epoch', type=float, default=1000.0, help='stamp of simulated t = 0')
    ap.add_argument('--burst-ms', type=float, default=5.0)
    ap.add_argument('--subscribers', type=int, default=1)
    ap.add_argument('--synthetic', action='store_true')
    ap.add_argument('--rate-hz', type=float, default=1000.0, help='synthetic rate')
    ap.add_argument('--frame-id', default='imu_link')
    ap.add_argument('--summary', default='')
    args = ap.parse_args(argv)

    t_imu, imu, t_enc, angle, truth = make_streams(args)
    rclpy.init()
    node = rclpy.create_node('bench_node_feed')
    pub_imu = node.create_publisher(Imu, 'imu/data_raw', qos_profile_sensor_data)
    pubs = [pub_imu]
    pub_enc = None
    if t_enc is not None:
        pub_enc = node.create_publisher(JointState, 'stand/joint_states',
                                        qos_profile_sensor_data)
        pubs.append(pub_enc)
    if not wait_for_subscribers(node, pubs, args.subscribers, 30.0):
        print('no subscriber matched within 30 s', file=sys.stderr)
        return 1
    time.sleep(1.0)  # let the reader side finish matching too (slow under load)
    sent = {'imu': 0, 'encoder': 0}
    burst = args.burst_ms * 1e-3
    t_end = max(t_imu[-1], t_enc[-1] if t_enc is not None else -math.inf)
    i = j = 0
    k = 0
    msg_imu = Imu()
    msg_enc = JointState()
    msg_enc.name = ['swing']
    print('publishing', flush=True)
    start = time.monotonic()
    while True:
        horizon = (k + 1) * burst
        while i < t_imu.size and t_imu[i] < horizon:
            fill_imu(msg_imu, args.epoch + t_imu[i], imu[i, :3], imu[i, 3:], args.frame_id)
            pub_imu.publish(msg_imu)
            i += 1
        while t_enc is not None and j < t_enc.size and t_enc[j] < horizon:
            to_stamp(msg_enc.header.stamp, args.epoch + t_enc[j])
            msg_enc.position = [float(angle[j])]
            pub_enc.publish(msg_enc)
            j += 1
        if horizon > t_end:
            break
        k += 1
        wait = start + horizon / args.speed - time.monotonic()
        if wait > 0:
            time.sleep(wait)
    elapsed = time.monotonic() - start
    sent['imu'], sent['encoder'] = i, j
    summary = {'sent': sent, 'truth': truth, 'epoch': args.epoch, 'elapsed_s': elapsed,
               'first_stamp': float(args.epoch + t_imu[0]),
               'last_stamp': float(args.epoch + t_imu[-1])}
    if args.summary:
        with open(args.summary, 'w') as f:
            json.dump(summary, f)
    print(json.dumps({'sent': sent, 'elapsed_s': elapsed}), flush=True)
    time.sleep(0.5)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
