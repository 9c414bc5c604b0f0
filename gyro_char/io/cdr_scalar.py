"""
Vectorised reading of one stamped scalar per message: a JointState position or Vector3Stamped x.

These messages have no fixed layout in general (names, sequences), but a stream of them almost
always repeats one layout. The first message of a block is parsed to find the value's offset and
checked against rosbags' own deserialisation; the block is then accepted only if every message has
the same size and the same bytes outside the stamp and the value sequence, which guarantees the
same structure, so rosbags would accept each one and read the same value. Any other block takes
the per-message path (the caller's).
"""
import struct
from typing import Any, Optional, Tuple, Union

import numpy as np

JOINT_STATE = 'sensor_msgs/msg/JointState'
VECTOR3_STAMPED = 'geometry_msgs/msg/Vector3Stamped'

Layout = Tuple[int, int, int]  # value offset, varying region [lo, hi)


def _align(p: int, n: int) -> int:
    """Align absolute offset ``p`` to ``n`` relative to the payload start (after 4 bytes)."""
    return 4 + ((p - 4 + n - 1) // n) * n


def parse_layout(raw: bytes, msgtype: str, joint: Union[str, int, None]) -> Optional[Layout]:
    """Locate the value in one serialised message; None if it cannot be located."""
    if len(raw) < 16 or raw[0] != 0 or raw[1] > 1:
        return None
    order = '<' if raw[1] else '>'

    def u32(p: int) -> int:
        return struct.unpack_from(order + 'I', raw, p)[0]

    p = 16 + u32(12)  # after header.frame_id
    if msgtype == VECTOR3_STAMPED:
        p = _align(p, 8)
        return p, p, p + 24
    if msgtype != JOINT_STATE:
        return None
    p = _align(p, 4)
    n_names = u32(p)
    if n_names > len(raw):
        return None
    p += 4
    names = []
    for _ in range(n_names):
        p = _align(p, 4)
        length = u32(p)
        names.append(raw[p + 4:p + 3 + length].decode('utf-8', 'replace'))
        p += 4 + length
    p = _align(p, 4)
    count = u32(p)
    start = _align(p + 4, 8)
    if isinstance(joint, str):
        if joint not in names:
            return None
        index = names.index(joint)
    else:
        index = 0 if joint is None else joint
    if not 0 <= index < count:
        return None
    return start + 8 * index, start, start + 8 * count


def decode_scalar(buf: np.ndarray, offsets: np.ndarray, sizes: np.ndarray, msgtype: str,
                  joint: Union[str, int, None], store: Any, sample) -> Optional[Tuple]:
    """
    Return ``(t, value)`` arrays for a uniform block, or None (use the per-message path).

    ``sample(msg)`` is the msg_adapters reader giving (stamp, value) for the first message, used
    to check the located offset against rosbags' deserialisation.
    """
    n = offsets.size
    if n < 2 or np.any(sizes != sizes[0]):
        return None
    size, first = int(sizes[0]), int(offsets[0])
    stride = int(offsets[1] - offsets[0])
    if (stride < size or first < 0 or first + (n - 1) * stride + size > buf.size
            or np.any(np.diff(offsets) != stride)):
        return None
    raw0 = buf[first:first + size].tobytes()
    try:
        layout = parse_layout(raw0, msgtype, joint)
        if layout is None:
            return None
        ref = sample(store.deserialize_cdr(raw0, msgtype))
    except Exception:  # noqa: B902 - anything odd about the first message: per-message path
        return None
    vpos, lo, hi = layout
    if ref is None or hi > size:
        return None
    rows = np.lib.stride_tricks.as_strided(buf[first:], shape=(n, size), strides=(stride, 1),
                                           writeable=False)
    row0 = rows[0]
    for a, b in ((0, 4), (12, lo), (hi, size)):
        if b > a and np.any(rows[:, a:b] != row0[a:b]):
            return None
    order = '<' if raw0[1] else '>'
    sec = np.ascontiguousarray(rows[:, 4:8]).view(order + 'i4')[:, 0].astype(np.float64)
    nsec = np.ascontiguousarray(rows[:, 8:12]).view(order + 'u4')[:, 0].astype(np.float64)
    value = np.ascontiguousarray(rows[:, vpos:vpos + 8]).view(order + 'f8')[:, 0]
    value = value.astype(np.float64)
    t = sec + nsec * 1e-9
    if t[0] != ref[0] or value[0] != ref[1] and not (np.isnan(value[0]) and np.isnan(ref[1])):
        return None  # the located offset disagrees with rosbags: trust rosbags
    return t, value
