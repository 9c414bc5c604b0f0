"""``gyro-char demo`` end to end on short runs (offline path, and the live nodes over DDS)."""
import json
import os

from gyro_char.cli import main
import pytest


def test_demo_offline_tables_beside_truth(tmp_path, capsys):
    out = tmp_path / 'demo'
    assert main(['demo', '--swing-duration', '40', '--static-duration', '200', '--seed', '3',
                 '--quiet', '--out', str(out)]) == 0
    text = capsys.readouterr().out
    assert 'Table 1.' in text and 'Table 2.' in text
    truth = json.loads((out / 'swing' / 'truth.json').read_text())
    est = json.loads((out / 'swing' / 'swing.json').read_text())
    # The printed truth is the simulator's; the estimate is the swing command's own output.
    line = next(s for s in text.splitlines() if s.startswith('scale-factor error'))
    cells = line.split()
    assert float(cells[3]) == pytest.approx(est['scale_factor_error']['value'] * 100, abs=1e-4)
    assert float(cells[5]) == pytest.approx(truth['swing']['scale_factor_error'] * 100,
                                            abs=1e-4)
    # 40 s at 1 kHz still pins the scale-factor error within a few filter sigmas.
    z = (est['scale_factor_error']['value'] - truth['swing']['scale_factor_error']) \
        / est['scale_factor_error']['sigma']
    assert abs(z) < 4
    assert (out / 'swing' / 'swing.png').is_file()
    assert (out / 'static' / 'recording.mcap').is_file()
    if (out / 'static' / 'noise.json').is_file():
        noise = json.loads((out / 'static' / 'noise.json').read_text())
        assert 'gyro_x' in noise['channels']
    assert (out / 'demo.txt').read_text().strip() in text


def test_demo_live_nodes_over_loopback(tmp_path, capsys, monkeypatch):
    pytest.importorskip('rclpy')
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    monkeypatch.setenv('ROS_DOMAIN_ID', '56')
    out = tmp_path / 'live'
    assert main(['demo', '--swing-duration', '20', '--no-static', '--live',
                 '--live-duration', '20', '--quiet', '--out', str(out)]) == 0
    text = capsys.readouterr().out
    assert 'live node: 20 s replayed' in text and 'converged True' in text, text
    assert 'Table 2.' not in text and not (out / 'static').exists()
    line = next(s for s in text.splitlines() if s.startswith('scale-factor error'))
    cells = line.split()
    # Same seed, same data: the live filter agrees with the offline one closely.
    assert float(cells[8]) == pytest.approx(float(cells[3]), abs=0.5 * float(cells[4]))
    assert os.path.getsize(out / 'demo.log') > 0


def test_allan_vs_truth_plot(tmp_path):
    allantools = pytest.importorskip('allantools')
    from gyro_char.bench_sim import simulate_static
    from gyro_char.report.sim import plot_allan_vs_truth
    run = simulate_static('adis16405', duration=300.0, seed=1, channels=['gyro_x', 'gyro_y'])
    channels = {}
    for name in ('gyro_x', 'gyro_y'):
        tau, adev, err, _ = allantools.oadev(run.imu.channels[name], rate=1000 / 3,
                                             data_type='freq', taus='octave')
        channels[name] = {'tau_s': list(tau), 'adev': list(adev), 'adev_lo': list(adev - err),
                          'adev_hi': list(adev + err), 'unit': 'rad/s'}
    path = tmp_path / 'a.png'
    plot_allan_vs_truth({'channels': channels}, run.truth, str(path))
    assert path.stat().st_size > 10_000
