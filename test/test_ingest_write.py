"""Vectorised bag writing: bytes identical to rosbags' serializer, readable by rosbags."""
from pathlib import Path
import sqlite3

from bag_factory import header_msg
from gyro_char.errors import InputError
from gyro_char.io import read_encoder, read_imu, write_bag
from gyro_char.io.bag_write import joint_state_encoder, merge_order
from gyro_char.io.cdr import decode_imu, encode_imu, imu_size
from gyro_char.io.typestore import typestore
from gyro_char.records import Recording
from msg_adapters import fill_imu, imu_sample, joint_angle
import numpy as np
import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag2 import Reader

STORE = typestore()
T = STORE.types


def _blank_imu():
    vec = T['geometry_msgs/msg/Vector3']
    return T['sensor_msgs/msg/Imu'](
        header=T['std_msgs/msg/Header'](stamp=T['builtin_interfaces/msg/Time'](sec=0, nanosec=0),
                                        frame_id=''),
        orientation=T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=np.zeros(9), angular_velocity=vec(x=0.0, y=0.0, z=0.0),
        angular_velocity_covariance=np.zeros(9), linear_acceleration=vec(x=0.0, y=0.0, z=0.0),
        linear_acceleration_covariance=np.zeros(9))


def _imu(n, seed=0, t0=1.7e9):
    rng = np.random.default_rng(seed)
    t = t0 + np.arange(n) / 333.0 + rng.uniform(0, 1e-4, n)
    return Recording(t, {k: rng.normal(size=n) for k in
                         ('gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y', 'accel_z')})


@pytest.mark.parametrize('frame_id', ['imu_link', '', 'a', 'abcdefgh', 'frame_ü_9'])
def test_imu_encoding_bit_for_bit(frame_id):
    rec = _imu(300)
    ch = [rec.channels[k] for k in ('gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y', 'accel_z')]
    raw = encode_imu(rec.t, ch[:3], ch[3:], frame_id=frame_id)
    assert raw.shape == (300, imu_size(frame_id))
    for i in range(300):
        msg = fill_imu(_blank_imu(), rec.t[i], [c[i] for c in ch[:3]], [c[i] for c in ch[3:]],
                       frame_id=frame_id)
        assert bytes(STORE.serialize_cdr(msg, 'sensor_msgs/msg/Imu')) == raw[i].tobytes()
    t, values, ok = decode_imu(raw.reshape(-1), np.arange(300) * raw.shape[1],
                               np.full(300, raw.shape[1]))
    # a non-ASCII frame_id is left to rosbags' per-message path (it judges the UTF-8)
    assert ok.all() if frame_id.isascii() else not ok.any()
    for i in range(0, 300 if frame_id.isascii() else 0, 7):
        msg = STORE.deserialize_cdr(raw[i].tobytes(), 'sensor_msgs/msg/Imu')
        stamp, six = imu_sample(msg)
        assert t[i] == stamp
        assert tuple(values[k][i] for k in ('gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y',
                                            'accel_z')) == six


def test_joint_state_encoding_bit_for_bit():
    enc = joint_state_encoder(STORE, 'stand_joint')
    t = 1.7e9 + np.arange(50) * 0.01
    pos = np.sin(t)
    raw = enc(t, pos)
    for i in range(50):
        msg = T['sensor_msgs/msg/JointState'](
            header=header_msg(T, t[i]),
            name=['stand_joint'], position=np.array([pos[i]]), velocity=np.array([], float),
            effort=np.array([], float))
        assert bytes(STORE.serialize_cdr(msg, 'sensor_msgs/msg/JointState')) == raw[i].tobytes()


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_written_bag_reads_back_with_rosbags(tmp_path, storage):
    imu = _imu(5000)
    enc = Recording(imu.t[::2], {'encoder': np.cos(imu.t[::2])})
    path = tmp_path / 'bag'
    write_bag(str(path), imu, enc, storage=storage)
    seen = {'/imu/data_raw': [], '/stand/joint_states': []}
    last = 0
    with AnyReader([Path(path)], default_typestore=STORE) as reader:
        for conn, stamp, raw in reader.messages():
            assert stamp >= last  # chunks written per topic still come back in time order
            last = stamp
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == '/imu/data_raw':
                seen[conn.topic].append(imu_sample(msg)[1][0])
                assert msg.header.frame_id == 'imu_link'
            else:
                seen[conn.topic].append(joint_angle(msg, 'stand_joint')[1])
    assert np.array_equal(seen['/imu/data_raw'], imu.channels['gyro_x'])
    assert np.array_equal(seen['/stand/joint_states'], enc.channels['encoder'])


