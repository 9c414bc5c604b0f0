"""The output-rate notch (``internal_lowpass:notch_hz,notch_q``): simulator, closed form, fit."""
from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.static_bands import with_notch_band
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS
from gyro_char.sim.effects.responses import output_notch, output_notch_gain2
import numpy as np
import pytest
from scipy import signal
from static_twin_base import BASE, DT

SPAN = (0.01, 50.0)


def notch(f0, q):
    return ('internal_lowpass', {'taps': 1.0, 'stages': 1.0, 'decimation': 1.0,
                                 'notch_hz': f0, 'notch_q': q})


@pytest.mark.parametrize('f0, q', [(8.0, 2.0), (29.3, 6.0), (45.0, 30.0)])
def test_gain_is_the_notch_filters_own(f0, q):
    b, a = output_notch(f0, q, DT)
    f = np.linspace(0.01, 49.99, 700)
    _, h = signal.freqz(b, a, worN=f, fs=1.0 / DT)
    np.testing.assert_allclose(output_notch_gain2(f, f0, q, DT), np.abs(h) ** 2,
                               rtol=1e-9, atol=1e-12)
    assert output_notch_gain2(np.array([f0]), f0, q, DT)[0] < 1e-20


def test_the_notch_is_checked_filters_the_twin_and_is_left_out_of_truth_when_absent():
    with pytest.raises(InputError, match='notch_q > 0'):
        EFFECTS['internal_lowpass'](notch_hz=20.0, notch_q=0.0).check()
    assert 'notch_q' not in EFFECTS['internal_lowpass'](taps=4.0).describe()['params']
    assert EFFECTS['internal_lowpass'](notch_hz=20.0).describe()['params']['notch_q'] == 5.0
    with pytest.raises(InputError, match='below the output Nyquist'):
        static.simulate_twin(BASE, 1000, [notch(70.0, 3.0)], 1)
    x = static.simulate_twin(BASE, 2 ** 18, [notch(20.0, 3.0)], 2)
    f, p = signal.welch(x - x.mean(), fs=1.0 / DT, nperseg=2048)
    assert p[np.argmin(abs(f - 20.0))] < 0.01 * np.median(p)


def test_a_notch_is_searched_only_at_a_dip_of_the_gap_away_from_the_ends():
    lp = EffectSpace('internal_lowpass', [Param('taps', 2, 32, integer=True)])
    other = EffectSpace('resonance', [Param('q', 1.0, 300.0)])
    dip = {'observable': 'psd', 'range': [19.6, 26.8], 'excess': -5.0}
    bump = {'observable': 'psd', 'range': [5.6, 7.7], 'excess': 6.0}
    fall = {'observable': 'psd', 'range': [36.6, 50.0], 'excess': -9.0}
    assert with_notch_band([lp, other], [bump], DT, SPAN)[0].alternatives == ()
    assert with_notch_band([lp, other], [fall], DT, SPAN)[0].alternatives == ()
    spaces = with_notch_band([lp, other], [bump, dip, fall], DT, SPAN)
    (alt,) = spaces[0].alternatives
    start = {p.name: p.init for p in alt.params}
    assert start['notch_hz'] == pytest.approx(np.sqrt(19.6 * 26.8))
    assert alt.fixed['taps'] == 1.0 and spaces[1] is other


def test_a_notch_is_named_with_its_centre():
    x = static.simulate_twin(BASE, 2 ** 18, [notch(31.0, 4.0)], 7)
    d = run(static_expect.closed_form_problem([x], DT, twins=8, seed=3), repeats=8, seed=3)
    assert d.selected_effects[:1] == ['internal_lowpass']
    fitted = d.refined['params']['internal_lowpass']
    assert fitted.get('notch_hz', 0.0) == pytest.approx(31.0, rel=0.1)
    assert d.final_gap < d.null_gap['q95'] < 0.2 * d.baseline_gap
