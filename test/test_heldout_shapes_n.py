# Held-out set N (bench/validate_diagnosis_heldout_n.py, static, and
# bench/validate_diagnosis_swing_heldout_n.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out n. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT,
                            fold_lines, G0, load_set, N_ARW, noisy_run, rng, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('n')


def acf(y, lags):
    y = y - y.mean()
    return np.array([np.mean(y[:-k] * y[k:]) for k in lags]) / np.mean(y * y)


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_idle_averager_smooths_only_during_markov_idle_spells():
    fn, levels = SHAPES['internal_lowpass']
    assert np.allclose(fn(np.full(50000, 0.003), rng(1), share=0.5), 0.003, rtol=1e-12)
    n, share = 2 ** 21, 0.5
    x = rng(2).standard_normal(n)
    y = fn(x.copy(), rng(3), share=share)
    idle = STATIC.idle_spells(n, share, DT, rng(3))
    box = np.convolve(np.r_[np.full(3, x[0]), x], np.full(4, 0.25), 'valid')
    assert np.allclose(y[idle], box[idle]) and np.array_equal(y[~idle], x[~idle])
    assert np.mean(idle) == pytest.approx(share, abs=0.05)
    edges = np.flatnonzero(np.diff(idle.astype(int)))
    spells = np.diff(edges)[0 if idle[edges[0] + 1] else 1::2] * DT
    assert np.mean(spells) == pytest.approx(STATIC.IDLE_S, rel=0.12)
    pooled = np.sum(y[1:] * y[:-1]) / np.sum(y * y)
    assert pooled == pytest.approx(STATIC.idle_r1(np.mean(idle), DT), abs=3 / np.sqrt(n))
    assert acf(y[idle], [1])[0] == pytest.approx(0.75, abs=0.02)    # 4-sample box inside
    assert abs(acf(y[~idle], [1])[0]) < 0.02


def test_hum_folds_to_a_constant_amplitude_line_wandering_about_zero(monkeypatch):
    fn, _ = SHAPES['vibration']
    monkeypatch.setattr(STATIC, 'GRID_SD', 0.0)
    y = fn(np.zeros(10000), rng(4), amplitude=1.0)
    assert np.ptp(y) < 1e-9                                         # 100 Hz at 100 Hz: DC
    monkeypatch.undo()
    ys = np.array([fn(np.zeros(2 ** 19), rng(5 + i), amplitude=1.0) for i in range(4)])
    assert np.max(np.abs(ys)) <= 1.0 + 1e-12 and np.var(ys) == pytest.approx(0.5, rel=0.15)
    assert stats.kurtosis(ys.ravel()) < -1.0                        # arcsine-like marginal
    f, p = signal.welch(ys, fs=1 / DT, nperseg=2 ** 14)
    p = p.mean(axis=0)
    assert np.sum(p[f < 0.2]) > 0.97 * np.sum(p)                    # folded to the lowest decade
    for lag in (0.5, 2.0, 5.0):
        k = int(lag / DT)
        got = np.mean([np.mean(v[:-k] * v[k:]) for v in ys])
        assert got == pytest.approx(STATIC.hum_cov(lag, 1.0), abs=0.06), lag


def test_chamber_staircase_settles_through_its_lag_at_every_step():
    fn, levels = SHAPES['temperature_drift']
    amp = levels[1]['amplitude']
    y = fn(np.zeros(720000), rng(6), amplitude=amp)
    t = np.arange(720000) * DT + rng(6).uniform(600, 1800)
    assert np.allclose(y, STATIC.staircase(t, amp), rtol=1e-12, atol=0)
    s = STATIC.staircase(np.array([1199.0, 1500.0, 2400.0, 2700.0, 7199.0]), 1.0)
    assert s == pytest.approx([0.0, 1 - np.exp(-1), 1 - np.exp(-4), 2 - np.exp(-5) - np.exp(-1),
                               5 - sum(np.exp(-(7199 - 1200 * j) / 300) for j in range(1, 6))],
                              abs=1e-6)
    assert np.all(np.diff(y) >= 0)                                  # never returns
    z = STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW)
    w = STATIC.staircase(np.arange(720000) * DT + 1200.0, amp)
    assert z == pytest.approx(np.std(w) * np.sqrt(720000) / SIG, rel=1e-9)