def test_write_refuses_bad_requests(tmp_path):
    imu = _imu(10)
    with pytest.raises(InputError, match='unknown bag storage'):
        write_bag(str(tmp_path / 'x'), imu, storage='rosbag1')
    (tmp_path / 'exists').mkdir()
    with pytest.raises(InputError, match='exists already'):
        write_bag(str(tmp_path / 'exists'), imu)
    imu.t[3] = np.nan
    with pytest.raises(InputError, match='stamps must be finite'):
        write_bag(str(tmp_path / 'nan'), imu)
    with pytest.raises(InputError, match='no encoder samples'):
        write_bag(str(tmp_path / 'e'), _imu(10), Recording(np.empty(0), {'encoder': []}))


def _log_order(path, storage):
    """(topic, log ns) of every message in the order the file holds them (no sorting)."""
    if storage == 'sqlite3':
        db = next(Path(path).glob('*.db3'))
        with sqlite3.connect(str(db)) as con:
            names = dict(con.execute('SELECT id, name FROM topics'))
            return [(names[c], ns) for c, ns in
                    con.execute('SELECT topic_id, timestamp FROM messages ORDER BY id')]
    with Reader(next(Path(path).glob('*.mcap'))) as reader:  # rosbags' record-by-record scan
        return [(c.topic, ns) for c, ns, _ in reader.storage.messages_scan(reader.connections)]


def _swing_pair(n, seed=0):
    imu = _imu(n, seed)
    enc_t = imu.t[0] + np.arange(int(0.9 * n)) / 300.0 + 1e-4  # other rate, other phase
    return imu, Recording(enc_t, {'encoder': np.sin(enc_t)})


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_topics_written_merged_in_stamp_order(tmp_path, storage):
    imu, enc = _swing_pair(12000)  # ~4.5 MB: several chunks
    write_bag(str(tmp_path / 'b'), imu, enc, storage=storage)
    order = _log_order(tmp_path / 'b', storage)
    ns = np.array([t for _, t in order])
    assert len(order) == len(imu) + len(enc)
    assert np.all(np.diff(ns) >= 0)  # the file itself is in stamp order, not only the index
    topics = np.array([t == '/stand/joint_states' for t, _ in order])
    assert np.array_equal(ns[~topics], np.round(imu.t * 1e9).astype(np.int64))
    assert np.array_equal(ns[topics], np.round(enc.t * 1e9).astype(np.int64))
    assert np.count_nonzero(np.diff(topics.astype(int))) > len(enc)  # interleaved throughout


def test_merge_order_keeps_each_stream_order():
    a = np.array([0, 10, 20, 5, 30])   # goes back once: merged by its running maximum
    b = np.array([10, 15, 25, 40])
    which = merge_order(a, b)
    assert which.tolist() == [0, 0, 1, 1, 0, 0, 1, 0, 1]  # a first at equal stamps
    merged = np.empty(which.size, dtype=int)
    merged[which == 0], merged[which == 1] = a, b
    assert merged.tolist() == [0, 10, 10, 15, 20, 5, 25, 30, 40]
    assert merge_order(a, b[:0]).tolist() == [0] * 5


def test_bag_cut_short_keeps_both_topics_up_to_the_cut(tmp_path):
    # A killed writer or a truncated copy: the MCAP has no summary and ends inside a chunk.
    imu, enc = _swing_pair(12000)
    write_bag(str(tmp_path / 'b'), imu, enc)
    data = next((tmp_path / 'b').glob('*.mcap')).read_bytes()
    for frac in (0.5, 0.8):
        cut = tmp_path / f'cut{frac}'
        cut.mkdir()
        (cut / 'metadata.yaml').write_bytes((tmp_path / 'b' / 'metadata.yaml').read_bytes())
        (cut / 'b.mcap').write_bytes(data[:int(frac * len(data))])
        got_imu, got_enc = read_imu(str(cut), quiet=True), read_encoder(str(cut), quiet=True)
        for got, rec in ((got_imu, imu), (got_enc, enc)):
            k = len(got)
            assert 0.4 * frac * len(rec) < k < len(rec)  # up to the chunk cut through
            assert np.array_equal(got.t, rec.t[:k].round(9))
            assert any('cut short' in n for n in got.notes)
        assert np.array_equal(got_enc.channels['encoder'], enc.channels['encoder'][:len(got_enc)])
        assert abs(got_imu.t[-1] - got_enc.t[-1]) < 1.0  # both topics up to the same time
    # cut inside the first chunk (which holds the channel records): a clear error
    cut = tmp_path / 'early'
    cut.mkdir()
    (cut / 'metadata.yaml').write_bytes((tmp_path / 'b' / 'metadata.yaml').read_bytes())
    (cut / 'b.mcap').write_bytes(data[:len(data) // 20])
    for read in (read_imu, read_encoder):
        with pytest.raises(InputError, match='cannot open bag'):
            read(str(cut), quiet=True)
