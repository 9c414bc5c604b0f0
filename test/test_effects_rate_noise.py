"""A gyro noise whose size follows the rate: the simulator's forms and the twins' N share."""
from gyro_char.diagnosis.swing_baseline import SwingBaseline
from gyro_char.diagnosis.swing_rate_noise import mean_power, rate_noise_gain, split
from gyro_char.errors import InputError
from gyro_char.sim.config import BenchConfig, noiseless
from gyro_char.sim.effects import EFFECTS
from gyro_char.sim.simulator import simulate_swing
import numpy as np
import pytest


def _extra(effect: str):
    """Return (true rate, added noise, sample step) of a noiseless 200 s swing of ``effect``."""
    cfg = noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)
    runs = [simulate_swing(cfg, duration=200.0, seed=5, channels=['gyro_x'], effects=fx)
            for fx in ([], [effect])]
    t = runs[0].imu.t
    plain, noisy = (r.imu.channels['gyro_x'] for r in runs)
    w = 2 * np.pi / cfg.stand.period_s
    # The noiseless output is the true rate (scale-factor errors and bias off).
    return plain, noisy - plain, float(np.median(np.diff(t))), \
        cfg.stand.amplitude * w


@pytest.mark.parametrize('spec, level', [
    ('scale_factor_nonlinearity:k2=0,sf_noise=2e-3', lambda w: 2e-3 * np.abs(w)),
    ('scale_factor_asymmetry:a=0,sf_noise=2e-3', lambda w: 2e-3 * np.maximum(-w, 0.0)),
    ('scale_factor_nonlinearity:k2=0,gate_noise=1e-3,noise_gate_rads=0.3',
     lambda w: 1e-3 * (np.abs(w) > 0.3)),
])
def test_the_added_noise_has_the_density_its_form_gives_at_each_rate(spec, level):
    rate, extra, dt, peak = _extra(spec)
    assert peak > 0.43
    expected = level(rate) / np.sqrt(dt)           # per-sample sd of a white density
    quiet = expected == 0
    assert np.all(extra[quiet] == 0.0)              # none where the form gives none
    z = extra[~quiet] / expected[~quiet]            # unit normal where it gives some
    assert z.size > 20000
    assert np.std(z) == pytest.approx(1.0, abs=0.02)
    assert abs(np.mean(z)) < 0.02
    assert abs(np.corrcoef(z[:-1], z[1:])[0, 1]) < 0.02   # white
    # The rate bins: the sd follows the form (the proportional forms grow with |rate|).
    for lo, hi in ((0.05, 0.15), (0.3, 0.42)):
        m = (np.abs(rate) > lo) & (np.abs(rate) < hi) & ~quiet
        if np.any(m):
            ratio = np.std(extra[m]) / np.sqrt(np.mean(expected[m] ** 2))
            assert ratio == pytest.approx(1.0, abs=0.05)


def test_a_switched_range_adds_its_gain_above_the_gate_only():
    cfg = noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)
    runs = [simulate_swing(cfg, duration=20.0, seed=5, channels=['gyro_x'], effects=fx)
            for fx in ([], ['scale_factor_nonlinearity:k2=0,noise_gate_rads=0.3,'
                            'gate_gain=0.02'])]
    rate, out = (r.imu.channels['gyro_x'] for r in runs)
    assert np.allclose(out - rate, 0.02 * rate * (np.abs(rate) > 0.3), rtol=0, atol=1e-15)
    assert np.any(np.abs(rate) > 0.3) and np.any((np.abs(rate) < 0.3) & (rate != 0))


def test_the_noise_parameters_are_checked_and_left_out_of_the_truth_when_off():
    for spec in ({'sf_noise': -1e-3}, {'gate_noise': -1.0}, {'noise_gate_rads': -0.1}):
        with pytest.raises(InputError, match='must be >= 0'):
            EFFECTS['scale_factor_nonlinearity'](**spec).check()
    with pytest.raises(InputError, match='sf_noise'):
        EFFECTS['scale_factor_asymmetry'](sf_noise=-1.0).check()
    assert 'sf_noise' not in EFFECTS['scale_factor_nonlinearity'](k3=0.1).describe()['params']
    assert EFFECTS['scale_factor_asymmetry'](sf_noise=1e-3).describe()['params'][
        'sf_noise'] == 1e-3


