"""``gyro-char allan``: output files per docs/design.md, and bad input -> exit 2."""
import json

from gyro_char.cli import main
from gyro_char.sim.noise_gen import generate
import numpy as np
import pytest
import yaml

DT = 0.02
TRUTH = {'gyro_x': {'N': 1e-3, 'B': 2e-4, 'Q': 3e-4}, 'gyro_y': {'N': 2e-3, 'K': 5e-5},
         'accel_z': {'N': 4e-3, 'B': 1e-3}}


def _write_csv(path, n=90_000, const=False):
    # The CSV contract of docs/design.md (written here, read by gyro_char's reader).
    rng = np.random.default_rng(1)
    cols = {'t_s': np.arange(n) * DT}
    for name, coeffs in TRUTH.items():
        col = f'{name}_rads' if name.startswith('gyro') else f'{name}_mps2'
        cols[col] = generate(n, DT, rng=rng, **coeffs)
    if const:
        cols['gyro_y_rads'][:] = 0.125
    cols['accel_z_mps2'] += 9.81
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=',',
               header=','.join(cols), comments='', fmt='%.10g')
    return str(path)


@pytest.fixture(scope='module')
def outputs(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('allan')
    csv = _write_csv(tmp / 'static.csv')
    rc = main(['allan', csv, '--out', str(tmp / 'out'), '--boot', '20', '--quiet'])
    assert rc == 0
    return tmp / 'out'


def test_allan_json(outputs):
    data = json.loads((outputs / 'allan.json').read_text())
    assert set(data) == {'channels'} and set(data['channels']) == set(TRUTH)
    for name, ch in data['channels'].items():
        assert set(ch) == {'tau_s', 'adev', 'adev_lo', 'adev_hi', 'adev_fit', 'unit'}
        assert ch['unit'] == ('rad/s' if name.startswith('gyro') else 'm/s^2')
        lo, mid, hi = (np.array(ch[k]) for k in ('adev_lo', 'adev', 'adev_hi'))
        assert len(ch['tau_s']) == len(mid) > 100 and np.all((lo < mid) & (mid < hi))
        # adev_fit: the fitted model at every tau, within a factor 1.5 of the curve where
        # the points are well determined (tau up to a tenth of the record)
        fit = np.array(ch['adev_fit'])
        well = np.array(ch['tau_s']) <= 180.0
        assert fit.shape == mid.shape and np.all(np.abs(np.log(fit / mid))[well] < np.log(1.5))
    # white-noise level at tau = 1 s: N / sqrt(1 s)
    x = data['channels']['gyro_y']
    k = int(np.argmin(np.abs(np.array(x['tau_s']) - 1.0)))
    assert x['adev'][k] * np.sqrt(x['tau_s'][k]) == pytest.approx(2e-3, rel=0.05)


def test_noise_json_and_kalibr_yaml(outputs):
    noise = json.loads((outputs / 'noise.json').read_text())['channels']
    assert set(noise) == set(TRUTH)
    units = {'N': 'rad/s^0.5', 'B': 'rad/s', 'K': 'rad/s^1.5', 'Q': 'rad', 'R': 'rad/s^2'}
    for term, unit in units.items():
        item = noise['gyro_x'][term]
        assert set(item) == {'value', 'unit', 'ci68', 'resolved'} and item['unit'] == unit
        assert (item['ci68'] is None) == (not item['resolved'])
    assert noise['accel_z']['N']['unit'] == 'm/s^1.5'
    assert noise['gyro_x']['N']['value'] == pytest.approx(1e-3, rel=0.05)
    assert noise['gyro_y']['N']['value'] == pytest.approx(2e-3, rel=0.05)
    assert noise['accel_z']['N']['value'] == pytest.approx(4e-3, rel=0.05)
    assert not noise['gyro_x']['R']['resolved']
    imu = yaml.safe_load((outputs / 'imu.yaml').read_text())
    assert imu['update_rate'] == pytest.approx(1 / DT)
    gyros = ('gyro_x', 'gyro_y')
    assert imu['gyroscope_noise_density'] == pytest.approx(
        max(noise[c]['N']['value'] for c in gyros), rel=1e-6)
    assert imu['gyroscope_random_walk'] == pytest.approx(
        max(noise[c]['K']['value'] for c in gyros), rel=1e-6)
    assert imu['accelerometer_noise_density'] == pytest.approx(noise['accel_z']['N']['value'],
                                                               rel=1e-6)
    assert len(imu['gyroscope_noise_density_xyz']) == 2
    assert (outputs / 'allan.png').stat().st_size > 10_000


@pytest.mark.parametrize('case,message', [
    ('missing', 'no such file'),
    ('constant', 'constant'),
    ('short', 'at least'),
    ('channel', 'no channel'),
])
def test_bad_input_exits_2(tmp_path, capsys, case, message):
    args = ['--out', str(tmp_path / 'o'), '--quiet', '--boot', '5']
    if case == 'missing':
        argv = ['allan', str(tmp_path / 'nope.csv')] + args
    elif case == 'constant':
        argv = ['allan', _write_csv(tmp_path / 'c.csv', 3000, const=True)] + args
    elif case == 'short':
        argv = ['allan', _write_csv(tmp_path / 's.csv', 10)] + args
    else:
        argv = ['allan', _write_csv(tmp_path / 'k.csv', 3000), '--channels', 'gyro_q'] + args
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err