def test_comparator_trim_is_two_levels_with_the_arcsine_law_autocovariance():
    fn, _ = SHAPES['bias_instability']
    ys = np.array([fn(np.zeros(2 ** 19), rng(10 + i), b=1.0) for i in range(6)])
    assert set(np.unique(ys)) == {-1.0, 1.0}
    assert abs(np.mean(ys)) < 0.2                                   # 1/f: slow, so a loose test
    g = STATIC.reference(2 ** 19, DT, rng(10))
    assert np.array_equal(ys[0], np.sign(g))
    assert np.var(g) == pytest.approx(1.0, rel=0.5)
    for lag in (0.05, 1.0, 10.0):
        k = int(lag / DT)
        got = np.mean([np.mean(v[:-k] * v[k:]) for v in ys])
        assert got == pytest.approx(float(STATIC.trim_cov(lag, 1.0)), abs=0.08), lag
    tau = np.geomspace(0.2, 300, 7)
    want = STATIC.cov_avar(lambda u: STATIC.trim_cov(u, 1.0), tau)
    slope = np.polyfit(np.log(tau), np.log(want), 1)[0]
    assert abs(slope) < 0.3                                         # near a flicker floor
    for m in (100, 1000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        assert got == pytest.approx(STATIC.cov_avar(lambda u: STATIC.trim_cov(u, 1.0),
                                                    m * DT)[0], rel=0.3)


def test_creep_is_a_geometric_martingale_whose_intensity_grows():
    fn, levels = SHAPES['rate_random_walk']
    k = 1e-3
    s0 = k / np.sqrt(STATIC.CREEP)
    y = fn(np.zeros(720000), rng(20), k=k)
    logs = np.diff(np.r_[0.0, np.log1p(y / s0)])                    # Brownian with drift
    assert np.var(logs) == pytest.approx(STATIC.CREEP * DT, rel=0.01)
    assert np.mean(logs) == pytest.approx(-STATIC.CREEP * DT / 2, abs=5 * np.sqrt(
        STATIC.CREEP * DT / logs.size))
    assert abs(acf(logs, [1])[0]) < 0.01
    ys = np.array([fn(np.zeros(720000), rng(21 + i), k=k) for i in range(24)])
    steps = np.diff(ys, axis=1)
    assert abs(np.mean(acf(steps.ravel(), [1]))) < 0.01             # uncorrelated increments
    level = STATIC.CREEP * DT * (s0 + ys[:, :-1]) ** 2              # intensity follows the level
    assert np.mean(steps ** 2) / np.mean(level) == pytest.approx(1.0, rel=0.01)
    big = ys[:, :-1] > np.median(ys)
    assert np.mean(steps[big] ** 2) > np.mean(steps[~big] ** 2)
    assert np.mean(steps ** 2) == pytest.approx(
        k * k * DT * STATIC.creep_mean_intensity(720000 * DT), rel=0.3)
    assert stats.skew(ys[:, -1]) > 0.5                              # a log-normal excursion


def test_amphoteric_trap_has_three_levels_and_exponential_correlation():
    fn, _ = SHAPES['gauss_markov']
    tc = 0.5
    y = fn(np.zeros(2 ** 21), rng(30), sd=1.0, tc=tc)
    top = 1 / np.sqrt(1 - STATIC.NEUTRAL)
    assert np.unique(np.round(y, 9)) == pytest.approx([-top, 0.0, top])
    assert np.mean(y == 0) == pytest.approx(STATIC.NEUTRAL, abs=0.01)
    assert np.mean(y > 0) == pytest.approx(np.mean(y < 0), abs=0.01)
    assert np.std(y) == pytest.approx(1.0, rel=0.03)
    assert stats.kurtosis(y) == pytest.approx(2.0, abs=0.3)
    for lag in (25, 50, 100):
        assert acf(y, [lag])[0] == pytest.approx(np.exp(-lag * DT / tc), abs=0.03)
    state = (y != 0).astype(int)
    edges = np.flatnonzero(np.diff(state))
    runs = np.diff(edges) * DT
    charged = runs[0::2] if state[edges[0] + 1] else runs[1::2]
    neutral = runs[1::2] if state[edges[0] + 1] else runs[0::2]
    assert np.mean(charged) == pytest.approx(tc, rel=0.05)
    assert np.mean(neutral) == pytest.approx(tc * 4, rel=0.05)


def test_latch_skew_glitches_a_whole_coarse_step_against_the_rate():
    fn, levels = SHAPES['quantization']
    n = 2 ** 21
    x = SIG * rng(40).standard_normal(n) + STATIC.BIAS
    q = STATIC.COARSE
    for p in levels[:2]:
        y = fn(x.copy(), rng(41), **p)
        theta0 = rng(41).uniform(0, 1000 * q)
        theta = theta0 + np.cumsum(x) * DT
        read = STATIC.split_read(np.r_[theta0, theta], np.r_[0.0, p['s'] * x])
        assert np.allclose(y, np.diff(read) / DT, rtol=0, atol=1e-9)
        glitch = (read - STATIC.split_read(np.r_[theta0, theta], 0.0))[1:] / q
        edge = np.floor(theta / q) != np.floor((theta - p['s'] * x) / q)
        assert np.array_equal(np.round(glitch) != 0, edge)
        assert np.allclose(glitch[edge], -np.sign(x[edge]))
        want_p = p['s'] * np.mean(np.abs(x)) / q
        assert np.mean(edge) == pytest.approx(want_p, rel=0.05)
        ex = avar(y, [1, 10]) - avar(x, [1, 10])
        for m, got in zip((1, 10), ex):
            want = STATIC.skew_excess(p['s'], DT, SIG, N_ARW, m) * N_ARW ** 2 / (m * DT)
            assert got == pytest.approx(want, rel=0.12), (p, m)


def test_tuned_mount_has_two_peaks_around_an_anti_resonance():
    fn, _ = SHAPES['resonance']
    y = fn(np.zeros(2 ** 21), rng(50), sigma=1.0)
    assert np.std(y) == pytest.approx(1.0, rel=0.05)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.tmd_psd(f, 1.0, DT)
    fa = STATIC.MOUNT_HZ / (1 + STATIC.ABSORBER)
    g = np.linspace(15, 35, 20001)
    exact = STATIC.tmd_psd(g, 1.0, DT)
    notch = g[(g > fa - 1) & (g < fa + 1)][np.argmin(exact[(g > fa - 1) & (g < fa + 1)])]
    assert notch == pytest.approx(fa, abs=0.05)
    peaks = g[signal.argrelmax(exact)[0]]
    assert peaks.size == 2 and peaks[0] < fa < peaks[1]
    assert np.min(exact[(g > fa - 0.2) & (g < fa + 0.2)]) < 1e-3 * exact.max()
    assert STATIC.tmd_psd(np.array([0.0]), 1.0, DT)[0] < 1e-12       # a zero at DC
    for c in peaks:
        k = np.abs(f - c) < 1.0
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.2), c
    k = np.abs(f - fa) < 0.3
    assert np.mean(p[k]) < 0.05 * np.mean(p[np.abs(f - peaks[0]) < 0.3])


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_adaptive_smoother_lags_near_rest_and_not_at_speed():
    fn, levels = SWING_SHAPES['time_delay']
    tau0 = levels[1]['tau0']
    t, rate, (ti, g, te, _) = swing(fn, levels[1], 20.0)
    assert np.array_equal(ti, t) and np.array_equal(te, t)
    tau = tau0 / (1 + (np.r_[rate[0], g[:-1]] / SWING.ADAPT_W) ** 2)
    a = np.exp(-1e-3 / tau)
    assert np.allclose(g[1:], a[1:] * g[:-1] + (1 - a[1:]) * rate[1:], atol=1e-12)
    assert np.allclose(fn(t, np.full(t.size, 0.3), t, t, None, rng(1), tau0=tau0)[1], 0.3)
    k = t > 5
    slow = k & (np.abs(rate) < 0.01)
    fast = k & (np.abs(rate) > 0.4)
    lag_slow = np.median(-(g - rate)[slow] / np.gradient(rate, t)[slow])
    assert 0.5 * tau0 < lag_slow < 1.1 * tau0                       # near the resting lag
    assert np.max(np.abs(g - rate)[fast]) < 0.02 * np.max(np.abs(g - rate)[k])
    spec = np.abs(np.fft.rfft((g - rate)[5000:20000].reshape(-1, 5000).mean(axis=0)))
    assert np.max(spec[2:40:2]) < 1e-3 * np.max(spec[1:40:2])       # odd lines only


