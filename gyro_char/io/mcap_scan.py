"""
Find the raw CDR payloads of one topic in an MCAP file without a Python loop per message.

The file is memory-mapped and walked record by record (a few per megabyte: chunks). Inside a
chunk, the message index records written after it (one per channel: log time and offset of each
message) give where message records start, for every topic; without an index (a file cut short,
a writer that omits it) a byte scan for message heads in the chunk's time range does. Either way
the candidates are only a shortcut: the chunk is walked exactly, jumping over runs of candidates
that chain end to start, and records that are not candidates (schemas, channels) are read one at
a time, so a wrong or partial index costs speed, never messages. Mixed chunks (several topics of
different record sizes, as recorders log them) thus cost a few numpy calls per chunk.
Compression: none, zstd and lz4, as rosbags reads them.
"""
import mmap
import struct
from typing import Callable, Dict, Iterator, Optional, Set, Tuple
import zlib

from gyro_char.errors import InputError
import numpy as np
from numpy.lib.stride_tricks import as_strided

MAGIC = b'\x89MCAP0\r\n'
OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_FOOTER, OP_DATA_END = 0x04, 0x05, 0x06, 0x02, 0x0F
OP_MESSAGE_INDEX = 0x07
MESSAGE_HEAD = 22  # channel id 2 + sequence 4 + log time 8 + publish time 8
RECORD_MIN = 9 + MESSAGE_HEAD  # opcode + length + message head
RESCAN_AFTER = 64  # records walked one by one in a chunk before its index is given up

Block = Tuple[np.ndarray, np.ndarray, np.ndarray]  # (uint8 buffer, offsets, sizes)
# the start of a message record: opcode, record length, channel id
_HEAD = np.dtype({'names': ['op', 'len', 'cid'], 'formats': ['u1', '<u8', '<u2'],
                  'offsets': [0, 1, 9], 'itemsize': 11})


def _decompress(kind: str, payload: bytes, size: int) -> bytes:
    if kind == 'zstd':
        try:
            from compression import zstd
        except ImportError:  # before Python 3.14 rosbags uses the backport
            from backports import zstd
        out = zstd.decompress(payload)
    elif kind == 'lz4':
        from lz4.frame import decompress
        out = decompress(payload)
    else:
        raise InputError(f'unsupported MCAP chunk compression {kind!r}')
    if len(out) != size:
        raise InputError('corrupt MCAP chunk: wrong decompressed size')
    return out


