"""
Fuzz the ingest: random byte mutations of small valid bags and of Imu payloads.

Files: every mutated bag either reads (values may change: MCAP from rosbags carries no CRC) or
raises InputError; any other exception fails. Payloads: whatever the vectorised decoder accepts,
rosbags' deserializer must accept too, with the same stamp and values bit for bit.
"""
import shutil

from bag_factory import imu_msg, imu_recording, STORE2
from gyro_char.errors import InputError
from gyro_char.io import read_imu, write_bag
from gyro_char.io.cdr import decode_imu
from gyro_char.records import IMU_CHANNELS
from msg_adapters import imu_sample
import numpy as np
import pytest

CASES = {'mcap': 600, 'sqlite3': 250}
PAYLOAD_CASES = 4000


def _mutate(rng, data: bytes) -> bytes:
    d = bytearray(data)
    kind = rng.integers(0, 5)
    if kind == 0:  # a few random bytes anywhere
        for _ in range(int(rng.integers(1, 9))):
            d[int(rng.integers(0, len(d)))] = int(rng.integers(0, 256))
    elif kind == 1:  # truncation
        d = d[:int(rng.integers(0, len(d)))]
    elif kind == 2:  # a run of garbage
        i = int(rng.integers(0, len(d)))
        n = int(rng.integers(1, 64))
        d[i:i + n] = rng.integers(0, 256, n, dtype=np.uint8).tobytes()
    elif kind == 3:  # bytes near the start or end (headers, footers, summary, sqlite header)
        for _ in range(int(rng.integers(1, 4))):
            i = int(rng.integers(0, min(len(d), 200)))
            d[i if rng.integers(0, 2) else len(d) - 1 - i] = int(rng.integers(0, 256))
    else:  # a length-like field blown up
        i = int(rng.integers(0, max(1, len(d) - 8)))
        d[i:i + 8] = (int(rng.integers(0, 2**63))).to_bytes(8, 'little')
    return bytes(d)


