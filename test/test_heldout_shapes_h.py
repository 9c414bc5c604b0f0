# Held-out set H (bench/validate_diagnosis_heldout_h.py, static, and
# bench/validate_diagnosis_swing_heldout_h.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out h. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            load_set, N_ARW, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('h')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


@pytest.mark.parametrize('every', [2, 5])
def test_skipped_conversions_are_filled_by_their_neighbours_mean_lag1_as_computed(every):
    fn, _ = SHAPES['internal_lowpass']
    x = np.random.default_rng(2).standard_normal(400000)
    y = fn(x.copy(), np.random.default_rng(3), every=every)
    filled = np.flatnonzero(y != x)
    assert np.all(np.diff(filled) == every) and filled.size > x.size // every - 2
    assert np.allclose(y[filled], 0.5 * (x[filled - 1] + x[filled + 1]), atol=1e-15)
    r1 = np.mean(y[:-1] * y[1:]) / np.mean(y * y)
    assert r1 == pytest.approx(STATIC.gap_lag1(every), abs=0.006)
    assert abs(np.mean(y[:-2] * y[2:]) / np.mean(y * y) - (0.125 / 0.75 if every == 2 else 0)
               ) < 0.006


def test_kicks_are_doublets_with_no_net_angle_and_lines_rising_toward_nyquist():
    fn, _ = SHAPES['vibration']
    m = STATIC.KICK_SAMPLES
    assert np.random.default_rng(4).integers(m) < m - 2      # whole doublets in 200 periods
    y = fn(np.zeros(200 * m), np.random.default_rng(4), amplitude=1.0)
    assert np.allclose(y[m:], y[:-m]) and np.count_nonzero(y[:m]) == 2
    angle = np.cumsum(y)
    assert set(np.unique(angle)) <= {0.0, 1.0} and angle[-1] == 0.0   # rocks and returns
    t = np.arange(y.size) * DT
    k, amp = STATIC.kick_lines(1.0)
    for j in (1, 20, 80):
        f = j / (m * DT)
        c = fit(y, (np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t), np.ones_like(t)))
        assert np.hypot(c[0], c[1]) == pytest.approx(amp[j - 1], rel=1e-6)
    assert amp[80] > 20 * amp[0]


def test_table_residual_drops_by_its_height_each_time_the_warming_crosses_a_cell():
    fn, levels = SHAPES['temperature_drift']
    h, n = levels[1]['height'], 720000
    rng = np.random.default_rng(5)
    y = fn(np.zeros(n), rng, height=h)
    t0 = np.random.default_rng(5).uniform(0, STATIC.CELL)        # the die's starting reading
    assert y.min() >= 0 and y.max() < h
    drops = np.flatnonzero(np.diff(y) < -h / 2) + 1
    j = np.arange(np.floor(t0 / STATIC.CELL) + 1, (t0 + STATIC.WARM_RISE) / STATIC.CELL)
    frac = (j * STATIC.CELL - t0) / STATIC.WARM_RISE
    crossing = -STATIC.WARM_TIME * np.log1p(-frac[frac < 1 - 1e-12])
    crossing = crossing[crossing < n * DT]
    assert drops.size == crossing.size >= 18
    assert np.all(np.abs(drops * DT - crossing) <= DT)
    grow = np.diff(crossing)
    assert np.all(np.diff(grow) > 0)                       # the teeth lengthen
    s = STATIC.table_residual(np.arange(n) * DT, h)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(s) * np.sqrt(n) / SIG, rel=1e-9)


def test_trapping_is_sparse_events_with_power_law_tails_and_allan_of_its_1_over_f():
    fn, _ = SHAPES['bias_instability']
    n, b = 2 ** 20, 1.0
    p = DT / STATIC.TRAP_INTERVAL
    ys = [fn(np.zeros(n), np.random.default_rng(6 + i), b=b) for i in range(3)]
    d = np.diff(ys[0])
    big = np.abs(d) > 0.75 * b / np.sqrt(p)
    assert abs(big.sum() - n * p) < 5 * np.sqrt(n * p)             # Poisson events
    assert stats.kurtosis(d) > 50                                   # not Gaussian
    ev = np.flatnonzero(big) + 1                                    # the events' samples
    k = ev[np.flatnonzero(np.diff(ev) > 400)[2]]                    # one alone for 400
    tail = ys[0][k:k + 400] - ys[0][k - 1]                          # its relaxation
    assert np.allclose(tail / tail[0], STATIC.frac_kernel(400), atol=0.02)
    for m in (100, 1000):
        a = np.mean([avar(y, [m])[0] for y in ys])
        assert a == pytest.approx(STATIC.psd_avar(
            lambda f: STATIC.trap_psd(f, b, DT), m * DT, DT)[0], rel=0.3)


