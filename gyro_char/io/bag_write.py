"""
Write a ROS 2 bag (mcap or sqlite3) of Imu and JointState messages, vectorised.

Hours of 333 Hz data are millions of messages, so neither per-message ``serialize_cdr`` nor
per-message ``Writer.write`` is used: messages are CDR-encoded in blocks (``cdr.encode_imu``; a
byte template with patched stamp/position for JointState) and, for mcap, whole chunks (message
records, message index, chunk index) are built with numpy and handed to rosbags' own MCAP storage,
which writes the schemas, channels, summary and ``metadata.yaml``. rosbags is pinned (0.11.x);
``test/test_ingest_bag.py`` reads every written bag back with rosbags itself.

Messages of both topics are written merged in stamp order, as a recorder logs them, so a bag cut
short (a killed writer, a truncated copy) holds both topics up to the cut: ``merge_order``.
"""
from io import BytesIO
from pathlib import Path
import struct
from typing import Callable, List, Optional, Tuple

from gyro_char.errors import InputError
from gyro_char.io.cdr import encode_imu, imu_size
from gyro_char.io.typestore import typestore
from gyro_char.progress import progress
from gyro_char.records import ENCODER_CHANNEL, IMU_CHANNELS, Recording
import numpy as np
from numpy.lib.stride_tricks import as_strided
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import PendingChunk

CHUNK_BYTES = 1 << 20  # same target chunk size as rosbags' own mcap writer
MCAP_HEAD = 31  # opcode 1 + length 8 + channel 2 + sequence 4 + log time 8 + publish time 8
IMU_TYPE = 'sensor_msgs/msg/Imu'
JOINT_TYPE = 'sensor_msgs/msg/JointState'


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

    def write_chunk(self, parts: List[Tuple[int, np.ndarray, np.ndarray]],
                    which: Optional[np.ndarray]) -> None:
        """
        Write one chunk of message records: ``parts`` [(channel id, log ns, payload rows)].

        ``which`` gives the part of each record in write order (None: the parts one after the
        other); each part's records keep their own order.
        """
        recs = [_records(cid, ns, data) for cid, ns, data in parts]
        prefix, self.prefix = self.prefix, b''
        if which is not None and len(recs) > 1:
            rec_size = np.array([r.dtype.itemsize for r in recs], dtype=np.int64)[which]
            at = np.zeros(which.size, dtype=np.int64)  # record offsets in the chunk's records
            np.cumsum(rec_size[:-1], out=at[1:])
            body = prefix + _interleave(recs, which, at)
            offsets = [len(prefix) + at[which == k] for k in range(len(recs))]
        else:
            body = prefix + b''.join(r.tobytes() for r in recs)
            starts = len(prefix) + np.cumsum([0] + [r.nbytes for r in recs])
            offsets = [s + np.arange(r.size, dtype=np.int64) * r.dtype.itemsize
                       for s, r in zip(starts.tolist(), recs)]
        start = min(int(ns.min()) for _, ns, _ in parts)
        end = max(int(ns.max()) for _, ns, _ in parts)
        st = self.storage
        bio = st.bio
        chunk_start = bio.tell()
        head = struct.pack('<QQQI', start, end, len(body), 0) + struct.pack('<I', 0) \
            + struct.pack('<Q', len(body))
        bio.write(struct.pack('<BQ', 0x06, len(head) + len(body)))
        bio.write(head)
        bio.write(body)
        chunk_end = bio.tell()
        index_at = []
        for k, (cid, ns, _) in enumerate(parts):
            index = np.empty((ns.size, 2), dtype='<u8')
            index[:, 0] = ns
            index[:, 1] = offsets[k]
            index_bytes = struct.pack('<HI', cid, 16 * ns.size) + index.tobytes()
            index_at.append((cid, bio.tell()))
            bio.write(struct.pack('<BQ', 0x07, len(index_bytes)))
            bio.write(index_bytes)
        chunk_index = BytesIO()
        chunk_index.write(struct.pack('<QQQQI', start, end, chunk_start, chunk_end - chunk_start,
                                      10 * len(index_at)))
        for cid, pos in index_at:
            chunk_index.write(struct.pack('<HQ', cid, pos))
        chunk_index.write(struct.pack('<Q', bio.tell() - chunk_end))
        chunk_index.write(struct.pack('<I', 0))  # compression '' (none)
        chunk_index.write(struct.pack('<QQ', len(body), len(body)))
        st.chunks.append(chunk_index)
        st.message_start_time = min(start, st.message_start_time)
        st.message_end_time = max(end, st.message_end_time)
        for cid, ns, _ in parts:
            st.channel_stats[cid] += ns.size
            self.writer.counts[cid] += ns.size
        self.writer.min_timestamp = min(start, self.writer.min_timestamp)
        self.writer.max_timestamp = max(end, self.writer.max_timestamp)


def _interleave(recs: List[np.ndarray], which: np.ndarray, at: np.ndarray) -> bytes:
    """
    Join the parts' records in the order ``which`` gives, record i at byte ``at[i]``.

    Records of different sizes cannot share one array, so each part is scattered as rows into
    a sliding-window view of the output (row j: bytes j .. j + record size; the rows written
    never overlap): one row copy per record, 0.2 ms per MB chunk over a plain join (a byte
    mask: 1 ms).
    """
    total = int(at[-1]) + recs[int(which[-1])].dtype.itemsize
    out = np.empty(total + max(r.dtype.itemsize for r in recs), dtype=np.uint8)
    for k, r in enumerate(recs):
        rows = r.view(np.uint8).reshape(r.size, r.dtype.itemsize)
        as_strided(out, shape=(total, rows.shape[1]), strides=(1, 1))[at[which == k]] = rows
    return out[:total].tobytes()


