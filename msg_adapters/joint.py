"""Encoder angle from sensor_msgs/JointState or a stamped scalar."""
from typing import Any, Optional, Tuple, Union

from msg_adapters.imu import stamp_seconds, to_stamp


def joint_angle(msg: Any, joint: Union[str, int] = 0) -> Optional[Tuple[float, float]]:
    """
    Return (stamp s, position rad) from a JointState, of the joint chosen by name or index.

    Returns None when the message does not carry that joint (a JointState may hold other
    joints); the caller counts such messages.
    """
    positions = msg.position
    if isinstance(joint, str):
        names = list(msg.name)
        if joint not in names:
            return None
        index = names.index(joint)
    else:
        index = joint
    if index < 0 or index >= len(positions):
        return None
    return stamp_seconds(msg.header.stamp), float(positions[index])


def vector3_x(msg: Any) -> Tuple[float, float]:
    """geometry_msgs/Vector3Stamped -> (stamp s, x), for users logging the angle that way."""
    return stamp_seconds(msg.header.stamp), float(msg.vector.x)


def fill_joint_state(msg: Any, t: float, positions, names, frame_id: str = '') -> Any:
    """Fill a JointState in place: stamp ``t`` (s), ``names`` and ``positions`` (rad)."""
    to_stamp(msg.header.stamp, t)
    msg.header.frame_id = frame_id
    msg.name = list(names)
    msg.position = [float(p) for p in positions]
    return msg