def test_memory_walk_whitens_by_its_fractional_difference_and_allan_rises_as_tau_1_5():
    fn, _ = SHAPES['rate_random_walk']
    n = 2 ** 18
    ys = [fn(np.zeros(n), np.random.default_rng(20 + i), q=1.0) for i in range(6)]
    w = signal.fftconvolve(ys[0], STATIC.frac_kernel(n, -STATIC.WALK_ORDER))[:n]
    assert np.std(w) == pytest.approx(1.0, rel=0.01) and abs(stats.kurtosis(w)) < 0.1
    taus = np.array([100, 1000])
    a = np.mean([avar(y, taus) for y in ys], axis=0)
    want = STATIC.psd_avar(lambda f: STATIC.walk_psd(f, 1.0, DT), taus * DT, DT)
    assert np.allclose(a, want, rtol=0.3)
    assert np.log10(want[1] / want[0]) == pytest.approx(1.5, abs=0.1)


def test_beat_is_arcsine_distributed_and_exponentially_correlated():
    fn, _ = SHAPES['gauss_markov']
    a, tc, n = 1.0, 0.5, 2 ** 20
    y = fn(np.zeros(n), np.random.default_rng(8), amplitude=a, tc=tc)
    assert np.max(np.abs(y)) <= a
    u = np.sort(y[::500])
    assert stats.kstest(u, stats.arcsine(loc=-a, scale=2 * a).cdf).pvalue > 1e-3
    for lag in (10, 50, 100):
        r = np.mean(y[:-lag] * y[lag:]) / np.mean(y * y)
        assert r == pytest.approx(np.exp(-lag * DT / tc), abs=0.02)


def test_noise_shaping_adds_the_second_difference_of_a_bounded_error_allan_as_computed():
    fn, levels = SHAPES['quantization']
    q = levels[1]['step']
    x = SIG * np.random.default_rng(9).standard_normal(300000)
    y = fn(x.copy(), None, step=q)
    assert np.allclose(y / q, np.round(y / q), atol=1e-9)         # on the output grid
    e = np.cumsum(np.cumsum(y - x))                                # undo the second difference
    assert np.max(np.abs(e)) <= q / 2 * (1 + 1e-6)
    assert np.std(e) == pytest.approx(q / np.sqrt(12), rel=0.02)
    ex = avar(y, [1, 10]) - avar(x, [1, 10])
    for m, got in zip((1, 10), ex):
        assert got * (m * DT) ** 2 == pytest.approx(STATIC.shaped_excess(m, q, DT), rel=0.1)


def test_rattle_is_impulsive_rings_with_the_computed_spectrum():
    fn, _ = SHAPES['resonance']
    n, amp, f0 = 2 ** 20, 1.0, 37.0
    y = fn(np.zeros(n), np.random.default_rng(11), amplitude=amp, freq=f0)
    assert stats.kurtosis(y) > 0.5                                 # Gaussian: 0
    f, pxx = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    b, a = STATIC.ring(f0, DT)
    want = 2 * DT * STATIC.RATTLE_RATE * DT * amp ** 2 * np.abs(
        signal.freqz(b, a, worN=f, fs=1 / DT)[1]) ** 2
    band = (f > 25) & (f < 49)
    assert np.mean(pxx[band]) == pytest.approx(np.mean(want[band]), rel=0.05)
    assert np.allclose(pxx[band], want[band], rtol=0.3)
    assert f[np.argmax(pxx)] == pytest.approx(f0, abs=0.6)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_latency_step_delays_the_stamps_once_in_the_middle_of_the_run():
    fn, levels = SWING_SHAPES['time_delay']
    d = levels[1]['delay']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 60.0)
    late = ti - t
    assert set(np.round(np.unique(late) / d, 9)) == {0.0, 1.0}
    at = t[np.argmax(late > 0)]
    assert 0.3 * 60 - 1e-3 <= at <= 0.7 * 60 and np.allclose(late[t >= at], d, rtol=1e-9)
    assert np.array_equal(g, rate) and np.array_equal(te, t)


