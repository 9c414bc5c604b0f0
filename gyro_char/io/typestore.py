"""The rosbags message type store (ROS 2 Jazzy) used for writing and per-message reading."""
from rosbags.typesys import get_typestore, Stores


def typestore():
    """Return the message type store used for writing and for the per-message read path."""
    return get_typestore(Stores.ROS2_JAZZY)
