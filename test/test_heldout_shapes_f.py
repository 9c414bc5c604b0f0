# Held-out set F (bench/validate_diagnosis_heldout_f.py, static, and
# bench/validate_diagnosis_swing_heldout_f.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out f. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            INC, load_set, N_ARW, S_LINE, SIG, stand, swing, W)
import numpy as np
import pytest
from scipy import signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('f')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


@pytest.mark.parametrize('s', [1.0, 2.0, 3.0])
def test_slew_limiter_cuts_only_large_steps_and_its_lag1_is_the_markov_chains(s):
    fn, _ = SHAPES['internal_lowpass']
    x = np.random.default_rng(2).standard_normal(400000)
    y = fn(x.copy(), None, rate=s / DT)
    step = np.diff(y)
    assert np.abs(step).max() <= s * (1 + 1e-12)
    free = np.abs(x[1:] - y[:-1]) <= s                       # within the limit: passed as is
    assert np.array_equal(y[1:][free], x[1:][free])
    assert np.allclose(np.abs(step[~free]), s, rtol=1e-12)
    assert np.mean(~free) > 0.003 and np.var(y) < np.var(x)
    assert np.corrcoef(y[:-1], y[1:])[0, 1] == pytest.approx(STATIC.slew_lag1(s), abs=0.005)


def test_hunting_pump_is_fm_with_bessel_sidebands_no_carrier_and_constant_envelope():
    fn, _ = SHAPES['vibration']
    y = fn(np.zeros(100000), np.random.default_rng(3), amplitude=1.0, freq=24.6)
    t = np.arange(y.size) * DT
    for k in range(-4, 5):
        f = 24.6 + k * STATIC.HUNT_FM
        c = fit(y, (np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)))
        assert np.hypot(*c) == pytest.approx(abs(special.jv(k, STATIC.HUNT_BETA)), abs=1e-3)
    assert abs(special.jv(0, STATIC.HUNT_BETA)) < 1e-3                # the carrier is nulled
    env = np.abs(signal.hilbert(y))[1000:-1000]
    assert np.allclose(env, 1.0, atol=0.02)


def test_oven_rings_from_the_set_point_error_with_the_stated_period_and_decrement():
    fn, levels = SHAPES['temperature_drift']
    amp, n = levels[1]['amplitude'], 720000
    y = fn(np.zeros(n), None, amplitude=amp)
    assert y[0] == pytest.approx(amp) and abs(y[1] - y[0]) < 1e-6 * amp   # zero slope at 0
    up = np.flatnonzero(np.diff(np.sign(y)) > 0) * DT
    assert np.allclose(np.diff(up), STATIC.RING_PERIOD, atol=0.05)
    ext = y[signal.argrelextrema(np.abs(y), np.greater)[0]]
    z = STATIC.RING_ZETA
    assert np.all(np.sign(ext[:-1]) != np.sign(ext[1:]))
    assert np.allclose(np.abs(ext[1:5] / ext[:4]), np.exp(-np.pi * z / np.sqrt(1 - z * z)),
                       rtol=1e-3)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(y) * np.sqrt(n) / SIG, rel=1e-9)


def test_switching_flicker_is_exact_1_over_f_of_a_two_level_intensity():
    fn, _ = SHAPES['bias_instability']
    n = 2 ** 19
    y = fn(np.zeros(n), np.random.default_rng(4), b=1.0)
    w = signal.fftconvolve(y, STATIC.frac_kernel(n, -0.5))[:n]          # the drive, exactly
    rng = np.random.default_rng(4)
    level = 1 + STATIC.SWITCH_DEPTH * STATIC.telegraph(n, DT, STATIC.SWITCH_DWELL / 2, rng)
    assert np.allclose(w, rng.standard_normal(n) * np.sqrt(level), atol=1e-8)
    assert set(np.round(level, 9)) == {0.2, 1.8}
    flips = np.count_nonzero(np.diff(level))
    assert flips * STATIC.SWITCH_DWELL / (n * DT) == pytest.approx(1, abs=0.6)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 15)
    sel = (f >= 0.05) & (f <= 5.0)
    assert np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0] == pytest.approx(-1.0, abs=0.08)
    mean = np.mean(level)
    assert np.median(p[sel] / STATIC.flicker_psd(f[sel], 1.0, DT)) == pytest.approx(mean,
                                                                                    rel=0.15)
    for m in (100, 1000):
        assert avar(y, [m])[0] == pytest.approx(
            mean * STATIC.psd_avar(lambda q: STATIC.flicker_psd(q, 1.0, DT), [m * DT], DT)[0],
            rel=0.25)


