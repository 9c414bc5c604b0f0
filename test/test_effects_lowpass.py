# internal_lowpass with a 1-tap kernel is the identity filter (no lfilter_zi on a length-1 kernel).
from gyro_char import bench_sim
from gyro_char.effects import EFFECTS
import numpy as np


def test_one_tap_lowpass_is_the_identity():
    x = np.random.default_rng(1).standard_normal((3, 50))
    for stages in (1, 2):
        lp = EFFECTS['internal_lowpass'](taps=1, stages=stages)
        y, a = lp.internal(None, x, x)
        assert np.array_equal(y, x) and np.array_equal(a, x)
        assert lp.noise_gain(1) == 1.0


def test_one_tap_lowpass_leaves_a_simulated_record_unchanged():
    clean = bench_sim.simulate_static(duration=2.0, seed=5, channels=('gyro_x',))
    one = bench_sim.simulate_static(duration=2.0, seed=5, channels=('gyro_x',),
                                    effects=[{'name': 'internal_lowpass',
                                              'params': {'taps': 1.0}}])
    assert np.array_equal(clean.imu.channels['gyro_x'], one.imu.channels['gyro_x'])
