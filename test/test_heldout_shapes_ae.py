# Held-out set AE (bench/validate_diagnosis_swing_heldout_ae.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4, and the swing harness reaches the set by
# --held-out ae. THE GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import (AMP, G0, rng, S_N, swing, swing_set_tests, unit_stamp_errors,
                            W)
import numpy as np
import pytest

SWING = bench_script.load('validate_diagnosis_swing_heldout_ae')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'slew': np.inf}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'r': np.inf}, 'scale_factor_asymmetry': {'a': 0.0},
       'timestamp_jitter': {'sigma': 0.0}, 'encoder_cyclic_error': {'o': 0.0}}


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)


def test_spike_guard_limits_each_step_and_lags_by_its_noise_driven_delay():
    fn, levels = SHAPES['time_delay']
    x = rng(1).standard_normal(5000)
    step = 0.3
    y = SWING.slew_limit(x, step)
    want = [x[0]]
    for v in x[1:]:
        want.append(want[-1] + float(np.clip(v - want[-1], -step, step)))
    assert np.allclose(y, want, rtol=0, atol=1e-12)
    assert np.all(np.abs(np.diff(y)) <= step + 1e-12) and y[0] == x[0]
    free = np.abs(np.diff(x)) < 0.05
    assert np.array_equal(SWING.slew_limit(x, 10.0), x) and free.any()
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    assert np.array_equal(ti, t) and np.array_equal(te, t)
    assert np.array_equal(enc, AMP * np.sin(W * t))
    assert np.array_equal(g, SWING.slew_limit(rate, levels[1]['slew'] * 1e-3))
    # The chain's delay against a noisy swing (the same noise without the motion taken off).
    t = np.arange(60000) * 1e-3
    rate, acc = AMP * W * np.cos(W * t), -AMP * W * W * np.sin(W * t)
    delays = [SWING.slew_delay(p['slew'], S_N, 1e-3) for p in levels]
    assert delays[1] > delays[0] > delays[2] > 0 and SWING.slew_delay(np.inf, S_N, 1e-3) == 0
    for p, d in zip(levels, delays):
        n = S_N * rng(2).standard_normal(t.size)
        lag = (SWING.slew_limit(rate + n, p['slew'] * 1e-3)
               - SWING.slew_limit(n, p['slew'] * 1e-3) - rate)
        got = np.linalg.lstsq(np.c_[-acc, rate, np.ones_like(t)][2000:], lag[2000:],
                              rcond=None)[0][0]
        assert got == pytest.approx(d, rel=0.06), p
    n = S_N * rng(3).standard_normal(200000)
    assert np.std(SWING.slew_limit(n, levels[2]['slew'] * 1e-3)) < 0.95 * np.std(n)   # clipped
    assert SWING.slew_gain(20.0) == pytest.approx(1.0, abs=1e-9)


def test_creeping_attach_loads_fast_recovers_slowly_and_makes_odd_lagging_lines():
    fn, levels = SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)

    def f(s):
        return G0 * np.sin(AMP * np.sin(W * s))
    assert np.allclose(g - rate, gy * (f(t) + SWING.creep(t, f)), rtol=0, atol=1e-15)

    def pulse(s):
        return np.where((s >= 0) & (s < 1), 1.0, 0.0)
    u = np.array([0.02, 0.05, 0.1, 0.999, 1.5, 2.0, 3.0])
    c = SWING.creep(np.r_[-1.0, u], pulse)[1:]
    load = 1 - np.exp(-u[:4] / SWING.CREEP_LOAD_S)
    assert np.allclose(c[:4], load, rtol=2e-3)
    after = c[3] * np.exp(-(u[4:] - 1) / SWING.CREEP_UNLOAD_S)
    assert np.allclose(c[4:], after, rtol=5e-3)
    neg = SWING.creep(np.r_[-1.0, u], lambda s: -pulse(s))[1:]
    assert np.allclose(neg, -c, rtol=0, atol=1e-12)                          # odd
    m = 5000                                                                 # one period
    lines = np.abs(np.fft.rfft((g - rate)[-m:])) / m
    assert lines[3] > 0.08 * lines[1] and lines[5] > 0.04 * lines[1]       # linear: 0.005
    assert np.all(lines[2:12:2] < 1e-3 * lines[1])                          # no even lines
    lag = np.angle(np.fft.rfft(f(t[-m:]))[1] / np.fft.rfft((g - rate)[-m:])[1])
    assert np.rad2deg(lag) > 20.0                                            # the bias lags