def test_stick_slip_holds_the_bias_inside_the_play_and_walks_at_k2_tau_over_3():
    fn, _ = SHAPES['rate_random_walk']
    n = 2_000_000
    y = fn(np.zeros(n), np.random.default_rng(6), k=1.0)
    walk = np.cumsum(np.random.default_rng(6).standard_normal(n)) * np.sqrt(DT)
    h = np.sqrt(STATIC.STICK_HOLD)
    gap = walk - y
    assert np.abs(gap).max() <= h * (1 + 1e-9)
    moved = np.diff(y) != 0
    assert np.allclose(np.abs(gap[1:][moved]), h)                  # slips only at the edge
    assert np.mean(moved) < 0.03
    assert np.var(gap[n // 10:]) == pytest.approx(h * h / 3, rel=0.3)    # reflected: uniform
    m = np.array([100, 40000])
    av = avar(y, m)
    assert av[0] < 0.2 * m[0] * DT / 3                              # stuck at short tau
    assert av[1] == pytest.approx(m[1] * DT / 3, rel=0.3)           # K^2 tau / 3 at long tau


def test_trap_count_steps_by_one_charge_poisson_levels_exponential_correlation():
    fn, _ = SHAPES['gauss_markov']
    sigma, tc = 2.0, 0.8
    y = fn(np.zeros(2_000_000), np.random.default_rng(7), sigma=sigma, tc=tc)
    count = y / (sigma / np.sqrt(STATIC.GR_MEAN)) + STATIC.GR_MEAN
    assert np.allclose(count, np.round(count), atol=1e-9) and count.min() >= 0
    k = np.bincount(np.round(count).astype(int))
    pmf = stats.poisson.pmf(np.arange(k.size), STATIC.GR_MEAN)
    assert np.allclose(k / k.sum(), pmf, atol=0.005)
    assert np.std(y) == pytest.approx(sigma, rel=0.03)
    assert stats.skew(y) == pytest.approx(1 / np.sqrt(STATIC.GR_MEAN), abs=0.06)
    assert np.mean(np.diff(count) != 0) == pytest.approx(2 * STATIC.GR_MEAN / tc * DT, rel=0.05)
    lag = int(tc / DT)
    assert np.corrcoef(y[:-lag], y[lag:])[0, 1] == pytest.approx(np.exp(-1), abs=0.03)
    m = int(1.89 * tc / DT)
    assert avar(y, [m])[0] == pytest.approx(STATIC.gm_avar(m * DT, sigma, tc), rel=0.1)


@pytest.mark.parametrize('bit', [2, 4, 5])
def test_stuck_bit_misses_codes_errs_periodically_and_its_allan_excess_as_stated(bit):
    fn, _ = SHAPES['quantization']
    step = INC / 24
    x = SIG * np.random.default_rng(8).standard_normal(400000)
    y = fn(x.copy(), np.random.default_rng(9), step=step, bit=bit)
    rng = np.random.default_rng(9)
    theta = np.r_[0.0, np.cumsum(x)] * DT + (rng.integers(2 ** 20) + rng.uniform()) * step
    read = np.floor(theta / step).astype(np.int64)
    read &= ~np.int64(1 << bit)
    assert np.allclose(y, np.diff(read) * step / DT, rtol=0, atol=1e-12)
    assert not np.any(read & (1 << bit))                           # half the codes missing
    e = STATIC.stuck_error(theta, step, bit)
    assert np.allclose(e, theta - read * step, atol=1e-15)
    period = 2 ** (bit + 1) * step
    assert np.allclose(STATIC.stuck_error(theta + period, step, bit), e, atol=1e-12)
    assert e.max() - e.min() == pytest.approx((2 ** bit + 1) * step, rel=1e-3)
    for m in (1, 4):
        ex = (avar(y, [m]) - avar(x, [m]))[0] * (m * DT) ** 2
        assert ex == pytest.approx(STATIC.stuck_excess(m, step, bit, INC), rel=0.12)


def test_pumped_mode_is_cyclostationary_at_twice_f0_and_its_line_narrowed():
    fn, _ = SHAPES['resonance']
    f0, q, sigma = 21.3, 25.0, 1.5
    y = fn(np.zeros(800000), np.random.default_rng(10), sigma=sigma, freq=f0, q=q)
    t = np.arange(y.size) * DT
    assert np.std(y) == pytest.approx(sigma, rel=0.05)
    c = fit(y * y, (np.cos(4 * np.pi * f0 * t), np.sin(4 * np.pi * f0 * t), np.ones(t.size)))
    assert np.hypot(c[0], c[1]) == pytest.approx(STATIC.PUMP * sigma ** 2, rel=0.1)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 15)
    narrow = np.abs(f - f0) <= f0 / q * (1 - STATIC.PUMP) / 2
    assert p[narrow].sum() / p.sum() == pytest.approx(0.457, abs=0.04)
    unpumped = (2 / np.pi) * np.arctan(1 - STATIC.PUMP)     # the same band, a plain mode
    assert p[narrow].sum() / p.sum() > 3 * unpumped


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


@pytest.mark.parametrize('level', [0, 1, 2])
def test_track_filter_makes_the_encoder_late_by_tau_compressed_at_high_rate(level):
    fn, levels = SWING_SHAPES['time_delay']
    tau = levels[level]['tau']
    t, rate, (_, g, te, enc) = swing(fn, levels[level], 20.0)
    phi = stand(t)[0]
    err = enc - phi
    assert np.array_equal(g, rate) and np.array_equal(te, t)
    lines = SWING.SIGNAL_LINES
    assert np.allclose(err, -np.arctan(lines * rate * tau) / lines, atol=1e-15)
    slow = (np.abs(rate) < 0.01) & (np.abs(rate) > 1e-6)
    assert np.allclose(err[slow] / -rate[slow], tau, rtol=0.01)   # the encoder is late by tau
    c = fit(err, (np.cos(W * t), np.sin(W * t)))
    assert -c[0] < AMP * W * tau                                    # less than a pure delay
    assert -c[0] * W / S_LINE == pytest.approx(
        SWING.detectability('time_delay', levels[level]), rel=1e-3)


def test_lever_arm_adds_tangential_and_centripetal_acceleration_to_the_g_terms():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy, gz = levels[1]['gy'], levels[1]['gz']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    phi = stand(t)[0]
    r, g0 = SWING.ARM, SWING.G0
    tangential, centripetal = -r * W * W * phi, r * rate * rate
    expect = gy * (g0 * np.sin(phi) + tangential) + gz * (g0 * (np.cos(phi) - 1) + centripetal)
    assert np.allclose((g - rate)[1:-1], expect[1:-1], rtol=0, atol=1e-6 * gy * g0)
    c = fit(g - rate, (np.sin(W * t), np.cos(W * t), np.cos(2 * W * t), np.ones(t.size)))
    assert np.hypot(c[0], c[1]) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=1e-3)
    assert np.hypot(c[0], c[1]) == pytest.approx(gy * (2 * g0 * special.jv(1, AMP)
                                                       - r * W * W * AMP), rel=1e-3)
    assert c[2] == pytest.approx(gz * (2 * g0 * special.jv(2, AMP)
                                       + r * AMP ** 2 * W ** 2 / 2), rel=1e-3)


