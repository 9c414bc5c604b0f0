# Held-out set AI (bench/validate_diagnosis_swing_heldout_ai.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4 and the levels are the solved ones, and the
# swing harness finds the set (by bench/heldout_sets). THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AI."""
import bench_script

from heldout_common import AMP, G0, lines, swing_runner, W
from heldout_common import period_z_ratio, rng, S_N, solved_levels_test, swing_set_tests

import numpy as np

import pytest

from scipy import signal, stats

SWING = bench_script.load('validate_diagnosis_swing_heldout_ai')
SETS = bench_script.load('heldout_sets')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'eps': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'a': 0.0}, 'scale_factor_asymmetry': {'a': 0.0},
       'timestamp_jitter': {'slot': 0.0}, 'encoder_cyclic_error': {'a': 0.0}}
run = swing_runner(SHAPES)


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)

test_levels_are_the_solved_ones = solved_levels_test(SWING)


def test_counted_stamps_ramp_from_each_resync_and_drop_back():
    """Check the latency eps (t - t_anchor), the resync gaps' law, the order and the mean."""
    eps = SHAPES['time_delay'][1][1]['eps']
    gaps, means, want_means = [], [], []
    for seed in range(6):
        t, angle, rate, x, (ti, g, te, enc) = run('time_delay', {'eps': eps}, 900.0,
                                                  noise=S_N, seed=seed)
        assert np.array_equal(g, x) and np.array_equal(te, t) and np.array_equal(enc, angle)
        draw = rng(seed).uniform(0.5, 1.5, 3000)[:int(900.0 / 10.0) + 2] * 20.0
        syncs = np.r_[0.0, np.cumsum(draw)]
        first = [int(np.ceil(s * 1000 - 1e-6)) for s in syncs if s * 1000 <= 899999]
        anchor = np.zeros(t.size)
        for k in first:
            anchor[k:] = t[k]
        want = t + eps * (t - anchor)
        for k in first[1:]:                                  # kept in order, 0.1 step apart
            j = k
            while want[j] < want[j - 1] + 1e-4:
                want[j] = want[j - 1] + 1e-4
                j += 1
        assert np.allclose(ti, want, rtol=0, atol=1e-12)
        assert np.all(np.diff(ti) >= 1e-4 * (1 - 1e-9)) and ti[0] == t[0]
        lat = ti - t
        drops = np.flatnonzero(np.diff(lat) < -1e-9) + 1
        starts = drops[np.r_[True, np.diff(drops) > 1]]
        assert np.array_equal(starts, np.array(first[1:]))  # it drops back at each resync
        raw = np.abs(ti - (t + eps * (t - anchor))) < 1e-12     # not held back for order
        ramp = np.diff(lat)[raw[1:] & raw[:-1] & (np.diff(anchor) == 0)]
        assert np.allclose(ramp, eps * 1e-3, rtol=1e-5) and np.mean(raw) > 0.99
        gaps.extend(np.diff(t[first]).tolist())
        means.append(lat.mean())
        edges = t[first + [t.size - 1]]
        want_means.append(eps * np.sum(np.diff(edges) ** 2) / 2 / 900.0)
        assert lat.max() <= eps * 30.0 + 1e-9
    gaps = np.array(gaps)
    assert gaps.min() >= 10.0 - 1e-3 and gaps.max() <= 30.0 + 1e-3
    assert gaps.mean() == pytest.approx(20.0, abs=1.2)
    assert stats.kstest((gaps - 10.0) / 20.0, 'uniform').pvalue > 1e-3
    assert np.allclose(means, want_means, rtol=5e-3)        # the sawtooth's own mean
    g = np.linspace(10.0, 30.0, 200001)                      # the gaps' uniform law
    mean = eps * np.trapezoid(g * g, g) / (2 * np.trapezoid(g, g))
    assert SWING.counted_mean(eps) == pytest.approx(mean, rel=1e-9)
    assert SWING.counted_mean(eps) == pytest.approx(10.83 * eps, rel=1e-3)   # docstring
    assert np.mean(means) == pytest.approx(SWING.counted_mean(eps), rel=0.1)
    assert period_z_ratio(SWING, 'time_delay') == pytest.approx(4.0, rel=0.01)


