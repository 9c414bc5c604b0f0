# Held-out set J (bench/validate_diagnosis_heldout_j.py, static, and
# bench/validate_diagnosis_swing_heldout_j.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out j. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            flicker_band_psd, fold_lines, load_set, N_ARW, noisy_run,
                            octave_ratios, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('j')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_sync_interpolation_mixes_neighbours_with_random_weights_up_to_m():
    fn, _ = SHAPES['internal_lowpass']
    m = 0.6
    x = np.random.default_rng(3).standard_normal(2 ** 20)
    y = fn(x.copy(), np.random.default_rng(4), m=m)
    ok = np.abs(x[1:] - x[:-1]) > 1e-3
    mu = ((x[1:] - y[1:]) / (x[1:] - x[:-1]))[ok]
    assert np.all((mu > -1e-9) & (mu < m + 1e-9))                       # convex, up to m
    assert np.mean(mu) == pytest.approx(m / 2, abs=0.005)
    assert np.histogram(mu, bins=6, range=(0, m))[0].min() > 0.95 * mu.size / 6   # uniform
    r = [np.mean(y[:-k] * y[k:]) / np.mean(y * y) for k in (1, 2)]
    assert r[0] == pytest.approx(STATIC.sync_lag1(m), abs=0.005) and abs(r[1]) < 0.005
    assert np.array_equal(fn(np.full(50, 1.5), np.random.default_rng(5), m=1.0), np.full(50, 1.5))


def test_two_fans_give_two_equal_lines_beating_at_their_difference():
    fn, levels = SHAPES['vibration']
    a, n = levels[1]['amplitude'], 60000
    y = fn(np.zeros(n), np.random.default_rng(6), amplitude=a)
    t = np.arange(n) * DT
    cols = [g(2 * np.pi * f * t) for f in STATIC.FANS_HZ for g in (np.sin, np.cos)]
    c = fit(y, cols)
    assert np.hypot(c[0], c[1]) == pytest.approx(a, rel=1e-9)
    assert np.hypot(c[2], c[3]) == pytest.approx(a, rel=1e-9)
    assert np.max(np.abs(y - np.c_[tuple(cols)] @ c)) < 1e-9 * a          # nothing else
    env = np.abs(signal.hilbert(y))[2000:-2000]
    assert env.max() == pytest.approx(2 * a, rel=0.01) and env.min() < 0.05 * a   # full beat
    f, p = signal.periodogram(env - env.mean(), fs=1 / DT)
    assert f[np.argmax(p)] == pytest.approx(abs(np.diff(STATIC.FANS_HZ)[0]), abs=0.01)


def test_warming_room_is_a_lagged_ramp_that_never_settles():
    fn, levels = SHAPES['temperature_drift']
    rate, n = levels[1]['rate'], 720000
    y = fn(np.zeros(n), np.random.default_rng(7), rate=rate)
    t0 = np.random.default_rng(7).uniform(0, STATIC.ROOM_LATE)
    t = np.arange(n) * DT + t0
    lag = STATIC.ROOM_LAG
    assert np.allclose(y, rate * (t - lag * (1 - np.exp(-t / lag))), rtol=1e-12, atol=0)
    slope = np.diff(y) / DT
    assert np.all(slope > 0) and slope[0] < 0.64 * rate                  # a curved start
    assert slope[-1] == pytest.approx(rate, rel=1e-6)                     # straight, no limit
    s = STATIC.room(np.arange(n) * DT, rate)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(s) * np.sqrt(n) / SIG, rel=1e-9)


def test_lagged_flicker_has_its_psd_one_over_f_below_the_lag_and_cubic_above():
    fn, _ = SHAPES['bias_instability']
    ys, f, pxx, band = flicker_band_psd(fn)
    want = STATIC.lagged_flicker_psd(f[band], 1.0, DT)
    ratio = octave_ratios(f, pxx, band, want)
    assert np.allclose(ratio, 1.0, atol=0.2), ratio
    for lo, hi, slope in ((1e-4, 1e-2, -1.0), (1.0, 4.0, -3.0)):
        g = np.geomspace(lo, hi, 20)
        got = np.polyfit(np.log(g), np.log(STATIC.lagged_flicker_psd(g, 1.0, DT)), 1)[0]
        assert got == pytest.approx(slope, abs=0.1)
    assert STATIC.lagged_flicker_psd(1e-3, 1.0, DT) * np.pi * 1e-3 == pytest.approx(1.0, rel=0.01)
    a = np.mean([avar(y, [1000])[0] for y in ys])
    assert a == pytest.approx(STATIC.psd_avar(
        lambda h: STATIC.lagged_flicker_psd(h, 1.0, DT), 10.0, DT)[0], rel=0.3)