def _index_after(mm: mmap.mmap, pos: int) -> Optional[np.ndarray]:
    """
    Message offsets (in the chunk's records) of the message index records at ``pos``, or None.

    They follow their chunk; any that is cut short or malformed ends the list.
    """
    parts = []
    size = len(mm)
    while pos + 15 <= size and mm[pos] == OP_MESSAGE_INDEX:
        (length,) = struct.unpack_from('<Q', mm, pos + 1)
        _cid, n_bytes = struct.unpack_from('<HI', mm, pos + 9)
        if pos + 9 + length > size or 6 + n_bytes > length or n_bytes % 16:
            break
        # (log time, offset) pairs: every second uint64
        parts.append(np.frombuffer(mm, '<u8', count=n_bytes // 8, offset=pos + 15)[1::2])
        pos += 9 + length
    return np.concatenate(parts) if parts else None


class McapTopicScan:
    """Iterate blocks of one topic's payloads from an MCAP file."""

    def __init__(self, path: str, topic: str, tolerate_truncation: bool = False) -> None:
        self.path = path
        self.topic = topic
        self.channels = {}  # id -> topic
        self.wanted: Set[int] = set()
        # for a file never closed (recording killed): stop at the cut instead of failing
        self.tolerate_truncation = tolerate_truncation
        self.truncated_at: Optional[int] = None

    def _channel(self, mv: memoryview, start: int) -> None:
        cid, _schema, nlen = struct.unpack_from('<HHI', mv, start)
        name = bytes(mv[start + 8:start + 8 + nlen]).decode('utf-8', 'replace')
        self.channels[cid] = name
        if name == self.topic:
            self.wanted.add(cid)

    def blocks(self) -> Iterator[Block]:
        """Yield ``(buffer, offsets, sizes)`` per chunk; raise InputError on a broken file."""
        with open(self.path, 'rb') as fh:
            try:
                mm = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
            except ValueError:
                raise InputError(f'{self.path}: empty file') from None
        try:
            yield from self._walk(mm)
        except struct.error:
            raise InputError(f'{self.path}: corrupt MCAP record') from None
        finally:
            try:
                mm.close()
            except BufferError:  # a caller still holds a view; the map closes when it is freed
                pass

    def _walk(self, mm: mmap.mmap) -> Iterator[Block]:
        size = len(mm)
        if mm[:8] != MAGIC:
            raise InputError(f'{self.path}: not an MCAP file (bad magic)')
        data = np.frombuffer(mm, np.uint8)
        mv = memoryview(mm)
        pos = 8
        loose = []
        while pos + 9 <= size:
            op = mm[pos]
            (length,) = struct.unpack_from('<Q', mm, pos + 1)
            start, end = pos + 9, pos + 9 + length
            if end > size:
                if self.tolerate_truncation:
                    self.truncated_at = pos
                    break
                raise InputError(f'{self.path}: truncated MCAP record at byte {pos} '
                                 f'(file cut short? `ros2 bag reindex` may help)')
            if op == OP_CHANNEL:
                self._channel(mv, start)
            elif op == OP_MESSAGE and length >= MESSAGE_HEAD:
                if struct.unpack_from('<H', mm, start)[0] in self.wanted:
                    loose.append((start + MESSAGE_HEAD, length - MESSAGE_HEAD))
            elif op == OP_CHUNK:
                block = self._chunk(mm, data, start, end, pos)
                if block is not None:
                    yield block
            elif op in (OP_DATA_END, OP_FOOTER):
                break
            pos = end
        else:
            if pos != size and not self.tolerate_truncation:
                raise InputError(f'{self.path}: truncated MCAP file (no data-end record)')
            if self.tolerate_truncation and self.truncated_at is None:
                self.truncated_at = pos
        if loose:
            offs, sizes = zip(*loose)
            yield data, np.array(offs, dtype=np.int64), np.array(sizes, dtype=np.int64)

    def _chunk(self, mm, data, start: int, end: int, pos: int):
        t0, t1, usize, crc, clen = struct.unpack_from('<QQQII', mm, start)
        kind = bytes(mm[start + 32:start + 32 + clen]).decode('ascii', 'replace')
        (rlen,) = struct.unpack_from('<Q', mm, start + 32 + clen)
        r0 = start + 40 + clen
        if r0 + rlen > end:
            raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos}')
        if kind:
            inner = np.frombuffer(_decompress(kind, bytes(mm[r0:r0 + rlen]), usize), np.uint8)
            base = 0
        else:
            if rlen != usize:
                raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos}')
            inner, base = data, r0
        # a zero CRC means 'not computed' (rosbags writes none; ros2 bag record does)
        if crc and zlib.crc32(inner[base:base + usize]) != crc:
            raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos} (CRC mismatch)')
        return self._records(inner, base, base + usize, pos, lambda: _index_after(mm, end),
                             (t0, t1))

    def _records(self, buf: np.ndarray, lo: int, hi: int, pos: int,
                 read_index: Callable[[], Optional[np.ndarray]], times: Tuple[int, int]):
        """
        Walk the chunk's records ``buf[lo:hi]``; return the wanted payloads' block or None.

        A chunk of message records of one size only (one topic) is read as a strided view.
        Otherwise the walk is exact (every record from ``lo`` to ``hi``, as one by one) but
        jumps over runs of *candidate* message records that chain end to start: from a true
        record start a run can only lead to the next true starts. Candidates come from the
        chunk's message index when there is one, else from a byte scan; records that are not
        candidates (schemas, channels, unindexed messages) are walked one at a time.
        """
        n_bytes = hi - lo
        if n_bytes >= 9 and buf[lo] == OP_MESSAGE:  # one topic, one size: a strided view
            length = int(buf[lo + 1:lo + 9].view('<u8')[0])
            rec = 9 + length
            if length >= MESSAGE_HEAD and n_bytes % rec == 0:
                heads = np.ndarray(shape=(n_bytes // rec,), dtype=_HEAD, buffer=buf, offset=lo,
                                   strides=(rec,))
                if np.all(heads['op'] == OP_MESSAGE) and np.all(heads['len'] == length):
                    cids = heads['cid']
                    hit = (np.flatnonzero(cids == next(iter(self.wanted)))
                           if len(self.wanted) == 1 else
                           np.flatnonzero(np.isin(cids, list(self.wanted))))
                    if hit.size == 0:
                        return None
                    offsets = lo + hit.astype(np.int64) * rec + 9 + MESSAGE_HEAD
                    return buf, offsets, np.full(hit.size, length - MESSAGE_HEAD, np.int64)
        index = read_index()  # (after the chunk: only read when needed)
        cand = (_Candidates.indexed(buf, lo, hi, index) if index is not None
                else _Candidates.scanned(buf, lo, hi, times))
        runs, loose, late = [], [], {}
        mv = memoryview(buf)
        steps = 0
        p = lo
        while p < hi:
            i = cand.at(p)
            if i >= 0:
                j = cand.run_end(i)
                runs.append((cand.pos[i:j + 1], cand.length[i:j + 1]))
                p = int(cand.succ[j])
                continue
            if p + 9 > hi:
                raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos}')
            op = buf[p]
            (length,) = struct.unpack_from('<Q', mv, p + 1)
            s, e = p + 9, p + 9 + length
            if e > hi:
                raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos}')
            if op == OP_MESSAGE and length >= MESSAGE_HEAD:
                if struct.unpack_from('<H', mv, s)[0] in self.wanted:
                    loose.append((s + MESSAGE_HEAD, length - MESSAGE_HEAD))
            elif op == OP_CHANNEL:
                known = set(self.wanted)
                self._channel(mv, s)
                late.update((cid, p) for cid in self.wanted - known)
            p = e
            steps += 1
            if steps == RESCAN_AFTER and index is not None:  # an index missing many messages
                cand = _Candidates.scanned(buf, p, hi, times)
        return self._selected(buf, runs, loose, late)

    def _selected(self, buf: np.ndarray, runs, loose, late):
        """Wanted payloads of the walked runs (channel known before the record) and loose."""
        offs, sizes = [], []
        if runs and self.wanted:
            at = np.concatenate([r[0] for r in runs]) if len(runs) > 1 else runs[0][0]
            length = np.concatenate([r[1] for r in runs]) if len(runs) > 1 else runs[0][1]
            cids = buf[at + 9].astype(np.uint16) | (buf[at + 10].astype(np.uint16) << 8)
            hit = (cids == next(iter(self.wanted)) if len(self.wanted) == 1
                   else np.isin(cids, list(self.wanted)))
            for cid, p in late.items():  # a message before its channel record is not read
                hit &= ~((cids == cid) & (at < p))
            offs.append(at[hit] + 9 + MESSAGE_HEAD)
            sizes.append(length[hit].astype(np.int64) - MESSAGE_HEAD)
        if loose:
            offs.append(np.array([o for o, _ in loose], dtype=np.int64))
            sizes.append(np.array([n for _, n in loose], dtype=np.int64))
        if not offs:
            return None
        offsets, sizes = np.concatenate(offs), np.concatenate(sizes)
        if offsets.size == 0:
            return None
        if loose and runs:  # file order
            order = np.argsort(offsets, kind='stable')
            offsets, sizes = offsets[order], sizes[order]
        return _packed(buf, offsets, sizes)