def test_play_sticks_after_each_turning_point():
    """Check the play's recursion, its lag and lines at 20 deg and the stuck small swing."""
    gy = SHAPES['g_sensitivity'][1][1]['gy']
    h = SWING.PLAY
    t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 20.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    p, want = 0.0, []
    for f in (G0 * np.sin(angle)).tolist():
        p = min(max(p, f - h), f + h)
        want.append(p)
    assert np.allclose(out[1] - x, gy * np.array(want), rtol=1e-9, atol=1e-15)
    walk = np.cumsum(rng(3).standard_normal(20000))
    walk[500:600] = walk[500]                                 # a flat stretch
    p, ref = 0.0, []
    for f in walk.tolist():
        p = min(max(p, f - 2.0), f + 2.0)
        ref.append(p)
    assert np.allclose(SWING.play(walk, 2.0), ref, rtol=0, atol=1e-12)
    f = G0 * np.sin(angle)
    c, raw = lines((out[1] - x)[t >= 5.0], 5000), lines(gy * f[t >= 5.0], 5000)
    assert abs(c[1] / raw[1]) == pytest.approx(0.65, abs=0.005)
    assert np.degrees(np.angle(c[1] / raw[1])) == pytest.approx(-29.0, abs=0.5)   # behind
    assert abs(c[3] / c[1]) == pytest.approx(0.16, abs=0.005)
    assert np.abs(c[2:40:2]).max() < 1e-9 * abs(c[1])                 # odd lines only
    top = (out[1] - x)[(t >= 5.0) & (t < 10.0)]
    assert top.max() == pytest.approx(gy * (G0 * np.sin(AMP) - h), rel=1e-9)
    held = SWING.play(f, h)[(t >= 5.0) & (t < 10.0)]
    stuck = np.mean(np.diff(held) == 0)                     # stuck past each turning point
    turn = np.arcsin(np.sin(AMP) - 2 * h / G0)              # the tilt at which it moves again
    assert stuck == pytest.approx(np.arccos(turn / AMP) / np.pi, abs=0.002)
    small = run('g_sensitivity', {'gy': gy}, 20.0, amp=np.deg2rad(8.5))
    assert np.all(small[4][1] == small[3])                  # never moves from the level's 0
    wide = run('g_sensitivity', {'gy': gy}, 20.0, amp=np.deg2rad(9.5))
    assert np.ptp((wide[4][1] - wide[3])[wide[0] >= 1.25]) > 0.1 * gy
    assert np.degrees(np.arcsin(h / G0)) == pytest.approx(8.8, abs=0.05)
    assert period_z_ratio(SWING, 'g_sensitivity') == pytest.approx(1.0, abs=0.01)