def test_g_scale_factor_multiplies_rate_and_specific_force_even_harmonics_only():
    fn, levels = SWING_SHAPES['g_sensitivity']
    c = levels[1]['c']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    assert np.allclose(err, c * 9.80665 * np.sin(AMP * np.sin(W * t)) * rate, atol=1e-15)
    h = [np.hypot(*fit(err, (np.sin(k * W * t), np.cos(k * W * t)))) for k in (1, 2, 3, 4)]
    assert h[0] < 1e-6 * h[1] and h[2] < 1e-6 * h[1] and h[3] > 1e-3 * h[1]
    assert h[1] == pytest.approx(c * 9.80665 * AMP ** 2 * W / 2, rel=0.05)   # small-angle 2f
    h6 = np.hypot(*fit(err, (np.sin(6 * W * t), np.cos(6 * W * t))))
    z = np.sqrt(h[1] ** 2 + h[3] ** 2 + h6 ** 2) / S_LINE
    assert z == pytest.approx(SWING.detectability('g_sensitivity', levels[1]), rel=1e-3)


def test_dead_band_offset_jumps_at_zero_rate_and_noise_smooths_it_as_computed():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    e0 = levels[1]['e0']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    assert np.all(np.abs(err[np.abs(rate) > 0.05]) > 0.99 * e0)
    assert np.all(np.sign(err[rate != 0]) == np.sign(rate[rate != 0]))
    s_n = N_ARW * np.sqrt(1000.0)
    w = np.full(200000, 0.01)
    noisy = SWING.sign_offset(w + s_n * np.random.default_rng(12).standard_normal(w.size), e0)
    assert noisy.mean() == pytest.approx(SWING.smoothed_offset(0.01, e0, s_n), rel=0.02)


def test_square_law_adds_an_even_2f_line_of_half_the_squared_peak_rate():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    b = levels[1]['b']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    c = fit(err, (np.ones_like(t), np.cos(W * t), np.cos(2 * W * t), np.sin(2 * W * t)))
    assert c[0] == pytest.approx(b * (AMP * W) ** 2 / 2, rel=1e-6)
    assert abs(c[1]) < 1e-9 and c[2] == pytest.approx(b * (AMP * W) ** 2 / 2, rel=1e-6)
    assert SWING.detectability('scale_factor_asymmetry', levels[1]) == pytest.approx(
        c[2] / S_LINE, rel=0.02)


def test_counter_truncates_stamps_to_whole_ticks_a_periodic_error_pattern():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    tick = levels[0]['tick']
    t, _, (_, _, te, _) = swing(fn, levels[0], 20.0)
    e = te - t
    assert np.all(e <= 1e-12) and np.all(e > -tick - 1e-12)
    ticks = np.diff(te) / tick
    assert np.allclose(ticks, np.round(ticks), atol=1e-5)          # whole ticks apart
    assert np.allclose(e[5:], e[:-5], atol=1e-11)                  # 409.6 ticks a sample
    assert np.std(e) > 0.25 * tick


def test_rocking_head_error_flips_with_the_direction_of_travel():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    delta = levels[1]['delta']
    t, rate, (_, _, _, enc) = swing(fn, levels[1], 20.0)
    err = enc - AMP * np.sin(W * t)
    u = SWING.SIGNAL_LINES * AMP * np.sin(W * t)
    approx = -0.5 * delta * np.sign(rate) * np.cos(2 * u) / SWING.SIGNAL_LINES
    assert np.allclose(err, approx, atol=0.02 * delta / SWING.SIGNAL_LINES)
    assert np.max(np.abs(err)) == pytest.approx(delta / 2 / SWING.SIGNAL_LINES, rel=0.02)


def test_both_harnesses_take_set_h_by_held_out_h(monkeypatch):
    check_harnesses('h', SHAPES, SWING_SHAPES, monkeypatch)
