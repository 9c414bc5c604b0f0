"""
Every node process stops cleanly on SIGINT and SIGTERM at any instant: exit 0, no traceback.

Real node executables on loopback DDS, stopped at the instants that used to go wrong:
allan_node in the middle of a ``~/compute`` bootstrap (its fit thread was still inside HiGHS
when the interpreter exited: "terminate called without an active exception", exit 134), with
its last checkpoint holding every sample; bench_sim_node while it generates a long run (it
finished the run first, then failed on the shut-down context); swing_kf_node while it takes
data; and every node while its process is still importing.
"""
import signal
import subprocess
import sys
import textwrap
import time

from gyro_char.live.checkpoint import load_checkpoint
from gyro_char.sim.simulator import simulate_static
from node_harness import (
    clean_exit_problems, DOMAINS, EPOCH, Feeder, Listener, make_executor, NodeProcess,
    ros_context, spin_until)
import numpy as np
import pytest
import rclpy
from std_srvs.srv import Trigger

DOMAIN = DOMAINS['shutdown']
SIGNALS = pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM],
                                  ids=['SIGINT', 'SIGTERM'])
CHANNELS = ('gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y', 'accel_z')
NS = '/shutdown_test'  # a namespace of our own: no other graph on the machine answers


def _saved_samples(path) -> int:
    live = load_checkpoint(path)['live']
    return sum(int(live[k]['n_samples']) for k in ('acc', 'pooled') if k in live)


def _inputs(listener, node: str, ns: str = NS) -> str:
    """Return the name of ``node``'s input status (its naming has its own tests)."""
    return next((n for n in listener.last if n in (f'{ns}/{node}: inputs', f'{node}: inputs')),
                '')


def _settled(ex, listener, node: str, key: str, timeout: float, ns: str = NS) -> dict:
    """Spin until ``key`` of the node's input status is positive and equal in two reports."""
    history = []

    def done():
        name = _inputs(listener, node, ns)
        count = listener.count.get(name, 0)
        if count and (not history or history[-1][0] != count):
            history.append((count, listener.values(name).get(key, 0)))
        return len(history) >= 2 and history[-1][1] == history[-2][1] > 0
    assert spin_until(ex, done, timeout), listener.last
    return listener.values(_inputs(listener, node, ns))


def test_allan_node_stops_in_the_middle_of_a_fit(tmp_path):
    """One node stopped with SIGINT, one with SIGTERM (in two namespaces, at the same time)."""
    run = simulate_static(duration=18.0, seed=2)
    x = np.column_stack([run.imu.channels[c] for c in CHANNELS])
    cases = {signal.SIGINT: f'{NS}/int', signal.SIGTERM: f'{NS}/term'}
    nodes, got = {}, {}
    for sig, ns in cases.items():
        nodes[sig] = NodeProcess('allan_node', [
            '-r', f'__ns:={ns}', '-p', f'checkpoint_path:={tmp_path / f"{sig}.npz"}',
            '-p', 'checkpoint_period_s:=3600.0', '-p', 'm_max:=4096',
            '-p', 'fit_bootstrap:=1000', '-p', 'max_rate_hz:=0.0'], DOMAIN)
    try:
        with ros_context(DOMAIN) as context:
            peers = {sig: rclpy.create_node('shutdown_allan_peer', context=context, namespace=ns)
                     for sig, ns in cases.items()}
            feeders = {sig: Feeder(peer, encoder=False) for sig, peer in peers.items()}
            listener = Listener(peers[signal.SIGINT], ['/diagnostics'])
            ex = make_executor(context)
            for peer in peers.values():
                ex.add_node(peer)
            assert spin_until(ex, lambda: all(f.imu.get_subscription_count() > 0
                                              for f in feeders.values()), 30.0), [
                n.output for n in nodes.values()]
            for k in range(run.imu.t.size):
                for feeder in feeders.values():
                    feeder.imu_sample(EPOCH + run.imu.t[k], x[k, :3], x[k, 3:])
                if k % 200 == 199:
                    spin_until(ex, lambda: False, 0.01)
            futures = {}
            for sig, ns in cases.items():
                got[sig] = _settled(ex, listener, 'allan_node', 'samples', 20.0, ns)
                assert got[sig]['samples'] > 1000
                client = peers[sig].create_client(Trigger, f'{ns}/allan_node/compute')
                assert client.wait_for_service(timeout_sec=10.0)
                futures[sig] = client.call_async(Trigger.Request())
            assert spin_until(ex, lambda: all(f.done() for f in futures.values()), 10.0)
            assert all(f.result().success for f in futures.values())
            spin_until(ex, lambda: False, 0.5)  # both bootstraps (6 x 1000 refits) are running
            for sig, node in nodes.items():
                node.proc.send_signal(sig)
            start = time.monotonic()
            for peer in peers.values():
                peer.destroy_node()
        for sig, node in nodes.items():
            assert node.stop(sig, timeout=5.0) is not None, node.output  # a repeated signal
        elapsed = time.monotonic() - start
    finally:
        for node in nodes.values():
            node.stop(signal.SIGKILL)
    assert elapsed < 5.0
    for sig, node in nodes.items():
        assert clean_exit_problems(node) == [], node.output
        assert 'fit cancelled' in node.output
        assert _saved_samples(tmp_path / f'{sig}.npz') == got[sig]['samples']


