"""
The ament_python packaging is real: colcon builds it and an installed node runs.

The package is copied into a temporary colcon workspace, built with colcon (from PyPI), and the
installed ``bench_sim_node`` executable from ``lib/gyro_char`` is started with
``--ros-args --params-file`` pointing at the installed ``config/`` file; a listener in this
process must receive its Imu messages over DDS on loopback.
"""
import os
from pathlib import Path
import shutil
import subprocess
import sys

import pytest

rclpy = pytest.importorskip('rclpy')
from node_harness import collect, DOMAINS, ROOT  # noqa: E402,I100
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402

DOMAIN_ID = DOMAINS['colcon']
NODES = ('swing_kf_node', 'allan_node', 'bench_sim_node')
SKIP = shutil.ignore_patterns('.git', '.venv', 'build', 'install', 'log', 'out', '__pycache__',
                              '*.egg-info', '.pytest_cache')


@pytest.fixture(scope='module')
def workspace(tmp_path_factory):
    ws = tmp_path_factory.mktemp('colcon_ws')
    shutil.copytree(ROOT, ws / 'src' / 'gyro_char', ignore=SKIP)
    colcon = Path(sys.executable).with_name('colcon')
    result = subprocess.run(
        [str(colcon), 'build', '--packages-select', 'gyro_char', '--event-handlers',
         'console_direct-'], cwd=ws, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return ws / 'install' / 'gyro_char'


def test_install_layout(workspace):
    for node in NODES + ('gyro-char',):
        assert (workspace / 'lib' / 'gyro_char' / node).is_file(), node
    share = workspace / 'share' / 'gyro_char'
    assert (share / 'package.xml').is_file()
    sources = sorted(p.name for p in (ROOT / 'config').glob('*.yaml'))
    assert 'bench_sim_node.yaml' in sources
    for name in sources:
        assert (share / 'config' / name).is_file(), name
    assert (share / 'launch' / 'gyro_char.launch.py').is_file()
    marker = workspace / 'share' / 'ament_index' / 'resource_index' / 'packages' / 'gyro_char'
    assert marker.is_file()


def test_installed_node_runs_with_params_file(workspace):
    site = next((workspace / 'lib').glob('python3*/site-packages'))
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST',
               ROS_DOMAIN_ID=str(DOMAIN_ID), PYTHONPATH=f'{site}{os.pathsep}'
               + os.environ.get('PYTHONPATH', ''))
    params = workspace / 'share' / 'gyro_char' / 'config' / 'bench_sim_node.yaml'
    proc = subprocess.Popen(
        [str(workspace / 'lib' / 'gyro_char' / 'bench_sim_node'), '--ros-args',
         '--params-file', str(params)], env=env, cwd=workspace,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        received = collect(DOMAIN_ID, Imu, 'imu/data_raw', qos_profile_sensor_data, 20, 30.0,
                           alive=lambda: proc.poll() is None, node_name='colcon_listener')
    finally:
        proc.terminate()
        try:
            _, err = proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            _, err = proc.communicate()
    assert len(received) >= 20, 'installed bench_sim_node published nothing: ' + err.decode()
    stamps = [m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in received]
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
