"""allan_node on a real DDS graph: in-process, and kill -9 / resume as a separate process."""
import json
import os
import signal
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticArray
from gyro_char.allan.compute import compute
from gyro_char.live.checkpoint import load_checkpoint
from gyro_char.nodes.allan_node import AllanNode
from gyro_char.nodes.common import LATCHED_1
from gyro_char.records import Recording
from gyro_char.sim.simulator import simulate_static
from msg_adapters.diagnostics import parse_multiarray
from node_harness import (
    DOMAINS, EPOCH, Feeder, Listener, make_executor, node_command, read_json, ROOT, ros_context,
    ros_env, spin_until, stop)
import numpy as np
import pytest
import rclpy
from rclpy.parameter import Parameter
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger

DOMAIN_IN_PROCESS, DOMAIN_PROCESS = DOMAINS['allan']
INPUTS = '/allan_node: inputs'
CHANNELS = ['gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y', 'accel_z']


@pytest.fixture(scope='module')
def sim():
    return simulate_static(duration=120.0, seed=7)


def _graph(context, **params):
    # The tests replay faster than real time (bursts of 300 messages); on an idle machine that
    # exceeds the node's 20 kHz flood cap and drops samples. The cap has its own tests
    # (test_node_swing.py, test_node_support.py), so it is off here unless a test sets it.
    params.setdefault('max_rate_hz', 0.0)
    node = AllanNode(context=context,
                     parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])
    peer = rclpy.create_node('allan_test_peer', context=context)
    listener = Listener(peer, ['/diagnostics'])
    feeder = Feeder(peer, encoder=False)
    ex = make_executor(context)
    ex.add_node(node)
    ex.add_node(peer)
    assert spin_until(ex, lambda: feeder.imu.get_subscription_count() > 0, 10.0)
    return node, peer, listener, feeder, ex


def _publish(ex, node, feeder, t, x, burst=300, frame_id='imu_link'):
    start = node.health.received
    for i in range(0, t.size, burst):
        for k in range(i, min(i + burst, t.size)):
            feeder.imu_sample(t[k], x[k, :3], x[k, 3:], frame_id=frame_id)
        assert spin_until(ex, lambda: node.health.received >= start + min(i + burst, t.size),
                          5.0), 'messages lost in process'
    node.process()


def _call(ex, peer, service):
    client = peer.create_client(Trigger, service)
    assert client.wait_for_service(timeout_sec=5.0)
    future = client.call_async(Trigger.Request())
    assert spin_until(ex, future.done, 10.0)
    return future.result()


def _sim_arrays(sim):
    return EPOCH + sim.imu.t, np.column_stack([sim.imu.channels[c] for c in CHANNELS])


