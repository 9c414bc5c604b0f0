# The swing kind of the diagnosis on simulated swing records with an effect it is not told of.
from gyro_char import bench_sim, diag_gap, diag_swing, diag_swing_obs, diagnose
from gyro_char.sim_config import BenchConfig
from gyro_char.swing_kf import estimate_swing
import numpy as np
import pytest

RATE_HZ = 200.0  # a 5 ms gyro step (the paper's MEMS runs: 2-3 ms); encoder at 1 kHz
DURATION = 60.0


def _record(effects, seed):
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': RATE_HZ}})
    effects = [{'name': n, 'params': p} for n, p in effects]
    run = bench_sim.simulate_swing(cfg, duration=DURATION, seed=seed, effects=effects,
                                   channels=('gyro_x',))
    return run.imu, run.encoder


def _diagnose(effects, seed):
    imu, enc = _record(effects, seed)
    return diagnose.run(diag_swing.swing_problem(imu, enc, 5.0), repeats=5, seed=seed)


def test_swing_observables_see_a_delay_in_quadrature_only():
    # Same seed with and without a stamp delay: only the cos θ component moves, by -A ω d.
    d = 0.37 / RATE_HZ
    (i0, e0), (i1, e1) = _record([], 3), _record([('time_delay', {'delay_s': d})], 3)
    base = diag_swing.fit_baseline(i0, e0, 5.0)
    ranges = diag_swing_obs.layout(len(i0), base.dt, 5.0)
    o0 = diag_swing_obs.swing_observables(i0.t, i0.channels['gyro_x'], e0.t,
                                          e0.channels['encoder'], 5.0, ranges)
    o1 = diag_swing_obs.swing_observables(i1.t, i1.channels['gyro_x'], e1.t,
                                          e1.channels['encoder'], 5.0, ranges)
    expected = -base.amplitude * 2 * np.pi / 5.0 * d
    assert o1['quadrature'][0] - o0['quadrature'][0] == pytest.approx(expected, rel=0.05)
    assert abs(o1['in_phase'][0] - o0['in_phase'][0]) < 0.01 * abs(expected)
    assert np.all(np.abs(o1['harmonic_3f'] - o0['harmonic_3f']) < 0.01 * abs(expected))


def test_fractional_sample_delay_is_found_and_flagged_against_g_sensitivity():
    d = 0.37 / RATE_HZ
    diag = _diagnose([('time_delay', {'delay_s': d})], seed=41)
    # One period, one amplitude: g-sensitivity leaves the same quadrature residual, so the two
    # lead the ranking (in either order), one is selected, and the step says it is ambiguous.
    pair = {'time_delay', 'g_sensitivity'}
    assert {r['effect'] for r in diag.ranking[:2]} == pair
    assert diag.selected_effects[0] in pair
    amb = diag.ambiguous[0]
    assert set(amb['effects']) == pair
    assert 'second period or amplitude' in amb['separating_run']
    assert diag.where[0]['observable'] == 'quadrature'
    fitted = next(r for r in diag.ranking if r['effect'] == 'time_delay')
    assert fitted['params']['delay_s'] == pytest.approx(d, rel=0.35)
    assert diag.final_gap < 0.5 * diag.baseline_gap
    # The located gap is closed (what is left is the twins' few-repeat scatter elsewhere).
    z = diag_gap.zscores(diag.reals[0], diag.evaluations['final'].stats[0],
                         diag.evaluations['baseline'].stats[0].std)
    assert abs(z['quadrature'][0]) < 3.0


def test_cubic_scale_factor_term_ranks_first_and_closes_the_gap():
    diag = _diagnose([('scale_factor_nonlinearity', {'k2': 0.0, 'k3': 0.1})], seed=42)
    assert diag.ranking[0]['effect'] == 'scale_factor_nonlinearity'
    assert diag.selected_effects[:1] == ['scale_factor_nonlinearity']
    assert any(w['observable'] == 'harmonic_3f' for w in diag.where)
    assert diag.final_gap < min(0.5 * diag.baseline_gap, diag.null_gap['final_model_q95'])


def test_clean_swing_record_raises_no_effect():
    diag = _diagnose([], seed=43)
    assert diag.selected_effects == []
    assert diag.baseline_gap < diag.null_gap['q95']


def test_baseline_takes_the_kalman_estimates():
    imu, enc = _record([], 44)
    est = estimate_swing(imu, enc, 5.0).estimates
    base = diag_swing.fit_baseline(imu, enc, 5.0)
    assert base.scale_factor_error == est.scale_factor_error.value
    assert base.dt == pytest.approx(1.0 / RATE_HZ, rel=1e-4)
    assert base.amplitude == pytest.approx(20.0 * np.pi / 180.0, rel=1e-3)
