"""The fleet's planning parts, without a cluster: inputs, device names, spec, units, table."""
import csv
import math

from gyro_char.cli import main
from gyro_char.errors import InputError
from gyro_char.fleet.inputs import discover, fingerprint
from gyro_char.fleet.run import job_options
from gyro_char.fleet.spec import judge, load_spec
from gyro_char.fleet.table import device_summaries, robust_z, write_csv, write_parquet
from gyro_char.jobs import allan_job
from gyro_char.jobs.base import is_upper_bound
from gyro_char.units import DEG, HUMAN_UNITS, SI_UNITS, to_si
import pyarrow.parquet as pq
import pytest


def _touch(path, text='t_s,gyro_x_rads\n0,0\n'):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_discover_walks_directories_and_keeps_bags_whole(tmp_path):
    _touch(tmp_path / 'line' / 'unit01' / 'static.csv')
    _touch(tmp_path / 'line' / 'unit02' / 'static.csv.gz')
    bag = tmp_path / 'line' / 'unit03_bag'
    _touch(bag / 'metadata.yaml', 'rosbag2_bagfile_information: {}\n')
    _touch(bag / 'unit03_bag_0.mcap', 'x')  # inside a bag: not a device of its own
    _touch(tmp_path / 'line' / 'solo.mcap', 'x')
    _touch(tmp_path / 'line' / 'old.bag', 'x')
    _touch(tmp_path / 'line' / 'notes.txt', 'not a recording')
    devices = discover([str(tmp_path / 'line')], 'allan')
    names = sorted(d.device for d in devices)
    # the two 'static' stems collide: their parent directory tells them apart
    assert names == ['old', 'solo', 'unit01_static', 'unit02_static', 'unit03_bag']
    assert all(d.kind == 'allan' for d in devices)
    assert {d.device: d.path for d in devices}['unit03_bag'] == str(bag)


def test_manifest_names_kinds_and_overrides(tmp_path):
    _touch(tmp_path / 'recs' / 'a.csv')
    _touch(tmp_path / 'recs' / 'b.csv')
    man = _touch(tmp_path / 'fleet.csv', 'device,path,kind,period_s,axis\n'
                                         'IMU 7,recs/a.csv,allan,,\n'
                                         'imu8,recs/b.csv,swing,4.0,z\n')
    devices = discover([str(man)], 'allan')
    assert [d.device for d in devices] == ['IMU_7', 'imu8']
    assert devices[0].path == str(tmp_path / 'recs' / 'a.csv')
    assert devices[1].kind == 'swing' and devices[1].overrides == {'period': 4.0, 'axis': 'z'}
    opts = job_options('swing', '--imu-topic /imu', devices[1].overrides)
    assert opts['period'] == 4.0 and opts['axis'] == 'z' and opts['imu_topic'] == '/imu'


@pytest.mark.parametrize('text,message', [
    ('device,path,kind\nx,a.csv,fft\n', "kind 'fft'"),
    ('device,path,kind,period_s\nx,a.csv,swing,-1\n', 'period_s must be positive'),
    ('device,path,kind,colour\nx,a.csv,allan,red\n', 'unknown manifest column'),
    ('device,path,kind\nx,a.csv,allan\nx,b.csv,allan\n', 'two recordings for device'),
])
def test_bad_manifest_is_input_error(tmp_path, text, message):
    man = _touch(tmp_path / 'm.csv', text)
    with pytest.raises(InputError, match=message):
        discover([str(man)], 'allan')


def test_bad_inputs_and_options(tmp_path):
    with pytest.raises(InputError, match='no such file'):
        discover([str(tmp_path / 'missing')], 'allan')
    (tmp_path / 'empty').mkdir()
    with pytest.raises(InputError, match='no recording found'):
        discover([str(tmp_path / 'empty')], 'allan')
    with pytest.raises(InputError, match='unrecognized arguments: --nope'):
        job_options('allan', '--nope 3')
    with pytest.raises(InputError, match='invalid choice'):
        job_options('allan', '--fit median')
    assert job_options('allan', '--boot 7 --tau-min 0.5')['boot'] == 7
    assert job_options('diagnose', '')['kind'] == 'static'


