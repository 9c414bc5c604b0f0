"""
Real DDS smoke test: a separate process publishes sensor_msgs/Imu on loopback.

The messages cross Fast DDS between two processes and are read back through ``msg_adapters``;
the same adapter is also checked on a rosbags-deserialized message (duck typing).
"""
import subprocess
import sys
import textwrap

from msg_adapters import fill_imu, imu_sample, joint_angle
import numpy as np
import pytest

rclpy = pytest.importorskip('rclpy')
from node_harness import collect, DOMAINS, ros_env  # noqa: E402,I100
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from sensor_msgs.msg import Imu  # noqa: E402

DOMAIN_ID = DOMAINS['dds_smoke']

PUBLISHER = textwrap.dedent("""
    import time
    import rclpy
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import Imu
    from msg_adapters import fill_imu

    rclpy.init()
    node = rclpy.create_node('smoke_imu_publisher')
    pub = node.create_publisher(Imu, 'imu/data_raw', qos_profile_sensor_data)
    deadline = time.monotonic() + 20.0
    k = 0
    while time.monotonic() < deadline:
        # Keep publishing a known sequence until the test has seen enough and kills us.
        t = 100.0 + 0.01 * k
        msg = fill_imu(Imu(), t, (0.001 * k, -0.5, 0.25), (0.0, 0.0, 9.81))
        pub.publish(msg)
        k += 1
        time.sleep(0.01)
    node.destroy_node()
    rclpy.try_shutdown()
""")


def test_imu_crosses_dds_between_processes(monkeypatch):
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    proc = subprocess.Popen([sys.executable, '-c', PUBLISHER], env=ros_env(DOMAIN_ID),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        received = collect(DOMAIN_ID, Imu, 'imu/data_raw', qos_profile_sensor_data, 5, 15.0,
                           alive=lambda: proc.poll() is None, convert=imu_sample,
                           node_name='smoke_imu_listener')
    finally:
        proc.kill()
        _, err = proc.communicate(timeout=10)
    assert len(received) >= 5, f'no Imu arrived over DDS; publisher stderr: {err.decode()}'
    for t, (gx, gy, gz, ax, ay, az) in received:
        k = round((t - 100.0) / 0.01)
        assert t == pytest.approx(100.0 + 0.01 * k, abs=1e-9)
        assert gx == pytest.approx(0.001 * k)
        assert (gy, gz, ax, ay, az) == (-0.5, 0.25, 0.0, 0.0, 9.81)
    stamps = [t for t, _ in received]
    assert stamps == sorted(stamps)


def test_adapter_reads_rosbags_messages_the_same_way():
    from rosbags.typesys import get_typestore, Stores
    store = get_typestore(Stores.ROS2_JAZZY)
    raw = fill_imu(Imu(), 12.345678901, (0.1, 0.2, 0.3), (1.0, 2.0, 3.0))
    cdr = store.serialize_cdr(_to_rosbags(store, raw), 'sensor_msgs/msg/Imu')
    bag_msg = store.deserialize_cdr(cdr, 'sensor_msgs/msg/Imu')
    assert imu_sample(bag_msg) == imu_sample(raw)
    assert bag_msg.orientation_covariance[0] == -1.0


def test_joint_angle_by_name_and_index():
    from sensor_msgs.msg import JointState
    msg = JointState(name=['other', 'stand'], position=[0.5, -0.25])
    msg.header.stamp.sec, msg.header.stamp.nanosec = 3, 500_000_000
    assert joint_angle(msg, 'stand') == (3.5, -0.25)
    assert joint_angle(msg, 0) == (3.5, 0.5)
    assert joint_angle(msg, 'missing') is None
    assert joint_angle(msg, 5) is None


def _to_rosbags(store, msg):
    """Convert an rclpy Imu into the rosbags dataclass (field by field, as a bag would hold)."""
    types = store.types
    header = types['std_msgs/msg/Header'](
        stamp=types['builtin_interfaces/msg/Time'](
            sec=msg.header.stamp.sec, nanosec=msg.header.stamp.nanosec),
        frame_id=msg.header.frame_id)
    quat = types['geometry_msgs/msg/Quaternion']
    vec = types['geometry_msgs/msg/Vector3']

    def as_vec(v):
        return vec(x=v.x, y=v.y, z=v.z)

    return types['sensor_msgs/msg/Imu'](
        header=header,
        orientation=quat(x=msg.orientation.x, y=msg.orientation.y, z=msg.orientation.z,
                         w=msg.orientation.w),
        orientation_covariance=np.array(msg.orientation_covariance, dtype=np.float64),
        angular_velocity=as_vec(msg.angular_velocity),
        angular_velocity_covariance=np.array(msg.angular_velocity_covariance),
        linear_acceleration=as_vec(msg.linear_acceleration),
        linear_acceleration_covariance=np.array(msg.linear_acceleration_covariance))
