# Optional catalogue shapes against closed forms: gauss_markov order 2 (two first-order stages
# in cascade), quantization with dither (white angle error), a speed-gated encoder cyclic
# error; the defaults are unchanged.
from gyro_char.errors import InputError
from gyro_char.sim import simulator
from gyro_char.sim.chain import stand_angle_clean, stand_rate_clean
from gyro_char.sim.config import BenchConfig, noiseless
from gyro_char.sim.effects import EFFECTS
from gyro_char.sim.effects.base import second_order_gm
import numpy as np
import pytest

DT = 0.01


def _quiet_config(n_arw: float = 1e-9) -> BenchConfig:
    return BenchConfig.from_preset('adis16405', {
        'noise': {'gyro_x': {'N': n_arw, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}},
        'gyro': {'static_rate_hz': 1 / DT, 'output_step': 0.0}})


def test_second_order_gm_is_stationary_from_the_first_sample():
    rng = np.random.default_rng(3)
    a = 0.8
    draws = np.array([second_order_gm(a, rng.standard_normal(40), rng.standard_normal(2))
                      for _ in range(20000)])
    var = draws.var(axis=0)
    assert np.all(np.abs(var[[0, 1, 20, 39]] - 1.0) < 0.04)
    # AR(2) with a double root a: rho_1 = 2 a / (1 + a^2), rho_2 = 2 rho_1 a - a^2
    rho1 = 2 * a / (1 + a * a)
    assert np.corrcoef(draws[:, 0], draws[:, 1])[0, 1] == pytest.approx(rho1, abs=0.003)
    assert np.corrcoef(draws[:, 10], draws[:, 12])[0, 1] == pytest.approx(2 * rho1 * a - a * a,
                                                                          abs=0.005)


def test_order_two_record_has_sigma_and_the_cascade_correlation():
    sigma, tc, dt = 0.02, 0.2, DT
    fx = [{'name': 'gauss_markov', 'params': {'sigma': sigma, 'tau_s': tc, 'axis': 0.0,
                                              'order': 2.0}}]
    x = simulator.simulate_static(_quiet_config(), duration=600.0, seed=4, channels=('gyro_x',),
                                  effects=fx).imu.channels['gyro_x']
    y = x - x.mean()
    assert np.std(y) == pytest.approx(sigma, rel=0.1)
    a = np.exp(-dt / tc)
    lag = 20                                   # one correlation time: (1 + 1) e^-1 = 0.74
    rho = np.dot(y[:-lag], y[lag:]) / np.dot(y, y)
    expected = (1 + lag * (1 - a * a) / (1 + a * a)) * a ** lag
    assert rho == pytest.approx(expected, abs=0.05) and abs(rho - a ** lag) > 0.2


def test_order_is_checked_and_defaults_to_the_first_order_process():
    with pytest.raises(InputError):
        EFFECTS['gauss_markov'](order=3)
    one = simulator.simulate_static(duration=5.0, seed=2, channels=('gyro_x',),
                                    effects=['gauss_markov:sigma=0.01,tau_s=0.5,axis=0'])
    same = simulator.simulate_static(duration=5.0, seed=2, channels=('gyro_x',),
                                     effects=['gauss_markov:sigma=0.01,tau_s=0.5,axis=0,'
                                              'order=1'])
    assert np.array_equal(one.imu.channels['gyro_x'], same.imu.channels['gyro_x'])


@pytest.mark.parametrize('dither,rms,lag1', [(0.0, np.sqrt(1 / 12), (0.3, 0.9)),
                                             (1.0, np.sqrt(1 / 6), (-0.03, 0.03))])
def test_dithered_angle_quantization_makes_the_angle_error_white(dither, rms, lag1):
    # Per-sample angle increments 10x finer than the step: without dither the angle error is
    # correlated from sample to sample; with it, white of variance step^2 / 6.
    step, cfg = 1e-4, _quiet_config(1e-4)
    runs = [simulator.simulate_static(cfg, duration=600.0, seed=4, channels=('gyro_x',),
                                      effects=fx).imu.channels['gyro_x']
            for fx in ([{'name': 'quantization', 'params': {
                'step_rad': step, 'dither': dither, 'axis': 0.0}}], [])]
    err = np.cumsum(runs[0] - runs[1]) * DT
    err -= err.mean()
    assert np.std(err) / step == pytest.approx(rms, rel=0.03)
    assert lag1[0] < np.corrcoef(err[:-1], err[1:])[0, 1] < lag1[1]
    with pytest.raises(InputError):
        EFFECTS['quantization'](dither=0.5)


def test_encoder_cyclic_error_speed_gate_leaves_the_slow_passes_clean():
    # gate_rads: the interpolation error only while the stand turns faster than the gate
    # (the clean stand rate), exactly the ungated error there; 0 keeps the ungated form.
    cfg = noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)
    spec = 'encoder_cyclic_error:lines=1024,a1=4e-6,a2=0,p1=0.3'
    runs = [simulator.simulate_swing(cfg, duration=10.0, seed=15, channels=['gyro_x'],
                                     effects=[spec + gate]) for gate in ('', ',gate_rads=0.3')]
    t = runs[0].encoder.t
    phi, rate = stand_angle_clean(cfg.stand, t), stand_rate_clean(cfg.stand, t)
    plain, gated = (r.encoder.channels['encoder'] - phi for r in runs)
    fast = np.abs(rate) > 0.3
    assert 0.3 < fast.mean() < 0.8
    assert np.allclose(plain, 4e-6 * np.sin(1024 * phi + 0.3), atol=1e-12)
    assert np.array_equal(gated[fast], plain[fast])
    assert np.all(gated[~fast] == 0.0)
    assert 'gate_rads' not in EFFECTS['encoder_cyclic_error']().describe()['params']
    with pytest.raises(InputError, match='gate_rads'):
        EFFECTS['encoder_cyclic_error'](gate_rads=-1.0)