def test_segmented_dac_is_an_odd_kinked_random_walk():
    """Check the INL's build from the mismatches, the error by hand, odd lines, memorylessness."""
    table = np.array(SWING.inl_table())
    n = SWING.INL_SEGMENTS
    assert table.size == n + 1 and table[0] == 0.0 and abs(table[-1]) < 1e-12
    assert np.abs(table).max() == pytest.approx(1.0, rel=1e-12)
    assert np.argmax(np.abs(table)) * SWING.INL_FULL / n == pytest.approx(0.8)   # docstring
    mismatch = np.random.default_rng(SWING.INL_SEED).standard_normal(n)
    slope = np.diff(table)
    scale = np.dot(slope, mismatch - mismatch.mean()) / np.dot(slope, slope)
    assert np.allclose(slope * scale, mismatch - mismatch.mean(), rtol=1e-9, atol=1e-12)
    a = SHAPES['scale_factor_nonlinearity'][1][1]['a']
    t, angle, rate, x, out = run('scale_factor_nonlinearity', {'a': a}, 20.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    seg = SWING.INL_FULL / n
    want = []
    for v in rate.tolist():
        j = min(int(abs(v) // seg), n - 1)
        u = abs(v) / seg - j
        want.append(np.sign(v) * a * ((1 - u) * table[j] + u * table[j + 1]))
    assert np.allclose(out[1] - x, want, rtol=1e-9, atol=1e-15)
    c = lines(out[1] - x, 5000)
    assert np.abs(c[2:60:2]).max() < 1e-9 * np.abs(c[3:60:2]).max()      # odd lines only
    assert np.abs(c[5:60:2]).max() > 0.1 * abs(c[3])                     # kinked: rich lines
    v = np.array([-0.3, 0.05, 0.3, 2.0, -2.0])
    assert np.allclose(SWING.inl_error(v, 1.0), [-table[6], table[1], table[6], 0.0, 0.0],
                       rtol=1e-9, atol=1e-12)

    k = np.arange(1, 5000)                           # memoryless: equal rates, equal errors
    assert np.allclose((out[1] - x)[k], (out[1] - x)[5000 - k], rtol=1e-6, atol=1e-15)
    assert int(np.sum(np.arange(1, n) * seg < AMP * W)) == 8         # kinks under the peak
    assert int(np.sum(np.arange(1, n) * seg < 2 * AMP * W)) == 17
    assert period_z_ratio(SWING, 'scale_factor_nonlinearity') == pytest.approx(1.1, abs=0.02)


def test_bootstrap_droops_through_each_positive_half_swing():
    """Check the droop's recursion, its steady range at each pace, positive rates only."""
    a = SHAPES['scale_factor_asymmetry'][1][1]['a']
    t, angle, rate, x, out = run('scale_factor_asymmetry', {'a': a}, 20.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    d, want = 0.0, []
    for v in rate.tolist():
        if v > 0:
            d = 1.0 - (1.0 - d) * np.exp(-v * 1e-3 / SWING.DROOP_Q)
        else:
            d = d * np.exp(-1e-3 / SWING.DROOP_TAU)
        want.append(d)
    want = np.array(want)
    err = out[1] - x
    assert np.allclose(err, np.where(rate > 0, -a * want * rate, 0.0), rtol=1e-9, atol=1e-15)
    assert np.all(err[rate <= 0] == 0) and np.all(err[rate > 0] <= 0)
    c = lines(err[t >= 10.0], 5000)
    assert abs(c[2]) > 0.1 * abs(c[1]) and abs(c[3]) > 0.05 * abs(c[1])   # even and odd
    for period, lo, hi in ((5.0, 0.069, 0.84), (2.5, 0.25, 0.87)):
        w = 2 * np.pi / period
        alpha, beta = np.exp(-2 * AMP / SWING.DROOP_Q), np.exp(-period / 2 / SWING.DROOP_TAU)
        top = (1 - alpha) / (1 - alpha * beta)                # end of a positive half-swing
        t = np.arange(int(6 * period * 1000)) * 1e-3
        rate = AMP * w * np.cos(w * t)
        last = SWING.droop(rate, 1e-3)[t >= 5 * period]
        assert last.max() == pytest.approx(top, rel=2e-3) and top == pytest.approx(hi, abs=0.005)
        assert last.min() == pytest.approx(beta * top, rel=5e-3)
        assert beta * top == pytest.approx(lo, abs=0.005)
    steady = SWING.droop(np.full(3000, 0.2), 1e-3)                 # a steady positive rate
    assert np.allclose(steady, 1 - np.exp(-0.2 * np.arange(1, 3001) * 1e-3 / SWING.DROOP_Q))
    assert period_z_ratio(SWING, 'scale_factor_asymmetry') == pytest.approx(2.0, abs=0.03)


def test_sample_and_hold_rotation_slips_at_random():
    """Check the units' stamp errors, the slips' share, the covariance law and the PSD."""
    fn, levels = SHAPES['timestamp_jitter']
    slot = levels[1]['slot']
    t = np.arange(2 ** 18) * 1e-3
    values = slot * np.array([1.5, -0.5, 0.5, -1.5])          # units 0-3: slots 0, 2, 1, 3
    errs, steps = [], []
    for seed in range(4):
        out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(30 + seed), slot=slot)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], np.sin(W * t))
        assert np.all(np.diff(out[2]) > 0)
        e = out[2] - t
        unit = np.argmin(np.abs(e[:, None] - values[None, :]), axis=1)
        assert np.allclose(e, values[unit], rtol=0, atol=1e-12)
        steps.append(np.diff(unit) % 4)
        errs.append(e)
    steps = np.concatenate(steps)
    assert set(np.unique(steps)) == {1, 2}
    assert np.mean(steps == 2) == pytest.approx(SWING.SLIP, abs=0.0006)
    e = np.concatenate(errs)
    assert np.mean(e) == pytest.approx(0.0, abs=0.01 * slot)
    assert np.std(e) / slot == pytest.approx(np.sqrt(1.25), rel=0.01)     # 1.12 slot rms
    p = SWING.SLIP
    f = np.linspace(-500.0, 500.0, 200001)
    psd = SWING.slot_psd(f, slot, 1000.0)
    assert np.trapezoid(psd, f) == pytest.approx(1.25 * slot ** 2, rel=1e-4)
    for lag in range(0, 13):                         # covariance from the chain, lag by lag
        pmf = stats.binom.pmf(np.arange(lag + 1), lag, p)
        acv = slot ** 2 * sum(q * np.mean(values / slot * np.roll(values / slot, -(lag + j)))
                              for j, q in enumerate(pmf))
        assert np.trapezoid(psd * np.cos(2 * np.pi * f * lag / 1000.0), f) == (
            pytest.approx(acv, rel=1e-3, abs=1e-4 * slot ** 2)), lag
        got = np.mean([np.mean(u[:u.size - lag] * u[lag:]) for u in errs])
        assert got == pytest.approx(acv, abs=0.02 * slot ** 2), lag
    fw, pxx = signal.welch(np.array(errs), fs=1000.0, nperseg=8192, return_onesided=True)
    pxx = pxx.mean(axis=0)
    for lo, hi in ((230.0, 275.0), (460.0, 500.0), (50.0, 200.0)):
        band = (fw >= lo) & (fw < hi)
        got = np.sum(pxx[band]) * (fw[1] - fw[0])
        grid = np.linspace(lo, hi, 20001)
        want = 2 * np.trapezoid(SWING.slot_psd(grid, slot, 1000.0), grid)
        assert got == pytest.approx(want, rel=0.1), (lo, hi)
    assert np.mean(values * (-1) ** np.arange(4)) ** 2 / np.mean(values ** 2) == 0.8   # 500 Hz
    assert period_z_ratio(SWING, 'timestamp_jitter') == pytest.approx(1.66, abs=0.03)


def test_smudge_confines_the_cyclic_error_to_a_stretch():
    """Check the error by its formula, where it lives, its frequency in the swing, still stand."""
    a = SHAPES['encoder_cyclic_error'][1][1]['a']
    t, angle, rate, x, out = run('encoder_cyclic_error', {'a': a}, 20.0)
    assert np.array_equal(out[0], t) and np.array_equal(out[1], x)
    e = out[3] - angle
    x0 = (angle - np.deg2rad(9.0)) / np.deg2rad(2.5)
    assert np.allclose(e, a * np.exp(-x0 ** 2 / 2) * np.sin(5000 * angle + SWING.SPOT_PHASE),
                       rtol=1e-9, atol=1e-15)
    assert np.abs(e[angle <= 0]).max() < 2e-3 * a
    assert np.abs(e[angle > np.deg2rad(19.9)]).max() < 1.2e-4 * a
    assert SWING.spot_error(np.linspace(0.1, 0.2, 400001), a).max() == pytest.approx(a, rel=1e-3)
    near = np.abs(angle - np.deg2rad(9.0)) < np.deg2rad(1.0)
    assert np.abs(e[near]).max() > 0.9 * a
    window = (t >= 0.05) & (t < 0.70)                       # the first crossing, rising
    spec = np.abs(np.fft.rfft(e[window] * np.hanning(window.sum())))
    freq = np.fft.rfftfreq(window.sum(), 1e-3)
    assert freq[np.argmax(spec)] == pytest.approx(312.0, abs=8.0)
    for period, alias in ((2.5, 377.0),):
        t2, angle2, rate2, x2, out2 = run('encoder_cyclic_error', {'a': a}, 5.0, period=period)
        win = (t2 >= 0.02) & (t2 < 0.35)
        spec = np.abs(np.fft.rfft((out2[3] - angle2)[win] * np.hanning(win.sum())))
        freq = np.fft.rfftfreq(win.sum(), 1e-3)
        assert freq[np.argmax(spec)] == pytest.approx(alias, abs=15.0)

    def still(u):
        return np.full_like(u, SWING.SPOT_PHI), np.zeros_like(u)
    t = np.arange(2000) * 1e-3
    enc = SHAPES['encoder_cyclic_error'][0](t, t * 0, t.copy(), np.full(t.size, SWING.SPOT_PHI),
                                            still, rng(0), a=a)[3]
    assert np.allclose(enc - SWING.SPOT_PHI,
                       a * np.sin(2 * SWING.SPOT_LINES * SWING.SPOT_PHI + SWING.SPOT_PHASE))
    assert 2 * np.pi / SWING.SPOT_LINES * 180 / np.pi * 3600 == pytest.approx(518.4, abs=0.1)
    assert period_z_ratio(SWING, 'encoder_cyclic_error') == pytest.approx(0.78, abs=0.02)


def test_swing_harness_finds_set_ai():
    """Check that the held-out set list the harness offers includes ai, by its file alone."""
    assert 'ai' in SETS.letters('validate_diagnosis_swing_heldout', 'b')
    assert SETS.module('validate_diagnosis_swing_heldout', 'ai', 'b') == SWING.__name__