def _base(n=5e-4, amplitude=0.35, period=5.0):
    return SwingBaseline(period_s=period, amplitude=amplitude, scale_factor_error=0.0,
                         bias=0.0, drift=0.0, N=n, encoder_sigma=1e-5, lsb=0.0, dt=1e-3,
                         encoder_dt=1e-3, duration=900.0, axis='x')


def test_the_mean_power_over_the_swing_is_the_closed_form_of_each_form():
    b = _base()
    w = b.peak_rate
    sf = {'name': 'scale_factor_nonlinearity', 'params': {'k2': 0.0, 'sf_noise': 1e-3}}
    half = {'name': 'scale_factor_asymmetry', 'params': {'a': 0.0, 'sf_noise': 1e-3}}
    gated = {'name': 'scale_factor_nonlinearity',
             'params': {'k2': 0.0, 'gate_noise': 2e-4, 'noise_gate_rads': 0.5 * w}}
    # <cos²> = 1/2 (half of it on one side); |cos θ| > 1/2 two thirds of the time.
    assert mean_power(sf, b) == pytest.approx((1e-3 * w) ** 2 / 2, rel=1e-4)
    assert mean_power(half, b) == pytest.approx((1e-3 * w) ** 2 / 4, rel=1e-4)
    assert mean_power(gated, b) == pytest.approx(2e-4 ** 2 * 2.0 / 3.0, rel=1e-3)
    # The twin gives up that mean power from the baseline's white noise, never all of it.
    assert rate_noise_gain([sf], b) == pytest.approx(1 - (1e-3 * w) ** 2 / 2 / 5e-4 ** 2)
    assert rate_noise_gain([gated, half], b) == pytest.approx(
        1 - (mean_power(gated, b) + mean_power(half, b)) / 5e-4 ** 2)
    assert rate_noise_gain([{**sf, 'params': {'sf_noise': 1.0}}], b) == 0.05
    assert rate_noise_gain([{'name': 'time_delay', 'params': {'delay_s': 1e-3}}], b) == 1.0


def test_a_spec_splits_into_its_deterministic_part_and_its_noise():
    cubic_noise = {'name': 'scale_factor_nonlinearity',
                   'params': {'k2': 0.0, 'k3': 0.1, 'sf_noise': 1e-3}}
    det, noise = split(cubic_noise)
    assert det == {'name': 'scale_factor_nonlinearity', 'params': {'k2': 0.0, 'k3': 0.1}}
    assert noise['params'] == {'k2': 0.0, 'sf_noise': 1e-3, 'gate_noise': 0.0,
                               'noise_gate_rads': 0.0}
    det, noise = split({'name': 'scale_factor_asymmetry', 'params': {'a': 0.0,
                                                                     'sf_noise': 1e-3}})
    assert det is None and noise['params'] == {'a': 0.0, 'sf_noise': 1e-3}
    # The plain form at its catalogue default (k2 not given) still acts.
    det, _ = split({'name': 'scale_factor_nonlinearity', 'params': {'sf_noise': 1e-3}})
    assert det == {'name': 'scale_factor_nonlinearity', 'params': {}}
    plain = {'name': 'scale_factor_nonlinearity', 'params': {'k3': 0.1}}
    assert split(plain) == (plain, None)
    # A switched range: the gate serves its gain (deterministic) and its noise.
    det, noise = split({'name': 'scale_factor_nonlinearity', 'params': {
        'k2': 0.0, 'gate_noise': 1e-3, 'noise_gate_rads': 0.2, 'gate_gain': 0.01}})
    assert det['params'] == {'k2': 0.0, 'noise_gate_rads': 0.2, 'gate_gain': 0.01}
    assert noise['params']['noise_gate_rads'] == 0.2 and 'gate_gain' not in noise['params']
