"""Small real bags for the ingest tests, written with rosbags' own per-message writers."""
from pathlib import Path

from gyro_char.records import IMU_CHANNELS, Recording
import numpy as np
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

STORE2 = get_typestore(Stores.ROS2_JAZZY)
STORE1 = get_typestore(Stores.ROS1_NOETIC)


def imu_recording(n=2000, rate=333.0, seed=0, t0=1.7e9):
    rng = np.random.default_rng(seed)
    t = t0 + np.arange(n) / rate
    return Recording(t, {k: rng.normal(scale=0.1, size=n) for k in IMU_CHANNELS})


def header_msg(ty, t, frame_id='', ros1=False):
    ns = int(round(t * 1e9))
    stamp = ty['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9)
    return (ty['std_msgs/msg/Header'](seq=0, stamp=stamp, frame_id=frame_id) if ros1
            else ty['std_msgs/msg/Header'](stamp=stamp, frame_id=frame_id))


def imu_msg(store, t, six, frame_id='imu_link', ros1=False):
    ty = store.types
    header = header_msg(ty, t, frame_id, ros1)
    vec = ty['geometry_msgs/msg/Vector3']
    return ty['sensor_msgs/msg/Imu'](
        header=header, orientation=ty['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.zeros(9), angular_velocity=vec(x=six[0], y=six[1], z=six[2]),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vec(x=six[3], y=six[4], z=six[5]),
        linear_acceleration_covariance=np.zeros(9))


def joint_msg(t, names, positions):
    ty = STORE2.types
    return ty['sensor_msgs/msg/JointState'](
        header=header_msg(ty, t),
        name=list(names), position=np.array(positions, dtype=np.float64),
        velocity=np.array([], dtype=np.float64), effort=np.array([], dtype=np.float64))


def vector3_msg(t, x):
    ty = STORE2.types
    return ty['geometry_msgs/msg/Vector3Stamped'](
        header=header_msg(ty, t),
        vector=ty['geometry_msgs/msg/Vector3'](x=float(x), y=0.0, z=0.0))


def write_ros2(path, topics, storage='mcap', compression=None):
    """
    Write ``topics``: {name: (msgtype, [(t, msg, little_endian), ...])}, messages interleaved.

    ``compression``: None or 'storage' / 'file' / 'message' (zstd), as rosbags offers.
    """
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    events = []
    writer = Writer(Path(path), version=9, storage_plugin=plugin)
    if compression:
        writer.set_compression(CompressionMode[compression.upper()], CompressionFormat.ZSTD)
    with writer:
        for name, (msgtype, msgs) in topics.items():
            conn = writer.add_connection(name, msgtype, typestore=STORE2)
            events += [(t, conn, msg, le) for t, msg, le in msgs]
        events.sort(key=lambda e: e[0])
        for t, conn, msg, le in events:
            raw = STORE2.serialize_cdr(msg, conn.msgtype, little_endian=le)
            writer.write(conn, int(round(t * 1e9)), raw)
    return str(path)


def write_ros1(path, rec, topic='/imu/data_raw'):
    with Writer1(Path(path)) as writer:
        conn = writer.add_connection(topic, 'sensor_msgs/msg/Imu', typestore=STORE1)
        for i, t in enumerate(rec.t):
            six = [float(rec.channels[k][i]) for k in IMU_CHANNELS]
            raw = STORE1.serialize_ros1(imu_msg(STORE1, t, six, ros1=True), 'sensor_msgs/msg/Imu')
            writer.write(conn, int(round(t * 1e9)), raw)
    return str(path)