@SIGNALS
def test_bench_sim_node_stops_while_generating_a_long_run(sig):
    # 8000 s at 333 Hz: seconds of generation (pocketfft), stopped half a second in.
    node = NodeProcess('bench_sim_node', ['-p', 'kind:=static', '-p', 'duration_s:=8000.0'],
                       DOMAIN)
    try:
        assert node.wait_for('generating run 0', 30.0), node.output
        time.sleep(0.5)
        elapsed = node.stop(sig)
    finally:
        node.stop(signal.SIGKILL)
    assert clean_exit_problems(node) == [], node.output
    assert 'generated in' not in node.output  # it did not finish the run first
    assert elapsed is not None and elapsed < 3.0, (elapsed, node.output)


@SIGNALS
def test_swing_kf_node_stops_while_taking_data(sig):
    node = NodeProcess('swing_kf_node', ['-r', f'__ns:={NS}', '-p', 'max_rate_hz:=0.0'], DOMAIN)
    try:
        with ros_context(DOMAIN) as context:
            peer = rclpy.create_node('shutdown_swing_peer', context=context, namespace=NS)
            feeder = Feeder(peer)
            listener = Listener(peer, ['/diagnostics'])
            ex = make_executor(context)
            ex.add_node(peer)
            assert spin_until(ex, lambda: feeder.enc.get_subscription_count() > 0, 30.0), \
                node.output
            k = 0

            def publish(n):
                nonlocal k
                for _ in range(n):
                    t = EPOCH + 1e-3 * k
                    feeder.imu_sample(t, (0.1 * np.sin(t), 0.0, 0.0))
                    feeder.encoder_sample(t, -0.1 * np.cos(t))
                    k += 1
                spin_until(ex, lambda: False, 0.02)
            while (listener.values(_inputs(listener, 'swing_kf_node')) or {}).get(
                    'imu_accepted', 0) < 500:
                assert k < 30000, (listener.last, node.output)
                publish(50)
            node.proc.send_signal(sig)
            start = time.monotonic()
            while node.proc.poll() is None and time.monotonic() - start < 5.0:
                publish(50)  # the data keeps flowing while the node stops
            elapsed = time.monotonic() - start
            node.stop(sig)
            peer.destroy_node()
    finally:
        node.stop(signal.SIGKILL)
    assert clean_exit_problems(node) == [], node.output
    assert elapsed is not None and elapsed < 3.0


def test_every_node_stops_while_still_importing():
    nodes = [NodeProcess(name, [], DOMAIN)
             for name in ('allan_node', 'swing_kf_node', 'bench_sim_node')]
    try:
        time.sleep(0.5)  # the interpreter runs; numpy, scipy and rclpy are being imported
        for sig, node in zip((signal.SIGTERM, signal.SIGINT, signal.SIGTERM), nodes):
            node.proc.send_signal(sig)
        for node in nodes:
            assert node.stop(signal.SIGTERM, timeout=30.0) is not None, node.output
    finally:
        for node in nodes:
            node.stop(signal.SIGKILL)
    for node in nodes:
        assert clean_exit_problems(node) == [], node.output


def test_a_process_stuck_after_a_stop_signal_prints_its_stacks_and_exits():
    """The deadline watchdog: a main thread that never returns (as in a stuck teardown)."""
    code = textwrap.dedent("""
        import os, signal, time
        from gyro_char.nodes.shutdown import STOP
        STOP.EXIT_DEADLINE_S = 1.0
        STOP.install()
        os.kill(os.getpid(), signal.SIGTERM)
        def stuck_in_teardown():
            time.sleep(60)
        stuck_in_teardown()
    """)
    start = time.monotonic()
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=30)
    assert done.returncode == 1, done
    assert 'stuck_in_teardown' in done.stderr, done.stderr
    assert time.monotonic() - start < 20.0