def test_wound_up_loop_flattens_and_stretches_the_peaks_and_keeps_the_angle():
    fn, levels = SHAPES['scale_factor_nonlinearity']
    r = levels[1]['r']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    assert np.array_equal(ti, t) and np.array_equal(te, t)
    u = g
    assert np.all(np.abs(u) <= r + 1e-12)
    over = np.abs(rate) > r
    assert np.allclose(u[over], r * np.sign(rate[over]), rtol=0, atol=1e-12)
    held = np.abs(np.abs(u) - r) < 1e-12
    assert held.sum() > 1.3 * over.sum()                                  # held past the range
    repaid = ~held & (np.abs(u - rate) > 1e-12)              # the step that ends a repayment
    assert repaid.sum() <= 9                                   # one a peak at most, else u = w
    debt = np.cumsum(rate - u) * 1e-3
    level = np.abs(np.sin(W * t)) > 0.999                                 # between the peaks
    assert np.abs(debt[level]).max() < 1e-9 * np.abs(debt).max() + 1e-12   # no angle lost
    assert np.abs(debt).max() > 1e-3
    x = rate[:3000]
    up = dn = 0.0
    out = []
    for v in x:                                     # apart, each peak's debt is a Lindley walk
        pu, pd = up, dn
        up, dn = max(0.0, up + (v - r) * 1e-3), max(0.0, dn + (-v - r) * 1e-3)
        out.append(v - (up - pu) / 1e-3 + (dn - pd) / 1e-3)
    assert np.allclose(SWING.windup(t[:3000], x, r), out, rtol=0, atol=1e-9)
    fast = 2 * AMP * W * np.cos(2 * W * t)          # 2.5 s: the peak twice the range
    u2 = SWING.windup(t, fast, r)
    debt2 = np.cumsum(fast - u2) * 1e-3
    assert np.all(np.abs(u2) <= r + 1e-12) and np.all(np.isfinite(u2))
    assert np.abs(debt2).max() < 2 * AMP and abs(debt2[-2500:].mean()) < 0.2 * AMP  # bounded
    assert np.any((u2 == r) & (fast < -r))          # still repaying the last peak's debt
    noisy = rate + 0.01 * rng(4).standard_normal(t.size)
    out = fn(t, noisy.copy(), t, enc, lambda s: (AMP * np.sin(W * s), AMP * W * np.cos(W * s)),
             rng(5), r=r)[1]
    assert np.allclose(out - noisy, u - rate, rtol=0, atol=1e-12)            # noise untouched
    t2, rate2, out2 = swing(fn, {'r': 1.001 * AMP * W}, 10.0)
    assert np.array_equal(out2[1], rate2)                                    # inside the range


def test_polarity_relay_reads_each_negative_half_low_by_its_own_contact():
    fn, levels = SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t = np.arange(900000) * 1e-3
    rate = AMP * W * np.cos(W * t)
    stand = (lambda s: (AMP * np.sin(W * s), AMP * W * np.cos(W * s)))
    g = fn(t, rate.copy(), t, t, stand, rng(6), a=a)[1]
    assert np.array_equal(g[rate >= 0], rate[rate >= 0])
    neg = rate < 0
    start = np.flatnonzero(neg[1:] & ~neg[:-1]) + 1
    end = np.flatnonzero(~neg[1:] & neg[:-1]) + 1
    eps = []
    for s0, s1 in zip(start, end[end > start[0]]):
        ratio = 1 - g[s0:s1] / rate[s0:s1]
        assert np.allclose(ratio, ratio[0], rtol=1e-9), s0                   # held a half swing
        eps.append(ratio[0])
    eps = np.array(eps)
    assert eps.size >= 178 and np.all(eps > 0) and np.unique(eps).size == eps.size
    assert np.median(eps) == pytest.approx(a, rel=0.15)
    assert np.std(np.log(eps)) == pytest.approx(SWING.CONTACT_SIGMA, rel=0.15)
    assert abs(np.corrcoef(eps[:-1], eps[1:])[0, 1]) < 0.2                   # a new draw each