def test_fingerprint_changes_with_the_file(tmp_path):
    p = _touch(tmp_path / 'a.csv')
    before = fingerprint(str(p))
    p.write_text('t_s,gyro_x_rads\n0,0\n1,1\n')
    assert fingerprint(str(p)) != before and fingerprint(str(p))['size'] == p.stat().st_size


def test_units_follow_the_project_tables():
    for kind, terms in HUMAN_UNITS.items():
        for term, (factor, unit) in terms.items():
            assert to_si(1.0, unit, SI_UNITS[kind][term]) == pytest.approx(factor, rel=1e-12)
    assert to_si(3.5, 'deg/sqrt(h)', 'rad/s^0.5') == pytest.approx(3.5 * DEG / 60, rel=1e-12)
    assert to_si(60, 'ug/sqrt(Hz)', 'm/s^1.5') == pytest.approx(60e-6 * 9.80665, rel=1e-12)
    assert to_si(500, 'ppm', '1') == pytest.approx(5e-4)
    with pytest.raises(ValueError, match='same kind'):
        to_si(1, 'deg/h', 'rad/s^0.5')
    with pytest.raises(ValueError, match='unknown unit'):
        to_si(1, 'furlong/s', 'rad/s')


def _spec(tmp_path, text):
    return load_spec(str(_touch(tmp_path / 'spec.yaml', text)))


def _row(channel, quantity, value, unit, message=''):
    return {'channel': channel, 'quantity': quantity, 'value': value, 'si_unit': unit,
            'message': message}


def test_spec_verdicts_in_the_fields_units(tmp_path):
    spec = _spec(tmp_path, 'gyro: {N: {max: 3.5, unit: deg/sqrt(h)}, B: {max: 60, unit: deg/h}}\n'
                           'gyro_z: {N: {max: 5, unit: deg/sqrt(h)}}\n'
                           'swing: {scale_factor_error: {max_abs: 500, unit: ppm}}\n')
    n = DEG / 60.0  # 1 deg/sqrt(h) in rad/s^0.5
    ok = [_row('gyro_x', 'N', 3.4 * n, 'rad/s^0.5'), _row('gyro_z', 'N', 4.9 * n, 'rad/s^0.5'),
          _row('gyro_x', 'B', 59 * DEG / 3600, 'rad/s'), _row('gyro_z', 'B', 1e-6, 'rad/s')]
    verdict, reasons, passes = judge(spec, 'allan', 'ok', '', ok)
    assert (verdict, reasons, passes) == ('pass', '', [True, True, True, True])
    bad = [dict(ok[0], value=3.6 * n)] + ok[1:]
    verdict, reasons, passes = judge(spec, 'allan', 'ok', '', bad)
    assert verdict == 'fail' and passes[0] is False and 'gyro_x N: 3.6 > max 3.5' in reasons
    # a limit that cannot be checked fails: no B row for gyro_z
    verdict, reasons, _ = judge(spec, 'allan', 'ok', '', ok[:3])
    assert verdict == 'fail' and 'gyro_z B: not measured' in reasons
    sw = [_row('gyro_z', 'scale_factor_error', -6e-4, '1')]
    verdict, reasons, _ = judge(spec, 'swing', 'ok', '', sw)
    assert verdict == 'fail' and '> (abs) max_abs 500 ppm' in reasons
    assert judge(spec, 'allan', 'error', 'corrupt', [])[:2] == ('error', 'corrupt')


