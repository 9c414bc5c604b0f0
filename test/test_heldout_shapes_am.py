# Held-out set AM (bench/validate_diagnosis_swing_heldout_am.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4 and the levels are the solved ones, and the
# swing harness takes the set by its letter. THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AM."""
import bench_script

from heldout_common import AMP, G0, lines, swing_runner, W
from heldout_common import period_z_ratio, rng, S_N, solved_levels_test, swing_set_tests

import numpy as np

import pytest

SWING = bench_script.load('validate_diagnosis_swing_heldout_am')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'d': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'k3': 0.0}, 'scale_factor_asymmetry': {'a': 0.0},
       'timestamp_jitter': {'sigma': 0.0}, 'encoder_cyclic_error': {'s': 0.0}}
run = swing_runner(SHAPES)


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)

test_levels_are_the_solved_ones = solved_levels_test(SWING)


def test_steered_resampler_wanders_about_its_mean_delay():
    """Check the delay by hand, its law and correlation time, the mean delay's line."""
    d = SHAPES['time_delay'][1][1]['d']
    t, angle, rate, x, out = run('time_delay', {'d': d}, 200.0, noise=S_N, seed=3)
    assert np.array_equal(out[0], t) and np.array_equal(out[2], t)
    assert np.array_equal(out[3], angle)
    u = rng(3).standard_normal(t.size)                             # the wander, by hand
    a = np.exp(-1e-3 / 20.0)
    g = np.empty(t.size)
    g[0] = u[0]
    g[1:] = u[1:] * np.sqrt(1 - a * a)
    for k in range(1, t.size):
        g[k] += a * g[k - 1]
    delays = np.maximum(d * (1 + 0.4 * g), 0.0)
    want = AMP * W * np.cos(W * (t - delays)) - rate
    assert np.allclose(out[1] - x, want, rtol=0, atol=1e-12)
    long = SWING.src_delays(np.arange(2_000_000) * 1e-3, d, rng(5))   # 2000 s: 100 tau
    assert np.mean(long) == pytest.approx(d, rel=0.1)
    assert np.std(long) == pytest.approx(0.4 * d, rel=0.15)
    v = long - long.mean()
    lag = 20000                                                     # 20 s: e^-1
    assert np.mean(v[:-lag] * v[lag:]) / np.var(v) == pytest.approx(np.exp(-1), abs=0.1)
    assert np.mean(long == 0) < 0.01
    err = SWING.src_error(t, lambda v: AMP * W * np.cos(W * v), np.full(t.size, d))
    c = lines(err, 5000)                                            # a constant d's line
    assert abs(c[1]) * 2 == pytest.approx(2 * AMP * W * np.sin(W * d / 2), rel=1e-3)
    assert period_z_ratio(SWING, 'time_delay') == pytest.approx(4.0, rel=0.01)


def test_compensation_radius_leaves_the_tangential_term():
    """Check the residual by hand, its size against the raw term, none at rest, w^2 scaling."""
    gy = SHAPES['g_sensitivity'][1][1]['gy']
    for period in (5.0, 2.5):
        w = 2 * np.pi / period
        t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 20.0, period=period,
                                     noise=S_N)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
        err = out[1] - x
        assert np.allclose(err, gy * 0.5 * w * w * angle, rtol=1e-5, atol=1e-12)
        per = int(period * 1000)
        raw = lines(gy * G0 * np.sin(angle), per)
        ratio = abs(lines(err, per)[1] / raw[1])
        assert ratio == pytest.approx(0.0818 * (5.0 / period) ** 2, rel=0.005)
        assert abs(lines(err, per)[3]) < 1e-6 * abs(lines(err, per)[1])   # no sin^3 part

    def tilted(u):
        return np.full_like(u, 0.3), np.zeros_like(u)
    t = np.arange(2000) * 1e-3
    y = SHAPES['g_sensitivity'][0](t, t * 0, t, t * 0, tilted, rng(0), gy=gy)[1]
    assert np.all(y == 0)                                           # none at rest, tilted
    assert gy * G0 * 180 / np.pi == pytest.approx(5.28, abs=0.01)   # docstring, deg/s/g
    assert period_z_ratio(SWING, 'g_sensitivity') == pytest.approx(4.0, rel=0.01)


