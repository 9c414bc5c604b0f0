"""
ROS message <-> core arrays, duck-typed (attribute access only).

The same functions serve live rclpy messages and rosbags-deserialized ones, so nothing here
imports rclpy or a message package. Builders take the message class as an argument.
"""
from msg_adapters.imu import fill_imu, imu_sample, stamp_seconds, to_stamp
from msg_adapters.joint import fill_joint_state, joint_angle, vector3_x

__all__ = [
    'fill_imu', 'fill_joint_state', 'imu_sample', 'joint_angle', 'stamp_seconds', 'to_stamp',
    'vector3_x',
]
