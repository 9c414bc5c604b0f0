"""Stale samples: the record's exact repeats beyond its rounding's (``holds.repeat_excess``)."""
from gyro_char.diagnosis import static
from gyro_char.diagnosis.holds import repeat_excess, REPEAT_Z
import numpy as np
import pytest

DT = 0.01
LSB = 0.05 * np.pi / 180.0
BASE = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=LSB, dt=DT)


@pytest.mark.parametrize('fx', [[], [('internal_lowpass', {'taps': 7.0, 'stages': 2.0,
                                                           'decimation': 8.0})],
                                [('gauss_markov', {'sigma': 5e-3, 'tau_s': 0.05})]])
def test_no_excess_of_repeats_without_holds_whatever_the_correlation(fx):
    x = static.simulate_twin(BASE, 2 ** 18, fx, 3)
    share, se = repeat_excess(x, LSB)
    assert np.mean(np.diff(x) == 0.0) > 0.02          # the rounding repeats samples itself
    assert abs(share) < REPEAT_Z * se


@pytest.mark.parametrize('isolated', [0.0, 1.0])
def test_the_excess_is_the_held_share_rounded_or_not(isolated):
    fx = [('stale_samples', {'p': 0.04, 'isolated': isolated})]
    x = static.simulate_twin(BASE, 2 ** 18, fx, 3)
    share, se = repeat_excess(x, LSB)
    assert share == pytest.approx(0.04, abs=4 * se) and share > 10 * REPEAT_Z * se
    fine = static.simulate_twin(static.StaticBaseline(**{**BASE.__dict__, 'lsb': 0.0}),
                                2 ** 18, fx, 3)
    share, se = repeat_excess(fine, 0.0)
    assert share == pytest.approx(0.04, abs=4 * se)
    # A step coarser than the differences' spread cannot tell.
    assert np.isnan(repeat_excess(np.round(fine / 1e-1) * 1e-1, 1e-1)[0])
