"""
Write a ROS 2 bag (mcap or sqlite3) of Imu and JointState messages, vectorised.

Hours of 333 Hz data are millions of messages, so neither per-message ``serialize_cdr`` nor
per-message ``Writer.write`` is used: messages are CDR-encoded in blocks (``cdr.encode_imu``; a
byte template with patched stamp/position for JointState) and, for mcap, whole chunks (message
records, message index, chunk index) are built with numpy and handed to rosbags' own MCAP storage,
which writes the schemas, channels, summary and ``metadata.yaml``. rosbags is pinned (0.11.x);
``test/test_ingest_bag.py`` reads every written bag back with rosbags itself.
"""
from io import BytesIO
from pathlib import Path
import struct
from typing import Callable, Optional

from gyro_char.ingest.cdr import encode_imu
from gyro_char.progress import progress
from gyro_char.recordings import ENCODER_CHANNEL, IMU_CHANNELS, InputError, Recording
import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import PendingChunk
from rosbags.typesys import get_typestore, Stores

CHUNK_BYTES = 1 << 20  # same target chunk size as rosbags' own mcap writer
MCAP_HEAD = 31  # opcode 1 + length 8 + channel 2 + sequence 4 + log time 8 + publish time 8
IMU_TYPE = 'sensor_msgs/msg/Imu'
JOINT_TYPE = 'sensor_msgs/msg/JointState'


def typestore():
    """Return the message type store used for writing and for the per-message read path."""
    return get_typestore(Stores.ROS2_JAZZY)


def stamps_ns(t: np.ndarray) -> np.ndarray:
    """Float seconds -> int64 ns, rounded as ``msg_adapters.to_stamp`` rounds."""
    return np.round(np.asarray(t, dtype=np.float64) * 1e9).astype(np.int64)


def joint_state_encoder(store, joint_name: str) -> Callable:
    """
    Return ``encode(t, position) -> (n, size) uint8`` for single-joint JointState messages.

    The message has a constant layout (one name, one position, empty velocity/effort), so one
    message is serialised by rosbags and only the stamp and position bytes are patched per row.
    """
    cls = store.types
    probe = cls[JOINT_TYPE](
        header=cls['std_msgs/msg/Header'](
            stamp=cls['builtin_interfaces/msg/Time'](sec=0, nanosec=0), frame_id=''),
        name=[joint_name], position=np.array([0.0]), velocity=np.array([], dtype=np.float64),
        effort=np.array([], dtype=np.float64))
    template = np.frombuffer(bytes(store.serialize_cdr(probe, JOINT_TYPE)), np.uint8)
    # position is the last 8-byte item before the two empty sequences' 4-byte counts
    pos_at = template.size - 8 - 8
    size = template.size

    def encode(t: np.ndarray, position: np.ndarray) -> np.ndarray:
        raw = np.empty((t.size, size), dtype=np.uint8)
        raw[:] = template
        dt = np.dtype({'names': ['sec', 'nsec', 'pos'], 'formats': ['<i4', '<u4', '<f8'],
                       'offsets': [4, 8, pos_at], 'itemsize': size})
        rec = raw.reshape(-1).view(dt)
        rec['sec'], rec['nsec'] = np.divmod(stamps_ns(t), 1_000_000_000)
        rec['pos'] = position
        return raw
    return encode


def _imu_channels(imu: Recording):
    missing = [k for k in IMU_CHANNELS if k not in imu.channels]
    nan = np.full(len(imu), np.nan)
    # a missing channel is written as NaN: readers then report it as absent, never as zeros
    gyro = [imu.channels.get(k, nan) for k in IMU_CHANNELS[:3]]
    accel = [imu.channels.get(k, nan) for k in IMU_CHANNELS[3:]]
    return gyro, accel, missing


class _McapBulk:
    """Append whole chunks to rosbags' ``McapWriter`` (mirrors its ``close_chunk`` format)."""

    def __init__(self, writer: Writer) -> None:
        self.writer = writer
        self.storage = writer.storage
        self.prefix = b''

    def take_prefix(self) -> None:
        # schema and channel records rosbags buffered in its pending chunk go into our first chunk
        pending = self.storage.chunk
        self.prefix = pending.bio.getvalue()
        self.storage.chunk = PendingChunk(2**63 - 1, 0, BytesIO(), pending.msgs.__class__(list))

    def write_block(self, cid: int, log_ns: np.ndarray, data: np.ndarray) -> None:
        n, size = data.shape
        rec_dt = np.dtype({'names': ['op', 'len', 'ch', 'seq', 'log', 'pub', 'data'],
                           'formats': ['u1', '<u8', '<u2', '<u4', '<u8', '<u8', (np.uint8, size)],
                           'offsets': [0, 1, 9, 11, 15, 23, MCAP_HEAD],
                           'itemsize': MCAP_HEAD + size})
        recs = np.empty(n, dtype=rec_dt)
        recs['op'] = 0x05
        recs['len'] = MCAP_HEAD - 9 + size
        recs['ch'] = cid
        recs['seq'] = 0
        recs['log'] = log_ns
        recs['pub'] = log_ns
        recs['data'] = data
        prefix, self.prefix = self.prefix, b''
        body = prefix + recs.tobytes()
        start, end = int(log_ns.min()), int(log_ns.max())
        st = self.storage
        bio = st.bio
        chunk_start = bio.tell()
        head = struct.pack('<QQQI', start, end, len(body), 0) + struct.pack('<I', 0) \
            + struct.pack('<Q', len(body))
        bio.write(struct.pack('<BQ', 0x06, len(head) + len(body)))
        bio.write(head)
        bio.write(body)
        chunk_end = bio.tell()
        index = np.empty((n, 2), dtype='<u8')
        index[:, 0] = log_ns
        index[:, 1] = len(prefix) + np.arange(n, dtype=np.uint64) * (MCAP_HEAD + size)
        index_bytes = struct.pack('<HI', cid, 16 * n) + index.tobytes()
        bio.write(struct.pack('<BQ', 0x07, len(index_bytes)))
        bio.write(index_bytes)
        chunk_index = BytesIO()
        chunk_index.write(struct.pack('<QQQQI', start, end, chunk_start, chunk_end - chunk_start,
                                      10))
        chunk_index.write(struct.pack('<HQ', cid, chunk_end))
        chunk_index.write(struct.pack('<Q', bio.tell() - chunk_end))
        chunk_index.write(struct.pack('<I', 0))  # compression '' (none)
        chunk_index.write(struct.pack('<QQ', len(body), len(body)))
        st.chunks.append(chunk_index)
        st.message_start_time = min(start, st.message_start_time)
        st.message_end_time = max(end, st.message_end_time)
        st.channel_stats[cid] += n
        self.writer.counts[cid] += n
        self.writer.min_timestamp = min(start, self.writer.min_timestamp)
        self.writer.max_timestamp = max(end, self.writer.max_timestamp)


