"""
bench_sim_node over real DDS: in-process (own Context) and as a separate process on loopback.

Checks that the published values are exactly the core's simulated run for the same seed, that
the stamps are the simulated sample instants (plus the start epoch), and that bad parameters
are refused with a reason.
"""
import subprocess
import sys

from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_static, simulate_swing
import numpy as np
import pytest

rclpy = pytest.importorskip('rclpy')
from node_harness import (  # noqa: E402,I100
    collect, DOMAINS, ROOT, ros_context, ros_env, spin_until)
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from sensor_msgs.msg import Imu, JointState  # noqa: E402

from gyro_char.nodes.bench_sim_node import BenchSimNode  # noqa: E402,I100

DOMAIN_IN_PROCESS, DOMAIN_CROSS_PROCESS = DOMAINS['bench_sim']
DEEP = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10000,
                  reliability=ReliabilityPolicy.BEST_EFFORT)


def _stamp(msg):
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


@pytest.fixture
def context():
    with ros_context(DOMAIN_IN_PROCESS) as ctx:
        yield ctx


def _graph(context, node, listener):
    executor = rclpy.executors.SingleThreadedExecutor(context=context)
    for n in (node, listener):
        if n is not None:
            executor.add_node(n)
    return executor


def _teardown(executor, *nodes):
    executor.shutdown()
    for n in nodes:
        n.destroy_node()


def test_in_process_swing_values_are_the_cores_run(context):
    node = BenchSimNode(context=context, parameter_overrides=[
        Parameter('duration_s', value=2.0), Parameter('rate_factor', value=4.0),
        Parameter('seed', value=5)])
    listener = rclpy.create_node('bench_sim_listener', context=context)
    imu, enc = [], []
    listener.create_subscription(Imu, 'imu/data_raw', imu.append, DEEP)
    listener.create_subscription(JointState, 'stand/joint_states', enc.append, DEEP)
    executor = _graph(context, node, listener)
    spin_until(executor, lambda: len(imu) >= 2000 and len(enc) >= 2000, 15.0)
    base = node.stamp_base_ns
    _teardown(executor, node, listener)
    run = simulate_swing(load(), duration=2.0, seed=5)
    assert len(imu) >= 0.95 * len(run.imu) and len(enc) >= 0.95 * len(run.encoder)
    want_t = np.round(run.imu.t * 1e9).astype(np.int64) + base
    index = np.searchsorted(want_t, [_stamp(m) for m in imu])
    assert np.array_equal(want_t[index], [_stamp(m) for m in imu])
    got = np.array([[m.angular_velocity.x, m.linear_acceleration.z] for m in imu])
    assert np.array_equal(got[:, 0], run.imu.channels['gyro_x'][index])
    assert np.array_equal(got[:, 1], run.imu.channels['accel_z'][index])
    assert imu[0].orientation_covariance[0] == -1.0
    enc_t = np.round(run.encoder.t * 1e9).astype(np.int64) + base
    index = np.searchsorted(enc_t, [_stamp(m) for m in enc])
    assert np.array_equal(enc_t[index], [_stamp(m) for m in enc])
    assert np.array_equal([m.position[0] for m in enc], run.encoder.channels['encoder'][index])
    assert all(list(m.name) == ['stand_joint'] for m in enc)


def test_parameters_are_validated(context):
    node = BenchSimNode(context=context, parameter_overrides=[
        Parameter('duration_s', value=1.0)])
    try:
        bad = node.set_parameters([Parameter('rate_factor', value=0.0)])[0]
        assert not bad.successful
        good = node.set_parameters([Parameter('rate_factor', value=2.5)])[0]
        assert good.successful and node.p['rate_factor'] == 2.5
        ro = node.set_parameters([Parameter('seed', value=3)])[0]
        assert not ro.successful    # read-only: shapes the run
        desc = node.describe_parameters(['rate_factor'])[0]
        assert desc.description and desc.floating_point_range
    finally:
        node.destroy_node()
    from gyro_char.nodes.common import InvalidParameter
    with pytest.raises(InvalidParameter, match='kind'):
        BenchSimNode(context=context, parameter_overrides=[Parameter('kind', value='moving')])


def _node_cmd(*params):
    cmd = [sys.executable, '-m', 'gyro_char.nodes.bench_sim_node', '--ros-args',
           '--params-file', str(ROOT / 'config' / 'bench_sim_node.yaml')]
    for p in params:
        cmd += ['-p', p]
    return cmd


