"""sensor_msgs/Imu <-> (stamp, 6 SI channels)."""
from typing import Any, Tuple


def stamp_seconds(stamp: Any) -> float:
    """builtin_interfaces/Time (``sec``, ``nanosec``) -> float seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def to_stamp(stamp: Any, t: float) -> Any:
    """Write float seconds ``t`` into a Time-like object (rounding to the nanosecond)."""
    ns = int(round(t * 1e9))
    stamp.sec, stamp.nanosec = divmod(ns, 1_000_000_000)
    return stamp


def imu_sample(msg: Any) -> Tuple[float, Tuple[float, float, float, float, float, float]]:
    """Imu message -> (header stamp in s, (gx, gy, gz, ax, ay, az)) in rad/s and m/s^2."""
    w = msg.angular_velocity
    a = msg.linear_acceleration
    return stamp_seconds(msg.header.stamp), (w.x, w.y, w.z, a.x, a.y, a.z)


def fill_imu(msg: Any, t: float, gyro, accel, frame_id: str = 'imu_link') -> Any:
    """Fill an Imu message in place; orientation is marked 'not reported' (cov[0] = -1)."""
    to_stamp(msg.header.stamp, t)
    msg.header.frame_id = frame_id
    msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = map(float, gyro)
    a = msg.linear_acceleration
    a.x, a.y, a.z = map(float, accel)
    cov = msg.orientation_covariance
    try:
        cov[0] = -1.0  # in place keeps the container type (rosbags serialises only ndarrays)
    except TypeError:  # an immutable sequence: replace it
        cov = list(cov)
        cov[0] = -1.0
        msg.orientation_covariance = cov
    return msg
