"""An interleaved front end's memory (``internal_lowpass:memory,interleave``): form, twin, fit."""
from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.engine import run
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS
from gyro_char.sim.effects.responses import interleaved_memory_gain2
import numpy as np
import pytest
from scipy import signal
from static_twin_base import BASE, DT


def memory(r, lags=2):
    return ('internal_lowpass', {'taps': 1.0, 'stages': 1.0, 'decimation': 1.0,
                                 'memory': r, 'interleave': float(lags)})


def test_gain_is_unity_at_dc_and_every_rate_over_l_with_dips_between():
    f = np.linspace(0.0, 50.0, 1001)
    r = 0.3
    g2 = interleaved_memory_gain2(f, r, 2, DT)
    assert g2[0] == pytest.approx(1.0) and g2[-1] == pytest.approx(1.0)     # 0 and 50 Hz
    assert interleaved_memory_gain2(np.array([25.0]), r, 2, DT)[0] == pytest.approx(
        ((1 - r) / (1 + r)) ** 2)
    w, h = signal.freqz([1 - r], [1.0, 0.0, 0.0, -r], worN=f, fs=1.0 / DT)
    np.testing.assert_allclose(interleaved_memory_gain2(f, r, 3, DT), np.abs(h) ** 2,
                               rtol=1e-9)


def test_the_twin_correlates_white_noise_at_multiples_of_l_only():
    with pytest.raises(InputError, match='memory'):
        EFFECTS['internal_lowpass'](memory=1.0).check()
    with pytest.raises(InputError, match='interleave'):
        EFFECTS['internal_lowpass'](memory=0.2, interleave=2.5).check()
    params = EFFECTS['internal_lowpass'](taps=4.0).describe()['params']
    assert 'memory' not in params and 'interleave' not in params
    x = static.simulate_twin(BASE, 2 ** 19, [memory(0.3, 3)], 2)
    u = x - x.mean()
    rho = [np.dot(u[:-k], u[k:]) / np.dot(u, u) for k in (1, 2, 3, 6)]
    # The output step's rounding noise (lsb^2 / 12, 0.6 % of the variance) dilutes a little.
    assert rho == pytest.approx([0.0, 0.0, 0.3, 0.09], abs=0.01)


def test_an_interleaved_memory_is_named_internal_lowpass_with_its_share_and_converters():
    # A 2 h twin: r 0.2 kept by each of two capacitors in turn (a double-sampled ADC). No
    # other catalogue filter leaves the top of the band at unity with a dip at a quarter rate.
    x = static.simulate_twin(BASE, 720000, [memory(0.2, 2)], 7)
    d = run(static_expect.closed_form_problem([x], DT, twins=8, seed=3), repeats=8, seed=3)
    assert d.selected_effects[:1] == ['internal_lowpass']
    fitted = d.refined['params']['internal_lowpass']
    assert fitted.get('interleave') == 2.0
    assert fitted.get('memory', 0.0) == pytest.approx(0.2, rel=0.05)
    assert d.final_gap < 0.1 * d.baseline_gap