def test_curve_and_noise_against_batch_and_truth(sim, tmp_path):
    t, x = _sim_arrays(sim)
    with ros_context(DOMAIN_IN_PROCESS) as context:
        node, peer, listener, feeder, ex = _graph(
            context, m_max=2 ** 12, fit_bootstrap=8, output_dir=str(tmp_path / 'out'))
        _publish(ex, node, feeder, t, x)
        assert node.live.n_samples == t.size
        result = _call(ex, peer, '/allan_node/compute')
        assert result.success, result.message
        # Late subscribers still get both results (reliable + TRANSIENT_LOCAL, depth 1).
        got = {}
        peer.create_subscription(Float64MultiArray, '/allan_node/allan_curve',
                                 lambda m: got.setdefault('curve', m), LATCHED_1)
        noise = Listener(peer, ['/allan_node/noise'], LATCHED_1)
        assert spin_until(ex, lambda: 'curve' in got, 5.0)
        assert spin_until(ex, lambda: len(noise.last) == 6, 90.0), node.fit_status
        data, labels = parse_multiarray(got['curve'])
        assert labels[0] == ('channel', CHANNELS)
        assert labels[1] == ('quantity', ['tau_s', 'adev', 'adev_lo', 'adev_hi'])
        # The curve equals the batch path on the same samples (tau differs by the dt estimate:
        # the node's is the median of the first 200 intervals, the batch's of all of them).
        batch = compute(sim.imu, m_max=2 ** 12)
        k = min(batch.tau.size, data.shape[2])
        np.testing.assert_allclose(data[0, 0, :k], batch.tau[:k], rtol=1e-4)
        np.testing.assert_allclose(data[:, 1, :k], batch.adev[:k].T, rtol=1e-9)
        assert np.all(data[:, 2] <= data[:, 1]) and np.all(data[:, 1] <= data[:, 3])
        # N of every gyro axis against the simulator's truth.
        for c in CHANNELS[:3]:
            level, _, v = noise.last[f'/allan_node: noise {c}']
            truth_n = sim.truth['channels'][c]['N']
            assert level == 0 and v['N_resolved'] == 1
            assert v['N_lo_rad_sqrt_s'] * 0.9 <= truth_n <= v['N_hi_rad_sqrt_s'] * 1.1, (v, c)
            assert v['samples'] == t.size
        assert spin_until(ex, lambda: 'files written' in node.fit_status, 30.0), node.fit_status
        noise_json = json.loads((tmp_path / 'out' / 'noise.json').read_text())
        gx = noise.last['/allan_node: noise gyro_x'][2]
        assert noise_json['channels']['gyro_x']['N']['value'] == pytest.approx(
            gx['N_rad_sqrt_s'], rel=1e-12)
        assert sorted(os.listdir(tmp_path / 'out')) == [
            'allan.json', 'allan.png', 'imu.yaml', 'noise.json']
        # ~/reset clears.
        assert _call(ex, peer, '/allan_node/reset').success
        assert node.live.n_samples == 0
        assert not _call(ex, peer, '/allan_node/compute').success
        node.destroy_node()


def test_channels_parameter_limits_what_is_accumulated_and_fitted(sim):
    t, x = _sim_arrays(sim)
    t, x = t[:8000], x[:8000]
    chosen = ['gyro_z', 'accel_x']
    with ros_context(DOMAIN_IN_PROCESS) as context:
        node, peer, listener, feeder, ex = _graph(context, m_max=2 ** 12, fit_bootstrap=8,
                                                  channels=chosen)
        _publish(ex, node, feeder, t, x)
        got = {}
        peer.create_subscription(Float64MultiArray, '/allan_node/allan_curve',
                                 lambda m: got.setdefault('curve', m), LATCHED_1)
        noise = Listener(peer, ['/allan_node/noise'], LATCHED_1)
        assert _call(ex, peer, '/allan_node/compute').success
        assert spin_until(ex, lambda: 'curve' in got and noise.last, 60.0), node.fit_status
        node.destroy_node()
    data, labels = parse_multiarray(got['curve'])
    assert labels[0] == ('channel', chosen)
    # The same curve as the batch path on those channels of the same samples.
    first = Recording(sim.imu.t[:8000], {c: sim.imu.channels[c][:8000] for c in chosen})
    batch = compute(first, channels=chosen, m_max=2 ** 12)
    k = min(batch.tau.size, data.shape[2])
    np.testing.assert_allclose(data[:, 1, :k], batch.adev[:k].T, rtol=1e-9)
    assert sorted(noise.last) == [f'/allan_node: noise {c}' for c in ('accel_x', 'gyro_z')]