def _mutated(rng, seeds, cases: int, max_edits: int):
    """
    Return ``(payloads, offsets, sizes)``: ``cases`` seed payloads with 1..max_edits edits each.

    An edit is a flipped byte in the first 16 (the header fields), a truncation, trailing zeros
    or a flipped byte anywhere.
    """
    payloads = []
    for _ in range(cases):
        d = bytearray(seeds[int(rng.integers(0, len(seeds)))])
        for _ in range(int(rng.integers(1, max_edits + 1))):
            where = rng.integers(0, 4)
            if where == 0 and len(d) >= 16:
                d[int(rng.integers(0, 16))] = int(rng.integers(0, 256))
            elif where == 1:
                d = d[:int(rng.integers(0, len(d) + 1))]
            elif where == 2:
                d += bytes(int(rng.integers(1, 9)))
            elif len(d):
                d[int(rng.integers(0, len(d)))] = int(rng.integers(0, 256))
        payloads.append(bytes(d))
    sizes = np.array([len(p) for p in payloads], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    return payloads, offsets, sizes


@pytest.mark.parametrize('storage', sorted(CASES))
def test_fuzz_bag_files(tmp_path, storage):
    base = tmp_path / 'base'
    write_bag(str(base), imu_recording(150), storage=storage)
    name = next(p.name for p in base.iterdir() if p.name != 'metadata.yaml')
    original = (base / name).read_bytes()
    work = tmp_path / 'work'
    shutil.copytree(base, work)
    rng = np.random.default_rng(12345 if storage == 'mcap' else 54321)
    outcomes = {'read': 0, 'InputError': 0}
    for _ in range(CASES[storage]):
        for side in work.glob(name + '-*'):  # sqlite journal files from a previous case
            side.unlink()
        (work / name).write_bytes(_mutate(rng, original))
        try:
            read_imu(str(work), quiet=True)
            outcomes['read'] += 1
        except InputError as exc:
            assert '\n' not in str(exc)
            outcomes['InputError'] += 1
    # both outcomes must occur, or the mutations are not exercising anything
    assert outcomes['read'] > 50 and outcomes['InputError'] > 50, outcomes


def test_fuzz_bare_mcap(tmp_path):
    base = tmp_path / 'base'
    write_bag(str(base), imu_recording(100))
    original = (base / 'base.mcap').read_bytes()
    rng = np.random.default_rng(99)
    target = tmp_path / 'x.mcap'
    for _ in range(200):
        target.write_bytes(_mutate(rng, original))
        try:
            read_imu(str(target), quiet=True)
        except InputError:
            pass


def test_fuzz_payloads_match_rosbags():
    rec = imu_recording(40, seed=2)
    rng = np.random.default_rng(2024)
    seeds = []
    for i, t in enumerate(rec.t):
        six = [float(rec.channels[k][i]) for k in IMU_CHANNELS]
        msg = imu_msg(STORE2, t, six, frame_id='f' * int(rng.integers(0, 12)))
        seeds.append(bytes(STORE2.serialize_cdr(msg, 'sensor_msgs/msg/Imu',
                                                little_endian=bool(i % 2))))
    # edits in the first 16 bytes hit the encapsulation header and frame_id length
    payloads, offsets, sizes = _mutated(rng, seeds, PAYLOAD_CASES, 3)
    buf = np.frombuffer(b''.join(payloads) + b'\0', np.uint8)
    accepted = _check_against_rosbags(payloads, offsets, sizes, buf)
    assert accepted > PAYLOAD_CASES // 4


def test_fuzz_uniform_batches_match_rosbags():
    """Equal-size payloads at a constant stride take the strided path; flip bytes in them."""
    rec = imu_recording(30, seed=4)
    rng = np.random.default_rng(77)
    accepted = 0
    for batch in range(150):
        payloads = []
        for i, t in enumerate(rec.t):
            six = [float(rec.channels[k][i]) for k in IMU_CHANNELS]
            d = bytearray(STORE2.serialize_cdr(imu_msg(STORE2, t, six), 'sensor_msgs/msg/Imu',
                                               little_endian=bool(batch % 2)))
            if rng.integers(0, 10) == 0:
                d[int(rng.integers(0, 40))] = int(rng.integers(0, 256))
            payloads.append(bytes(d))
        stride = len(payloads[0]) + 5
        buf = np.frombuffer(b''.join(p + b'gap!!' for p in payloads), np.uint8)
        offsets = np.arange(len(payloads), dtype=np.int64) * stride
        sizes = np.full(len(payloads), len(payloads[0]), dtype=np.int64)
        accepted += _check_against_rosbags(payloads, offsets, sizes, buf)
    assert accepted > 1000


def _check_against_rosbags(payloads, offsets, sizes, buf, decode=decode_imu, deserialize=None):
    """
    Return how many payloads the fast decoder accepted; each must equal rosbags' reading.

    ``decode``/``deserialize`` default to the ROS 2 CDR decoder and rosbags' CDR reader.
    """
    if deserialize is None:
        def deserialize(raw):
            return STORE2.deserialize_cdr(raw, 'sensor_msgs/msg/Imu')
    t, values, ok = decode(buf, offsets, sizes)
    accepted = 0
    for i, raw in enumerate(payloads):
        try:
            stamp, six = imu_sample(deserialize(raw))
        except Exception:  # noqa: B902 - rosbags refusing it is a valid outcome
            assert not ok[i], f'case {i}: fast path accepted what rosbags refuses'
            continue
        if ok[i]:
            accepted += 1
            got = np.array([t[i]] + [values[k][i] for k in IMU_CHANNELS])
            want = np.array([stamp] + list(six))
            assert np.array_equal(got.view(np.int64), want.view(np.int64)), f'case {i}'
    return accepted


def test_fuzz_scalar_blocks_match_rosbags():
    """Flip bytes in JointState blocks: an accepted block equals rosbags, message by message."""
    from bag_factory import joint_msg
    from gyro_char.io.cdr_scalar import decode_scalar, JOINT_STATE
    from msg_adapters import joint_angle
    rng = np.random.default_rng(31)
    accepted = 0
    for batch in range(300):
        t = 1.7e9 + np.arange(20) * 0.01 + batch
        payloads = []
        victim = int(rng.integers(0, 40))  # half of the batches get one flipped byte
        for k in range(20):
            d = bytearray(STORE2.serialize_cdr(
                joint_msg(t[k], ['a', 'stand_joint'], [1.0, 0.1 * k]), JOINT_STATE,
                little_endian=bool(batch % 2)))
            if k == victim:
                d[int(rng.integers(0, len(d)))] = int(rng.integers(0, 256))
            payloads.append(bytes(d))
        size = len(payloads[0])
        buf = np.frombuffer(b''.join(payloads), np.uint8)
        joint = 'stand_joint' if batch % 3 else 1

        def sample(msg, joint=joint):
            return joint_angle(msg, joint)
        got = decode_scalar(buf, np.arange(20, dtype=np.int64) * size, np.full(20, size),
                            JOINT_STATE, joint, STORE2, sample)
        if got is None:
            continue
        accepted += 1
        for k, raw in enumerate(payloads):
            ref = sample(STORE2.deserialize_cdr(raw, JOINT_STATE))
            assert ref is not None
            assert np.array([got[0][k], got[1][k]]).view(np.int64).tolist() == \
                np.array(ref).view(np.int64).tolist()
    assert accepted > 100


def test_fuzz_ros1_payloads_match_rosbags():
    from bag_factory import STORE1
    from gyro_char.io.ros1_imu import decode_imu_ros1
    rec = imu_recording(30, seed=6)
    rng = np.random.default_rng(6)
    seeds = []
    for i, t in enumerate(rec.t):
        msg = imu_msg(STORE1, t, [float(rec.channels[k][i]) for k in IMU_CHANNELS],
                      frame_id='f' * int(rng.integers(0, 10)), ros1=True)
        seeds.append(bytes(STORE1.serialize_ros1(msg, 'sensor_msgs/msg/Imu')))
    # edits in the first 16 bytes hit seq, stamp and frame_id length
    payloads, offsets, sizes = _mutated(rng, seeds, 3000, 2)
    accepted = _check_against_rosbags(
        payloads, offsets, sizes, np.frombuffer(b''.join(payloads), np.uint8),
        decode=decode_imu_ros1,
        deserialize=lambda raw: STORE1.deserialize_ros1(raw, 'sensor_msgs/msg/Imu'))
    assert accepted > 500


def test_fuzz_metadata_yaml(tmp_path):
    write_bag(str(tmp_path / 'b'), imu_recording(100))
    meta = tmp_path / 'b' / 'metadata.yaml'
    original = meta.read_bytes()
    rng = np.random.default_rng(17)
    for _ in range(200):
        meta.write_bytes(_mutate(rng, original))
        try:
            read_imu(str(tmp_path / 'b'), quiet=True)
        except InputError as exc:
            assert '\n' not in str(exc)


@pytest.mark.parametrize('gz', [False, True])
def test_fuzz_csv(tmp_path, gz):
    import gzip
    rows = '\n'.join(f'{i * 0.01:.2f},{0.1 * (i % 7):.2f},-0.30,9.81' for i in range(300))
    text = ('t_s,gyro_x_dps,gyro_y_rads,accel_z_mps2\n' + rows + '\n').encode()
    original = gzip.compress(text) if gz else text
    target = tmp_path / ('x.csv.gz' if gz else 'x.csv')
    rng = np.random.default_rng(5 + gz)
    for _ in range(300):
        target.write_bytes(_mutate(rng, original))
        try:
            read_imu(str(target), quiet=True)
        except InputError as exc:
            assert '\n' not in str(exc)
