"""The output-rate low-pass (``internal_lowpass:corner_hz,order``): simulator, closed form, fit."""
from dataclasses import replace

from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.fit import EffectSpace, Evaluation, fit_effect, Param
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS
from gyro_char.sim.effects.responses import output_lowpass, output_lowpass_gain2
import numpy as np
import pytest
from scipy import signal
from static_twin_base import BASE, DT


def dlpf(corner, order):
    return ('internal_lowpass', {'taps': 1.0, 'stages': 1.0, 'decimation': 1.0,
                                 'corner_hz': corner, 'order': float(order)})


@pytest.mark.parametrize('corner, order', [(12.0, 1), (30.0, 2), (49.8, 2)])
def test_gain_is_the_butterworth_filters_own(corner, order):
    b, a = output_lowpass(corner, order, DT)
    f = np.linspace(0.01, 49.99, 500)
    _, h = signal.freqz(b, a, worN=f, fs=1.0 / DT)
    np.testing.assert_allclose(output_lowpass_gain2(f, corner, order, DT), np.abs(h) ** 2,
                               rtol=1e-6, atol=1e-12)


def test_the_corner_is_searched_on_the_prewarped_tangent():
    p = Param('corner_hz', 2.0, 49.95, nyquist=50.0)
    for v in (2.0, 30.0, 49.8, 49.95):
        assert p.from_u(p.to_u(v)) == pytest.approx(v, rel=1e-12)
    # Equal steps in the search variable: 49.7 -> 49.85 Hz (the tangent doubles) is as far as
    # 25 -> 35.2 Hz, and as 4.5 -> 9 Hz.
    for lo, hi in ((49.7, 49.85), (25.0, 35.24), (4.5, 9.0)):
        assert p.to_u(hi) - p.to_u(lo) == pytest.approx(np.log(2.0), rel=0.05)


def test_the_form_is_checked_and_left_out_of_truth_when_absent():
    with pytest.raises(InputError, match='order 1 or 2'):
        EFFECTS['internal_lowpass'](corner_hz=20.0, order=3.0).check()
    assert set(EFFECTS['internal_lowpass'](taps=4.0).describe()['params']) == {
        'taps', 'stages', 'decimation', 'accel'}
    lp = EFFECTS['internal_lowpass'](taps=1.0, corner_hz=20.0, order=1.0)
    assert lp.describe()['params']['corner_hz'] == 20.0
    with pytest.raises(InputError, match='below the output Nyquist'):
        static.simulate_twin(BASE, 1000, [dlpf(60.0, 2)], 1)


@pytest.mark.parametrize('corner, order', [(49.85, 2), (38.0, 1)])
def test_a_dlpf_is_named_with_its_corner_where_the_averages_cannot_follow(corner, order):
    # A gentle roll-off below Nyquist: the averages, decimated, make whole steps of
    # correlation; 49.85 Hz is a filter the lag-1 correlation shows at a few sigma only.
    x = static.simulate_twin(BASE, 2 ** 18, [dlpf(corner, order)], 7)
    problem = static_expect.closed_form_problem([x], DT, twins=8, seed=3)
    d = run(problem, repeats=8, seed=3)
    assert d.selected_effects[:1] == ['internal_lowpass']
    fitted = d.refined['params']['internal_lowpass']
    assert fitted.get('corner_hz', 0.0) > 0.0
    warp = np.tan(np.pi * DT * np.array([fitted['corner_hz'], corner]))
    assert abs(np.log(warp[0] / warp[1])) < 0.3
    assert d.final_gap < d.null_gap['q95']


class _Toy:
    """A gap with two forms of one effect: form b is better only once 'other' is selected."""

    def evaluate(self, effects):
        other = any(n == 'other' for n, _ in effects)
        p = dict(effects)['lp']
        if 'corner_hz' in p:
            gap = 5.0 + (p['corner_hz'] - 40.0) ** 2 / 100 - (4.0 if other else 0.0)
        else:
            gap = 3.0 + (p['taps'] - 8.0) ** 2 / 10
        return Evaluation(effects=list(effects), gap=gap, stats=[])


def test_a_refit_tries_the_forms_the_earlier_fit_did_not_take_where_asked():
    taps = EffectSpace('lp', [Param('taps', 2, 32, integer=True)])
    corner = EffectSpace('lp', [Param('corner_hz', 2.0, 49.9, nyquist=50.0)],
                         fixed={'taps': 1.0})
    for refit_all, form in ((False, 'taps'), (True, 'corner_hz')):
        space = replace(taps, alternatives=(corner,), refit_all=refit_all)
        first, ev = fit_effect(_Toy(), [], space)
        assert 'corner_hz' not in first and ev.gap == pytest.approx(3.0)
        # With 'other' selected the corner form is the better (gap ~1); a refit near the
        # first fit finds it only if it also fits the form the first fit did not take.
        again, ev = fit_effect(_Toy(), [('other', {})], space, near=first)
        assert form in again
