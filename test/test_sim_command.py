"""``gyro-char simulate``: a real ROS 2 bag + truth.json, reproducible by seed."""
import json

from gyro_char.cli import main
from gyro_char.io import read_encoder, read_imu
from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_swing
import numpy as np
import pytest

TRUTH_KEYS = {'kind', 'channels', 'swing', 'effects', 'preset', 'seed'}


def test_swing_bag_round_trip_and_truth(tmp_path):
    out = tmp_path / 'a'
    assert main(['simulate', 'swing', '--duration', '4', '--seed', '2', '--quiet',
                 '--effect', 'time_delay:delay_s=0.0015', '--out', str(out)]) == 0
    truth = json.loads((out / 'truth.json').read_text())
    assert set(truth) == TRUTH_KEYS
    assert truth['kind'] == 'swing' and truth['seed'] == 2 and truth['preset'] == 'adis16405'
    assert truth['effects'] == [{'name': 'time_delay', 'params': {'delay_s': 0.0015}}]
    assert set(truth['swing']) == {'scale_factor_error', 'bias', 'bias_drift', 'period_s',
                                   'amplitude'}
    for terms in truth['channels'].values():
        assert set(terms) == {'N', 'B', 'K', 'Q', 'R'}
    imu = read_imu(str(out / 'recording.mcap'), quiet=True)
    enc = read_encoder(str(out / 'recording.mcap'), quiet=True)
    run = simulate_swing(load(), duration=4.0, seed=2, effects=['time_delay:delay_s=0.0015'])
    # Stamps go through integer nanoseconds; values are float64 bit for bit.
    assert np.allclose(imu.t, run.imu.t, atol=1e-9, rtol=0)
    assert np.allclose(enc.t, run.encoder.t, atol=1e-9, rtol=0)
    for name, values in run.imu.channels.items():
        assert np.array_equal(imu.channels[name], values), name
    assert np.array_equal(enc.channels['encoder'], run.encoder.channels['encoder'])


def test_same_seed_same_bytes_other_seed_differs(tmp_path):
    def make(name, seed):
        assert main(['simulate', 'static', '--duration', '3', '--seed', str(seed), '--quiet',
                     '--out', str(tmp_path / name)]) == 0
        return (tmp_path / name / 'recording.mcap').read_bytes()
    first = make('a', 7)
    assert make('b', 7) == first
    assert make('c', 8) != first
    # An existing record is not overwritten unless asked.
    assert main(['simulate', 'static', '--duration', '3', '--quiet',
                 '--out', str(tmp_path / 'a')]) == 2
    assert main(['simulate', 'static', '--duration', '3', '--seed', '8', '--quiet',
                 '--overwrite', '--out', str(tmp_path / 'a')]) == 0
    assert (tmp_path / 'a' / 'recording.mcap').read_bytes() == make('d', 8)


def test_config_yaml_and_sqlite3(tmp_path):
    cfg = tmp_path / 'bench.yaml'
    cfg.write_text('preset: vg910\nstand: {period_s: 3.0}\ngyro: {rate_hz: 200.0}\n')
    out = tmp_path / 'o'
    assert main(['simulate', 'swing', '--config', str(cfg), '--duration', '2', '--quiet',
                 '--storage', 'sqlite3', '--out', str(out)]) == 0
    truth = json.loads((out / 'truth.json').read_text())
    assert truth['preset'] == 'vg910' and truth['swing']['period_s'] == 3.0
    imu = read_imu(str(out / 'recording'), quiet=True)
    assert len(imu) == 400


@pytest.mark.parametrize('argv,message', [
    (['--effect', 'no_such_effect'], 'unknown effect'),
    (['--effect', 'time_delay:delay=1'], 'unknown parameter'),
    (['--duration', '-1'], 'duration'),
    (['--config', '/nonexistent.yaml'], 'cannot read config'),
])
def test_bad_input_exits_2(tmp_path, capsys, argv, message):
    assert main(['simulate', 'swing', '--quiet', '--out', str(tmp_path / 'x')] + argv) == 2
    assert message in capsys.readouterr().err


def test_unknown_config_key_is_refused(tmp_path, capsys):
    cfg = tmp_path / 'bad.yaml'
    cfg.write_text('stand: {amplitud: 0.1}\n')
    assert main(['simulate', 'static', '--config', str(cfg), '--out', str(tmp_path)]) == 2
    assert "unknown key 'amplitud'" in capsys.readouterr().err