def _packed(buf: np.ndarray, offsets: np.ndarray, sizes: np.ndarray) -> Block:
    """
    Copy equal-size payloads lying at uneven strides (other topics between) into one array.

    The decoders read a block at a constant stride with one record view; scattered payloads
    would each be gathered field by field (several times slower than this one copy).
    """
    size = int(sizes[0])
    if (offsets.size < 2 or size == 0 or np.any(sizes != size)
            or np.all(np.diff(offsets) == offsets[1] - offsets[0])):
        return buf, offsets, sizes
    rows = as_strided(buf, shape=(buf.size - size + 1, size), strides=(buf.strides[0], 1))
    return (rows[offsets].reshape(-1), np.arange(offsets.size, dtype=np.int64) * size,
            sizes)


def _u64(buf: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Little-endian uint64 at byte positions ``at`` (each at most ``buf.size - 8``)."""
    if at.size == 0:
        return np.zeros(0, dtype='<u8')
    win = as_strided(buf, shape=(buf.size - 7, 8), strides=(buf.strides[0], 1))
    return win[at].view('<u8').reshape(-1)


class _Candidates:
    """
    Sorted positions that may start a message record, each with its length and its end.

    Every candidate is a message record head (opcode, length >= 22) whose record fits before
    the chunk's end; ``run_end`` says how far candidates chain (one's end is the next start).
    """

    def __init__(self, buf: np.ndarray, at: np.ndarray, hi: int) -> None:
        ok = buf[at] == OP_MESSAGE
        at = at[ok]
        length = _u64(buf, at + 1)
        ok = (length >= MESSAGE_HEAD) & (length <= (hi - 9 - at).astype(np.uint64))
        self.pos = at[ok]
        self.length = length[ok]
        self.succ = self.pos + 9 + self.length.astype(np.int64)
        # the last candidate of the run each candidate is in
        breaks = np.flatnonzero(self.succ[:-1] != self.pos[1:])
        self._breaks = np.append(breaks, self.pos.size - 1)

    @classmethod
    def indexed(cls, buf: np.ndarray, lo: int, hi: int, index: np.ndarray) -> '_Candidates':
        """From message index offsets (relative to the chunk's records, any order)."""
        if hi - lo < RECORD_MIN:
            index = index[:0]
        index = index[index <= np.uint64(max(hi - lo - RECORD_MIN, 0))]
        at = lo + index.astype(np.int64)
        if at.size > 1 and np.any(at[1:] <= at[:-1]):  # several channels: merge, drop repeats
            at = np.sort(at, kind='stable')  # a merge of the sorted per-channel runs
            at = at[np.append(True, at[1:] != at[:-1])]
        return cls(buf, at, hi)

    @classmethod
    def scanned(cls, buf: np.ndarray, lo: int, hi: int, times: Tuple[int, int]) -> '_Candidates':
        """
        Every message opcode byte whose log time lies in the chunk's time range.

        The time test makes a false candidate (an opcode byte inside a payload) unlikely;
        one only ends a run early, never changes what the walk finds.
        """
        at = np.flatnonzero(buf[lo:max(hi - RECORD_MIN + 1, lo)] == OP_MESSAGE) + lo
        log = _u64(buf, at + 15)
        at = at[(log >= np.uint64(times[0])) & (log <= np.uint64(times[1]))]
        return cls(buf, at, hi)

    def at(self, p: int) -> int:
        """Index of the candidate at byte ``p``, or -1."""
        i = int(np.searchsorted(self.pos, p))
        return i if i < self.pos.size and self.pos[i] == p else -1

    def run_end(self, i: int) -> int:
        """Index of the last candidate chained to candidate ``i``."""
        return int(self._breaks[np.searchsorted(self._breaks, i)])


def list_channels(path: str) -> Dict[str, str]:
    """
    Topic -> message type of an MCAP file that rosbags cannot open (no summary: cut short).

    Reads from the start until the first message: channels announced later are not seen.
    """
    found: Dict[str, str] = {}
    schemas: Dict[int, str] = {}
    with open(path, 'rb') as fh:
        data = fh.read(64 << 20)  # the first records; a recording announces its channels early
    if data[:8] != MAGIC:
        return found

    def walk(buf: bytes, pos: int, end: int) -> bool:
        while pos + 9 <= end:
            op = buf[pos]
            (length,) = struct.unpack_from('<Q', buf, pos + 1)
            s, e = pos + 9, pos + 9 + length
            if e > end:
                return True
            if op == 0x03:
                sid, nlen = struct.unpack_from('<HI', buf, s)
                schemas[sid] = buf[s + 6:s + 6 + nlen].decode('utf-8', 'replace')
            elif op == OP_CHANNEL:
                _cid, sid, nlen = struct.unpack_from('<HHI', buf, s)
                topic = buf[s + 8:s + 8 + nlen].decode('utf-8', 'replace')
                found[topic] = schemas.get(sid, '?')
            elif op == OP_MESSAGE:
                return True
            elif op == OP_CHUNK:
                _t0, _t1, usize, _crc, clen = struct.unpack_from('<QQQII', buf, s)
                kind = buf[s + 32:s + 32 + clen].decode('ascii', 'replace')
                (rlen,) = struct.unpack_from('<Q', buf, s + 32 + clen)
                r0 = s + 40 + clen
                inner = buf[r0:r0 + rlen] if not kind else _decompress(kind, buf[r0:r0 + rlen],
                                                                       usize)
                if walk(inner, 0, len(inner)):
                    return True
            pos = e
        return True

    try:
        walk(data, 8, len(data))
    except (struct.error, InputError, ValueError, RuntimeError, OSError):
        pass
    return found
