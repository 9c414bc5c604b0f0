"""Bag reading: every format, fast path equal to rosbags bit for bit, topic choice, encoders."""
from pathlib import Path
import shutil

from bag_factory import (imu_msg, imu_recording, joint_msg, STORE2, vector3_msg, write_ros1,
                         write_ros2)
from gyro_char.errors import InputError
from gyro_char.io import read_encoder, read_imu, write_bag
from gyro_char.io.bag_read import read_imu_bag
from gyro_char.io.encoder_read import read_encoder_bag
from gyro_char.records import IMU_CHANNELS, Recording
import numpy as np
import pytest

IMU = 'sensor_msgs/msg/Imu'


def _same(a, b):
    assert np.array_equal(a.t, b.t)
    assert sorted(a.channels) == sorted(b.channels)
    for k in a.channels:
        assert np.array_equal(a.channels[k], b.channels[k]), k


def _expected_t(rec):
    ns = np.round(rec.t * 1e9).astype(np.int64)
    return (ns // 10**9) + (ns % 10**9) * 1e-9


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_own_writer_round_trip(tmp_path, storage):
    rec = imu_recording(3000)
    write_bag(str(tmp_path / 'b'), rec, storage=storage)
    got = read_imu(str(tmp_path / 'b'), quiet=True)
    assert got.notes == []
    assert np.array_equal(got.t, _expected_t(rec))
    for k in IMU_CHANNELS:
        assert np.array_equal(got.channels[k], rec.channels[k])
    _same(read_imu_bag(tmp_path / 'b'), read_imu_bag(tmp_path / 'b', fast=False))


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_fast_path_general_layouts_bit_for_bit(tmp_path, storage):
    """Mixed endianness and frame_id lengths, interleaved with another topic (non-uniform)."""
    rec = imu_recording(600, seed=3)
    rng = np.random.default_rng(3)
    msgs = []
    for i, t in enumerate(rec.t):
        six = [float(rec.channels[k][i]) for k in IMU_CHANNELS]
        frame = 'f' * int(rng.integers(0, 12))
        msgs.append((t, imu_msg(STORE2, t, six, frame_id=frame), bool(rng.integers(0, 2))))
    joints = [(t, joint_msg(t, ['a', 'stand_joint'], [0.0, np.sin(t)]), True) for t in rec.t[::3]]
    path = write_ros2(tmp_path / 'mixed', {'/imu/data_raw': (IMU, msgs),
                                           '/stand/joint_states': ('sensor_msgs/msg/JointState',
                                                                   joints)}, storage)
    fast = read_imu_bag(Path(path))
    _same(fast, read_imu_bag(Path(path), fast=False))
    assert np.array_equal(fast.channels['gyro_y'], rec.channels['gyro_y'])
    enc = read_encoder(path, joint='stand_joint', quiet=True)
    assert np.array_equal(enc.channels['encoder'], np.sin(rec.t[::3]))
    enc1 = read_encoder(path, joint=1, quiet=True)
    assert np.array_equal(enc1.channels['encoder'], enc.channels['encoder'])
    with pytest.raises(InputError, match="joint 'nope' is in none"):
        read_encoder(path, joint='nope')


def test_bare_mcap_db3_and_ros1_bag(tmp_path):
    rec = imu_recording(800, seed=5)
    write_bag(str(tmp_path / 'b'), rec)
    bare = tmp_path / 'copy.mcap'
    shutil.copy(tmp_path / 'b' / 'b.mcap', bare)
    _same(read_imu(str(bare)), read_imu(str(tmp_path / 'b')))
    write_bag(str(tmp_path / 's'), rec, storage='sqlite3')
    _same(read_imu(str(tmp_path / 's' / 's.db3')), read_imu(str(tmp_path / 'b')))
    ros1 = write_ros1(tmp_path / 'r.bag', rec)
    got = read_imu(ros1, quiet=True)
    assert np.array_equal(got.t, _expected_t(rec))
    assert np.array_equal(got.channels['accel_z'], rec.channels['accel_z'])


def test_vector3_stamped_encoder(tmp_path):
    t = 1.7e9 + np.arange(100) * 0.01
    msgs = [(x, vector3_msg(x, 0.5 * k), True) for k, x in enumerate(t)]
    path = write_ros2(tmp_path / 'v', {'/angle': ('geometry_msgs/msg/Vector3Stamped', msgs)})
    enc = read_encoder(path)
    assert np.array_equal(enc.channels['encoder'], 0.5 * np.arange(100))


def _two_imu_topics(tmp_path):
    rec = imu_recording(50)
    msgs = [(t, imu_msg(STORE2, t, [0.1] * 6), True) for t in rec.t]
    return write_ros2(tmp_path / 'two', {'/imu_a': (IMU, msgs), '/imu_b': (IMU, msgs),
                                         '/empty': (IMU, []),
                                         '/js': ('sensor_msgs/msg/JointState', [])})


def test_topic_choice_errors(tmp_path):
    path = _two_imu_topics(tmp_path)
    with pytest.raises(InputError, match=r'several sensor_msgs/Imu topics.*/imu_a \['):
        read_imu(path)
    assert len(read_imu(path, topic='imu_b')) == 50  # leading slash optional
    with pytest.raises(InputError, match=r"no topic '/imu_c'; did you mean /imu_[ab]\? \(topi"):
        read_imu(path, topic='/imu_c')
    with pytest.raises(InputError, match=r"no topic '/zzz'; \(topics: /empty"):
        read_imu(path, topic='/zzz')
    with pytest.raises(InputError, match='carries sensor_msgs/msg/JointState, not'):
        read_imu(path, topic='/js')
    with pytest.raises(InputError, match='has no messages'):
        read_imu(path, topic='/empty')
    with pytest.raises(InputError, match='topic /js has no messages'):
        read_encoder(path)  # the only encoder-type topic is empty
    with pytest.raises(InputError, match='carries sensor_msgs/msg/Imu'):
        read_encoder(path, topic='/imu_a')


def test_not_a_bag(tmp_path):
    (tmp_path / 'd').mkdir()
    with pytest.raises(InputError, match='without metadata.yaml'):
        read_imu(str(tmp_path / 'd'))
    (tmp_path / 'x.txt').write_text('hello')
    with pytest.raises(InputError, match='unknown input type'):
        read_imu(str(tmp_path / 'x.txt'))


def _same_encoder(path, **kw):
    fast = read_encoder_bag(Path(path), quiet=True, **kw)
    slow = read_encoder_bag(Path(path), quiet=True, fast=False, **kw)
    assert np.array_equal(fast.t, slow.t)
    assert np.array_equal(fast.channels['encoder'], slow.channels['encoder'], equal_nan=True)
    assert fast.notes == slow.notes
    return fast


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_encoder_fast_path_equals_rosbags(tmp_path, storage):
    rec = imu_recording(400, seed=8)
    enc = Recording(rec.t, {'encoder': np.sin(rec.t)})
    write_bag(str(tmp_path / 'w'), rec, enc, storage=storage)
    got = _same_encoder(tmp_path / 'w', joint='stand_joint')
    assert np.array_equal(got.channels['encoder'], enc.channels['encoder'])
    _same_encoder(tmp_path / 'w', joint=0)
    # joints in varying order and sometimes absent: per-message path, missing ones counted
    rng = np.random.default_rng(8)
    msgs = []
    for k, t in enumerate(rec.t):
        names = [['stand_joint', 'b'], ['b', 'stand_joint'], ['b']][int(rng.integers(0, 3))]
        msgs.append((t, joint_msg(t, names, [0.25 * k if n == 'stand_joint' else -1.0
                                             for n in names]), bool(rng.integers(0, 2))))
    vec = [(t, vector3_msg(t, t - rec.t[0]), True) for t in rec.t]
    path = write_ros2(tmp_path / 'm', {'/js': ('sensor_msgs/msg/JointState', msgs),
                                       '/v': ('geometry_msgs/msg/Vector3Stamped', vec)},
                      storage)
    got = _same_encoder(path, topic='/js', joint='stand_joint')
    assert any('without joint' in n for n in got.notes)
    _same_encoder(path, topic='/js', joint=1)
    v = _same_encoder(path, topic='/v')
    assert np.array_equal(v.channels['encoder'], rec.t - rec.t[0])


@pytest.mark.parametrize('storage,compression', [('mcap', 'storage'), ('mcap', 'file'),
                                                 ('mcap', 'message'), ('sqlite3', 'file'),
                                                 ('sqlite3', 'message')])
def test_compressed_bags(tmp_path, storage, compression):
    """Chunk-compressed (zstd) MCAP takes the fast path; file and message compression: rosbags."""
    rec = imu_recording(500, seed=9)
    msgs = [(t, imu_msg(STORE2, t, [float(rec.channels[k][i]) for k in IMU_CHANNELS]), True)
            for i, t in enumerate(rec.t)]
    path = write_ros2(tmp_path / 'c', {'/imu': (IMU, msgs)}, storage, compression)
    fast = read_imu_bag(Path(path))
    _same(fast, read_imu_bag(Path(path), fast=False))
    assert np.array_equal(fast.channels['accel_x'], rec.channels['accel_x'])


def _malformed_joint_bag(path, storage):
    """Write a JointState topic of good, NaN, empty, nameless, truncated, foreign payloads."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    t0 = 1.7e9
    good = [joint_msg(t0 + k, ['stand_joint'], [0.1 * k]) for k in range(6)]
    payloads = [bytes(STORE2.serialize_cdr(m, 'sensor_msgs/msg/JointState')) for m in good]
    odd = {
        'nan': [joint_msg(t0 + 10, ['stand_joint'], [np.nan])],
        'missing': [joint_msg(t0 + 11, [], []), joint_msg(t0 + 12, ['other'], [1.0]),
                    joint_msg(t0 + 13, ['stand_joint'], [])],  # a name without a position
        'bad': [payloads[0][:len(payloads[0]) // 2], b'\x00\x01\x00\x00\xff'],
    }
    raws = payloads[:3] + [bytes(STORE2.serialize_cdr(m, 'sensor_msgs/msg/JointState'))
                           for m in odd['nan'] + odd['missing']] + odd['bad'] + payloads[3:]
    # a Vector3Stamped payload on the JointState topic: judged the same way by both paths
    raws.append(bytes(STORE2.serialize_cdr(vector3_msg(t0 + 20, 1.0),
                                           'geometry_msgs/msg/Vector3Stamped')))
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(Path(path), version=9, storage_plugin=plugin) as writer:
        conn = writer.add_connection('/js', 'sensor_msgs/msg/JointState', typestore=STORE2)
        for k, raw in enumerate(raws):
            writer.write(conn, int(t0 * 1e9) + k, raw)
    return len(raws)


@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_malformed_joint_states_counted_alike_by_both_paths(tmp_path, storage):
    n = _malformed_joint_bag(tmp_path / 'm', storage)
    good = 0.1 * np.arange(6)
    # by index, the joint named 'other' is joint 0 of its message
    for joint, want in (('stand_joint', good), (0, np.insert(good, 3, 1.0))):
        got = _same_encoder(tmp_path / 'm', joint=joint)  # fast path == rosbags path, notes too
        values = got.channels['encoder']
        assert np.array_equal(values[~np.isnan(values)], want)
        assert np.isnan(values).sum() == 1  # a NaN position is a reading, left to sanitize
        counts = {k: int(next((n.split()[0] for n in got.notes if word in n), 0))
                  for k, word in (('bad', 'undecodable'), ('missing', 'without joint'))}
        assert counts['bad'] >= 2 and counts['bad'] + counts['missing'] + len(got) == n
    clean = read_encoder(str(tmp_path / 'm'), joint='stand_joint', quiet=True)  # sanitised
    assert np.array_equal(clean.channels['encoder'], good)


def test_one_rule_for_malformed_messages():
    from types import SimpleNamespace as Ns

    from gyro_char.io.encoder_read import _Samples
    from msg_adapters import joint_angle
    stamp = Ns(sec=5, nanosec=0)

    def js(**kw):
        fields = {'header': Ns(stamp=stamp), 'name': ['j'], 'position': [0.5]}
        fields.update(kw)
        return Ns(**fields)
    for joint in ('j', 0):
        out = _Samples(lambda m: joint_angle(m, joint))
        wrong = [js(position=None), js(position=['abc']), js(position=[[1.0, 2.0]]),
                 js(header=None), js(header=Ns(stamp=Ns(sec='x', nanosec=0))),
                 js(header=Ns(stamp=Ns(sec=np.array([1, 2]), nanosec=0))),
                 js(header=Ns(stamp=Ns(sec=np.inf, nanosec=0)))]
        if joint == 'j':
            wrong.append(js(name=5))
        for msg in wrong + [None]:
            out.take(msg)
        out.take(b'\x00', lambda raw: STORE2.deserialize_cdr(raw, 'sensor_msgs/msg/JointState'))
        assert out.bad == len(wrong) + 2
        for msg in (js(name=[], position=[]), js(position=[])):
            out.take(msg)
        assert out.missing == 2
        out.take(js(position=[np.nan]))
        out.take(js())
        out.flush()
        assert np.array_equal(np.concatenate(out.ts), [5.0, 5.0])
        assert np.isnan(out.vs[0][0]) and out.vs[0][1] == 0.5
