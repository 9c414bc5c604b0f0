"""
Vectorised CDR for ``sensor_msgs/msg/Imu``: many messages <-> numpy arrays in one go.

Layout after the 4-byte encapsulation header (offsets relative to its end, CDR alignment):
``stamp.sec`` int32 @0, ``stamp.nanosec`` uint32 @4, ``frame_id`` uint32 length L (with the
NUL) @8 and its bytes @12, then, from A = ceil8(12 + L): orientation 4 x f8 @A, its covariance
9 x f8 @A+32, angular_velocity 3 x f8 @A+104, covariance @A+128, linear_acceleration 3 x f8
@A+200, covariance @A+224; size 4 + A + 296. Only L varies per message, so every field sits at an
offset computable with array arithmetic; values are read with aligned word views of the raw
buffer (one per byte residue) instead of a Python loop. Messages this cannot decode as rosbags
would (other encapsulation, bad length, trailing bytes) are flagged for the per-message path.
"""
from typing import Dict, Tuple

import numpy as np

IMU_TAIL = 296  # bytes from orientation to the end of linear_acceleration_covariance
MAX_TRAILING = 3  # rosbags accepts up to 3 padding bytes after the message


def _align8(x: np.ndarray) -> np.ndarray:
    return (x + 7) & ~np.int64(7)


def imu_size(frame_id: str) -> int:
    """Return the CDR size in bytes (encapsulation header included) of an Imu with ``frame_id``."""
    strlen = len(frame_id.encode()) + 1
    return 4 + int(_align8(np.int64(12 + strlen))) + IMU_TAIL


def encode_imu(t: np.ndarray, gyro: Tuple[np.ndarray, np.ndarray, np.ndarray],
               accel: Tuple[np.ndarray, np.ndarray, np.ndarray],
               frame_id: str = 'imu_link') -> np.ndarray:
    """
    Serialise n Imu messages (little-endian CDR) as an (n, size) uint8 array.

    Stamps are rounded to the nanosecond as ``msg_adapters.to_stamp`` does; orientation is the
    identity quaternion marked 'not reported' (``orientation_covariance[0] = -1``), other
    covariances zero (unknown), matching ``msg_adapters.fill_imu`` on a default message.
    """
    t = np.asarray(t, dtype=np.float64)
    n = t.size
    name = frame_id.encode()
    strlen = len(name) + 1
    a = int(_align8(np.int64(12 + strlen)))
    size = 4 + a + IMU_TAIL
    template = np.zeros(size, dtype=np.uint8)
    template[1] = 1  # CDR_LE
    template[12:16] = np.frombuffer(np.uint32(strlen).tobytes(), np.uint8)
    template[16:16 + len(name)] = np.frombuffer(name, np.uint8)
    body = 4 + a
    template[body + 24:body + 32] = np.frombuffer(np.float64(1.0).tobytes(), np.uint8)
    template[body + 32:body + 40] = np.frombuffer(np.float64(-1.0).tobytes(), np.uint8)
    raw = np.empty((n, size), dtype=np.uint8)
    raw[:] = template
    fields = np.dtype({'names': ['sec', 'nsec', 'gyro', 'accel'],
                       'formats': ['<i4', '<u4', ('<f8', 3), ('<f8', 3)],
                       'offsets': [4, 8, body + 104, body + 200], 'itemsize': size})
    rec = raw.reshape(-1).view(fields)
    ns = np.round(t * 1e9).astype(np.int64)
    sec, nsec = np.divmod(ns, 1_000_000_000)
    if n and (sec.min() < -2**31 or sec.max() >= 2**31):
        raise ValueError('stamps outside the int32 seconds range of builtin_interfaces/Time')
    rec['sec'] = sec
    rec['nsec'] = nsec
    rec['gyro'] = np.column_stack(gyro)
    rec['accel'] = np.column_stack(accel)
    return raw


