"""Bench simulator API: presets, YAML overrides, reproducibility, truth contract, bad input."""
import math

from gyro_char.errors import InputError
from gyro_char.sim.config import BenchConfig, load
from gyro_char.sim.presets import PRESETS
from gyro_char.sim.simulator import simulate_static, simulate_swing
import numpy as np
import pytest


@pytest.mark.parametrize('name', sorted(PRESETS))
def test_presets_build_and_run(name):
    cfg = BenchConfig.from_preset(name)
    run = simulate_swing(cfg, duration=2.0, seed=1)
    assert run.truth['preset'] == name and len(run.imu) == int(2.0 * cfg.gyro.rate_hz)
    assert set(run.imu.channels) == {'gyro_x', 'gyro_y', 'gyro_z', 'accel_x', 'accel_y',
                                     'accel_z'}
    assert np.all(np.diff(run.imu.t) > 0) and np.all(np.diff(run.encoder.t) > 0)
    assert run.imu.t[0] >= 0 and run.encoder.t[0] >= 0
    static = simulate_static(cfg, duration=2.0, seed=1)
    assert static.encoder is None and 'swing' not in static.truth


def test_paper_values_in_the_mems_preset():
    cfg = BenchConfig.from_preset('adis16405')
    deg = math.pi / 180
    assert cfg.gyro.output_step == pytest.approx(0.05 * deg)
    assert cfg.noise['gyro_x']['N'] == pytest.approx(1.890 * deg / 60)
    assert cfg.noise['gyro_x']['B'] == pytest.approx(36.950 * deg / 3600)
    assert cfg.gyro.scale_factor_error['x'] == pytest.approx(-0.09e-2)


def test_same_seed_same_run_other_seed_differs():
    a = simulate_swing('adis16405', duration=3.0, seed=4)
    b = simulate_swing('adis16405', duration=3.0, seed=4)
    c = simulate_swing('adis16405', duration=3.0, seed=5)
    assert np.array_equal(a.imu.t, b.imu.t) and np.array_equal(
        a.imu.channels['gyro_x'], b.imu.channels['gyro_x'])
    assert np.array_equal(a.encoder.channels['encoder'], b.encoder.channels['encoder'])
    assert not np.array_equal(a.imu.channels['gyro_x'], c.imu.channels['gyro_x'])
    assert a.truth == b.truth


def test_channel_subset_is_the_same_data():
    full = simulate_swing('adis16405', duration=3.0, seed=6)
    part = simulate_swing('adis16405', duration=3.0, seed=6, channels=['gyro_x'])
    assert set(part.imu.channels) == {'gyro_x'}
    assert np.array_equal(full.imu.channels['gyro_x'], part.imu.channels['gyro_x'])
    assert set(part.truth['channels']) == {'gyro_x'}


def test_yaml_overrides(tmp_path):
    path = tmp_path / 'c.yaml'
    path.write_text('preset: vg910\nstand: {period_s: 2.5}\ngyro: {bias: {x: 0.001}}\n'
                    'noise: {gyro_x: {N: 1.0e-5}}\n')
    cfg = load(str(path))
    assert cfg.preset == 'vg910' and cfg.stand.period_s == 2.5
    assert cfg.gyro.bias['x'] == 0.001 and cfg.gyro.bias['y'] == pytest.approx(-0.04 * math.pi
                                                                               / 180)
    assert cfg.noise['gyro_x']['N'] == 1e-5
    assert load(str(path), preset_name='adis16405').preset == 'adis16405'


@pytest.mark.parametrize('text,message', [
    ('stand: {period_s: -1}', 'must be >= 0'),
    ('stand: {period_s: 0}', 'must be > 0'),
    ('gyro: {axis: w}', 'gyro.axis'),
    ('gyro: {quantizer: ceil}', 'quantizer'),
    ('gyro: {rate_hz: .nan}', 'finite'),
    ('noise: {gyro_x: {N: abc}}', 'must be a number'),
    ('encoder: 3', 'expected a mapping'),
    ('bogus: 1', 'unknown key'),
    ('- a list', 'mapping'),
    ('preset: nope', 'unknown preset'),
])
def test_bad_config_is_refused(tmp_path, text, message):
    path = tmp_path / 'bad.yaml'
    path.write_text(text + '\n')
    with pytest.raises(InputError, match=message):
        load(str(path))


@pytest.mark.parametrize('kw', [{'duration': 0.0}, {'duration': float('nan')},
                                {'seed': -1}, {'seed': 1.5}, {'duration': 1e-4},
                                {'duration': 1e6}])
def test_bad_run_arguments(kw):
    args = {'duration': 1.0, 'seed': 0, **kw}
    with pytest.raises(InputError):
        simulate_swing('adis16405', **args)


def test_bad_channel_and_effect():
    with pytest.raises(InputError, match='unknown channel'):
        simulate_static('adis16405', duration=1.0, channels=['gyro_w'])
    with pytest.raises(InputError, match='unknown effect'):
        simulate_static('adis16405', duration=1.0, effects=['warp_drive'])
