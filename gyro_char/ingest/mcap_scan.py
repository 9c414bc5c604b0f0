"""
Find the raw CDR payloads of one topic in an MCAP file without a Python loop per message.

The file is memory-mapped and walked record by record (a few per megabyte: chunks); inside a
chunk, the common case - only message records of one size - is recognised with strided numpy
views and the payload offsets come out as an array. Chunks holding other records (schemas,
channels, several topics of different sizes) are walked with ``struct`` (about a microsecond a
record, still far below deserialising). Compression: none, zstd and lz4, as rosbags reads them.
"""
import mmap
import struct
from typing import Dict, Iterator, Optional, Set, Tuple
import zlib

from gyro_char.recordings import InputError
import numpy as np

MAGIC = b'\x89MCAP0\r\n'
OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_FOOTER, OP_DATA_END = 0x04, 0x05, 0x06, 0x02, 0x0F
MESSAGE_HEAD = 22  # channel id 2 + sequence 4 + log time 8 + publish time 8

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
                block = self._chunk(mm, data, mv, start, end, pos)
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

    def _chunk(self, mm, data, mv, start: int, end: int, pos: int):
        _t0, _t1, usize, crc, clen = struct.unpack_from('<QQQII', mm, start)
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
        return self._records(inner, base, base + usize, pos)

    def _records(self, buf: np.ndarray, lo: int, hi: int, pos: int):
        n_bytes = hi - lo
        if n_bytes >= 9 and buf[lo] == OP_MESSAGE:
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
        mv = memoryview(buf)
        offs, sizes = [], []
        p = lo
        while p < hi:
            if p + 9 > hi:
                raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos}')
            op = buf[p]
            (length,) = struct.unpack_from('<Q', mv, p + 1)
            s, e = p + 9, p + 9 + length
            if e > hi:
                raise InputError(f'{self.path}: corrupt MCAP chunk at byte {pos}')
            if op == OP_MESSAGE and length >= MESSAGE_HEAD:
                if struct.unpack_from('<H', mv, s)[0] in self.wanted:
                    offs.append(s + MESSAGE_HEAD)
                    sizes.append(length - MESSAGE_HEAD)
            elif op == OP_CHANNEL:
                self._channel(mv, s)
            p = e
        if not offs:
            return None
        return buf, np.array(offs, dtype=np.int64), np.array(sizes, dtype=np.int64)


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
