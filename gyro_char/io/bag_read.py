"""
Read IMU streams from ROS 2 bags (sqlite3, mcap), bare ``.mcap`` / ``.db3`` and ROS 1 ``.bag``.

rosbags' ``AnyReader`` opens every format and lists the topics. IMU samples take the fast path:
raw payloads straight from sqlite (``fetchmany``), the MCAP scan or (ROS 1) rosbags' raw message
iterator, decoded in blocks by ``cdr.decode_imu`` / ``ros1_imu.decode_imu_ros1``. The per-message
path (rosbags deserialisation + ``msg_adapters``) serves file-compressed bags and any payload the
fast path declines; both give identical values. ``encoder_read`` shares ``Bag`` and the sources.
"""
from contextlib import contextmanager
import difflib
from pathlib import Path
import sqlite3
import struct
from typing import Dict, Iterator, List, Optional, Tuple

from gyro_char.errors import InputError
from gyro_char.io.cdr import decode_imu
from gyro_char.io.mcap_scan import list_channels, McapTopicScan
from gyro_char.io.ros1_imu import decode_imu_ros1
from gyro_char.io.typestore import typestore
from gyro_char.progress import progress
from gyro_char.records import IMU_CHANNELS, Recording
from msg_adapters import imu_sample
import numpy as np
from rosbags.highlevel import AnyReader
import yaml

IMU_TYPE = 'sensor_msgs/msg/Imu'
ENCODER_TYPES = ('sensor_msgs/msg/JointState', 'geometry_msgs/msg/Vector3Stamped')
SQL_BATCH = 32768
# what rosbags, sqlite, the decompressors and the deserialisers raise on damaged input
READ_ERRORS = (ArithmeticError, AssertionError, AttributeError, EOFError, IndexError, KeyError,
               LookupError, MemoryError, OSError, RuntimeError, TypeError, ValueError,
               sqlite3.Error, struct.error)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


@contextmanager
def reading(path: Path, topic: str) -> Iterator[None]:
    """Turn any reader failure inside the block into ``InputError('<path>: cannot read ...')``."""
    try:
        yield
    except InputError:
        raise
    except Exception as exc:  # noqa: B902 - READ_ERRORS and rosbags' own errors alike
        raise InputError(f'{path}: cannot read {topic}: {_first_line(exc)}') from None


