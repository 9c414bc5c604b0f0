"""CSV ingest (docs/design.md) and the shared sanitiser, each case with a real file."""
import gzip
import math

from gyro_char.errors import InputError
from gyro_char.io import read_encoder, read_imu
from gyro_char.io.csv_io import G0
from gyro_char.io.sanitize import segments
import numpy as np
import pytest


def _write(path, header, rows, gz=False):
    text = header + '\n' + '\n'.join(','.join(str(v) for v in r) for r in rows) + '\n'
    if gz:
        with gzip.open(path, 'wt') as fh:
            fh.write(text)
    else:
        path.write_text(text)
    return str(path)


def _rows(n, dt=0.01, gyro=0.1, accel=1.0):
    return [(round(i * dt, 6), gyro, -gyro, 2 * gyro, 0.0, 0.0, accel) for i in range(n)]


def test_units_converted_to_si(tmp_path):
    p = _write(tmp_path / 'a.csv.gz', 't_s,gyro_x_dps,gyro_y_dps,gyro_z_dps,accel_x_g,accel_y_g,'
               'accel_z_g', _rows(100), gz=True)
    rec = read_imu(p)
    assert len(rec) == 100
    np.testing.assert_allclose(rec.channels['gyro_x'], 0.1 * math.pi / 180, rtol=1e-15)
    np.testing.assert_allclose(rec.channels['accel_z'], G0, rtol=1e-15)
    assert rec.notes == []


def test_partial_channels_and_encoder(tmp_path):
    rows = [(i * 0.01, 0.5, 90.0, 7) for i in range(50)]
    p = _write(tmp_path / 'b.csv', 't_s,gyro_z_rads,encoder_deg,extra', rows)
    imu = read_imu(p)
    assert sorted(imu.channels) == ['gyro_z']
    assert any('ignored: extra' in n for n in imu.notes)
    enc = read_encoder(p)
    np.testing.assert_allclose(enc.channels['encoder'], math.pi / 2)


def test_real_adis_record(adis_records):
    rec = read_imu(str(adis_records[0]))
    assert len(rec) == 1_000_000 and abs(rec.dt - 0.01) < 1e-9
    assert sorted(rec.channels) == sorted(['gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y',
                                           'accel_z'])
    # at rest: |accel| is one g
    g = np.median(np.sqrt(sum(rec.channels[f'accel_{a}'] ** 2 for a in 'xyz')))
    assert abs(g - G0) < 0.3


@pytest.mark.parametrize('header,rows,match', [
    ('gyro_x_rads', [(1,)], 'no t_s'),
    ('t_s,foo', [(1, 2)], 'no gyro_'),
    ('t_s,gyro_x_rads', [], 'no data rows'),
    ('t_s,gyro_x_rads', [(0, 1), (1, 'abc')], 'cannot read CSV'),
    ('t_s,gyro_x_rads,gyro_x_dps', [(0, 1, 2)], 'two columns'),
    ('t_s,gyro_x_rads', [(0, 1), (1, 2, 3)], 'cannot read CSV'),
])
def test_bad_csv_one_line_error(tmp_path, header, rows, match):
    p = _write(tmp_path / 'bad.csv', header, rows)
    with pytest.raises(InputError, match=match) as info:
        read_imu(p)
    assert '\n' not in str(info.value)


def test_missing_file_and_corrupt_gzip(tmp_path):
    with pytest.raises(InputError, match='no such file'):
        read_imu(str(tmp_path / 'nope.csv'))
    p = tmp_path / 'c.csv.gz'
    p.write_bytes(gzip.compress(b't_s,gyro_x_rads\n0,1\n1,2\n')[:-12])
    with pytest.raises(InputError, match='cannot read CSV'):
        read_imu(str(p))


def test_sanitiser_counts_every_treatment(tmp_path):
    t = np.arange(4000) * 0.01
    g = np.full(t.size, 0.01)
    t[10], t[11] = t[11], t[10]          # one out-of-order pair
    t = np.insert(t, 20, t[20])          # a duplicate stamp
    g = np.insert(g, 20, 0.01)
    g[30] = np.nan                       # NaN value
    t[40] = np.inf                       # Inf stamp
    t[3000:] += 2.0                      # a 2 s gap
    rows = [(repr(float(a)), repr(float(b))) for a, b in zip(t, g)]
    p = _write(tmp_path / 's.csv', 't_s,gyro_x_rads', rows)
    rec = read_imu(p)
    text = ' | '.join(rec.notes)
    assert '2 sample(s) with NaN/Inf' in text
    assert '1 out-of-order' in text
    assert '1 sample(s) with a repeated stamp' in text
    assert '1 gap(s)' in text
    assert np.all(np.diff(rec.t) > 0) and np.all(np.isfinite(rec.channels['gyro_x']))
    assert len(rec) == t.size - 3
    assert segments(rec) == [(0, 2997), (2997, len(rec))]


def test_rate_change_and_deg_s_warning(tmp_path):
    t = np.concatenate([np.arange(2000) * 0.01, 20.0 + np.arange(2000) * 0.005])
    g = 100.0 * np.sin(t)  # 100 "rad/s" amplitude: really deg/s
    rows = [(repr(float(a)), repr(float(b))) for a, b in zip(t, g)]
    rec = read_imu(_write(tmp_path / 'r.csv', 't_s,gyro_x_rads', rows))
    text = ' | '.join(rec.notes)
    assert 'sample rate changes' in text
    assert 'looks like deg/s' in text


def test_clean_record_has_no_notes(tmp_path):
    t = np.arange(3000) * 0.01
    rows = [(repr(float(a)), 0.01, 9.81) for a in t]
    rec = read_imu(_write(tmp_path / 'ok.csv', 't_s,gyro_x_rads,accel_z_mps2', rows))
    assert rec.notes == []
    assert segments(rec) == [(0, 3000)]
