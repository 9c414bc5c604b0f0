"""Damaged and awkward inputs, each as a real file: one-line InputError or a counted note."""
import os
from pathlib import Path
import shutil

from bag_factory import imu_msg, imu_recording, STORE2, write_ros2
from gyro_char import cli
from gyro_char.errors import InputError
from gyro_char.io import read_imu, write_bag
from gyro_char.records import IMU_CHANNELS, Recording
import numpy as np
import pytest


def _bag_file(path):
    return next(p for p in Path(path).iterdir() if p.name != 'metadata.yaml')


def _damaged(tmp_path, storage, how):
    base = tmp_path / storage
    write_bag(str(base), imu_recording(20000), storage=storage)
    dst = tmp_path / f'{storage}_{how}'
    shutil.copytree(base, dst)
    f = _bag_file(dst)
    data = bytearray(f.read_bytes())
    if how == 'truncated':
        data = data[:int(len(data) * 0.6)]
    else:  # a 4 KiB run of garbage in the middle: a corrupt sqlite page / mcap chunk
        rng = np.random.default_rng(7)
        i = len(data) // 2
        data[i:i + 4096] = rng.integers(0, 256, 4096, dtype=np.uint8).tobytes()
    f.write_bytes(bytes(data))
    return str(dst)


@pytest.mark.parametrize('storage,how', [('mcap', 'garbage'), ('sqlite3', 'garbage'),
                                         ('sqlite3', 'truncated')])
def test_damaged_bag_one_line_error(tmp_path, storage, how):
    path = _damaged(tmp_path, storage, how)
    with pytest.raises(InputError) as info:
        read_imu(path, quiet=True)
    assert '\n' not in str(info.value) and path in str(info.value)


def test_truncated_mcap_is_read_up_to_the_cut(tmp_path):
    """A recording killed mid-write has no summary: read what is there, and say so."""
    rec = imu_recording(20000)
    write_bag(str(tmp_path / 'b'), rec)
    f = _bag_file(tmp_path / 'b')
    data = f.read_bytes()
    f.write_bytes(data[:int(len(data) * 0.6)])
    got = read_imu(str(tmp_path / 'b'))
    assert 10000 < len(got) < 12000
    assert np.array_equal(got.channels['gyro_x'], rec.channels['gyro_x'][:len(got)])
    assert any('has no index' in n for n in got.notes)
    assert any('ends inside a record at byte' in n for n in got.notes)
    f.write_bytes(data[:1000])  # cut before any message
    with pytest.raises(InputError):
        read_imu(str(tmp_path / 'b'))


def test_cli_exit_code_2_one_line(tmp_path, capsys):
    path = _damaged(tmp_path, 'mcap', 'garbage')
    code = cli.main(['swing', path, '--period', '2', '--out', str(tmp_path / 'o'), '--quiet'])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert len(err.splitlines()) == 1 and 'corrupt MCAP chunk' in err


def test_undecodable_messages_are_counted(tmp_path):
    rec = imu_recording(300)
    msgs = [(t, imu_msg(STORE2, t, [float(rec.channels[k][i]) for k in IMU_CHANNELS]), True)
            for i, t in enumerate(rec.t)]
    path = write_ros2(tmp_path / 'b', {'/imu': ('sensor_msgs/msg/Imu', msgs)}, 'sqlite3')
    import sqlite3
    con = sqlite3.connect(str(_bag_file(path)))
    con.execute('UPDATE messages SET data = substr(data, 1, 100) WHERE id % 50 = 0')
    con.commit()
    con.close()
    got = read_imu(path)
    assert '6 undecodable message(s) on /imu dropped' in got.notes
    assert len(got) == 294


def test_zero_messages_and_all_nan(tmp_path):
    path = write_ros2(tmp_path / 'z', {'/imu': ('sensor_msgs/msg/Imu', [])})
    with pytest.raises(InputError, match='has no messages'):
        read_imu(path)
    rec = imu_recording(100)
    nan = Recording(rec.t, {k: np.full(100, np.nan) for k in IMU_CHANNELS})
    write_bag(str(tmp_path / 'nan'), nan)
    with pytest.raises(InputError, match='every IMU channel on /imu/data_raw is NaN'):
        read_imu(str(tmp_path / 'nan'))


def test_stamp_and_value_treatments_through_a_bag(tmp_path):
    n = 6000
    t = 1.7e9 + np.arange(n) * 0.003
    t[3000:] += 1.0                                   # a long gap
    t[4500:] = t[4500] + (np.arange(n - 4500)) * 0.006  # the rate halves
    rng = np.random.default_rng(1)
    ch = {k: rng.normal(scale=0.01, size=n) for k in IMU_CHANNELS}
    ch['accel_z'] += 9.81
    ch['gyro_x'][100] = np.nan
    ch['gyro_y'][200] = np.inf
    order = np.arange(n)
    order[[10, 11]] = order[[11, 10]]                 # out of order in the file
    t_file = np.concatenate([t[order], t[[500, 501]]])  # and two repeated stamps
    ch_file = {k: np.concatenate([v[order], v[[500, 501]]]) for k, v in ch.items()}
    write_bag(str(tmp_path / 'b'), Recording(t_file, ch_file))
    got = read_imu(str(tmp_path / 'b'))
    text = ' | '.join(got.notes)
    for expect in ('2 sample(s) with NaN/Inf', 'out-of-order stamp(s)',
                   '2 sample(s) with a repeated stamp', '1 gap(s) longer',
                   'sample rate changes'):
        assert expect in text, (expect, text)
    assert len(got) == n - 2 and np.all(np.diff(got.t) > 0)


def test_deg_s_in_rad_s_warning(tmp_path):
    rec = imu_recording(3000)
    rec.channels['gyro_z'] = 90.0 * np.sin(np.arange(3000) * 0.01)  # deg/s written as rad/s
    write_bag(str(tmp_path / 'b'), rec)
    got = read_imu(str(tmp_path / 'b'))
    assert any('gyro_z' in n and 'looks like deg/s' in n for n in got.notes)
    assert np.array_equal(got.channels['gyro_z'], rec.channels['gyro_z'])  # warned, not changed


def test_unreadable_file(tmp_path):
    p = tmp_path / 'x.mcap'
    p.write_bytes(os.urandom(100))
    with pytest.raises(InputError, match='cannot open bag'):
        read_imu(str(p))


def test_mcap_chunk_crc_checked_when_present(tmp_path):
    import struct
    import zlib
    write_bag(str(tmp_path / 'b'), imu_recording(2000))
    f = _bag_file(tmp_path / 'b')
    data = bytearray(f.read_bytes())
    pos = 8
    while data[pos] != 0x06:  # first chunk record
        pos += 9 + struct.unpack_from('<Q', data, pos + 1)[0]
    start = pos + 9
    usize = struct.unpack_from('<Q', data, start + 16)[0]
    records = start + 40  # no compression: empty compression string
    struct.pack_into('<I', data, start + 24, zlib.crc32(data[records:records + usize]))
    f.write_bytes(bytes(data))
    assert len(read_imu(str(tmp_path / 'b'))) == 2000  # a correct CRC passes
    data[records + usize - 100] ^= 0xFF  # one payload byte of the chunk's last message
    f.write_bytes(bytes(data))
    with pytest.raises(InputError, match='CRC mismatch'):
        read_imu(str(tmp_path / 'b'))
