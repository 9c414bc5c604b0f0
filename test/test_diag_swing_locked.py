"""
The swing residual's phase-locked part and the tabulated forms that follow it.

Ground truth: waveforms of known harmonics, the simulator's tables at known coefficients, and
least squares against numpy's on a toy objective.
"""
from types import SimpleNamespace

from gyro_char.diagnosis import swing as diag_swing, swing_locked
from gyro_char.diagnosis.fit import (EffectSpace, Evaluation, fit_effect, LinearTerms,
                                     solve_linear)
from gyro_char.diagnosis.gap import sim_stats
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
import numpy as np
import pytest

PERIOD = 5.0
W = 2 * np.pi / PERIOD


def test_high_harmonics_read_known_coefficients_of_a_waveform_in_noise():
    t = np.arange(0.0, 300.0, 1e-3)
    th = W * t + 0.3
    rng = np.random.default_rng(1)
    want = rng.standard_normal(26) * 1e-5
    r = 1e-4 * np.sin(2 * th) + 2e-6 * rng.standard_normal(t.size)
    for j in range(13):
        r = r + want[2 * j] * np.sin((j + 4) * th) + want[2 * j + 1] * np.cos((j + 4) * th)
    got = swing_locked.high_harmonics(th, r)
    # The noise's own scatter on a coefficient is 2e-6 sqrt(2 / n) = 5e-9.
    assert np.max(np.abs(got - want)) < 3e-8


def test_wave_is_the_harmonic_series_of_its_coefficients():
    th = np.linspace(0.0, 40.0, 9001)
    rng = np.random.default_rng(5)
    low, high = rng.standard_normal(6), rng.standard_normal(26)
    coef = np.r_[low, high].reshape(-1, 2)
    want = sum(a * np.sin((k + 1) * th) + b * np.cos((k + 1) * th)
               for k, (a, b) in enumerate(coef))
    assert swing_locked.wave(th, low, high) == pytest.approx(want, abs=1e-11)


def test_phase_mean_takes_the_waveform_and_leaves_the_noise():
    t = np.arange(0.0, 200.0, 1e-3)
    th = W * t
    rng = np.random.default_rng(2)
    noise = 1e-3 * rng.standard_normal(t.size)
    smooth = 0.01 * np.sin(3 * th) + 0.005 * np.cos(17 * th)
    mean, k = swing_locked.phase_mean(th, smooth + noise)
    left = smooth + noise - mean[k]
    # The waveform is gone; the noise keeps all but 1 / (number of periods) of its power.
    assert np.var(left) == pytest.approx(np.var(noise) * (1 - PERIOD / 200.0), rel=0.02)


def test_locked_bands_hold_the_harmonics_beyond_sixteen_and_a_noise_floor():
    dt, n_per = 1e-3, int(PERIOD / 1e-3)
    f0 = 1.0 / PERIOD
    th = 2 * np.pi * np.arange(n_per) / n_per
    # The 3rd harmonic is below the bands, the 150th (30 Hz) above their top (2 % of 1 kHz).
    mean = (0.02 * np.cos(30 * th) + 0.01 * np.sin(80 * th) + 0.5 * np.cos(3 * th)
            + 0.3 * np.cos(150 * th))
    got = swing_locked.locked_bands(mean, f0, dt)
    edges = swing_locked.locked_edges(f0, dt)
    assert edges[-1] == pytest.approx(20.0)
    want = np.zeros(swing_locked.LOCKED_BANDS)
    for k, a in ((30, 0.02), (80, 0.01)):
        want[np.searchsorted(edges, k * f0) - 1] += a * a / 2
    assert got == pytest.approx(want, abs=1e-12)
    # White noise's phase mean over P periods: 2 sigma^2 / (P n) a harmonic.
    rng = np.random.default_rng(3)
    p, sigma = 40, 0.1
    x = [sigma * rng.standard_normal((p, n_per)).mean(axis=0) for _ in range(20)]
    count = [np.sum((np.arange(n_per // 2 + 1) * f0 >= a) & (np.arange(n_per // 2 + 1) * f0 < b))
             for a, b in zip(edges[:-1], edges[1:])]
    floor = 2 * sigma ** 2 / (p * n_per) * np.array(count)
    got = np.mean([swing_locked.locked_bands(m, f0, dt) for m in x], axis=0)
    assert got == pytest.approx(floor, rel=0.2)


def _swing(effects, seed=0, noise=False, duration=20.0):
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 1000.0}})
    cfg.stand.amplitude_noise = cfg.stand.drift_rate_noise = cfg.stand.drift_rate = 0.0
    cfg.stand.drift_accel = 0.0
    if not noise:
        cfg.noise['gyro_x'] = dict.fromkeys(cfg.noise['gyro_x'], 0.0)
        cfg.gyro.output_step = 0.0
    run = simulator.simulate_swing(cfg, duration=duration, seed=seed, channels=('gyro_x',),
                                   effects=[{'name': n, 'params': p} for n, p in effects])
    return run, cfg