def test_settling_walk_relaxes_its_intensity_and_has_its_allan_variance():
    fn, _ = SHAPES['rate_random_walk']
    n = 720000
    ys = [fn(np.zeros(n), np.random.default_rng(30 + i), q=1.0) for i in range(4)]
    d2 = np.mean([np.diff(y) ** 2 for y in ys], axis=0)
    t = np.arange(1, n) * DT
    for lo in (0.0, 1200.0, 6000.0):
        k = (t >= lo) & (t < lo + 300)
        want = np.mean(STATIC.settling(t[k] + STATIC.POWER_ON / 2))
        assert np.mean(d2[k]) == pytest.approx(want, rel=0.04)
    assert np.mean(d2[:30000]) > 3 * np.mean(d2[-30000:])               # 4x at first, then 1x
    mean = np.mean(STATIC.settling(np.arange(n) * DT))
    for m in (100, 3000):
        got = np.mean([avar(y, [m])[0] for y in ys])
        assert got == pytest.approx(mean * STATIC.walk_avar(m, 1.0), rel=0.25)


def test_charging_events_are_sparse_symmetric_jumps_with_exponential_correlation():
    fn, _ = SHAPES['gauss_markov']
    tc, n = 0.5, 2 ** 21
    y = fn(np.zeros(n), np.random.default_rng(8), sd=1.0, tc=tc)
    a = np.exp(-DT / tc)
    kicks = y[1:] - a * y[:-1]
    lam = STATIC.EVENTS_PER_TC / tc * DT
    assert np.mean(np.abs(kicks) > 1e-12) == pytest.approx(1 - np.exp(-lam), rel=0.05)
    assert np.std(y) == pytest.approx(1.0, rel=0.1) and abs(stats.skew(y)) < 0.5
    assert stats.kurtosis(y) == pytest.approx(6 * (1 - a * a) / ((1 + a * a) * lam), rel=0.25)
    for lag in (10, 25, 50):
        r = np.mean(y[:-lag] * y[lag:]) / np.mean(y * y)
        assert r == pytest.approx(np.exp(-lag * DT / tc), abs=0.03)


def test_whole_angle_readout_reads_phases_of_rounded_pickoffs():
    fn, levels = SHAPES['quantization']
    x = SIG * np.random.default_rng(9).standard_normal(400000)
    cyc = STATIC.CYCLE
    y = fn(x.copy(), np.random.default_rng(10), amplitude=3.0)          # a 3-count pickoff
    theta0 = np.random.default_rng(10).uniform(0, cyc)
    theta = theta0 + np.r_[0.0, np.cumsum(x)] * DT
    read = theta[0] + STATIC.readout_error(theta[0], 3.0) + np.r_[0.0, np.cumsum(y)] * DT
    grid = np.arange(-3, 4)
    phases = np.arctan2(grid[:, None], grid[None, :]).ravel()
    u = np.angle(np.exp(2j * np.pi * read[:50000] / cyc))
    assert np.min(np.abs(np.angle(np.exp(1j * (u[:, None] - phases[None, :])))), axis=1).max() \
        < 1e-6                                                              # the lattice only
    p = levels[1]
    y = fn(x.copy(), np.random.default_rng(10), **p)
    read = theta[0] + STATIC.readout_error(theta[0], p['amplitude']) + np.r_[0.0, np.cumsum(
        y)] * DT
    e = read - theta
    sd = cyc / (2 * np.pi) / (p['amplitude'] * np.sqrt(12))                 # two rounded channels
    assert np.std(e) == pytest.approx(sd, rel=0.05)
    ex = avar(y, [1, 10]) - avar(x, [1, 10])
    for m, got in zip((1, 10), ex):
        want = STATIC.readout_excess(m, p['amplitude'], DT, N_ARW) * N_ARW ** 2 / (m * DT)
        assert got == pytest.approx(want, rel=0.15)


