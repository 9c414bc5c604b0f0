"""
``gyro-char fleet`` on a real LocalCluster of worker processes.

A simulated fleet with varied N and B, one corrupt and one too-short file and a spec: each
device's files equal the single command's bit for bit, the bad files are error rows, the
out-of-spec unit fails, a re-run takes finished devices from the cache, and report.html renders
in headless Chromium.
"""
import csv
from html.parser import HTMLParser
import json
import os
import shutil
import subprocess

from fleet_factory import static_recording, write_csv, write_mcap_file
from gyro_char.cli import main
from gyro_char.io import write_bag
import pyarrow.parquet as pq
import pytest

DURATION = 300.0
# device -> (N deg/sqrt(h), B deg/h, format); u4's N breaks the spec's 3.5 deg/sqrt(h)
UNITS = {'u1': (2.0, 10.0, 'csv'), 'u2': (2.5, 20.0, 'bag'), 'u3': (3.0, 40.0, 'csv.gz'),
         'u4': (5.0, 15.0, 'mcap')}
SPEC = 'gyro: {N: {max: 3.5, unit: deg/sqrt(h)}, B: {max: 200, unit: deg/h}}\n'
OPTIONS = ['--boot', '20']
FILES = ('allan.json', 'noise.json', 'imu.yaml', 'allan.png')


@pytest.fixture(scope='module')
def fleet(tmp_path_factory):
    tmp = tmp_path_factory.mktemp('fleet')
    data = tmp / 'line'
    data.mkdir()
    paths = {}
    for i, (name, (n, b, fmt)) in enumerate(UNITS.items()):
        rec = static_recording(n, b, seed=10 + i, duration=DURATION)
        if fmt == 'bag':
            write_bag(str(data / name), rec)
            paths[name] = str(data / name)
        elif fmt == 'mcap':
            paths[name] = write_mcap_file(data / f'{name}.mcap', rec, tmp / 'scratch_bag')
        else:
            paths[name] = write_csv(data / f'{name}.{fmt}', rec, compress=fmt == 'csv.gz')
    (data / 'corrupt.mcap').write_bytes(os.urandom(4096))
    (data / 'short.csv').write_text('t_s,gyro_x_rads\n0,0.001\n0.02,0.002\n0.04,-0.001\n')
    (tmp / 'spec.yaml').write_text(SPEC)
    out = tmp / 'out'
    argv = ['fleet', str(data), '--out', str(out), '--workers', '2', '--spec',
            str(tmp / 'spec.yaml'), '--allan-options=' + ' '.join(OPTIONS), '--quiet']
    rc = main(argv)
    return {'tmp': tmp, 'out': out, 'paths': paths, 'argv': argv, 'rc': rc}


def _rows(path):
    with open(path, newline='') as fh:
        return list(csv.DictReader(fh))


def test_exit_code_and_error_rows(fleet):
    assert fleet['rc'] == 3  # finished, with devices in error
    rows = _rows(fleet['out'] / 'fleet.csv')
    assert list(rows[0]) == ['device', 'path', 'kind', 'status', 'message', 'channel',
                             'quantity', 'value', 'si_unit', 'lo68', 'hi68', 'pass']
    bad = {r['device']: r for r in rows if r['status'] == 'error'}
    assert set(bad) == {'corrupt', 'short'}
    assert sum(r['device'] in bad for r in rows) == 2  # one row per failed recording
    for r in bad.values():
        assert r['message'] and not r['message'].startswith('internal error'), r['message']
        assert r['value'] == '' and r['pass'] == 'false'
    assert {r['device'] for r in rows if r['status'] == 'ok'} == set(UNITS)


def test_devices_equal_the_single_command_bit_for_bit(fleet, tmp_path):
    rows = _rows(fleet['out'] / 'fleet.csv')
    for name, path in fleet['paths'].items():
        single = tmp_path / name
        assert main(['allan', path, '--out', str(single), '--quiet'] + OPTIONS) == 0
        mine = fleet['out'] / 'devices' / name
        for f in FILES:
            assert (mine / f).read_bytes() == (single / f).read_bytes(), (name, f)
        noise = json.loads((single / 'noise.json').read_text())['channels']
        got = {(r['channel'], r['quantity']): r for r in rows if r['device'] == name}
        assert len(got) == 5 * len(noise)  # N, B, K, Q, R of every channel
        for ch, fields in noise.items():
            for term in ('N', 'B', 'K', 'Q', 'R'):
                t = fields[term]
                r = got[(ch, term)]
                assert float(r['value']) == t['value'] and r['si_unit'] == t['unit']
                if t['ci68'] is not None:
                    assert [float(r['lo68']), float(r['hi68'])] == t['ci68']
                assert ('upper bound' in r['message']) == (not t['resolved'])
    table = pq.read_table(fleet['out'] / 'fleet.parquet').to_pydict()
    assert table['device'] == [r['device'] for r in rows]
    expected = [float(r['value']) for r in rows if r['value']]
    assert [v for v in table['value'] if v == v] == expected


