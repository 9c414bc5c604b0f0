"""
MCAP chunks mixing topics (as recorders write them) read by the fast path as rosbags reads them.

Bags of Imu + JointState (+ std_msgs/String of varying length) interleaved by stamp, from our
writer and from rosbags' own (uncompressed, zstd, lz4 chunks); each read bit for bit equal to the
per-message rosbags path, through the message index, and through the byte-scan fallback when
the index is hidden, cut short or wrong.
"""
from pathlib import Path
import shutil
import struct

from gyro_char.io import mcap_scan
from gyro_char.io import write_bag
from gyro_char.io.bag_read import read_imu_bag
from gyro_char.io.bag_write import IMU_TYPE, joint_state_encoder, JOINT_TYPE, stamps_ns
from gyro_char.io.cdr import encode_imu
from gyro_char.io.encoder_read import read_encoder_bag
from gyro_char.io.typestore import typestore
from gyro_char.records import ENCODER_CHANNEL, IMU_CHANNELS, Recording
import numpy as np
import pytest
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

N = 5000  # per topic: a few 1 MB chunks
T0 = 1.7e9


def _recordings(n=N, seed=3):
    rng = np.random.default_rng(seed)
    t = T0 + np.arange(n) / 333.0 + rng.uniform(0, 2e-5, n)
    imu = Recording(t, {k: rng.normal(size=n) for k in IMU_CHANNELS})
    t_enc = T0 + np.arange(n) / 333.0 + 1e-3 + rng.uniform(0, 2e-5, n)
    return imu, Recording(t_enc, {ENCODER_CHANNEL: rng.normal(size=n)})