class Bag:
    """An open bag: topic table plus the reader, closing on exit."""

    def __init__(self, path: Path) -> None:
        self.path = path
        if path.is_dir() and not (path / 'metadata.yaml').exists():
            raise InputError(f'{path}: a directory without metadata.yaml is not a ROS 2 bag')
        if path.is_file() and path.suffix not in ('.mcap', '.bag', '.db3'):
            raise InputError(f'{path}: unknown input type (expected a bag directory, .mcap, '
                             f'.bag or .csv/.csv.gz)')
        self.notes: List[str] = []
        self.scans: List[McapTopicScan] = []
        self.recovered: Optional[Dict[str, str]] = None  # topic -> type, for a cut-short MCAP
        try:
            self.reader = AnyReader([path], default_typestore=typestore())
            self.reader.open()
        except Exception as exc:  # noqa: B902 - rosbags' own error classes derive from Exception
            self.reader = None
            self._recover(f'{path}: cannot open bag (truncated or corrupt?): {_first_line(exc)}')

    def _recover(self, reason: str) -> None:
        """Read an MCAP that was never closed (no summary) from the start, or raise ``reason``."""
        files = list(self.path.glob('*.mcap')) if self.path.is_dir() else [self.path]
        if len(files) != 1 or files[0].suffix != '.mcap':
            raise InputError(reason)
        try:
            found = list_channels(str(files[0]))
        except Exception:  # noqa: B902 - any failure here means: not recoverable
            found = {}
        if not found:
            raise InputError(reason)
        self.recovered = found
        self.notes.append(f'{files[0].name} has no index (recording cut short?): read from the '
                          f'start; topics first announced later are not seen')

    def __enter__(self) -> 'Bag':
        return self

    def __exit__(self, *exc) -> None:
        try:
            if self.reader is not None:
                self.reader.close()
        except Exception:  # noqa: B902 - closing a damaged bag must not mask the real error
            pass

    def total(self, topic: str) -> Optional[int]:
        """Message count of ``topic`` from the bag's index (None when there is no index)."""
        if self.recovered is not None:
            return None
        return sum(c.msgcount for c in self.connections(topic))

    def topics(self) -> Dict[str, Tuple[str, int]]:
        """Topic -> (message type, count); count -1 when the bag has no index."""
        if self.recovered is not None:
            return {t: (k, -1) for t, k in self.recovered.items()}
        out: Dict[str, Tuple[str, int]] = {}
        for conn in self.reader.connections:
            kind, count = out.get(conn.topic, (conn.msgtype, 0))
            out[conn.topic] = (kind, count + conn.msgcount)
        return out

    def pick(self, topic: Optional[str], types: Tuple[str, ...], what: str) -> str:
        """Resolve the topic to read: given (checked) or the only one of ``types``."""
        table = self.topics()
        listing = ', '.join(f'{t} [{k}]' for t, (k, _) in sorted(table.items())) or 'none'
        if topic is None:
            found = sorted(t for t, (k, _) in table.items() if k in types)
            if len(found) != 1:
                many = 'several' if found else 'no'
                raise InputError(f'{self.path}: {many} {what} topics; choose one with --topic '
                                 f'(topics: {listing})')
            topic = found[0]
        name = topic if topic in table else '/' + topic.lstrip('/')
        if name not in table:
            close = difflib.get_close_matches(name, list(table), n=1)
            hint = f'did you mean {close[0]}? ' if close else ''
            raise InputError(f'{self.path}: no topic {topic!r}; {hint}(topics: {listing})')
        kind, count = table[name]
        if kind not in types:
            raise InputError(f'{self.path}: topic {name} carries {kind}, not {" or ".join(types)}')
        if count == 0:  # -1: unknown (no index)
            raise InputError(f'{self.path}: topic {name} has no messages')
        return name

    def connections(self, topic: str) -> List:
        return [c for c in self.reader.connections if c.topic == topic]

    def _metadata(self) -> dict:
        try:
            with open(self.path / 'metadata.yaml') as fh:
                return yaml.safe_load(fh)['rosbag2_bagfile_information']
        except (OSError, KeyError, TypeError, yaml.YAMLError) as exc:
            raise InputError(f'{self.path}: bad metadata.yaml: {_first_line(exc)}') from None

    def storage(self) -> str:
        """'sqlite3' or 'mcap' for raw-CDR files the fast path reads, else 'other'."""
        if self.recovered is not None:
            return 'mcap'
        if self.path.is_file():
            return {'.mcap': 'mcap', '.db3': 'sqlite3'}.get(self.path.suffix, 'other')
        meta = self._metadata()
        if meta.get('compression_mode') or meta.get('compression_format'):
            return 'other'  # file-compressed bag: rosbags' reader decompresses it
        return str(meta.get('storage_identifier', 'other'))

    def files(self) -> List[Path]:
        if self.path.is_file():
            return [self.path]
        if self.recovered is not None:
            return list(self.path.glob('*.mcap'))
        return [self.path / Path(p).name for p in self._metadata()['relative_file_paths']]

    def messages(self, topic: str, desc: str, quiet: bool) -> Iterator:
        """Yield (connection, deserialised message or None) per message: the slow path."""
        conns = self.connections(topic)
        total = sum(c.msgcount for c in conns)
        bar = progress(total=total, desc=desc, quiet=quiet, unit='msg')
        with bar:
            for conn, _, raw in self.reader.messages(connections=conns):
                bar.update(1)
                try:
                    msg = self.reader.deserialize(raw, conn.msgtype)
                except READ_ERRORS:
                    yield conn, None
                    continue
                except Exception:  # noqa: B902 - rosbags.serde.SerdeError and relatives
                    yield conn, None
                    continue
                yield conn, msg


def _sqlite_blocks(files: List[Path], topic: str) -> Iterator[Tuple]:
    for db in files:
        con = sqlite3.connect(f'file:{db}?mode=ro', uri=True)
        try:
            row = con.execute('SELECT id FROM topics WHERE name = ?', (topic,)).fetchone()
            if row is None:
                continue
            cur = con.execute('SELECT data FROM messages WHERE topic_id = ? ORDER BY id',
                              (row[0],))
            while True:
                rows = cur.fetchmany(SQL_BATCH)
                if not rows:
                    break
                yield _joined([r[0] for r in rows])
        finally:
            con.close()


def payload_blocks(bag: Bag, topic: str) -> Iterator[Tuple]:
    files = bag.files()
    if bag.storage() == 'sqlite3':
        return _sqlite_blocks(files, topic)
    bag.scans = [McapTopicScan(str(f), topic, tolerate_truncation=bag.recovered is not None)
                 for f in files]
    return (b for scan in bag.scans for b in scan.blocks())


def bag_notes(bag: Bag) -> List[str]:
    notes = list(bag.notes)
    for scan in bag.scans:
        if scan.truncated_at is not None:
            notes.append(f'{Path(scan.path).name} ends inside a record at byte '
                         f'{scan.truncated_at}: the messages before it were read')
    return notes


def _ros1_blocks(bag: Bag, topic: str) -> Iterator[Tuple]:
    """Raw ROS 1 payloads via rosbags (no deserialisation), joined in blocks."""
    payloads = []
    for _, _, raw in bag.reader.messages(connections=bag.connections(topic)):
        payloads.append(raw)
        if len(payloads) == SQL_BATCH:
            yield _joined(payloads)
            payloads = []
    if payloads:
        yield _joined(payloads)


def _joined(payloads: List[bytes]) -> Tuple:
    sizes = np.fromiter(map(len, payloads), dtype=np.int64, count=len(payloads))
    offsets = np.zeros(sizes.size, dtype=np.int64)
    np.cumsum(sizes[:-1], out=offsets[1:])
    return np.frombuffer(b''.join(payloads), np.uint8), offsets, sizes