def test_a_table_puts_its_coefficient_on_the_rate_line_at_n_f_on_a_swing_of_its_range():
    base, cfg = _swing([])
    peak = cfg.stand.amplitude * W
    for name, key, order in (('scale_factor_nonlinearity', 'c5', 5),
                             ('scale_factor_asymmetry', 'c4', 4)):
        plain = {'k2': 0.0} if name == 'scale_factor_nonlinearity' else {'a': 0.0}
        run, _ = _swing([(name, {**plain, 'table_rads': peak, key: 1e-3})])
        d = run.imu.channels['gyro_x'] - base.imu.channels['gyro_x']
        th = W * run.imu.t + cfg.stand.phase          # the true rate is peak cos th
        line = 2 * np.mean(d * np.cos(order * th))
        assert line == pytest.approx(1e-3, rel=0.03), name
    zero, _ = _swing([('scale_factor_nonlinearity', {'k2': 0.0, 'table_rads': peak})])
    assert np.array_equal(zero.imu.channels['gyro_x'], base.imu.channels['gyro_x'])


def test_a_table_on_the_sensed_value_bends_the_noise_by_its_slope():
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 1000.0}})
    peak = cfg.stand.amplitude * W
    span = 1.2 * peak                          # beyond the noise: nothing clipped
    fx = ('scale_factor_nonlinearity', {'k2': 0.0, 'table_rads': span, 'c3': 0.02,
                                        'on_output': 1.0})
    true_rate = dict(fx[1], on_output=0.0)
    b, c = (_swing([fx], 4, True)[0],
            _swing([('scale_factor_nonlinearity', true_rate)], 4, True)[0])
    # Same noise n: on the true rate the table adds a deterministic part only; on the sensed
    # value the difference is the noise times the table's slope, c3 (12 u^2 - 3) / span.
    bent = b.imu.channels['gyro_x'] - c.imu.channels['gyro_x']
    u = peak / span * np.cos(W * b.imu.t + cfg.stand.phase)
    sd = cfg.noise['gyro_x']['N'] / np.sqrt(1e-3)
    for lo, hi in ((0.0, 0.1), (0.75, 0.8)):
        m = (np.abs(u) >= lo) & (np.abs(u) < hi)
        slope = 0.02 * np.abs(12 * u[m] ** 2 - 3) / span
        assert np.std(bent[m]) == pytest.approx(sd * np.sqrt(np.mean(slope ** 2)), rel=0.05)


def test_a_speed_dependent_latency_moves_the_stamps_by_the_table_of_the_true_rate():
    base, cfg = _swing([('time_delay', {'delay_s': 0.0})])
    peak = cfg.stand.amplitude * W
    run, _ = _swing([('time_delay', {'delay_s': 0.0, 'table_rads': peak, 'd2': 1e-3})])
    late = run.imu.t - base.imu.t
    u = np.cos(W * base.imu.t + cfg.stand.phase)      # true rate / peak at each sample
    # T_2(u) - T_2(0) = 2 u^2: 2 ms at the peak rate, 0 at the turning points.
    assert late == pytest.approx(1e-3 * 2 * u ** 2, abs=2e-5)
    assert np.all(np.diff(run.imu.t) > 0)