def _rosbags_three(path, compression=None):
    """
    Imu (two frame_ids: two payload sizes) + JointState + String, written by rosbags.

    ``compression``: None, 'zstd' (rosbags' storage compression) or 'lz4' (its MCAP writer's
    compressor swapped, since rosbags writes no lz4 itself but reads it).
    """
    store = typestore()
    imu, enc = _recordings()
    six = [imu.channels[k] for k in IMU_CHANNELS]
    long_frame = encode_imu(imu.t, six[:3], six[3:], frame_id='imu_link')
    short_frame = encode_imu(imu.t, six[:3], six[3:], frame_id='imu')
    imu_raw = [bytes(long_frame[i] if i % 3 else short_frame[i]) for i in range(N)]
    enc_raw = joint_state_encoder(store, 'stand_joint')(enc.t, enc.channels[ENCODER_CHANNEL])
    t_str = T0 + np.arange(N // 10) / 33.3 + 2e-4
    text = store.types['std_msgs/msg/String']
    str_raw = [bytes(store.serialize_cdr(text(data='x' * (k % 37)), 'std_msgs/msg/String'))
               for k in range(t_str.size)]
    writer = Writer(Path(path), version=9, storage_plugin=StoragePlugin.MCAP)
    if compression:
        writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
    with writer:
        if compression == 'lz4':
            from lz4.frame import compress
            writer.storage.compression, writer.storage.compressor = 'lz4', compress
        conns = [writer.add_connection(name, kind, typestore=store) for name, kind in
                 (('/imu', IMU_TYPE), ('/js', JOINT_TYPE), ('/text', 'std_msgs/msg/String'))]
        stamps = [stamps_ns(imu.t), stamps_ns(enc.t), stamps_ns(t_str)]
        rows = [imu_raw, enc_raw, str_raw]
        events = sorted((int(ns), k, i) for k, s in enumerate(stamps) for i, ns in enumerate(s))
        for ns, k, i in events:
            writer.write(conns[k], ns, bytes(rows[k][i]))
    return Path(path)


def _ours_two(path):
    imu, enc = _recordings()
    write_bag(str(path), imu, enc, storage='mcap', imu_topic='/imu', encoder_topic='/js')
    return Path(path)


def _same(a, b):
    assert np.array_equal(a.t.view(np.int64), b.t.view(np.int64))
    assert sorted(a.channels) == sorted(b.channels)
    for k in a.channels:
        assert np.array_equal(a.channels[k].view(np.int64), b.channels[k].view(np.int64)), k


@pytest.fixture
def paths(monkeypatch):
    """Count which candidate source each chunk used."""
    used = {'indexed': 0, 'scanned': 0}
    for name in used:
        original = getattr(mcap_scan._Candidates, name).__func__

        def spy(cls, *args, _name=name, _original=original):
            used[_name] += 1
            return _original(cls, *args)
        monkeypatch.setattr(mcap_scan._Candidates, name, classmethod(spy))
    return used


def _check_both_topics(path, n_imu=N):
    fast = read_imu_bag(path, topic='/imu', quiet=True)
    assert len(fast) == n_imu
    _same(fast, read_imu_bag(path, topic='/imu', quiet=True, fast=False))
    enc = read_encoder_bag(path, topic='/js', quiet=True)
    _same(enc, read_encoder_bag(path, topic='/js', quiet=True, fast=False))
    return fast


@pytest.mark.parametrize('source', ['ours', 'rosbags', 'rosbags-zstd', 'rosbags-lz4'])
def test_mixed_chunks_equal_rosbags_via_index(tmp_path, paths, source):
    path = (_ours_two(tmp_path / 'b') if source == 'ours' else
            _rosbags_three(tmp_path / 'b', None if source == 'rosbags' else source[8:]))
    _check_both_topics(path)
    assert paths['indexed'] >= 2 * 3 and paths['scanned'] == 0  # 3+ chunks, both topics


def _top_records(data):
    """(position, opcode, length) of the data section's records (up to data end)."""
    pos = 8
    while pos + 9 <= len(data):
        op = data[pos]
        (length,) = struct.unpack_from('<Q', data, pos + 1)
        yield pos, op, length
        if op == 0x0F:
            return
        pos += 9 + length


def _mcap_of(bag_dir):
    return next(Path(bag_dir).glob('*.mcap'))


@pytest.mark.parametrize('source', ['ours', 'rosbags-zstd'])
def test_hidden_index_read_by_scan(tmp_path, paths, source):
    """Message index records turned into private records: the summary still lets rosbags in."""
    path = (_ours_two(tmp_path / 'b') if source == 'ours'
            else _rosbags_three(tmp_path / 'b', 'zstd'))
    f = _mcap_of(path)
    data = bytearray(f.read_bytes())
    hidden = [pos for pos, op, _ in _top_records(data) if op == 0x07]
    assert len(hidden) >= 6
    for pos in hidden:
        data[pos] = 0x80  # a private record type, which readers skip
    f.write_bytes(bytes(data))
    _check_both_topics(path)
    assert paths['indexed'] == 0 and paths['scanned'] >= 6


def test_wrong_index_costs_speed_not_messages(tmp_path, paths):
    """Index offsets pointing inside records or past the chunk: the exact walk is unchanged."""
    path = _rosbags_three(tmp_path / 'b')
    f = _mcap_of(path)
    data = bytearray(f.read_bytes())
    rng = np.random.default_rng(5)
    for pos, op, length in _top_records(data):
        if op == 0x07:
            entries = np.frombuffer(data, '<u8', count=(length - 6) // 8, offset=pos + 15)
            wrong = entries.copy()
            wrong[1::2] = rng.integers(0, 2**21, wrong.size // 2)
            data[pos + 15:pos + 9 + length] = wrong.tobytes()
    f.write_bytes(bytes(data))
    _check_both_topics(path)
    assert paths['indexed'] >= 6 and paths['scanned'] >= 3  # each chunk rescanned


def test_cut_inside_an_index_reads_the_whole_chunks(tmp_path, paths):
    """
    A bag cut inside the second message index of a middle chunk (a killed recorder).

    Every Imu message of the chunks up to the cut is read, equal to rosbags' read of the whole
    bag; the last chunk has only one topic's index, so the walk falls back to the scan there.
    """
    full = _ours_two(tmp_path / 'full')
    reference = read_imu_bag(full, topic='/imu', quiet=True, fast=False)
    data = _mcap_of(full).read_bytes()
    records = list(_top_records(data))
    chunks = [k for k, (_, op, _) in enumerate(records) if op == 0x06]
    assert len(chunks) >= 3
    k = chunks[len(chunks) // 2]
    chunk_pos = records[k][0]
    (chunk_end_ns,) = struct.unpack_from('<Q', data, chunk_pos + 9 + 8)
    second_index = records[k + 2]
    assert records[k + 1][1] == 0x07 and second_index[1] == 0x07
    cut = tmp_path / 'cut'
    shutil.copytree(full, cut)
    _mcap_of(cut).write_bytes(data[:second_index[0] + 9 + second_index[2] // 2])
    got = read_imu_bag(cut, topic='/imu', quiet=True)
    n = int(np.count_nonzero(stamps_ns(reference.t) <= chunk_end_ns))
    assert 0 < n < len(reference)
    assert len(got) == n
    _same(got, Recording(reference.t[:n], {c: v[:n] for c, v in reference.channels.items()}))
    assert paths['scanned'] >= 1 and paths['indexed'] >= 2
    assert any('no index' in note or 'ends inside' in note for note in got.notes)