def test_charging_electrodes_grow_a_cubic_through_the_run():
    """Check the cubic by hand, its growth, its 3f line against a settled cubic's."""
    k3 = SHAPES['scale_factor_nonlinearity'][1][1]['k3']
    t, angle, rate, x, out = run('scale_factor_nonlinearity', {'k3': k3}, 900.0)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    q = 1 - np.exp(-t / 300.0)
    err = out[1] - x
    assert np.allclose(err, -k3 * q * rate ** 3, rtol=1e-9, atol=1e-15)
    assert abs(err[:100]).max() < 1e-3 * k3 * (AMP * W) ** 3          # nil at power-on
    early, late = (lines(err[k * 5000:(k + 10) * 5000], 5000)[3] for k in (0, 170))
    settled = lines(-k3 * rate ** 3, 5000)[3]
    assert abs(late / settled) == pytest.approx(1 - np.exp(-2.95), rel=0.02)
    assert abs(early / settled) == pytest.approx(np.mean(q[:50000]), rel=0.02)
    assert np.mean(q) == pytest.approx(0.683, abs=0.001)
    assert q[-1] == pytest.approx(0.95, abs=0.001)
    assert period_z_ratio(SWING, 'scale_factor_nonlinearity') == pytest.approx(8.0, rel=0.01)


