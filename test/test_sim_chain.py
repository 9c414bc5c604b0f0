"""Each element of the paper's bench model against its closed form."""
import math

from gyro_char.sim.chain import (encoder_reading, G0, quantize, sample_times, specific_force,
                                 stand_angle_clean, stand_motion)
from gyro_char.sim.config import BenchConfig, EncoderConfig, noiseless, StandConfig
from gyro_char.sim.simulator import simulate_static, simulate_swing
import numpy as np
import pytest


def _stand(**kw):
    base = {'amplitude': 0.3, 'period_s': 4.0, 'phase': 0.2, 'offset': 1e-3,
            'drift_rate': 2e-5, 'drift_accel': 1e-7, 'amplitude_noise': 0.0,
            'drift_rate_noise': 0.0}
    base.update(kw)
    return StandConfig(**base)


@pytest.mark.parametrize('mode,mean', [('floor', -0.5), ('round', 0.0)])
def test_quantizer_error_moments(mode, mean):
    rng = np.random.default_rng(1)
    x = rng.uniform(-100.0, 100.0, 400_000)
    step = 0.37
    err = quantize(x, step, mode) - x
    assert abs(err.mean() - mean * step) < 0.005 * step
    assert err.var() == pytest.approx(step ** 2 / 12.0, rel=0.01)
    assert np.allclose(np.round(quantize(x, step, mode) / step),
                       quantize(x, step, mode) / step, atol=1e-9)


def test_sampling_jitter_moments():
    rng = np.random.default_rng(2)
    dt, sigma = 1e-3, 2e-5
    t = sample_times(200_000, dt, sigma, rng)
    nominal = dt * np.arange(t.size)
    assert (t - nominal).std() == pytest.approx(sigma, rel=0.01)
    assert np.diff(t).std() == pytest.approx(sigma * math.sqrt(2.0), rel=0.01)
    assert np.all(np.diff(t) > 0)


def test_stand_rate_is_the_derivative_of_the_angle():
    cfg = _stand()
    t = np.linspace(0.0, 20.0, 200_001)
    angle, rate, accel = stand_motion(cfg, t, np.random.default_rng(0))
    assert np.allclose(angle, stand_angle_clean(cfg, t))
    h = t[1] - t[0]
    assert np.allclose(np.gradient(angle, h)[1:-1], rate[1:-1], atol=1e-6)
    assert np.allclose(np.gradient(rate, h)[1:-1], accel[1:-1], atol=1e-5)


def test_stand_system_noises_have_the_papers_variance():
    sa, sw = 4e-6, 3e-9
    cfg = _stand(amplitude_noise=sa, drift_rate_noise=sw)
    t = np.linspace(0.0, 900.0, 400_000)
    angle, _, _ = stand_motion(cfg, t, np.random.default_rng(3))
    resid = angle - stand_angle_clean(cfg, t)
    s = np.sin(2 * np.pi * t / cfg.period_s + cfg.phase)
    expected = sa ** 2 * s ** 2 + (sw * t) ** 2
    assert np.mean(resid ** 2) == pytest.approx(expected.mean(), rel=0.02)


def test_encoder_quantization_and_adc_noise_moments():
    d1, d2, sigma = 2e-5, 7e-6, 3e-6
    cfg = EncoderConfig(rate_hz=1000.0, level_step=d1, adc_noise=sigma, word_step=d2,
                        jitter_s=0.0)
    angle = np.random.default_rng(4).uniform(-0.5, 0.5, 400_000)
    err = encoder_reading(cfg, angle, np.random.default_rng(5)) - angle
    # Two floors: mean -(d1 + d2)/2; independent errors: variances add.
    assert err.mean() == pytest.approx(-(d1 + d2) / 2.0, abs=2e-8)
    assert err.var() == pytest.approx(d1 ** 2 / 12 + sigma ** 2 + d2 ** 2 / 12, rel=0.02)


def test_specific_force_is_gravity_rotated():
    phi = np.linspace(-1.0, 1.0, 11)
    for axis in range(3):
        f = specific_force(axis, phi)
        assert np.allclose(np.linalg.norm(f, axis=0), G0)
    assert np.allclose(specific_force(0, phi)[1], G0 * np.sin(phi))
    assert np.allclose(specific_force(1, phi)[0], -G0 * np.sin(phi))


def test_gyro_scale_misalignment_bias_and_drift_closed_form():
    cfg = noiseless(BenchConfig.from_preset('adis16405'))
    cfg.gyro.misalignment = 0.05            # cos = 0.99875: visible
    cfg.gyro.misalignment_noise = 0.02      # E[cos] factor exp(-sigma^2/2) = 0.9998
    run = simulate_swing(cfg, duration=120.0, seed=7, channels=['gyro_x'])
    t = run.imu.t
    _, rate, _ = stand_motion(cfg.stand, t, np.random.default_rng(0))
    design = np.column_stack([rate, np.ones_like(t), t])
    y = run.imu.channels['gyro_x']
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    # Standard errors of the regression (the misalignment instability is white noise).
    resid = y - design @ coef
    se = np.sqrt(np.diag(np.linalg.inv(design.T @ design)) * resid.var())
    truth = run.truth['swing']
    expected = (1 + cfg.gyro.scale_factor_error['x']) * math.cos(0.05) * math.exp(-2e-4) - 1
    assert truth['scale_factor_error'] == pytest.approx(expected, abs=1e-12)
    want = np.array([1.0 + truth['scale_factor_error'], truth['bias'], truth['bias_drift']])
    assert np.all(np.abs(coef - want) < 4.0 * se), (coef, want, se)
    assert se[0] < 3e-5 and se[2] < 0.1 * abs(want[2])