def _sqlite_block(writer: Writer, cid: int, log_ns: np.ndarray, data: np.ndarray) -> None:
    rows = zip([cid] * len(log_ns), log_ns.tolist(), (r.tobytes() for r in data))
    writer.storage.cursor.executemany(
        'INSERT INTO messages (topic_id, timestamp, data) VALUES(?, ?, ?)', rows)
    writer.counts[cid] += len(log_ns)
    writer.min_timestamp = min(int(log_ns.min()), writer.min_timestamp)
    writer.max_timestamp = max(int(log_ns.max()), writer.max_timestamp)


def write_bag(path: str, imu: Recording, encoder: Optional[Recording] = None, *,
              storage: str = 'mcap', imu_topic: str = '/imu/data_raw',
              encoder_topic: str = '/stand/joint_states', joint_name: str = 'stand_joint',
              frame_id: str = 'imu_link', quiet: bool = True) -> None:
    """
    Write ``imu`` (and ``encoder``) as a ROS 2 bag directory at ``path``.

    Messages are logged at their header stamps. Missing IMU channels are written as NaN.
    """
    plugins = {'mcap': StoragePlugin.MCAP, 'sqlite3': StoragePlugin.SQLITE3}
    if storage not in plugins:
        raise InputError(f'unknown bag storage {storage!r} (use mcap or sqlite3)')
    if Path(path).exists():
        raise InputError(f'{path} exists already; not overwriting')
    if len(imu) == 0:
        raise InputError('no IMU samples to write')
    if encoder is not None and (ENCODER_CHANNEL not in encoder.channels or len(encoder) == 0):
        raise InputError('encoder recording has no encoder samples')
    for rec, what in ((imu, 'IMU'), (encoder, 'encoder')):
        if rec is not None and not (np.all(np.isfinite(rec.t)) and np.all(np.abs(rec.t) < 2**31)):
            raise InputError(f'{what} stamps must be finite seconds within the int32 range of '
                             f'builtin_interfaces/Time')
    store = typestore()
    gyro, accel, _ = _imu_channels(imu)
    imu_ns = stamps_ns(imu.t)
    per_block = max(1, CHUNK_BYTES // (MCAP_HEAD + encode_imu(imu.t[:1], *[
        [c[:1] for c in gyro], [c[:1] for c in accel]], frame_id=frame_id).shape[1]))
    writer = Writer(path, version=9, storage_plugin=plugins[storage])
    writer.open()
    try:
        cid = writer.add_connection(imu_topic, IMU_TYPE, typestore=store).id
        enc_cid = None
        if encoder is not None:
            enc_cid = writer.add_connection(encoder_topic, JOINT_TYPE, typestore=store).id
        if storage == 'mcap':
            bulk = _McapBulk(writer)
            bulk.take_prefix()
            write = bulk.write_block
        else:
            def write(c, ns, data):
                _sqlite_block(writer, c, ns, data)
        n = len(imu)
        bar = progress(total=n, desc=f'writing {Path(path).name}', quiet=quiet, unit='msg')
        with bar:
            for s in range(0, n, per_block):
                e = min(n, s + per_block)
                data = encode_imu(imu.t[s:e], [c[s:e] for c in gyro], [c[s:e] for c in accel],
                                  frame_id=frame_id)
                write(cid, imu_ns[s:e], data)
                bar.update(e - s)
        if encoder is not None:
            enc = joint_state_encoder(store, joint_name)
            pos = encoder.channels[ENCODER_CHANNEL]
            ns = stamps_ns(encoder.t)
            for s in range(0, len(encoder), 16384):
                e = min(len(encoder), s + 16384)
                write(enc_cid, ns[s:e], enc(encoder.t[s:e], pos[s:e]))
    except BaseException:
        writer.abort()
        raise
    writer.close()