def _fast_imu(bag: Bag, topic: str, quiet: bool) -> Recording:
    ros1 = bag.path.suffix == '.bag'
    blocks = _ros1_blocks(bag, topic) if ros1 else payload_blocks(bag, topic)
    decode = decode_imu_ros1 if ros1 else decode_imu
    store = typestore()
    total = bag.total(topic)
    # decode straight into preallocated outputs: fresh memory is the costly part at this size
    out = _Columns(total or 1 << 16)
    with progress(total=total, desc=f'reading {topic}', quiet=quiet, unit='msg') as bar:
        for buf, offsets, sizes in blocks:
            t, values, ok = decode(buf, offsets, sizes)
            for i in np.flatnonzero(~ok):  # payloads the vectorised decoder declined
                raw = buf[offsets[i]:offsets[i] + sizes[i]].tobytes()
                try:
                    msg = (bag.reader.deserialize(raw, IMU_TYPE) if ros1
                           else store.deserialize_cdr(raw, IMU_TYPE))
                    stamp, six = imu_sample(msg)
                except Exception:  # noqa: B902 - any undecodable payload is counted, not fatal
                    continue
                ok[i] = True
                t[i] = stamp
                for k, v in zip(IMU_CHANNELS, six):
                    values[k][i] = v
            out.add(t, values, ok)
            bar.update(ok.size)
    return _assemble(bag, topic, *out.result())


class _Columns:
    """Growable float64 columns (t + IMU channels) filled block by block."""

    def __init__(self, capacity: int) -> None:
        self.n = 0
        self.bad = 0
        self.cols = {k: np.empty(max(capacity, 1)) for k in ('t',) + IMU_CHANNELS}

    def add(self, t: np.ndarray, values: Dict[str, np.ndarray], ok: np.ndarray) -> None:
        keep = None if ok.all() else ok
        m = int(ok.size if keep is None else np.count_nonzero(keep))
        self.bad += ok.size - m
        cap = self.cols['t'].size
        if self.n + m > cap:  # more messages than the bag's index announced
            grow = max(self.n + m, 2 * cap)
            self.cols = {k: np.concatenate([v[:self.n], np.empty(grow - self.n)])
                         for k, v in self.cols.items()}
        for k, v in (('t', t),) + tuple(values.items()):
            self.cols[k][self.n:self.n + m] = v if keep is None else v[keep]
        self.n += m

    def result(self):
        cols = {k: v[:self.n] for k, v in self.cols.items()}
        t = cols.pop('t')
        return [t], {k: [v] for k, v in cols.items()}, self.bad


def _slow_imu(bag: Bag, topic: str, quiet: bool) -> Recording:
    ts, rows, bad = [], [], 0
    for _, msg in bag.messages(topic, f'reading {topic}', quiet):
        try:
            stamp, six = imu_sample(msg)
        except (AttributeError, TypeError):
            bad += 1
            continue
        ts.append(stamp)
        rows.append(six)
    arr = np.array(rows, dtype=np.float64).reshape(-1, 6)
    return _assemble(bag, topic, [np.array(ts, dtype=np.float64)],
                     {k: [arr[:, i]] for i, k in enumerate(IMU_CHANNELS)}, bad)


def _assemble(bag: Bag, topic: str, ts, chans, bad: int) -> Recording:
    def join(parts):  # a single part is used as is: copying 3.6 M samples is not free
        return parts[0] if len(parts) == 1 else np.concatenate(parts) if parts else np.empty(0)
    t = join(ts)
    channels = {k: join(v) for k, v in chans.items()}
    if t.size == 0:
        raise InputError(f'{bag.path}: no decodable messages on {topic}'
                         + (f' ({bad} undecodable)' if bad else ''))
    notes = bag_notes(bag)
    if bad:
        notes.append(f'{bad} undecodable message(s) on {topic} dropped')
    absent = [k for k, v in channels.items() if np.all(np.isnan(v))]
    if absent:
        notes.append(f'channels not reported (all NaN) left out: {", ".join(absent)}')
        channels = {k: v for k, v in channels.items() if k not in absent}
    if not channels:
        raise InputError(f'{bag.path}: every IMU channel on {topic} is NaN')
    return Recording(t, channels, source=f'{bag.path}:{topic}', notes=notes)


def read_imu_bag(path: Path, topic: Optional[str] = None, quiet: bool = False,
                 fast: bool = True) -> Recording:
    """Read a bag's Imu topic (auto-detected if it is the only one); not yet sanitised."""
    with Bag(path) as bag:
        name = bag.pick(topic, (IMU_TYPE,), 'sensor_msgs/Imu')
        with reading(path, name):
            if fast and (bag.storage() in ('sqlite3', 'mcap') or bag.path.suffix == '.bag'):
                return _fast_imu(bag, name, quiet)
            return _slow_imu(bag, name, quiet)