def gather(buf: np.ndarray, pos: np.ndarray, code: str, big: np.ndarray) -> np.ndarray:
    """Read one ``code`` item (e.g. 'f8') at each byte position ``pos``; ``big`` marks BE ones."""
    itemsize = int(code[1])
    out = np.empty(pos.size, dtype='<' + code)
    residue = pos % itemsize
    for r in range(itemsize):
        sel = residue == r
        if not sel.any():
            continue
        words = (buf.size - r) // itemsize
        view = buf[r:r + words * itemsize].view('<' + code)
        out[sel] = view[(pos[sel] - r) // itemsize]
    if big.any():
        out[big] = out[big].byteswap()
    return out


def ascii_frames(buf: np.ndarray, start: np.ndarray, length: np.ndarray) -> np.ndarray:
    """
    Whether each frame_id (``length`` bytes at ``start``) is pure ASCII.

    rosbags rejects frame_ids that are not UTF-8; ASCII always is, and anything else is left to
    the per-message path so both paths accept exactly the same messages.
    """
    if start.size == 0:
        return np.ones(0, dtype=bool)
    lo, hi = int(start.min()), int((start + length).max())
    high = np.flatnonzero(buf[lo:hi] >= 0x80) + lo  # only the span the messages cover
    if high.size == 0:
        return np.ones(start.size, dtype=bool)
    return np.searchsorted(high, start) == np.searchsorted(high, start + length)


def decode_imu(buf: np.ndarray, offsets: np.ndarray, sizes: np.ndarray
               ) -> Tuple[np.ndarray, Dict[str, np.ndarray], np.ndarray]:
    """
    Decode Imu messages lying at ``offsets`` (``sizes`` bytes each) in the uint8 ``buf``.

    Returns ``(t, channels, ok)``: stamps (``sec + nanosec * 1e-9``, as ``msg_adapters`` computes
    them), the six SI channels, and the mask of messages decoded here; values where ``ok`` is
    False are undefined and those messages need the per-message path.
    """
    offsets = np.asarray(offsets, dtype=np.int64)
    sizes = np.asarray(sizes, dtype=np.int64)
    uniform = _decode_uniform(buf, offsets, sizes)
    if uniform is not None:
        return uniform
    ok = (sizes >= 4 + 16 + IMU_TAIL) & (offsets >= 0) & (offsets + sizes <= buf.size)
    idx = np.flatnonzero(ok)
    off = offsets[idx]
    b0 = buf[off]
    b1 = buf[off + 1]
    good = (b0 == 0) & (b1 <= 1)
    big = b1 == 0
    strlen = gather(buf, off + 12, 'u4', big).astype(np.int64)
    a = _align8(12 + strlen)
    need = 4 + a + IMU_TAIL
    size = sizes[idx]
    good &= (strlen >= 1) & (size >= need) & (size <= need + MAX_TRAILING)
    good &= ascii_frames(buf, off + 16, np.where(good, strlen - 1, 0))
    nul = np.where(good, off + 15 + strlen, off)  # rosbags requires the string's terminator
    good &= buf[nul] == 0
    idx, off, big, a = idx[good], off[good], big[good], a[good]
    ok[:] = False
    ok[idx] = True
    t, channels = stamp_and_rates(buf, offsets.size, idx, off, off + 4 + a, big)
    return t, channels, ok


def stamp_and_rates(buf: np.ndarray, n: int, idx: np.ndarray, off: np.ndarray,
                    body: np.ndarray, big: np.ndarray
                    ) -> Tuple[np.ndarray, Dict[str, np.ndarray]]:
    """
    Read the header stamp and the gyro/accel vectors of the accepted messages ``idx``.

    ``off`` is where each accepted payload starts (stamp secs at +4, nsecs at +8, as both the
    ROS 1 and the CDR layouts put them) and ``body`` where its packed float64 block starts;
    rejected messages get NaN.
    """
    t = np.full(n, np.nan)
    sec = gather(buf, off + 4, 'i4', big).astype(np.float64)
    nsec = gather(buf, off + 8, 'u4', big).astype(np.float64)
    t[idx] = sec + nsec * 1e-9
    channels = {}
    for base, start in (('gyro', 104), ('accel', 200)):
        for k, axis in enumerate('xyz'):
            values = np.full(n, np.nan)
            values[idx] = gather(buf, body + start + 8 * k, 'f8', big)
            channels[f'{base}_{axis}'] = values
    return t, channels


def _decode_uniform(buf: np.ndarray, offsets: np.ndarray, sizes: np.ndarray):
    """
    Decode the common case fast: equal sizes at a constant stride, one header and frame_id length.

    Returns None when the batch is not uniform (the general path then handles it).
    """
    n = offsets.size
    if n < 2 or buf.size == 0:
        return None
    size = int(sizes[0])
    stride = int(offsets[1] - offsets[0])
    first = int(offsets[0])
    if (size < 4 + 16 + IMU_TAIL or stride < size or first < 0
            or first + (n - 1) * stride + size > buf.size or np.any(sizes != size)
            or np.any(np.diff(offsets) != stride)):
        return None
    rows = np.lib.stride_tricks.as_strided(buf[first:], shape=(n, size), strides=(stride, 1),
                                           writeable=False)
    head = bytes(rows[0, :16])
    if head[0] != 0 or head[1] > 1:
        return None
    order = '<' if head[1] else '>'
    strlen = int(np.frombuffer(head[12:16], order + 'u4')[0])
    a = int(_align8(np.int64(12 + strlen)))
    need = 4 + a + IMU_TAIL
    if strlen < 1 or not need <= size <= need + MAX_TRAILING:
        return None
    if np.any(rows[:, 0:2] != rows[0, 0:2]) or np.any(rows[:, 12:16] != rows[0, 12:16]):
        return None
    if strlen > 1 and np.any(rows[:, 16:15 + strlen] >= 0x80):
        return None  # non-ASCII frame_id: let rosbags judge its UTF-8
    if np.any(rows[:, 15 + strlen] != 0):
        return None  # a missing string terminator, which rosbags refuses
    body = 4 + a
    # one strided record view; the fields are read straight from the buffer (no copies until the
    # caller stores them), so the channels returned are read-only views of ``buf``
    fields = np.dtype({'names': ['sec', 'nsec', 'gyro', 'accel'],
                       'formats': [order + 'i4', order + 'u4', (order + 'f8', 3),
                                   (order + 'f8', 3)],
                       'offsets': [4, 8, body + 104, body + 200], 'itemsize': size})
    recs = np.ndarray(shape=(n,), dtype=fields, buffer=buf, offset=first, strides=(stride,))
    t = recs['sec'].astype(np.float64)
    t += recs['nsec'].astype(np.float64) * 1e-9
    channels = {}
    for base in ('gyro', 'accel'):
        block = recs[base]
        for k, axis in enumerate('xyz'):
            channels[f'{base}_{axis}'] = block[:, k]
    return t, channels, np.ones(n, dtype=bool)