def _toy(reals, means):
    return SimpleNamespace(reals=reals, reference=[{b: np.ones_like(v) for b, v in r.items()}
                                                   for r in reals],
                           evaluate=lambda fx: SimpleNamespace(stats=[SimpleNamespace(
                               mean=m, std=None) for m in means]))


def test_solve_linear_is_the_gap_weighted_least_squares_and_states_its_optimism():
    rng = np.random.default_rng(4)
    basis = {'a': rng.standard_normal((2, 6)), 'b': rng.standard_normal((2, 1))}
    truth = np.array([0.7, -1.3])
    zero = {'a': np.zeros(6), 'b': np.zeros(1), 'c': np.zeros(3)}
    real = {b: truth @ basis[b] for b in ('a', 'b')}
    real['c'] = np.zeros(3)
    obj = _toy([real], [zero])
    terms = LinearTerms(('x', 'y'), ('a', 'b'), (basis,))
    got, optimism = solve_linear(obj, [], terms)
    assert [got['x'], got['y']] == pytest.approx(list(truth), abs=1e-12)
    # Rows weighted 1 / sqrt(block size x blocks): the 1-element block counts as the 6.
    real['a'] = real['a'] + rng.standard_normal(6)
    a = np.vstack([basis['a'].T / np.sqrt(6 * 3), basis['b'].T / np.sqrt(1 * 3)])
    y = np.r_[real['a'] / np.sqrt(6 * 3), real['b'] / np.sqrt(3)]
    want = np.linalg.lstsq(a, y, rcond=None)[0]
    got, optimism = solve_linear(obj, [], terms)
    assert [got['x'], got['y']] == pytest.approx(list(want), rel=1e-10)
    hat = np.diag(a @ np.linalg.pinv(a))
    assert optimism == pytest.approx(np.sum(hat / np.r_[np.full(6, 18.0), 3.0]), rel=1e-10)
    assert 0 < optimism < 2 / 3


def test_fit_effect_solves_a_linear_space_against_what_the_model_leaves():
    calls = []
    basis = {'a': np.array([[1.0, 2.0, 0.0]])}

    class Objective:
        reals = [{'a': np.array([3.0, 6.0, 0.5])}]
        reference = [{'a': np.ones(3)}]

        def evaluate(self, fx):
            calls.append(list(fx))
            c = sum(p.get('x', 0.0) for _, p in fx)
            mean = {'a': c * basis['a'][0]}
            st = sim_stats([mean, mean, mean])
            real = self.reals[0]['a']
            return Evaluation(list(fx), float(np.sqrt(np.mean((real - mean['a']) ** 2))), [st])

    space = EffectSpace('e', [], fixed={'x': 0.0},
                        linear=LinearTerms(('x',), ('a',), (basis,)))
    params, ev = fit_effect(Objective(), [], space)
    assert params['x'] == pytest.approx(3.0)
    assert calls[0] == []            # solved against the model without the effect


@pytest.fixture(scope='module')
def problem():
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 200.0}})
    run = simulator.simulate_swing(cfg, duration=60.0, seed=3, channels=('gyro_x',))
    return diag_swing.swing_problem(run.imu, run.encoder, 5.0), cfg


def test_every_table_is_an_alternative_whose_blocks_are_linear_in_its_coefficients(problem):
    prob, cfg = problem
    tables = {sp.name: [a for a in sp.alternatives if a.linear is not None]
              for sp in prob.spaces}
    assert {n: len(v) for n, v in tables.items() if v} == {
        'scale_factor_nonlinearity': 2, 'scale_factor_asymmetry': 2, 'g_sensitivity': 1,
        'time_delay': 1}
    # Two coefficients at once move the linear blocks by the sum of their probes.
    sp = tables['scale_factor_nonlinearity'][0]
    c = {sp.linear.names[0]: 3e-4, sp.linear.names[2]: -2e-4}
    zero = prob.simulate(0, [], 4242)
    both = prob.simulate(0, [(sp.name, {**sp.fixed, **c})], 4242)
    for b in ('harmonic_3f', 'harmonic_high'):
        want = 3e-4 * sp.linear.basis[0][b][0] - 2e-4 * sp.linear.basis[0][b][2]
        assert both[b] - zero[b] == pytest.approx(want, rel=1e-6, abs=1e-12)