def test_regenerating_driver_gains_only_while_the_rate_falls():
    """Check the gate, both directions, its 2f line against a |w|'s, even lines only."""
    a = SHAPES['scale_factor_asymmetry'][1][1]['a']
    t, angle, rate, x, out = run('scale_factor_asymmetry', {'a': a}, 20.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    err = out[1] - x
    fall = np.abs(np.cos(W * t)) < np.abs(np.cos(W * (t - 1e-4)))
    assert np.allclose(err, np.where(fall, a * np.abs(rate), 0.0), rtol=1e-12, atol=1e-15)
    phase = np.mod(W * t, np.pi)                                # peak rate at 0, turn at pi/2
    inner = np.minimum(np.abs(phase - np.pi / 2), np.minimum(phase, np.pi - phase)) > 0.01
    assert np.all(fall[inner] == (phase[inner] < np.pi / 2))
    assert np.any(fall & (rate > 0.1)) and np.any(fall & (rate < -0.1))   # both directions
    c, full = lines(err, 5000), lines(a * np.abs(rate), 5000)
    assert c[2].real / full[2].real == pytest.approx(0.5, abs=0.003)
    assert abs(c[2].imag / full[2].real) == pytest.approx(1.0, abs=0.005)
    assert abs(c[2] / full[2]) == pytest.approx(1.118, abs=0.005)
    assert np.degrees(abs(np.angle(c[2] / full[2]))) == pytest.approx(63.4, abs=0.3)
    assert c[0].real == pytest.approx(full[0].real / 2, rel=0.003)
    assert np.abs(c[1:60:2]).max() < 1e-3 * abs(c[2])                  # no odd lines
    assert period_z_ratio(SWING, 'scale_factor_asymmetry') == pytest.approx(2.0, rel=0.01)


def test_kicked_stand_jitters_only_near_the_level():
    """Check the errors by hand, their gate and duty, law, whiteness, the angle noise's PSD."""
    fn, levels = SHAPES['timestamp_jitter']
    sigma = levels[1]['sigma']
    t = np.arange(200000) * 1e-3
    angle = AMP * np.sin(W * t)

    def stand(u):
        return AMP * np.sin(W * u), AMP * W * np.cos(W * u)
    out = fn(t, t * 0, t.copy(), angle.copy(), stand, rng(4), sigma=sigma)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    assert np.all(np.diff(out[2]) > 0)
    e = out[2] - t
    gate = np.abs(angle) < np.deg2rad(3.0)
    assert np.allclose(e, np.where(gate, sigma * rng(4).standard_normal(t.size), 0.0),
                       rtol=0, atol=1e-12)
    assert np.all(e[~gate] == 0)
    assert np.mean(gate) == pytest.approx(2 / np.pi * np.arcsin(3 / 20), abs=0.002)   # 9.6 %
    z = e[gate] / sigma
    assert np.std(z) == pytest.approx(1.0, abs=0.02) and abs(np.mean(z)) < 0.03
    assert abs(np.corrcoef(z[:-1], z[1:])[0, 1]) < 0.03
    assert abs(np.mean(z ** 4) - 3) < 0.15
    ang = AMP * W * np.cos(W * t) * e                             # the angle error w dt
    assert np.var(ang) * 1e-3 == pytest.approx(SWING.kick_psd(sigma, AMP, W, 1000.0),
                                               rel=0.05)
    assert np.abs(ang).max() < AMP * W * 6 * sigma
    assert period_z_ratio(SWING, 'timestamp_jitter') == pytest.approx(1.96, abs=0.02)


def test_recalibrated_interpolator_draws_a_new_error_each_run():
    """Check atan2 by hand, the first-order harmonics, a new draw per run, rms sizes."""
    s = SHAPES['encoder_cyclic_error'][1][1]['s']
    errs = []
    for seed in range(3):
        t, angle, rate, x, out = run('encoder_cyclic_error', {'s': s}, 20.0, seed=seed)
        assert np.array_equal(out[0], t) and np.array_equal(out[1], x)
        o_s, o_c, r, dl = s * rng(seed).standard_normal(4)
        u = 720 * angle
        got = np.arctan2((1 + r / 2) * np.sin(u) + o_s, (1 - r / 2) * np.cos(u + dl) + o_c)
        want = np.angle(np.exp(1j * (got - u))) / 720
        e = out[3] - angle
        assert np.allclose(e, want, rtol=0, atol=1e-15)
        first = o_s * np.cos(u) - o_c * np.sin(u)
        lin = (first + r / 2 * np.sin(2 * u) + dl / 2 * (1 - np.cos(2 * u))) / 720
        assert np.abs(e - lin).max() < 0.02 * np.abs(lin - dl / 1440).max()
        errs.append(e)
    assert not np.allclose(errs[0], errs[1], rtol=0, atol=1e-9)      # a new draw each run
    draws = rng(9).standard_normal((20000, 4))
    first = np.hypot(draws[:, 0], draws[:, 1]) * s / 720
    second = np.hypot(draws[:, 2], draws[:, 3]) * s / 1440
    assert np.sqrt(np.mean(first ** 2)) == pytest.approx(np.sqrt(2) * s / 720, rel=0.02)
    assert np.sqrt(np.mean(second ** 2)) == pytest.approx(s / (np.sqrt(2) * 720), rel=0.02)
    assert 2 * np.pi / 720 * 180 / np.pi * 3600 == pytest.approx(1800.0)   # docstring pitch
    assert period_z_ratio(SWING, 'encoder_cyclic_error') == pytest.approx(1.75, abs=0.02)


def test_swing_harness_takes_set_am_by_held_out_am(monkeypatch):
    harness = bench_script.load('validate_diagnosis_swing')
    assert 'am' in harness.held_out_letters()
    got = harness.held_out_shapes(1000.0, 'am')
    assert sorted(got) == sorted(SHAPES)
    assert all(got[k][1] == SHAPES[k][1] for k in SHAPES)
    seen = []
    monkeypatch.setattr(harness, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    assert harness.main(['--held-out', 'am']) == 0
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['time_delay'][1] == SHAPES['time_delay'][1]