def _records(cid: int, log_ns: np.ndarray, data: np.ndarray) -> np.ndarray:
    """MCAP message records (structured array, one record per row of ``data``)."""
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
    return recs


def _sqlite_chunk(writer: Writer, parts: List[Tuple[int, np.ndarray, np.ndarray]],
                  which: Optional[np.ndarray]) -> None:
    """Insert the rows of ``parts`` in the order ``which`` gives (see ``write_chunk``)."""
    flat = [row for cid, ns, data in parts
            for row in zip([cid] * ns.size, ns.tolist(), (r.tobytes() for r in data))]
    if which is not None and len(parts) > 1:
        # flat row f goes to position dest[f]; read flat back in output order
        dest = np.argsort(which, kind='stable')
        flat = [flat[f] for f in np.argsort(dest).tolist()]
    writer.storage.cursor.executemany(
        'INSERT INTO messages (topic_id, timestamp, data) VALUES(?, ?, ?)', flat)
    for cid, ns, _ in parts:
        writer.counts[cid] += ns.size
        writer.min_timestamp = min(int(ns.min()), writer.min_timestamp)
        writer.max_timestamp = max(int(ns.max()), writer.max_timestamp)


def merge_order(a_ns: np.ndarray, b_ns: np.ndarray) -> np.ndarray:
    """
    Return the stream (0: a, 1: b) of each message in write order: a merge by stamp.

    Each stream keeps its own order (a stream with stamps going back is merged by its running
    maximum); at equal stamps stream a goes first.
    """
    ka, kb = np.maximum.accumulate(a_ns), np.maximum.accumulate(b_ns)
    which = np.zeros(a_ns.size + b_ns.size, dtype=np.int8)
    which[np.arange(b_ns.size) + np.searchsorted(ka, kb, side='right')] = 1
    return which


def _chunk_bounds(which: Optional[np.ndarray], n: int, sizes: Tuple[int, int]) -> np.ndarray:
    """Start indices (write order) of chunks of about CHUNK_BYTES, plus the end."""
    if which is None:
        return np.append(np.arange(0, n, max(1, CHUNK_BYTES // sizes[0])), n)
    ends = np.cumsum(np.where(which == 1, sizes[1], sizes[0]))
    cuts = np.searchsorted(ends, np.arange(CHUNK_BYTES, int(ends[-1]), CHUNK_BYTES), 'right')
    return np.unique(np.concatenate([[0], cuts, [n]]))


def write_bag(path: str, imu: Recording, encoder: Optional[Recording] = None, *,
              storage: str = 'mcap', imu_topic: str = '/imu/data_raw',
              encoder_topic: str = '/stand/joint_states', joint_name: str = 'stand_joint',
              frame_id: str = 'imu_link', quiet: bool = True) -> None:
    """
    Write ``imu`` (and ``encoder``) as a ROS 2 bag directory at ``path``.

    Messages are logged at their header stamps, both topics merged in stamp order
    (``merge_order``). Missing IMU channels are written as NaN.
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
    enc_ns = stamps_ns(encoder.t) if encoder is not None else None
    which = merge_order(imu_ns, enc_ns) if encoder is not None else None
    sizes = (MCAP_HEAD + imu_size(frame_id), 0)
    if encoder is not None:  # (building the encoder costs rosbags' serializer generation)
        enc = joint_state_encoder(store, joint_name)
        sizes = (sizes[0], MCAP_HEAD + enc(imu.t[:1], [0.0]).shape[1])
    n = len(imu) + (len(encoder) if encoder is not None else 0)
    bounds = _chunk_bounds(which, n, sizes)
    # messages of stream b before each chunk start: where each stream's slice begins
    b_before = (np.concatenate([[0], np.cumsum(which)])[bounds] if which is not None
                else np.zeros(bounds.size, dtype=np.int64))
    writer = Writer(path, version=9, storage_plugin=plugins[storage])
    writer.open()
    try:
        cid = writer.add_connection(imu_topic, IMU_TYPE, typestore=store).id
        enc_cid = None
        if encoder is not None:
            enc_cid = writer.add_connection(encoder_topic, JOINT_TYPE, typestore=store).id
            pos = encoder.channels[ENCODER_CHANNEL]
        if storage == 'mcap':
            bulk = _McapBulk(writer)
            bulk.take_prefix()
            write = bulk.write_chunk
        else:
            def write(parts, w):
                _sqlite_chunk(writer, parts, w)
        bar = progress(total=n, desc=f'writing {Path(path).name}', quiet=quiet, unit='msg')
        with bar:
            for k in range(bounds.size - 1):
                s, e = int(bounds[k]), int(bounds[k + 1])
                b0, b1 = int(b_before[k]), int(b_before[k + 1])
                a0, a1 = s - b0, e - b1
                parts = []
                if a1 > a0:
                    parts.append((cid, imu_ns[a0:a1], encode_imu(
                        imu.t[a0:a1], [c[a0:a1] for c in gyro], [c[a0:a1] for c in accel],
                        frame_id=frame_id)))
                if b1 > b0:
                    parts.append((enc_cid, enc_ns[b0:b1], enc(encoder.t[b0:b1], pos[b0:b1])))
                write(parts, which[s:e] if len(parts) == 2 else None)
                bar.update(e - s)
    except BaseException:
        writer.abort()
        raise
    writer.close()
