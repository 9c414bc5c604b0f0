#!/usr/bin/env python3
"""
swing_kf_node throughput over DDS on loopback: 1 kHz Imu + 1 kHz JointState for 60 s.

Processes on one ROS domain (loopback only): the feeder (``bench_node_feed.py --synthetic``),
the real ``swing_kf_node`` and, as peers measured in the same run, a bare rclpy subscriber with
the same executor and QoS that only counts messages (the floor any Python node pays for
receiving these messages) and the same with rclpy's SingleThreadedExecutor (why the nodes use
the EventsExecutor). CPU is utime + stime of each process from /proc/<pid>/stat over the
feeding window, in % of one core. Drops are messages sent minus messages the node's own
counters saw (``imu_received`` in /diagnostics).

    python bench/bench_node_throughput.py --duration 60 --domain 28
"""
import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
BARE = r"""
import sys, time, rclpy
from gyro_char.nodes.common import make_executor, sensor_qos
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import Imu, JointState
rclpy.init()
node = rclpy.create_node('bare_counter_' + sys.argv[2])
n = [0, 0]
node.create_subscription(Imu, 'imu/data_raw', lambda m: n.__setitem__(0, n[0] + 1),
                         sensor_qos(2000))
node.create_subscription(JointState, 'stand/joint_states',
                         lambda m: n.__setitem__(1, n[1] + 1), sensor_qos(2000))
ex = make_executor() if sys.argv[2] == 'events' else SingleThreadedExecutor()
ex.add_node(node)
end = time.monotonic() + float(sys.argv[1])
while time.monotonic() < end:
    ex.spin_once(timeout_sec=0.2)
print(n[0], n[1], flush=True)
"""


def cpu_ticks(pid: int) -> int:
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return int(fields[11]) + int(fields[12])  # utime + stime


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--duration', type=float, default=60.0)
    ap.add_argument('--domain', type=int, default=28)
    args = ap.parse_args()
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               ROS_DOMAIN_ID=str(args.domain))
    env['PYTHONPATH'] = str(ROOT) + os.pathsep + env.get('PYTHONPATH', '')
    hz = os.sysconf('SC_CLK_TCK')
    tmp = Path(tempfile.mkdtemp(prefix='bench_node_'))
    node = subprocess.Popen([sys.executable, '-m', 'gyro_char.nodes.swing_kf_node', '--ros-args',
                             '-p', 'publish_rate_hz:=2.0'], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    bare = subprocess.Popen([sys.executable, '-c', BARE, str(args.duration + 10), 'events'],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    single = subprocess.Popen([sys.executable, '-c', BARE, str(args.duration + 10), 'single'],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    listen = subprocess.Popen(
        [sys.executable, '-c', LISTEN, str(args.duration + 15), str(tmp / 'diag.json')],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(3.0)
    feed = subprocess.Popen(
        [sys.executable, str(ROOT / 'bench' / 'bench_node_feed.py'), 'swing', '--synthetic',
         '--duration', str(args.duration), '--subscribers', '3', '--summary',
         str(tmp / 'feed.json')], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    # The feeder waits for both subscribers and says when it starts publishing.
    while feed.stdout.readline().strip() != b'publishing':
        if feed.poll() is not None:
            raise SystemExit('feeder ended before publishing: ' + feed.stdout.read().decode())
    t0, n0, b0, s0 = (time.monotonic(), cpu_ticks(node.pid), cpu_ticks(bare.pid),
                      cpu_ticks(single.pid))
    feed.wait()
    t1, n1, b1, s1 = (time.monotonic(), cpu_ticks(node.pid), cpu_ticks(bare.pid),
                      cpu_ticks(single.pid))
    sent = json.loads((tmp / 'feed.json').read_text())['sent']
    time.sleep(3.0)
    listen.wait()
    diag = json.loads((tmp / 'diag.json').read_text())
    bare_counts = bare.communicate(timeout=60)[0].decode().split()
    single_counts = single.communicate(timeout=60)[0].decode().split()
    node.send_signal(2)
    node.wait(timeout=10)
    wall = t1 - t0
    node_cpu = 100.0 * (n1 - n0) / hz / wall
    bare_cpu = 100.0 * (b1 - b0) / hz / wall
    single_cpu = 100.0 * (s1 - s0) / hz / wall
    print(f'window {wall:.1f} s; sent imu {sent["imu"]}, encoder {sent["encoder"]}')
    print(f'swing_kf_node: received imu {diag["imu_received"]}, encoder '
          f'{diag["encoder_received"]}; dropped {sent["imu"] - diag["imu_received"]} / '
          f'{sent["encoder"] - diag["encoder_received"]}; samples in filter '
          f'{diag["samples_gyro"]} / {diag["samples_encoder"]}')
    print(f'bare counter (EventsExecutor): received {bare_counts[0]} / {bare_counts[1]}, '
          f'CPU {bare_cpu:.1f} %; same with SingleThreadedExecutor: received '
          f'{single_counts[0]} / {single_counts[1]}, CPU {single_cpu:.1f} %')
    print(f'CPU (% of one core): swing_kf_node {node_cpu:.1f}, bare subscriber {bare_cpu:.1f}, '
          f'ratio {node_cpu / max(bare_cpu, 1e-9):.2f}; target < 25 %')
    return 0


LISTEN = r"""
import json, sys, time, rclpy
from diagnostic_msgs.msg import DiagnosticArray
from msg_adapters.diagnostics import parse_key_values
rclpy.init()
node = rclpy.create_node('bench_listener')
last = {}
def on(m):
    for s in m.status:
        last.update(parse_key_values(s))
node.create_subscription(DiagnosticArray, '/diagnostics', on, 10)
node.create_subscription(DiagnosticArray, '/swing_kf_node/estimates', on, 10)
end = time.monotonic() + float(sys.argv[1])
while time.monotonic() < end:
    rclpy.spin_once(node, timeout_sec=0.2)
json.dump(last, open(sys.argv[2], 'w'))
"""


if __name__ == '__main__':
    sys.exit(main())