@pytest.mark.parametrize('text,message', [
    ('gyro: {N: {max: 3, unit: deg/h}}\n', 'not a unit of the same kind'),
    ('gyro: {X: {max: 3}}\n', 'unknown quantity'),
    ('magnetometer: {N: {max: 3}}\n', 'unknown section'),
    ('gyro: {N: {below: 3}}\n', 'give min, max'),
    ('gyro: [1, 2\n', 'not YAML'),
])
def test_bad_spec_is_input_error(tmp_path, text, message):
    with pytest.raises(InputError, match=message):
        _spec(tmp_path, text)


def test_table_files_and_robust_z(tmp_path):
    rows = [{'device': f'd{i}', 'path': f'/p/{i}', 'kind': 'allan', 'status': 'ok',
             'message': '', 'channel': 'gyro_x', 'quantity': 'N', 'value': v,
             'si_unit': 'rad/s^0.5', 'lo68': v * 0.9, 'hi68': math.nan, 'pass': i != 4}
            for i, v in enumerate([1.0e-3, 1.1e-3, 0.9e-3, 1.05e-3, 9e-3])]
    z = robust_z(rows)
    assert abs(z[4]) > 10 and all(abs(v) < 3.5 for v in z[:4])
    order = device_summaries(rows, z, None)
    assert order[0]['device'] == 'd4' and order[0]['state'] == 'outlier'
    cols = ('device', 'value', 'lo68', 'hi68', 'pass')
    write_csv(str(tmp_path / 't.csv'), rows, cols)
    back = list(csv.DictReader(open(tmp_path / 't.csv')))
    assert [float(r['value']) for r in back] == [r['value'] for r in rows]  # bit for bit
    assert back[0]['hi68'] == '' and back[4]['pass'] == 'false'
    write_parquet(str(tmp_path / 't.parquet'), rows, cols)
    table = pq.read_table(tmp_path / 't.parquet').to_pydict()
    assert table['value'] == [r['value'] for r in rows] and table['pass'][4] is False


def test_bad_usage_exits_2_before_any_work(tmp_path, capsys):
    _touch(tmp_path / 'recs' / 'a.csv')
    (tmp_path / 'bad_spec.yaml').write_text('gyro: {N: {max: 3, unit: furlong}}\n')
    out = tmp_path / 'out'
    for argv, message in (
            ([str(tmp_path / 'missing')], 'no such file or directory'),
            ([str(tmp_path / 'recs'), '--allan-options=--nope 1'], 'unrecognized arguments'),
            ([str(tmp_path / 'recs'), '--spec', str(tmp_path / 'bad_spec.yaml')],
             "unknown unit 'furlong'"),
            ([str(tmp_path / 'recs'), '--workers', '0'], '--workers must be >= 1')):
        assert main(['fleet'] + argv + ['--out', str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith('gyro-char fleet: ') and message in err and len(
            err.strip().splitlines()) == 1, err
    assert not out.exists()  # nothing written, no cluster started


def test_allan_tidy_rows_include_markov_terms():
    term = {'value': 1e-3, 'unit': 'rad/s^0.5', 'ci68': [0.9e-3, 1.1e-3], 'resolved': True}
    bound = dict(term, ci68=None, resolved=False)
    noise = {'gyro_x': {'N': term, 'B': bound, 'K': term, 'Q': bound, 'R': bound,
                        'sensor_filter': {'kind': 'none'},
                        'markov': [{'q': term, 'sigma': term,
                                    'tau_c': {'value': 30.0, 'unit': 's'}}]}}
    rows = {r['quantity']: r for r in allan_job.tidy(noise)}
    assert list(rows) == ['N', 'B', 'K', 'Q', 'R', 'M1_q', 'M1_sigma', 'M1_tau_c']
    assert rows['N']['lo68'] == 0.9e-3 and rows['N']['message'] == ''
    assert is_upper_bound(rows['B']) and rows['B']['lo68'] is None
    assert rows['M1_tau_c']['value'] == 30.0 and rows['M1_tau_c']['si_unit'] == 's'