def test_converter_inl_ripples_with_the_rate_and_its_lines_are_jacobi_anger():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    e0 = levels[1]['e0']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    assert np.allclose(err, e0 * np.sin(2 * np.pi * rate / SWING.INL_PERIOD + SWING.INL_PHASE))
    lines = SWING.inl_lines(e0, AMP * W)
    for k in (2, 3, 7, 8):
        c = fit(err, (np.cos(k * W * t), np.sin(k * W * t)))
        assert np.hypot(*c) == pytest.approx(lines[k - 2], rel=1e-3, abs=1e-4 * e0)
    sn = 0.03                                                     # noise dithers the ripple
    w = np.repeat(np.linspace(-0.4, 0.4, 9), 200000)
    noisy = np.random.default_rng(3).standard_normal(w.size) * sn
    mean = SWING.inl(w + noisy, 1.0).reshape(9, -1).mean(axis=1)
    assert np.allclose(mean, SWING.inl(w[::200000], 1.0) * np.exp(
        -2 * (np.pi * sn / SWING.INL_PERIOD) ** 2), atol=0.01)


def test_warming_asymmetry_is_a_abs_w_whose_coefficient_settles_after_power_on():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    ok = np.abs(rate) > 0.05
    coef = (g - rate)[ok] / (a * np.abs(rate[ok]))
    assert np.allclose(coef, 1 + SWING.WARM_EXCESS * np.exp(-t[ok] / SWING.WARM_TAU))
    assert coef[0] == pytest.approx(1 + SWING.WARM_EXCESS, rel=1e-3)
    c = fit(g - rate, (np.cos(2 * W * t), np.sin(2 * W * t), np.ones(t.size)))
    assert np.hypot(c[0], c[1]) / S_LINE == pytest.approx(
        SWING.detectability('scale_factor_asymmetry', levels[1]), rel=0.01)


