"""
Two IMUs in namespaces, as an integrator runs them: real allan_node processes on loopback DDS.

Both instances load the shipped parameter file (``/**/allan_node:`` keys, so it applies under
``-r __ns:=/imu0``), one of them also a section for itself only (``/imu1/allan_node:``). Their
/diagnostics statuses are named after the fully qualified node names and carry different
default hardware_ids; imu0's input is remapped, and its imu.yaml names the resolved topic. Its
accelerometers are noiseless, so their fits fail: the gyro results are still written, and the
failures are reported on ~/noise and in the diagnostics.
"""
import json
import signal

from diagnostic_msgs.msg import DiagnosticArray
from gyro_char.sim.simulator import simulate_static
from msg_adapters import fill_imu
from msg_adapters.diagnostics import level_of, parse_key_values
from node_harness import (
    clean_exit_problems, DOMAINS, EPOCH, make_executor, NodeProcess, ROOT, ros_context,
    spin_until)
import rclpy
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger
import yaml

DOMAIN = DOMAINS['instances']
REMAPPED = '/drivers/imu0/raw'
GYROS = ['gyro_x', 'gyro_y', 'gyro_z']


class Statuses:
    """Last (level, message, hardware_id, values) of each status name seen on some topics."""

    def __init__(self, node, topics, qos=10) -> None:
        self.last = {}
        for topic in topics:
            node.create_subscription(DiagnosticArray, topic, self._on, qos)

    def _on(self, msg) -> None:
        for st in msg.status:
            self.last[st.name] = (level_of(st), st.message, st.hardware_id, parse_key_values(st))


def _params_file(tmp_path):
    """Return the shipped allan_node.yaml with a few test values, plus an /imu1-only section."""
    shipped = yaml.safe_load((ROOT / 'config' / 'allan_node.yaml').read_text())
    assert list(shipped) == ['/**/allan_node']
    params = shipped['/**/allan_node']['ros__parameters']
    params.update({'m_max': 4096, 'fit_bootstrap': 8, 'max_rate_hz': 0.0,
                   'output_dir': str(tmp_path / 'out')})
    shipped['/imu1/allan_node'] = {'ros__parameters': {'hardware_id': 'imu1_board'}}
    path = tmp_path / 'allan_node.yaml'
    path.write_text(yaml.safe_dump(shipped, sort_keys=False))
    return path


def test_two_imus_in_namespaces(tmp_path):
    params = _params_file(tmp_path)
    imu0 = NodeProcess('allan_node', ['-r', '__ns:=/imu0', '--params-file', str(params),
                                      '-r', f'imu/data_raw:={REMAPPED}'], DOMAIN)
    imu1 = NodeProcess('allan_node', ['-r', '__ns:=/imu1', '--params-file', str(params),
                                      '-p', f'output_dir:={tmp_path / "out1"}'], DOMAIN)
    run = simulate_static(duration=18.0, seed=5)
    try:
        with ros_context(DOMAIN) as context:
            peer = rclpy.create_node('instances_peer', context=context)
            pub = peer.create_publisher(Imu, REMAPPED, qos_profile_sensor_data)
            diags = Statuses(peer, ['/diagnostics'])
            noise = Statuses(peer, ['/imu0/allan_node/noise'], 1)
            ex = make_executor(context)
            ex.add_node(peer)
            names = ['/imu0/allan_node: inputs', '/imu1/allan_node: inputs']
            assert spin_until(ex, lambda: all(n in diags.last for n in names), 30.0), (
                diags.last.keys(), imu0.output, imu1.output)
            # The statuses differ by name and by their default hardware_id.
            assert diags.last[names[0]][2] == REMAPPED
            assert diags.last[names[1]][2] == 'imu1_board'  # its own section applied
            assert 'allan_node: inputs' not in diags.last
            assert spin_until(ex, lambda: pub.get_subscription_count() > 0, 10.0)
            msg = Imu()
            gyro = [run.imu.channels[c] for c in GYROS]
            for k in range(run.imu.t.size):
                # Noiseless accelerometers: a constant reading, whose fits must fail.
                fill_imu(msg, EPOCH + run.imu.t[k], [g[k] for g in gyro], (0.0, 0.0, 9.81))
                pub.publish(msg)
                if k % 200 == 199:
                    spin_until(ex, lambda: False, 0.01)
            assert spin_until(ex, lambda: diags.last[names[0]][3].get('samples', 0)
                              > 0.9 * run.imu.t.size, 15.0), diags.last[names[0]]
            client = peer.create_client(Trigger, '/imu0/allan_node/compute')
            assert client.wait_for_service(timeout_sec=10.0)
            future = client.call_async(Trigger.Request())
            assert spin_until(ex, future.done, 10.0) and future.result().success
            assert spin_until(ex, lambda: len(noise.last) == 6, 60.0), imu0.output
            assert spin_until(ex, lambda: 'files written' in diags.last[names[0]][3].get(
                'fit_status', ''), 30.0), diags.last[names[0]]
            status = diags.last[names[0]][3]['fit_status']
            peer.destroy_node()
    finally:
        for node in (imu0, imu1):
            node.stop(signal.SIGINT)
    for node in (imu0, imu1):
        assert clean_exit_problems(node) == [], node.output
    for c in GYROS:
        level, _, hardware_id, v = noise.last[f'/imu0/allan_node: noise {c}']
        assert level == 0 and v['N_resolved'] == 1 and hardware_id == REMAPPED
    for c in ('accel_x', 'accel_y', 'accel_z'):
        level, message, _, _ = noise.last[f'/imu0/allan_node: noise {c}']
        assert level == 2 and 'fit failed' in message
        assert c in status
    out = tmp_path / 'out'
    assert sorted(p.name for p in out.iterdir()) == [
        'allan.json', 'allan.png', 'imu.yaml', 'noise.json']
    assert sorted(json.loads((out / 'noise.json').read_text())['channels']) == GYROS
    kalibr = yaml.safe_load((out / 'imu.yaml').read_text())
    assert kalibr['rostopic'] == REMAPPED
    assert 'failed' in imu0.output  # the log says it too