def test_velocity_mode_has_a_zero_at_dc_and_the_computed_spectrum():
    fn, _ = SHAPES['resonance']
    n, f0, q = 2 ** 20, 21.5, 21.5 / 2
    y = fn(np.zeros(n), np.random.default_rng(11), sigma=1.0, freq=f0, q=q)
    assert np.std(y) == pytest.approx(1.0, rel=0.05) and abs(stats.kurtosis(y)) < 0.1
    f, pxx = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.velocity_mode_psd(f, 1.0, f0, q, DT)
    assert np.allclose(pxx[2:-1], want[2:-1], rtol=0.3)
    for band in ((f > 2) & (f < 8), (f > 18) & (f < 25)):
        assert np.mean(pxx[band]) == pytest.approx(np.mean(want[band]), rel=0.06)
    low = (f > 0.2) & (f < 1)
    assert np.mean(pxx[low]) < 0.005 * pxx.max()                         # no plateau: a zero
    g = np.geomspace(0.05, 0.5, 10)
    slope = np.polyfit(np.log(g), np.log(STATIC.velocity_mode_psd(g, 1.0, f0, q, DT)), 1)[0]
    assert slope == pytest.approx(2.0, abs=0.05)
    assert f[np.argmax(pxx)] == pytest.approx(f0, abs=1.0)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


@pytest.mark.parametrize('level', [0, 1, 2])
def test_async_read_returns_the_latest_conversion_aged_up_to_its_period(level):
    fn, levels = SWING_SHAPES['time_delay']
    ti = levels[level]['period']
    t, rate, (t_out, g, te, enc) = swing(fn, levels[level], 20.0)
    phase = np.random.default_rng(10).uniform(0, ti) + t[0] - ti
    j = np.floor((t - phase) / ti)
    s = j * ti + phase
    age = t - s
    assert np.all(age >= 0) and np.all(age < ti)
    assert np.mean(age) == pytest.approx(ti / 2, rel=0.02)
    assert np.allclose(g, AMP * W * np.cos(W * s), rtol=0, atol=1e-12)
    assert np.array_equal(t_out, t) and np.array_equal(te, t)
    c = fit(g - rate, (AMP * W * W * np.sin(W * t), np.cos(W * t)))
    assert c[0] == pytest.approx(ti / 2, rel=0.03)                      # late by Ti / 2
    noise = np.random.default_rng(12).standard_normal(t.size)
    out = fn(t, rate + noise, t, AMP * np.sin(W * t), lambda x: (AMP * np.sin(W * x),
             AMP * W * np.cos(W * x)), np.random.default_rng(10), period=ti)[1]
    rest = out - AMP * W * np.cos(W * s)
    same = np.diff(j) == 0
    assert np.array_equal(rest[1:][same], rest[:-1][same])               # a conversion re-read
    _, first, inverse = np.unique(j, return_index=True, return_inverse=True)
    assert np.allclose(rest, noise[first[inverse]], rtol=0, atol=1e-12)  # its own noise
    assert (ti < 1e-3) == (not same.any())


def test_anisoelastic_bias_is_a_square_law_on_the_linear_term():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    err = g - rate
    fy = 9.80665 * np.sin(AMP * np.sin(W * t))
    assert np.allclose(err, gy * fy + gy / 9.80665 * fy ** 2, rtol=1e-9, atol=1e-15)
    c = fit(err, (np.sin(W * t), np.cos(W * t), np.cos(2 * W * t), np.sin(2 * W * t),
                  np.ones_like(t)))
    assert np.hypot(c[0], c[1]) == pytest.approx(2 * special.j1(AMP) * 9.80665 * gy, rel=0.01)
    assert np.hypot(c[2], c[3]) == pytest.approx(special.jv(2, 2 * AMP) * 9.80665 * gy,
                                                 rel=0.01)
    side = np.max(err) / -np.min(err)
    sa = np.sin(AMP)
    assert side == pytest.approx((1 + sa) / (1 - sa), rel=1e-3)   # one side larger
    assert np.linalg.norm(c[:4]) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.02)