def test_ascii_stamps_are_late_by_the_extra_characters_of_each_message():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    char = levels[2]['char']
    t, _, (_, _, te, enc) = swing(fn, levels[2], 20.0)
    deg = np.degrees(enc)
    e = te - t
    assert SWING.extra_chars(np.radians([5.0, -5.0, 15.0, -15.0])).tolist() == [0, 1, 1, 2]
    assert np.allclose(e - e.mean(), char * (SWING.extra_chars(enc) - SWING.extra_chars(
        enc).mean()), atol=1e-12)
    for sel, n_extra in (((deg >= 0) & (deg < 10), 0), (deg <= -10, 2)):
        assert np.allclose(e[sel] - e[(deg >= 0) & (deg < 10)][0], n_extra * char, atol=1e-12)
    assert abs(e.mean()) < 1e-12 and np.all(np.diff(te) > 0)


def test_dirty_scale_errs_only_near_the_spot_at_twice_the_line_frequency():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    depth = levels[1]['depth']
    t, _, (_, _, _, enc) = swing(fn, levels[1], 20.0)
    phi = stand(t)[0]
    err = enc - phi
    far = np.abs(phi - SWING.SPOT_AT) > 6 * SWING.SPOT_WIDTH
    assert np.abs(err[far]).max() < 1e-12 and np.abs(err).max() > 0
    lines = SWING.SPOT_LINES
    u = np.linspace(0, 2 * np.pi, 4001)[:-1]
    at = (np.round(SWING.SPOT_AT * lines / (2 * np.pi)) * 2 * np.pi + u) / lines   # one period
    e = SWING.spot(at, depth) * lines
    c = fit(e, (np.sin(2 * u), np.cos(2 * u), np.sin(u), np.cos(u)))
    assert -c[0] == pytest.approx(depth / 2, rel=0.1) and abs(c[2]) < 5e-3 * depth
    d = depth * np.exp(-0.5 * ((at - SWING.SPOT_AT) / SWING.SPOT_WIDTH) ** 2)
    exact = np.arctan2((1 - d) * np.sin(u), np.cos(u)) - np.arctan2(np.sin(u), np.cos(u))
    assert np.allclose(e, exact, rtol=0, atol=1e-12)              # track A attenuated by d
    assert np.allclose(e, -d / 2 * np.sin(2 * u), atol=depth ** 2 / 2)


def test_both_harnesses_take_set_f_by_held_out_f(monkeypatch):
    check_harnesses('f', SHAPES, SWING_SHAPES, monkeypatch)