def test_bad_input_motion_and_gaps_reported(sim):
    t, x = _sim_arrays(sim)
    t, x = t[:20_000].copy(), x[:20_000].copy()
    x[5000, 0] = np.nan
    # A knock on the table (0.2 g peak) at t = 1040 s (sample 13333 at 333 Hz).
    k = np.arange(13_333, 13_433)
    tau = (k - k[0]) / 333.3
    x[k, 3] += 2.0 * np.exp(-tau / 0.05) * np.sin(2 * np.pi * 15 * tau)
    keep = np.ones(t.size, bool)
    keep[15_000:15_100] = False  # 100 samples lost
    with ros_context(DOMAIN_IN_PROCESS) as context:
        node, peer, listener, feeder, ex = _graph(context, m_max=2 ** 12, frame_id='imu_link')
        _publish(ex, node, feeder, t[keep], x[keep])
        for _ in range(3):
            feeder.imu_sample(0.0, (0, 0, 0), raw_stamp=(0, 0))
        for j in range(4):
            feeder.imu_sample(t[100 + j], (0, 0, 0))  # long past
        for j in range(5):
            feeder.imu_sample(t[-1] + 1e-4 * (j + 1), (0, 0, 0), frame_id='other')
        assert spin_until(ex, lambda: node.health.received == keep.sum() + 12, 5.0)
        node.process()
        node.publish_diagnostics()
        # Wait for a status with the current counts (a timer one may still be in flight).
        assert spin_until(ex, lambda: (listener.values(INPUTS) or {}).get('imu_received')
                          == keep.sum() + 12, 3.0)
        level, message, v = listener.last[INPUTS]
        assert v['imu_dropped_zero_stamp'] == 3, v
        assert v['imu_dropped_backwards'] == 4
        assert v['imu_dropped_wrong_frame'] == 5
        assert v['dropped_non_finite'] == 1 and v['imu_dropped_non_finite'] == 1
        assert v['gaps'] == 2 and v['segments'] == 3
        assert v['samples'] == keep.sum() - 1
        assert v['motion_events'] == 1
        assert 1039.0 <= v['motion_last_start_s'] <= 1040.0 <= v['motion_last_end_s']
        assert level == 1 and 'motion detected' in message  # persists: the record is tainted
        node.destroy_node()


def test_parameters_are_validated():
    with ros_context(DOMAIN_IN_PROCESS) as context:
        node = AllanNode(context=context)
        for p in (Parameter('fit_method', value='ols'), Parameter('m_max', value=1024),
                  Parameter('checkpoint_period_s', value=0.0),
                  Parameter('fit_bootstrap', value=1)):
            r = node.set_parameters([p])[0]
            assert not r.successful and r.reason, p.name
        assert node.set_parameters([Parameter('fit_method', value='weighted')])[0].successful
        assert node.describe_parameter('checkpoint_path').read_only
        node.destroy_node()