def test_gyro_output_quantization_white_contribution_in_truth():
    cfg = noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)
    n_white = 5e-4
    cfg.noise['gyro_x']['N'] = n_white
    cfg.gyro.output_step = 0.01
    run = simulate_static(cfg, duration=600.0, seed=8, channels=['gyro_x'])
    x = run.imu.channels['gyro_x']
    dt = 1.0 / cfg.gyro.static_rate_hz
    expected_var = n_white ** 2 / dt + 0.01 ** 2 / 12.0
    assert x.var() == pytest.approx(expected_var, rel=0.02)
    assert run.truth['channels']['gyro_x']['N'] == pytest.approx(
        math.sqrt(expected_var * dt), rel=1e-12)
    assert np.allclose(np.round(x / 0.01) * 0.01, x)


def test_floor_quantizer_bias_enters_truth():
    cfg = noiseless(BenchConfig.from_preset('adis16405'))
    cfg.gyro.output_step = 0.002
    cfg.gyro.quantizer = 'floor'
    run = simulate_swing(cfg, duration=60.0, seed=9, channels=['gyro_x'])
    t = run.imu.t
    _, rate, _ = stand_motion(cfg.stand, t, np.random.default_rng(0))
    g = cfg.gyro
    resid = run.imu.channels['gyro_x'] - (1 + run.truth['swing']['scale_factor_error']) * rate \
        - run.truth['swing']['bias_drift'] * t
    assert resid.mean() == pytest.approx(run.truth['swing']['bias'], abs=2e-5)
    assert run.truth['swing']['bias'] == pytest.approx(g.bias['x'] - 0.001)


def test_encoder_stream_matches_the_stand_at_its_jittered_instants():
    cfg = noiseless(BenchConfig.from_preset('adis16405'))
    cfg.encoder.jitter_s = 50e-6
    run = simulate_swing(cfg, duration=30.0, seed=10, channels=['gyro_x'])
    te = run.encoder.t
    assert np.allclose(run.encoder.channels['encoder'], stand_angle_clean(cfg.stand, te),
                       atol=1e-12)
    nominal = np.arange(te.size) / cfg.encoder.rate_hz
    assert (te - nominal).std() == pytest.approx(50e-6, rel=0.05)


def _adev_closed_form(terms, tau):
    return np.sqrt(terms['R'] ** 2 * tau ** 2 / 2 + terms['K'] ** 2 * tau / 3
                   + terms['B'] ** 2 * 2 * math.log(2) / math.pi + terms['N'] ** 2 / tau
                   + 3 * terms['Q'] ** 2 / tau ** 2)


def test_static_record_allan_matches_truth_on_every_channel():
    allantools = pytest.importorskip('allantools')
    cfg = BenchConfig.from_preset('adis16405')
    cfg.gyro.static_rate_hz = 100.0
    cfg.noise['gyro_y']['Q'] = 2e-4
    cfg.noise['accel_z']['K'] = 1e-4
    run = simulate_static(cfg, duration=2 * 3600.0, seed=11)
    taus = np.array([0.1, 1.0, 10.0, 100.0])
    for name, terms in run.truth['channels'].items():
        x = run.imu.channels[name]
        got = allantools.oadev(x, rate=100.0, data_type='freq', taus=taus)[1]
        want = _adev_closed_form(terms, taus)
        # 2 h record: the 100 s point has ~70 equivalent degrees of freedom (~9 % 1-sigma).
        assert np.all(np.abs(got / want - 1.0) < np.array([0.05, 0.05, 0.12, 0.3])), name


def test_realized_bias_and_drift_include_the_runs_correlated_noise():
    cfg = noiseless(BenchConfig.from_preset('adis16405'))
    cfg.noise['gyro_x']['K'] = 1e-4        # large rate random walk: the run's own drift
    cfg.noise['gyro_x']['B'] = 1e-3
    run = simulate_swing(cfg, duration=60.0, seed=12, channels=['gyro_x'])
    t = run.imu.t
    _, rate, _ = stand_motion(cfg.stand, t, np.random.default_rng(0))
    resid = run.imu.channels['gyro_x'] - (1 + run.truth['swing']['scale_factor_error']) * rate
    drift, bias = np.polyfit(t, resid, 1)
    assert bias == pytest.approx(run.realized['bias'], abs=1e-9)
    assert drift == pytest.approx(run.realized['bias_drift'], abs=1e-10)
    assert abs(run.realized['bias'] - run.truth['swing']['bias']) > 1e-5
