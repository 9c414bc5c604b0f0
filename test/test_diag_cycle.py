"""A periodic thermal cycle (``temperature_drift:cycle_s``): simulator, start, closed form."""
from gyro_char.diagnosis import cycle, expected, static, static_spaces
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.deterministic import mean_term
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.diagnosis.static_expect import closed_form_problem
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS, SimContext
import numpy as np
import pytest
from static_twin_base import BASE, check_twin_means, DT, LSB, N_ARW

CYCLE = {'cycle_s': 900.0, 'amplitude': 3e-3, 'phase': 0.7, 'amplitude2': 1e-3, 'phase2': -2.0}
SHORTEST = 2 * 2048 * DT        # two Welch segments of a long record


def test_the_cycle_is_the_sum_of_its_harmonics_and_replaces_the_transient():
    with pytest.raises(InputError, match='cycle_s'):
        EFFECTS['temperature_drift'](cycle_s=-1.0).check()
    n = 5000
    ctx = SimContext(config=None, kind='static', seed=1, dt=DT)
    ctx.t = np.arange(n) * DT
    gyro = np.zeros((3, n))
    eff = EFFECTS['temperature_drift'](**CYCLE, amplitude3=5e-4, phase3=1.0, axis=2)
    y, _ = eff.sensor(ctx, gyro, gyro)
    t = ctx.t
    want = (3e-3 * np.sin(2 * np.pi * t / 900 + 0.7) + 1e-3 * np.sin(4 * np.pi * t / 900 - 2.0)
            + 5e-4 * np.sin(6 * np.pi * t / 900 + 1.0))
    assert y[2] == pytest.approx(want, abs=1e-15) and not y[:2].any()
    # The transient's lag is not applied to a cycle; its description keeps the cycle's terms.
    assert 'cycle_s' in eff.describe()['params']
    assert 'cycle_s' not in EFFECTS['temperature_drift']().describe()['params']


def test_the_record_start_reads_period_amplitudes_and_phases_of_a_two_hour_cycle():
    x = static.simulate_twin(BASE, 720000, [('temperature_drift', CYCLE)], 5)
    c = cycle.cycle_start(obs.detrend(x), DT, SHORTEST)
    assert c.period == pytest.approx(900.0, rel=1e-3)
    assert c.amplitudes[:2] == pytest.approx((3e-3, 1e-3), rel=0.03)
    assert c.amplitudes[2] == 0.0                            # no third harmonic: not kept
    assert c.phases[:2] == pytest.approx((0.7, -2.0), abs=0.05)


def test_a_second_harmonic_stronger_than_the_fundamental_keeps_the_true_period():
    # A bias near its turnover: the square of the die's swing doubles the cycle's frequency.
    p = {**CYCLE, 'amplitude': 6e-4, 'amplitude2': 3e-3}
    x = static.simulate_twin(BASE, 720000, [('temperature_drift', p)], 6)
    c = cycle.cycle_start(obs.detrend(x), DT, SHORTEST)
    assert c.period == pytest.approx(900.0, rel=1e-3)
    assert c.amplitudes[:2] == pytest.approx((6e-4, 3e-3), rel=0.1)


@pytest.mark.parametrize('effects', [
    [], [('gauss_markov', {'sigma': 3e-3, 'tau_s': 200.0, 'order': 1.0})],
    [('rate_random_walk', {'K': 3e-5})], [('bias_instability', {'B': 2e-3})],
    [('temperature_drift', {'amplitude': 5e-3, 'tau_s': 900.0})]])
def test_noise_walks_and_a_warm_up_show_no_cycle(effects):
    x = static.simulate_twin(BASE, 720000, effects, 7)
    assert cycle.cycle_start(obs.detrend(x), DT, SHORTEST) is None


