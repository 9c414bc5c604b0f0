# gauss_markov order 2 (two first-order stages in cascade): stationary variance and correlation
# against the closed forms; order 1 unchanged by the new option.
from gyro_char import bench_sim
from gyro_char.effects import EFFECTS
from gyro_char.effects_sensor import second_order_gm
from gyro_char.recordings import InputError
import numpy as np
import pytest


def test_second_order_gm_is_stationary_from_the_first_sample():
    rng = np.random.default_rng(3)
    a = 0.8
    draws = np.array([second_order_gm(a, rng.standard_normal(40), rng) for _ in range(20000)])
    var = draws.var(axis=0)
    assert np.all(np.abs(var[[0, 1, 20, 39]] - 1.0) < 0.04)
    # AR(2) with a double root a: rho_1 = 2 a / (1 + a^2), rho_2 = 2 rho_1 a - a^2
    rho1 = 2 * a / (1 + a * a)
    assert np.corrcoef(draws[:, 0], draws[:, 1])[0, 1] == pytest.approx(rho1, abs=0.003)
    assert np.corrcoef(draws[:, 10], draws[:, 12])[0, 1] == pytest.approx(2 * rho1 * a - a * a,
                                                                          abs=0.005)


def test_order_two_record_has_sigma_and_the_cascade_correlation():
    sigma, tc, dt = 0.02, 0.2, 0.01
    cfg_noise = {'noise': {'gyro_x': {'N': 1e-9, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}}}
    from gyro_char.sim_config import BenchConfig
    cfg = BenchConfig.from_preset('adis16405', {**cfg_noise, 'gyro': {
        'static_rate_hz': 1 / dt, 'output_step': 0.0}})
    x = bench_sim.simulate_static(cfg, duration=600.0, seed=4, channels=('gyro_x',), effects=[
        {'name': 'gauss_markov', 'params': {'sigma': sigma, 'tau_s': tc, 'axis': 0.0,
                                            'order': 2.0}}]).imu.channels['gyro_x']
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
    one = bench_sim.simulate_static(duration=5.0, seed=2, channels=('gyro_x',),
                                    effects=['gauss_markov:sigma=0.01,tau_s=0.5,axis=0'])
    same = bench_sim.simulate_static(duration=5.0, seed=2, channels=('gyro_x',),
                                     effects=['gauss_markov:sigma=0.01,tau_s=0.5,axis=0,'
                                              'order=1'])
    assert np.array_equal(one.imu.channels['gyro_x'], same.imu.channels['gyro_x'])