def test_stiction_is_a_relay_with_hysteresis_on_specific_force():
    fn, levels = SWING_SHAPES['g_sensitivity']
    c = levels[1]['c']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 60.0)
    err = g - rate
    f_y = G0 * np.sin(AMP * np.sin(W * t))
    assert set(np.round(np.unique(err) / c, 9)) <= {-1.0, 0.0, 1.0}
    on = err != 0
    assert np.all(np.sign(err[on]) == np.sign(f_y[on]))
    assert np.all(on[np.abs(f_y) > SWING.STICK_ON]) and not np.any(on[np.abs(f_y) < 1.0])
    mid = (np.abs(f_y) > 1.0) & (np.abs(f_y) < SWING.STICK_ON)
    rising = np.gradient(np.abs(f_y)) > 0
    assert not np.any(on[mid & rising]) and np.all(on[mid & ~rising])   # late release
    starts = np.sum(np.diff(on.astype(int)) == 1)
    assert starts == pytest.approx(24, abs=1)                       # once a half swing
    assert fold_lines(err, kmin=1) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.02)


def test_table_residual_is_parabolic_arches_between_knots():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    h = SWING.KNOT
    knots = h * np.arange(-3, 4)
    assert np.allclose(SWING.table_residual(knots, 1.0), 0, atol=1e-15)
    x = np.linspace(-0.6, 0.6, 12001)
    r = SWING.table_residual(x, 1.0)
    assert np.allclose(r, -r[::-1], atol=1e-12)                     # odd
    lo = h * np.floor(x / h)
    assert np.allclose(r, (x - lo) * (x - lo - h) * (x + 2 * lo + h), atol=1e-12)   # less chord
    assert np.all(r[x > 0] <= 1e-15) and np.all(r[x < 0] >= -1e-15)
    t, gyro = noisy_run()
    p = levels[1]
    _, out, _, _ = fn(t, gyro.copy(), t, t, None, rng(1), **p)
    assert np.allclose(out - gyro, SWING.table_residual(gyro, p['k3']))
    assert fold_lines(out - gyro, kmin=2) / S_LINE == pytest.approx(
        SWING.detectability('scale_factor_nonlinearity', p), rel=0.1)