def test_separate_process_static_run_over_loopback(monkeypatch):
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    proc = subprocess.Popen(_node_cmd('kind:=static', 'duration_s:=30.0', 'seed:=9'),
                            env=ros_env(DOMAIN_CROSS_PROCESS), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    try:
        imu = collect(DOMAIN_CROSS_PROCESS, Imu, 'imu/data_raw', DEEP, 300, 20.0,
                      alive=lambda: proc.poll() is None, node_name='bench_sim_remote_listener',
                      poll=0.05)
    finally:
        proc.terminate()
        _, err = proc.communicate(timeout=10)
    assert len(imu) >= 300, f'no Imu from bench_sim_node; stderr: {err.decode()[-2000:]}'
    stamps = np.array([_stamp(m) for m in imu], dtype=np.int64)
    # Real time at 333 Hz: consecutive stamps 3 ms apart (jitter 10 us), and the values are
    # the core's static run of the same seed.
    assert np.all(np.diff(stamps) > 0)
    assert np.median(np.diff(stamps)) == pytest.approx(3e6, rel=0.01)
    run = simulate_static(load(), duration=30.0, seed=9)
    gx = run.imu.channels['gyro_x']
    rel = np.round(run.imu.t * 1e9).astype(np.int64)
    offsets = stamps - stamps[0]
    # Find the run index of the first received message: the only candidate whose stamp
    # offsets (ns, with jitter) and values match every received message (drops tolerated).
    values = np.array([m.angular_velocity.x for m in imu])
    found = []
    for k in np.flatnonzero(gx == values[0]):
        idx = np.searchsorted(rel, rel[k] + offsets)
        if idx[-1] < rel.size and np.array_equal(rel[idx], rel[k] + offsets) \
                and np.array_equal(gx[idx], values):
            found.append(k)
    assert len(found) == 1


@pytest.mark.parametrize('param,message', [
    ('kind:=moving', b'kind must be one of'),
])
def test_bad_parameter_exits_2(param, message):
    proc = subprocess.run(_node_cmd(param), env=ros_env(DOMAIN_CROSS_PROCESS),
                          capture_output=True, timeout=60)
    assert proc.returncode == 2
    assert message in proc.stdout + proc.stderr


def test_repeat_continues_stamps_with_the_next_seed(context):
    listener = rclpy.create_node('bench_sim_repeat_listener', context=context)
    imu = []
    listener.create_subscription(Imu, 'imu/data_raw', imu.append, DEEP)
    node = BenchSimNode(context=context, parameter_overrides=[
        Parameter('duration_s', value=0.3), Parameter('rate_factor', value=0.5),
        Parameter('kind', value='static'), Parameter('repeat', value=True)])
    executor = _graph(context, node, listener)
    spin_until(executor, lambda: node.run_index >= 2, 10.0)
    runs = node.run_index
    _teardown(executor, node, listener)
    assert runs >= 2
    stamps = np.array([_stamp(m) for m in imu])
    assert np.all(np.diff(stamps) > 0)
    # Run 1 (seed 1) follows run 0 (seed 0): its first samples are the core's seed-1 run,
    # stamped after the last one of run 0.
    first = simulate_static(load(), duration=0.3, seed=1).imu.channels['gyro_x'][:10]
    values = np.array([m.angular_velocity.x for m in imu])
    hits = [k for k in range(len(values) - 10) if np.array_equal(values[k:k + 10], first)]
    assert len(hits) == 1 and hits[0] > 0


def test_unknown_effect_is_refused_in_process(context):
    from gyro_char.errors import InputError
    with pytest.raises(InputError, match='unknown effect'):
        BenchSimNode(context=context, parameter_overrides=[
            Parameter('effects', value=['warp_drive'])])


def test_wait_for_subscribers_holds_the_first_sample(context):
    node = BenchSimNode(context=context, parameter_overrides=[
        Parameter('duration_s', value=1.0), Parameter('kind', value='static'),
        Parameter('rate_factor', value=2.0), Parameter('wait_for_subscribers', value=1)])
    executor = _graph(context, node, None)
    spin_until(executor, lambda: False, 0.5)  # no subscriber for 0.5 s: nothing goes out
    assert node.published['imu'] == 0 and node.waiting
    listener = rclpy.create_node('bench_sim_wait_listener', context=context)
    imu = []
    listener.create_subscription(Imu, 'imu/data_raw', imu.append, DEEP)
    executor.add_node(listener)
    spin_until(executor, lambda: len(imu) >= 333, 10.0)
    base = node.stamp_base_ns
    _teardown(executor, node, listener)
    run = simulate_static(load(), duration=1.0, seed=0)
    assert len(imu) == len(run.imu)
    assert _stamp(imu[0]) == base + int(np.round(run.imu.t[0] * 1e9))


def test_empty_effects_and_an_integer_duration_are_accepted(context):
    node = BenchSimNode(context=context, parameter_overrides=[
        Parameter('effects', value=[]), Parameter('duration_s', value=1),
        Parameter('kind', value='static')])
    try:
        assert node.effects == [] and node.p['duration_s'] == 1.0
        assert node.imu_t.size == simulate_static(load(), duration=1.0, seed=0).imu.t.size
    finally:
        node.destroy_node()
