# Bad input for the swing fit gets a clear one-line reason (InputError / exit 2), never a
# traceback or a silent wrong number; and the `gyro-char swing` command end to end on a CSV.
import json

from gyro_char.cli import main
from gyro_char.errors import InputError
from gyro_char.records import Recording
from gyro_char.swing.filter import estimate_swing
import numpy as np
import pytest
from test_swing_kf import make_run, T, TRUTH


def _with(rec, t=None, **chans):
    c = dict(rec.channels)
    c.update(chans)
    return Recording(rec.t if t is None else t, c, source=rec.source)


@pytest.fixture(scope='module')
def run():
    return make_run(seed=5, duration=12.0)


def _raises(match, imu, enc, **kw):
    with pytest.raises(InputError, match=match):
        estimate_swing(imu, enc, kw.pop('period', T), **kw)


def test_no_encoder_data(run):
    imu, _ = run
    _raises('no encoder data', imu, None)
    _raises('no encoder data', imu, Recording(imu.t, {'other': imu.t}))


def test_no_time_overlap(run):
    imu, enc = run
    _raises('no time overlap', imu, Recording(enc.t + 100.0, enc.channels))


@pytest.mark.parametrize('which', ['imu', 'encoder'])
def test_out_of_order_and_duplicated_stamps(run, which):
    imu, enc = run
    rec = imu if which == 'imu' else enc
    t = rec.t.copy()
    t[10], t[11] = t[11], t[10]
    t[20] = t[19]
    bad = Recording(t, rec.channels)
    args = (bad, enc) if which == 'imu' else (imu, bad)
    _raises(r'not strictly increasing \(1 duplicated, 1 out of order\)', *args)


def test_nan_samples(run):
    imu, enc = run
    y = enc.channels['encoder'].copy()
    y[[5, 50]] = np.nan
    _raises('encoder: 2 NaN/inf samples', imu, _with(enc, encoder=y))


def test_large_gaps(run):
    imu, enc = run
    # An IMU gap is bridged by releasing the gyro angle offset (test_swing_gaps.py), noted.
    keep = (imu.t < imu.t[0] + 4.0) | (imu.t > imu.t[0] + 4.2)
    gappy = Recording(imu.t[keep], {k: v[keep] for k, v in imu.channels.items()})
    notes = estimate_swing(gappy, enc, T).estimates.notes
    assert any(n.startswith('imu: 1 gaps > 3.5 sample intervals (longest 0.20') for n in notes)
    keep = (enc.t < enc.t[0] + 4.0) | (enc.t > enc.t[0] + 5.0)
    _raises('encoder: gap of 1.00', imu,
            Recording(enc.t[keep], {'encoder': enc.channels['encoder'][keep]}))


def test_wrong_axis(run):
    imu, enc = run
    _raises('no swing signal on gyro_y.*the swing shows on gyro_x', imu, enc, axis='y')
    _raises('no gyro_q channel', imu, enc, axis='q')
    # Without --axis, the axis that carries the swing is chosen and the choice is noted.
    est = estimate_swing(imu, enc, T).estimates
    assert any('chosen automatically: gyro_x' in n for n in est.notes)


def test_encoder_without_swing(run):
    imu, enc = run
    still = 1e-3 + 1e-5 * np.random.default_rng(0).standard_normal(len(enc))
    _raises('the encoder shows no swing', imu, _with(enc, encoder=still))


def test_too_short_and_bad_period(run):
    imu, enc = run
    _raises('record too short: 12.0. s .* 1.5 periods', imu, enc, period=8.0)
    _raises('--period must be a positive', imu, enc, period=-1.0)


def test_period_disagreement_warns(run):
    imu, enc = run
    est = estimate_swing(imu, enc, 1.03 * T).estimates
    assert any('WARNING: the dominant period of the encoder angle is 2' in n for n in est.notes)
    assert not any('WARNING' in n for n in estimate_swing(imu, enc, T).estimates.notes)
    # Far off, the model cannot follow the swing at all: refused, with the period it has.
    _raises('no swing at the 2.6 s period .* dominant period is 2', imu, enc, period=2.6)


def _write_csv(path, imu, enc):
    # The CSV contract has one stamp column: put the encoder on the IMU stamps.
    angle = np.interp(imu.t, enc.t, enc.channels['encoder'])
    cols = [imu.t] + [imu.channels[f'gyro_{a}'] for a in 'xyz'] + [angle]
    np.savetxt(path, np.column_stack(cols), delimiter=',', comments='',
               header='t_s,gyro_x_rads,gyro_y_rads,gyro_z_rads,encoder_rad')


def test_cli_writes_contract_json_and_png(tmp_path, capsys):
    imu, enc = make_run(seed=6, duration=30.0, dt_g=0.004, dt_e=0.004, jitter=0.0)
    csv = tmp_path / 'run.csv'
    _write_csv(csv, imu, enc)
    out = tmp_path / 'out'
    assert main(['swing', str(csv), '--period', str(T), '--axis', 'x', '--out', str(out),
                 '--quiet']) == 0
    data = json.loads((out / 'swing.json').read_text())
    assert set(data) == {'scale_factor_error', 'bias', 'bias_drift', 'amplitude_encoder',
                         'amplitude_gyro', 'period_s', 'samples'}
    units = {k: data[k]['unit'] for k in data if isinstance(data[k], dict)}
    assert units == {'scale_factor_error': '1', 'bias': 'rad/s', 'bias_drift': 'rad/s^2',
                     'amplitude_encoder': 'rad', 'amplitude_gyro': 'rad'}
    assert data['period_s'] == T and data['samples'] == 2 * imu.t.size
    sfe = data['scale_factor_error']
    assert abs(sfe['value'] - TRUTH['rho']) < 4 * sfe['sigma']
    assert (out / 'swing.png').stat().st_size > 20_000
    assert 'scale-factor error' in capsys.readouterr().out


def test_cli_bad_input_exit_2(tmp_path, capsys):
    csv = tmp_path / 'imu_only.csv'
    t = np.arange(0, 10, 0.01)
    np.savetxt(csv, np.column_stack([t, np.sin(t)]), delimiter=',', comments='',
               header='t_s,gyro_x_rads')
    assert main(['swing', str(csv), '--period', '2', '--out', str(tmp_path / 'o')]) == 2
    err = capsys.readouterr().err
    assert 'no encoder data' in err and len(err.strip().splitlines()) == 1
