"""allan_node's ``sensor_filter`` parameter: validated on a real node, passed to the fit."""
import subprocess

from gyro_char.allan.compute import compute
from gyro_char.allan.sensor_filter import SensorFilter
from gyro_char.nodes.allan_node import AllanNode
from gyro_char.records import Recording
from gyro_char.sim.noise_gen import generate
from node_harness import DOMAINS, node_command, ros_context, ros_env
import numpy as np
from rclpy.parameter import Parameter

DOMAIN = DOMAINS['allan_filter']


def test_sensor_filter_parameter_is_validated_and_reaches_the_fit():
    rate = generate(20_000, 0.01, rng=np.random.default_rng(2), N=1e-3)
    res = compute(Recording(np.arange(rate.size) * 0.01, {'gyro_x': rate}))
    with ros_context(DOMAIN) as context:
        node = AllanNode(context=context)
        assert node.get_parameter('sensor_filter').value == 'none'
        for bad in ('auto', 'gauss:3', 'bartlett'):
            r = node.set_parameters([Parameter('sensor_filter', value=bad)])[0]
            assert not r.successful and 'sensor' in r.reason, bad
        assert node.fit(res)['fits']['gyro_x'].sensor_filter is None
        ok = node.set_parameters([Parameter('sensor_filter', value='bartlett:7@8x')])[0]
        assert ok.successful
        fit = node.fit(res)['fits']['gyro_x']
        assert fit.sensor_filter.sensor_filter == SensorFilter('bartlett', 7, 8)
        assert fit.extra_json()['sensor_filter']['source'] == 'user'
        node.destroy_node()


def test_auto_at_startup_exits_2_with_the_reason():
    proc = subprocess.run(node_command('allan_node') + ['--ros-args', '-p',
                                                        'sensor_filter:=auto'],
                          env=ros_env(DOMAIN), capture_output=True, timeout=60)
    assert proc.returncode == 2
    assert b'sensor_filter auto needs the samples' in proc.stderr  # one line, on stderr