def test_network_stamps_are_long_range_dependent_fractional_gaussian_noise():
    fn, levels = SHAPES['timestamp_jitter']
    sigma = levels[1]['sigma']
    x = unit_stamp_errors(fn, sigma, 10)
    assert np.mean(x * x) == pytest.approx(1.0, rel=0.05)
    for lag in (1, 10, 100):                                                # the known mean 0
        got = np.mean(x[:, :-lag] * x[:, lag:])
        assert got == pytest.approx(float(SWING.fgn_cov(lag)), rel=0.12), lag
    assert SWING.fgn_cov(100) / SWING.fgn_cov(10) == pytest.approx(10 ** -0.4, rel=0.01)
    for m in (10, 100, 1000):                                               # self-similar
        blocks = x[:, :x.shape[1] // m * m].reshape(4, -1, m).mean(axis=2)
        assert np.mean(blocks ** 2) == pytest.approx(m ** (2 * SWING.HURST - 2), rel=0.15), m
    grid, table = SWING._fgn_table()
    assert table.mean() == pytest.approx(1.0, rel=1e-9) and table.min() > 0   # int S df = var
    psd = SWING.network_psd(np.array([1.0, 10.0, 100.0]), sigma, 1000.0)
    assert psd[1] / psd[2] == pytest.approx(10 ** 0.6, rel=0.05)             # f^(1 - 2 H)
    assert psd[0] / psd[1] == pytest.approx(10 ** 0.6, rel=0.02)
    assert SWING.network_psd(1000.3, sigma, 1000.0) == pytest.approx(
        float(SWING.network_psd(0.3, sigma, 1000.0)))


def test_overdriven_tracks_err_only_near_the_crests_four_times_a_line():
    fn, levels = SHAPES['encoder_cyclic_error']
    o = levels[1]['o']
    lines = SWING.CLIP_LINES
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    angle = AMP * np.sin(W * t)
    assert np.array_equal(ti, t) and np.array_equal(g, rate) and np.array_equal(te, t)
    assert np.allclose(enc - angle, SWING.clipped_error(angle, o), rtol=0, atol=1e-15)
    phi = np.linspace(0, 2 * np.pi / lines, 40001)
    e = SWING.clipped_error(phi, o)
    u = lines * phi + SWING.CLIP_PHASE
    clipped = np.maximum(np.abs(np.sin(u)), np.abs(np.cos(u))) * (1 + o) > 1
    assert np.all(np.abs(e[~clipped]) < 1e-15) and np.abs(e[clipped]).max() > 0
    v = np.linspace(-0.3, 0.3, 601)                                          # the sine's crest
    crest = (np.pi / 2 + v - SWING.CLIP_PHASE) / lines
    inside = np.abs(np.cos(v)) * (1 + o) > 1
    want = (np.arctan((1 + o) * np.sin(v)) - v) / lines
    assert np.allclose(SWING.clipped_error(crest, o)[inside], want[inside], rtol=0, atol=1e-12)
    quarter = np.pi / 2 / lines
    assert np.allclose(SWING.clipped_error(phi + quarter, o), e, rtol=0, atol=1e-13)
    spec = np.abs(np.fft.rfft(SWING.clipped_error(np.arange(4096) / 4096 * 2 * np.pi / lines,
                                                  o)))
    k = np.arange(spec.size)
    assert np.all(spec[(k % 4 != 0)] < 1e-9 * spec.max())                   # 4, 8, 12 a line
    small = [np.abs(SWING.clipped_error(phi, oo)).max() for oo in (1e-3, 4e-3)]
    assert small[1] / small[0] == pytest.approx(8.0, rel=0.05)              # onset o^(3/2)


def test_swing_harness_takes_set_ae_by_held_out_ae(monkeypatch):
    harness = bench_script.load('validate_diagnosis_swing')
    assert 'ae' in harness.held_out_letters()
    got = harness.held_out_shapes(1000.0, 'ae')
    assert sorted(got) == sorted(SHAPES)
    assert all(got[k][1] == SHAPES[k][1] for k in SHAPES)
    seen = []
    monkeypatch.setattr(harness, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    assert harness.main(['--held-out', 'ae']) == 0
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['time_delay'][1] == SHAPES['time_delay'][1]