def test_dead_time_compresses_as_one_over_one_plus_rate_with_lines_as_computed():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    t, gyro = noisy_run()
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, AMP * np.sin(W * t), None, None, **p)[1]
        assert np.allclose(out, gyro / (1 + np.abs(gyro) / p['scale']), rtol=1e-12)
        assert fold_lines(out - gyro) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_nonlinearity', p), rel=0.08)
    w = np.linspace(-0.5, 0.5, 1001)
    d = SWING.dead_time(w, 20.0)
    assert np.allclose(d, -d[::-1])                                         # odd
    small = np.abs(w) < 0.02
    assert np.allclose(d[small] - w[small], -w[small] * np.abs(w[small]) / 20.0, atol=1e-6)


def test_wandering_asymmetry_is_a_abs_w_with_a_gauss_markov_coefficient():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    t, gyro = noisy_run()
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, AMP * np.sin(W * t), None, np.random.default_rng(14), **p)[1]
        factor = SWING.wandering(t.size, 1e-3, np.random.default_rng(14))
        assert np.allclose(out - gyro, p['a'] * factor * np.abs(gyro), rtol=0, atol=1e-12)
        assert fold_lines(out - gyro) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_asymmetry', p) * np.mean(factor), rel=0.08)
    u = [(SWING.wandering(10 ** 6, 1e-3, np.random.default_rng(s)) - 1) / 0.5
         for s in range(8)]
    assert np.std(u) == pytest.approx(1.0, rel=0.1)
    lag = 6000                                                              # 6 s
    r = np.mean([np.mean(v[:-lag] * v[lag:]) / np.mean(v * v) for v in u])
    assert r == pytest.approx(np.exp(-0.1), abs=0.03)


def test_interrupt_collisions_delay_encoder_stamps_in_ramped_bursts_at_the_beat():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    h = levels[1]['busy']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 60.0)
    e = te - t + h * h / (2e-3)                                         # the raw delay
    assert np.all(e >= -1e-12) and np.max(e) == pytest.approx(h, rel=0.01)
    late = e > 1e-12
    assert np.mean(late) == pytest.approx(h / 1e-3, rel=0.05)            # a fraction h / P
    starts = t[1:][np.diff(late.astype(int)) == 1]
    assert np.allclose(np.diff(starts), 1 / SWING.BEAT_HZ, atol=2e-3)     # bursts at the beat
    ramp = np.diff(e)[late[1:] & late[:-1]]
    assert np.allclose(ramp, -SWING.BEAT_HZ * 1e-3 * 1e-3, rtol=1e-6)   # h down to 0
    assert np.array_equal(ti, t) and np.array_equal(g, rate) and np.all(np.diff(te) > 0)
    assert abs(np.mean(te - t)) < 0.05 * h * h / 2e-3                   # mean calibrated out


def test_scale_joint_steps_the_reading_by_the_gap_twice_a_swing():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    gap = levels[1]['gap']
    t, rate, (_, _, _, enc) = swing(fn, levels[1], 20.0)
    phi = AMP * np.sin(W * t)
    err = enc - phi
    before, beyond = phi < SWING.JOINT - SWING.HEAD / 2, phi > SWING.JOINT + SWING.HEAD / 2
    assert np.all(err[before] == 0) and np.allclose(err[beyond], gap, rtol=1e-9)
    mid = ~before & ~beyond
    assert np.all((err[mid] >= 0) & (err[mid] <= gap)) and mid.any()
    crossings = np.flatnonzero(np.diff(beyond.astype(int)) != 0)
    assert crossings.size == 8                                              # 4 swings, twice each
    zs = [SWING.detectability('encoder_cyclic_error', p) for p in levels]
    assert zs[0] / zs[2] == pytest.approx(levels[0]['gap'] / levels[2]['gap'], rel=1e-6)


def test_both_harnesses_take_set_j_by_held_out_j(monkeypatch):
    check_harnesses('j', SHAPES, SWING_SHAPES, monkeypatch)