def _start_node(env, ck, extra=()):
    return subprocess.Popen(
        node_command('allan_node') + [
            '--ros-args', '--params-file', str(ROOT / 'config' / 'allan_node.yaml'),
            '-p', f'checkpoint_path:={ck}', '-p', 'checkpoint_period_s:=1.0',
            '-p', 'm_max:=4096', '-p', 'fit_bootstrap:=8', '-p', 'feed_chunk:=500', *extra],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


def test_kill_9_and_resume_loses_at_most_one_checkpoint_period(tmp_path):
    """Kill the node process with SIGKILL mid-record, restart it, and finish the record."""
    env = ros_env(DOMAIN_PROCESS)
    ck = tmp_path / 'allan.npz'
    summary = tmp_path / 'feed.json'
    speed, rate = 3.0, 1000.0 / 3.0
    node = _start_node(env, ck)
    feed = subprocess.Popen(
        [sys.executable, str(ROOT / 'bench' / 'bench_node_feed.py'), 'static', '--duration',
         '75', '--speed', str(speed), '--seed', '11', '--summary', str(summary)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    second = None
    try:
        with ros_context(DOMAIN_PROCESS) as context:
            peer = rclpy.create_node('allan_kill_listener', context=context)
            diags = []
            peer.create_subscription(DiagnosticArray, '/diagnostics',
                                     lambda m: diags.append(m), 10)
            listener = Listener(peer, ['/diagnostics'])
            ex = make_executor(context)
            ex.add_node(peer)
            assert spin_until(ex, lambda: (listener.values(INPUTS) or {}).get('samples', 0)
                              > 6 * rate * speed, 40.0), listener.last
            # Kill right after a fresh diagnostics message (its counts are then current).
            n_seen = len(diags)
            assert spin_until(ex, lambda: len(diags) > n_seen, 3.0)
            before = listener.values(INPUTS)
            node.send_signal(signal.SIGKILL)
            node.wait(timeout=10)
            saved = load_checkpoint(ck)['live']
            saved_samples = int(saved['acc']['n_samples']) if 'acc' in saved else 0
            saved_samples += int(saved['pooled']['n_samples']) if 'pooled' in saved else 0
            # Lost: what the node had before the kill minus the checkpoint: at most one
            # checkpoint period (1 s; or the checkpoint's age the node reported, where a
            # loaded machine ran its timer late) plus the processing timer's tick and a margin.
            assert before['checkpoint_writes'] >= 1
            window = max(1.0, float(before['checkpoint_age_s'])) + 0.1 + 0.1
            assert before['samples'] - saved_samples <= window * rate * speed, (
                before['samples'], saved_samples)
            assert before['last_stamp_s'] - float(saved['last_t']) <= window * speed
            time.sleep(0.5)
            second = _start_node(env, ck)
            assert spin_until(ex, lambda: (listener.values(INPUTS) or {}).get(
                'resumed_samples') == saved_samples, 20.0), listener.last
            assert spin_until(ex, lambda: listener.values(INPUTS)['samples']
                              > saved_samples + 2 * rate * speed, 20.0), (
                'the restarted node got no data before the feeder ended', listener.last)
            assert feed.wait(timeout=60) == 0
            sent = read_json(summary)['sent']['imu']
            # Wait until the count stops moving (the last messages are in).
            counts = []
            peer.create_subscription(
                DiagnosticArray, '/diagnostics',
                lambda m: counts.append(listener.values(INPUTS)['samples']), 10)
            assert spin_until(ex, lambda: len(counts) > 2 and counts[-1] == counts[-2], 10.0)
            final = listener.values(INPUTS)
            # Everything published while a node was up is in, except one period before the
            # kill: the gap from the kill to the restart is the only other loss.
            downtime = final['gap_time_s']
            assert final['gaps'] >= 1 and downtime > 0, final
            assert sent - final['samples'] <= rate * (downtime + window * speed) + 50
            assert final['resumed_samples'] == saved_samples
            client = peer.create_client(Trigger, '/allan_node/compute')
            assert client.wait_for_service(timeout_sec=10.0)
            future = client.call_async(Trigger.Request())
            assert spin_until(ex, future.done, 20.0) and future.result().success
            noise = Listener(peer, ['/allan_node/noise'], LATCHED_1)
            assert spin_until(ex, lambda: '/allan_node: noise gyro_x' in noise.last, 90.0)
            v = noise.last['/allan_node: noise gyro_x'][2]
            truth = read_json(summary)['truth']['channels']['gyro_x']['N']
            assert v['samples'] == final['samples']
            assert v['N_rad_sqrt_s'] == pytest.approx(truth, rel=0.1)
            peer.destroy_node()
    finally:
        for proc in (feed, node, second):
            if proc is not None:
                stop(proc)
    assert second.returncode == 0


def test_invalid_startup_parameter_exits_2_with_the_reason():
    proc = subprocess.run(node_command('allan_node') + ['--ros-args', '-p', 'fit_method:=ols'],
                          env=ros_env(DOMAIN_PROCESS), capture_output=True, timeout=60)
    assert proc.returncode == 2
    assert proc.stderr.decode().strip().splitlines() == [
        "allan_node: invalid parameter: fit_method must be one of ['l1', 'l1w', 'weighted'], "
        "got 'ols'"]