def test_values_follow_the_simulated_truth(fleet):
    rows = _rows(fleet['out'] / 'fleet.csv')
    n_si = {r['device']: float(r['value']) for r in rows
            if r['channel'] == 'gyro_x' and r['quantity'] == 'N'}
    for name, (n, _, _) in UNITS.items():
        assert n_si[name] * 60 / 0.017453292519943295 == pytest.approx(n, rel=0.1)


def test_spec_verdicts(fleet):
    verdicts = {r['device']: r for r in _rows(fleet['out'] / 'verdicts.csv')}
    assert {d: v['verdict'] for d, v in verdicts.items()} == {
        'u1': 'pass', 'u2': 'pass', 'u3': 'pass', 'u4': 'fail', 'corrupt': 'error',
        'short': 'error'}
    assert 'gyro_x N' in verdicts['u4']['reasons'] and 'max 3.5 deg/sqrt(h)' in \
        verdicts['u4']['reasons']
    rows = _rows(fleet['out'] / 'fleet.csv')
    n_rows = [r for r in rows if r['device'] == 'u4' and r['quantity'] == 'N']
    assert n_rows and all(r['pass'] == 'false' for r in n_rows)
    assert all(r['pass'] == '' for r in rows if r['quantity'] in ('K', 'Q', 'R'))


def test_rerun_takes_finished_devices_from_the_cache(fleet, capsys):
    out = fleet['out']
    stamps = {d: (out / 'devices' / d).stat().st_mtime_ns for d in UNITS}
    before = (out / 'fleet.csv').read_bytes()
    capsys.readouterr()
    assert main(fleet['argv']) == 3
    assert '(6 from the cache)' in capsys.readouterr().out
    assert {d: (out / 'devices' / d).stat().st_mtime_ns for d in UNITS} == stamps
    assert (out / 'fleet.csv').read_bytes() == before
    # a changed input is recomputed, and only it (one worker is enough for one device)
    os.utime(fleet['paths']['u1'], ns=(1, 1))
    argv = list(fleet['argv'])
    argv[argv.index('--workers') + 1] = '1'
    assert main(argv) == 3
    assert '(5 from the cache)' in capsys.readouterr().out
    assert (out / 'devices' / 'u2').stat().st_mtime_ns == stamps['u2']
    assert (out / 'fleet.csv').read_bytes() == before


class _Dom(HTMLParser):
    """Device rows of the report's table, and the body's attributes."""

    def __init__(self):
        super().__init__()
        self.states, self.body, self.images = [], {}, 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == 'tr' and 'data-state' in a:
            self.states.append((a['data-device'], a['data-state']))
        elif tag == 'body':
            self.body = a
        elif tag == 'img':
            self.images += 1


def _chromium():
    exe = shutil.which('chromium') or shutil.which('chromium-browser')
    if exe is None:
        pytest.skip('headless Chromium not installed (Debian package chromium; .ci/run '
                    'installs it with apt-get where it can)')
    return exe


def _render(exe, page, tmp_path, *extra):
    cmd = [exe, '--headless', '--no-sandbox', '--disable-gpu', '--no-first-run',
           f'--user-data-dir={tmp_path / "profile"}', '--enable-logging=stderr', '--v=0',
           '--virtual-time-budget=5000'] + list(extra) + [page.as_uri()]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=120)


def _console(stderr):
    return [line for line in stderr.splitlines() if ':CONSOLE' in line]


def test_report_renders_in_headless_chromium(fleet, tmp_path):
    exe = _chromium()
    # the console check must be able to fail: a page with a script error is caught
    broken = tmp_path / 'broken.html'
    broken.write_text('<!DOCTYPE html><html><body><script>notDefined();</script></body></html>')
    assert any('notDefined' in line for line in _console(_render(exe, broken, tmp_path).stderr))
    page = fleet['out'] / 'report.html'
    run = _render(exe, page, tmp_path, '--dump-dom')
    assert run.returncode == 0, run.stderr[-2000:]
    assert _console(run.stderr) == []
    dom = _Dom()
    dom.feed(run.stdout)
    states = [s for _, s in dom.states]
    assert dom.states[0] == ('u4', 'fail')  # failing devices first, then errors
    assert states[1:3] == ['error', 'error'] and states.count('pass') + \
        states.count('outlier') == 3
    assert dom.body.get('data-images-loaded') == 'all'  # set by the page once all loaded
    assert int(dom.body['data-images']) == dom.images >= 5
    shot = tmp_path / 'report.png'
    run = _render(exe, page, tmp_path, '--hide-scrollbars', '--window-size=1280,2000',
                  f'--screenshot={shot}')
    assert run.returncode == 0 and shot.stat().st_size > 20_000
    print(f'screenshot: {shot}')