def test_diode_leak_is_one_sided_and_exponential():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    w = SWING.DIODE_W
    assert SWING.diode(np.array([0.0]), 1.0)[0] == 0.0
    assert SWING.diode(0.4, 1.0) / SWING.diode(-0.4, 1.0) > 15
    assert SWING.diode(0.3, 1.0) - SWING.diode(0.2, 1.0) == pytest.approx(
        np.exp(3) - np.exp(2) - 1.0, rel=1e-12)
    t, gyro = noisy_run()
    p = levels[1]
    _, out, _, _ = fn(t, gyro.copy(), t, t, None, rng(1), **p)
    err = out - gyro
    assert np.allclose(err, p['c'] * (np.expm1(gyro / w) - gyro / w))
    assert fold_lines(err, kmin=2) / S_LINE == pytest.approx(
        SWING.detectability('scale_factor_asymmetry', p), rel=0.05)
    m = err[:900000 // 5000 * 5000].reshape(-1, 5000).mean(axis=0)
    spec = np.abs(np.fft.rfft(m))
    assert spec[2] > 0.3 * spec[3] and spec[3] > 0.1 * spec[2]      # even and odd lines


def test_wake_up_latency_alternates_between_two_levels():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    lat = levels[1]['latency']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(60), latency=lat)
    e = out[2] - t
    assert np.all(np.diff(out[2]) > 0) and np.array_equal(out[0], t)
    share = SWING.deep_share()
    assert share == pytest.approx(7 / 15)
    assert np.unique(np.round(e / lat, 9)) == pytest.approx([-share, 1 - share])
    deep = e > 0
    assert np.mean(deep) == pytest.approx(share, abs=0.005)
    assert np.mean(deep[1:][deep[:-1]]) == pytest.approx(SWING.DEEP_AFTER[1], abs=0.01)
    assert np.mean(deep[1:][~deep[:-1]]) == pytest.approx(SWING.DEEP_AFTER[0], abs=0.01)
    assert acf(e, [1, 2, 3]) == pytest.approx([-0.5, 0.25, -0.125], abs=0.01)
    f = np.linspace(-500, 500, 200001)
    assert np.trapezoid(SWING.wake_psd(f, lat, 1000.0), f) == pytest.approx(
        lat ** 2 * share * (1 - share), rel=1e-4)
    fw, pw = signal.welch(e, fs=1000.0, nperseg=2 ** 12)
    for lo, hi in ((10, 60), (200, 300), (440, 499)):
        k = (fw > lo) & (fw < hi)
        assert np.mean(pw[k]) == pytest.approx(np.mean(2 * SWING.wake_psd(fw[k], lat, 1000.0)),
                                               rel=0.05), lo
    assert np.mean(pw[fw > 400]) > 5 * np.mean(pw[fw < 100])         # blue


def test_gear_mesh_adds_a_twelve_degree_periodic_transmission_error():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    a = levels[1]['a']
    t, rate, (_, _, te, enc) = swing(fn, levels[1], 20.0)
    angle = AMP * np.sin(W * t)
    assert np.allclose(enc - angle, SWING.mesh_error(angle, a), atol=1e-15)
    phi = np.linspace(-0.4, 0.4, 10001)
    assert np.allclose(SWING.mesh_error(phi + 2 * np.pi / SWING.TEETH, 1.0),
                       SWING.mesh_error(phi, 1.0), atol=1e-9)
    cyc = np.linspace(0, 2 * np.pi / SWING.TEETH, 30000, endpoint=False)
    c = np.abs(np.fft.rfft(SWING.mesh_error(cyc, 1.0))) * 2 / cyc.size
    assert c[1:4] == pytest.approx([r for r, _ in SWING.MESH], rel=1e-6)
    assert np.max(c[4:]) < 1e-9
    zs = [SWING.detectability('encoder_cyclic_error', q) for q in levels]
    assert zs[0] / zs[2] == pytest.approx(levels[0]['a'] / levels[2]['a'], rel=1e-6)


def test_both_harnesses_take_set_n_by_held_out_n(monkeypatch):
    check_harnesses('n', SHAPES, SWING_SHAPES, monkeypatch)
