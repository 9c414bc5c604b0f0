# internal_lowpass with a 1-tap kernel is the identity filter (no lfilter_zi on a length-1 kernel);
# the 3-stage (CIC) filter the diagnosis searches.
from gyro_char.diagnosis import observables as diag_observables, static as diag_static
from gyro_char.sim import simulator
from gyro_char.sim.effects import EFFECTS
import numpy as np
import pytest


def test_one_tap_lowpass_is_the_identity():
    x = np.random.default_rng(1).standard_normal((3, 50))
    for stages in (1, 2):
        lp = EFFECTS['internal_lowpass'](taps=1, stages=stages)
        y, a = lp.internal(None, x, x)
        assert np.array_equal(y, x) and np.array_equal(a, x)
        assert lp.noise_gain(1) == 1.0


def test_one_tap_lowpass_leaves_a_simulated_record_unchanged():
    clean = simulator.simulate_static(duration=2.0, seed=5, channels=('gyro_x',))
    one = simulator.simulate_static(duration=2.0, seed=5, channels=('gyro_x',),
                                    effects=[{'name': 'internal_lowpass',
                                              'params': {'taps': 1.0}}])
    assert np.array_equal(clean.imu.channels['gyro_x'], one.imu.channels['gyro_x'])


def test_three_stage_cic_kernel_and_twin_keep_the_baseline_arw():
    # sinc^3 (CIC) kernel of 4 taps: coefficients of (1 + z + z^2 + z^3)^3 / 64.
    h = EFFECTS['internal_lowpass'](taps=4, stages=3).kernel()
    want = np.array([1, 3, 6, 10, 12, 12, 10, 6, 3, 1]) / 64.0
    assert np.allclose(h, want)
    # A diagnosis twin with the 3-stage filter at 8x keeps the baseline's N at long tau, also
    # where the filter alone would change it by 58 % (2 taps: ARW gain sqrt(8 * 20 / 64)).
    lp = EFFECTS['internal_lowpass'](taps=2, stages=3, decimation=8)
    assert lp.noise_gain(8) == pytest.approx(np.sqrt(8 * 20 / 64))
    base = diag_static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=0.0, dt=0.01)
    fx = [('internal_lowpass', {'taps': 2.0, 'stages': 3.0, 'decimation': 8.0})]
    x = diag_static.simulate_twin(base, 2 ** 17, fx, seed=3)
    m = np.array([50, 100, 400])                       # 0.5-4 s: well averaged
    adev = diag_observables.overlapping_adev(x, m, base.dt)
    assert np.allclose(adev, base.N / np.sqrt(m * base.dt), rtol=0.06)