def test_the_cycles_observables_equal_the_twins_and_its_welch_segments_a_direct_welch():
    p = {**CYCLE, 'cycle_s': 60.0, 'amplitude3': 4e-4, 'phase3': 2.5}
    n = 2 ** 16
    check_twin_means([('temperature_drift', p)], n=n)
    spec = model_spectrum(N_ARW, LSB, DT, [('temperature_drift', p)])
    det = expected.deterministic(spec, expected.grids(n, DT), obs.ACF_LAGS)
    direct = obs.welch_psd(obs.detrend(mean_term(spec, n)), DT)[1]
    assert det.welch == pytest.approx(direct, rel=1e-6, abs=1e-9 * direct.max())


@pytest.mark.parametrize('onset', [{'t0_s': 200.0}, {'t0_s': 150.0, 'rise_s': 300.0}])
def test_a_cycle_switched_on_mid_record_equals_its_twins_and_a_direct_welch(onset):
    p = {**CYCLE, 'cycle_s': 60.0, **onset}
    n = 2 ** 16
    ctx = SimContext(config=None, kind='static', seed=1, dt=DT)
    ctx.t = np.arange(n) * DT
    y, _ = EFFECTS['temperature_drift'](**p, axis=2).sensor(ctx, np.zeros((3, n)),
                                                            np.zeros((3, n)))
    plain, _ = EFFECTS['temperature_drift'](**{**CYCLE, 'cycle_s': 60.0}, axis=2).sensor(
        ctx, np.zeros((3, n)), np.zeros((3, n)))
    t0, rise = onset['t0_s'], onset.get('rise_s', 0.0)
    ramp = np.clip((ctx.t - t0) / rise, 0, 1) if rise else (ctx.t >= t0) * 1.0
    assert y[2] == pytest.approx(plain[2] * ramp, abs=1e-15)
    assert not y[2][ctx.t < t0].any()
    check_twin_means([('temperature_drift', p)], n=n)
    spec = model_spectrum(N_ARW, LSB, DT, [('temperature_drift', p)])
    det = expected.deterministic(spec, expected.grids(n, DT), obs.ACF_LAGS)
    direct = obs.welch_psd(obs.detrend(mean_term(spec, n)), DT)[1]
    assert det.welch == pytest.approx(direct, rel=1e-6, abs=1e-9 * direct.max())


def test_a_cycle_that_starts_mid_record_is_offered_the_onset_form():
    p = {**CYCLE, 't0_s': 2400.0, 'rise_s': 1200.0}
    x = static.simulate_twin(BASE, 720000, [('temperature_drift', p)], 9)
    space = static_spaces.static_spaces(BASE, x, ['temperature_drift'])[0]
    onset = space.alternatives[-1]
    names = [q.name for q in onset.params]
    assert names[-2:] == ['t0_s', 'rise_s'] and onset.fixed['cycle_s'] == pytest.approx(
        900.0, rel=0.01)
    # The record's average amplitude, diluted by the two thirds the cycle is off or rising,
    # is inside the onset form's range and under its true value.
    amp = onset.params[0]
    assert amp.lo < 3e-3 < amp.hi and amp.init < 1.5 * 3e-3


def test_a_two_hour_cycle_is_named_with_its_period_and_amplitudes():
    x = static.simulate_twin(BASE, 720000, [('temperature_drift', CYCLE)], 8)
    space = static_spaces.static_spaces(BASE, x, ['temperature_drift'])[0]
    assert space.alternatives[-2].fixed['cycle_s'] == pytest.approx(900.0, rel=1e-3)
    d = run(closed_form_problem([x], DT, twins=8, seed=3), repeats=8, seed=3)
    assert d.selected_effects[:1] == ['temperature_drift']
    fit = d.steps[0]['params']
    assert fit['cycle_s'] == pytest.approx(900.0, rel=1e-3)
    assert fit['amplitude'] == pytest.approx(3e-3, rel=0.05)
    assert fit['amplitude2'] == pytest.approx(1e-3, rel=0.15)
    assert d.final_gap < 2.0 < d.baseline_gap
