# Held-out set L (bench/validate_diagnosis_heldout_l.py, static, and
# bench/validate_diagnosis_swing_heldout_l.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out l. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            fold_lines, G0, load_set, N_ARW, noisy_run, rng, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('l')
S_N = S_LINE / np.sqrt(2 / 900.0) * np.sqrt(1000.0)      # the preset gyro's noise per sample


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_soak_releases_what_it_absorbs_through_the_stated_multi_exponential_kernel():
    fn, levels = SHAPES['internal_lowpass']
    eps = levels[1]['eps']
    imp = fn(np.r_[0.0, 1.0, np.zeros(5000)], rng(1), eps=eps)[1:]
    j = np.arange(1, 5001)
    want = eps * sum((1 - np.exp(-1 / t)) * np.exp(-(j - 1) / t) for t in (1, 10, 100, 1000)) / 4
    assert imp[0] == pytest.approx(1 - eps) and np.allclose(imp[1:], want, atol=1e-14)
    assert np.allclose(fn(np.full(3000, 0.003), rng(1), eps=eps), 0.003, rtol=1e-12)
    h = STATIC.soak_kernel(eps)
    r = STATIC.kernel_corr(h)
    assert r[:3] == pytest.approx([np.dot(h[:-k], h[k:]) / np.dot(h, h) for k in (1, 2, 3)])
    y = fn(rng(2).standard_normal(2 ** 21), rng(2), eps=eps)
    y -= y.mean()
    got = [np.mean(y[:-k] * y[k:]) / np.mean(y * y) for k in (1, 2, 50)]
    assert got == pytest.approx(r[[0, 1, 49]], abs=0.004)
    z = STATIC.detectability('internal_lowpass', levels[2], DT, SIG, N_ARW)
    h = STATIC.soak_kernel(levels[2]['eps'])
    r = [np.dot(h[:-k], h[k:]) / np.dot(h, h) for k in range(1, 3000)]
    assert z == pytest.approx(np.sqrt(720000 * np.sum(np.square(r))), rel=0.01)


def test_traffic_bursts_carry_the_floor_band_under_envelopes_with_the_computed_power():
    fn, levels = SHAPES['vibration']
    ys = np.array([fn(np.zeros(2 ** 20), rng(3 + i), amplitude=1.0) for i in range(4)])
    assert np.mean(ys ** 2) == pytest.approx(STATIC.envelope_power(1.0), rel=0.25)
    f, p = signal.welch(ys, fs=1 / DT, nperseg=4096)
    p = p.mean(axis=0) / np.mean(ys ** 2) * STATIC.envelope_power(1.0)
    want = STATIC.traffic_psd(f, 1.0, DT)
    for lo, hi in ((8, 12), (12, 18), (18, 24), (24, 30), (30, 40)):
        band = (f > lo) & (f < hi)
        assert np.mean(p[band]) == pytest.approx(np.mean(want[band]), rel=0.1)
    assert np.sum(p[(f > 12) & (f < 30)]) > 0.8 * np.sum(p)
    assert stats.kurtosis(ys.ravel()) > 10                           # bursts, not a steady hum
    rms = np.sqrt(np.convolve(ys[0] ** 2, np.ones(100) / 100, 'valid'))
    assert np.mean(rms < 0.01 * rms.max()) > 0.5                     # quiet between passes


def test_radio_heating_is_the_periodic_steady_state_of_a_lagged_duty_cycle():
    fn, levels = SHAPES['temperature_drift']
    t = np.arange(0, 20 * STATIC.RADIO_S, DT)
    on = np.mod(t, STATIC.RADIO_S) < STATIC.TX_S
    c = np.exp(-DT / STATIC.DIE_S)
    die = signal.lfilter([1 - c], [1, -c], on.astype(float))        # from cold, stepped
    last = t >= 18 * STATIC.RADIO_S
    assert np.allclose(die[last], STATIC.radio_heat(t[last] + DT, 1.0), atol=2e-3)
    amp = levels[1]['amplitude']
    y = fn(np.zeros(int(3 * STATIC.RADIO_S / DT)), rng(4), amplitude=amp)
    per = int(STATIC.RADIO_S / DT)
    assert np.allclose(y[per:2 * per], y[2 * per:], atol=1e-12)          # 300 s period
    assert np.ptp(y) == pytest.approx(amp * (1 - np.exp(-0.5)) * (1 - 0.0044), rel=0.01)
    s = STATIC.radio_heat(np.arange(720000) * DT, amp)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(s) * np.sqrt(720000) / SIG, rel=1e-9)


def test_hopping_trap_is_one_two_level_fluctuator_with_a_one_over_f_spectrum():
    fn, _ = SHAPES['bias_instability']
    ys = np.array([fn(np.zeros(2 ** 20), rng(5 + i), b=1.0) for i in range(6)])
    assert set(np.unique(ys)) == {-1.0, 1.0}
    d = STATIC.hop_dwells(200000, rng(6))
    a, top = STATIC.HOP_S
    for x in (0.1, 1.0, 100.0):                                       # P(tau > x) ~ 1 / x
        assert np.mean(d > x) == pytest.approx((1 / x - 1 / top) / (1 / a - 1 / top), rel=0.1)
    f, p = signal.welch(ys, fs=1 / DT, nperseg=2 ** 15)
    p = p.mean(axis=0)
    want = STATIC.hopper_psd(f, 1.0)
    for lo, hi in ((0.01, 0.1), (0.1, 1.0), (1.0, 10.0)):
        k = (f >= lo) & (f < hi)
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.15)
    g = np.geomspace(1e-3, 1.0, 20)
    assert np.polyfit(np.log(g), np.log(STATIC.hopper_psd(g, 1.0)), 1)[0] == \
        pytest.approx(-1.0, abs=0.1)
    g = np.geomspace(1e-9, 1e6, 400001)
    assert np.trapezoid(STATIC.hopper_psd(g, 1.0), g) == pytest.approx(1.0, rel=0.02)
    got = np.mean([avar(y, [1000])[0] for y in ys])
    assert got == pytest.approx(STATIC.psd_avar(lambda h: STATIC.hopper_psd(h, 1.0), 10.0,
                                                DT)[0], rel=0.35)


def test_avalanche_walk_has_clustered_slips_and_the_allan_variance_of_a_walk():
    fn, _ = SHAPES['rate_random_walk']
    lam, eta, kern = STATIC.AVALANCHE
    ys = [fn(np.zeros(2 ** 21), rng(30 + i), k=1.0) for i in range(4)]
    win = int(200 / DT)
    counts = np.concatenate([(np.diff(y) != 0)[:y.size // win * win - win].reshape(-1, win)
                             .sum(axis=1) for y in ys])
    assert counts.mean() == pytest.approx(lam * 200, rel=0.15)
    te = kern / (1 - eta)
    fano = 1 + (1 / (1 - eta) ** 2 - 1) * (1 - te / 200 * (1 - np.exp(-200 / te)))
    assert counts.var() / counts.mean() == pytest.approx(fano, rel=0.3)   # Poisson: 1
    for m in (100, 3000):
        got = np.mean([avar(y, [m])[0] for y in ys])
        assert got == pytest.approx(STATIC.walk_avar(m, np.sqrt(DT)), rel=0.3)


def test_pearson_diffusion_has_exponential_correlation_and_state_dependent_noise():
    fn, _ = SHAPES['gauss_markov']
    tc = 0.5
    y = fn(np.zeros(2 ** 20), rng(8), sd=1.0, tc=tc)
    c = np.exp(-DT / tc)
    assert np.std(y) == pytest.approx(1.0, rel=0.05)
    for lag in (10, 25, 50):
        assert np.mean(y[:-lag] * y[lag:]) / np.mean(y * y) == pytest.approx(
            np.exp(-lag * DT / tc), abs=0.03)
    inc2 = (y[1:] - c * y[:-1]) ** 2 / (1 - c * c)
    slope, icpt = np.polyfit(y[:-1] ** 2, inc2, 1)
    assert slope == pytest.approx(STATIC.PEARSON, abs=0.02)
    assert icpt == pytest.approx(1 - STATIC.PEARSON, abs=0.03)
    assert stats.kurtosis(y, fisher=False) == pytest.approx(STATIC.pearson_kurtosis(c), rel=0.15)
    assert STATIC.pearson_kurtosis(c) > 4.0


def test_alternating_counters_read_half_a_step_apart_with_the_computed_allan_excess():
    fn, levels = SHAPES['quantization']
    n = 2 ** 21
    x = SIG * rng(9).standard_normal(n) + 0.003
    for p in levels[:2] + [{'step': 1.5 * N_ARW * np.sqrt(DT)}]:
        step = p['step']
        y = fn(x.copy(), rng(10), **p)
        start = rng(10).uniform(0, step)
        read = start + np.cumsum(y) * DT
        theta = start + np.cumsum(x) * DT
        off = (np.arange(n) % 2) * step / 2
        assert np.allclose((read - off) / step, np.round((read - off) / step), atol=1e-6)
        assert np.all((theta - read > -1e-9) & (theta - read < step + 1e-9))
        ex = avar(y, [1, 10]) - avar(x, [1, 10])
        for m, got in zip((1, 10), ex):
            want = STATIC.pair_excess(m, step, DT, N_ARW) * N_ARW ** 2 / (m * DT)
            assert got == pytest.approx(want, rel=0.12, abs=0.002 * N_ARW ** 2 / DT)


def test_clamped_mode_switches_between_two_lines_with_the_computed_mean_spectrum():
    fn, _ = SHAPES['resonance']
    y = fn(np.zeros(2 ** 21), rng(11), sigma=1.0)
    assert np.std(y) == pytest.approx(1.0, rel=0.05)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.clamp_psd(f, 1.0, DT)
    band = (f > 20) & (f < 45)
    assert np.allclose(p[band], want[band], rtol=0.4)
    for lo, hi in ((29, 33), (34.5, 38.5)):
        k = (f > lo) & (f < hi)
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.25)
    seg = y[:y.size // 2000 * 2000].reshape(-1, 2000)                  # 20 s windows
    fs, ps = signal.welch(seg, fs=1 / DT, nperseg=1000)
    peak = fs[np.argmax(ps, axis=1)]
    near = [np.mean(np.abs(peak - c) < 1.5) for c in STATIC.CLAMP_HZ]
    assert min(near) > 0.25 and sum(near) > 0.85                       # one line at a time


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_predictor_leads_the_motion_and_lifts_only_the_fast_noise():
    fn, levels = SWING_SHAPES['time_delay']
    for p in levels[:2]:
        t, rate, (ti, g, te, _) = swing(fn, p, 60.0)
        k = t > 1
        c = fit((g - rate)[k], (-AMP * W * W * np.sin(W * t[k]), np.cos(W * t[k])))
        assert c[0] == pytest.approx(p['lead_s'], rel=0.02)          # g(t) ~ rate(t + lead)
        assert np.array_equal(ti, t) and np.array_equal(te, t)
    p = levels[1]
    noise = rng(12).standard_normal(2 ** 18)
    t = np.arange(noise.size) * 1e-3
    out = fn(t, noise, t, np.zeros_like(t), None, None, **p)[1]
    q = p['lead_s'] * 1000.0 / SWING.SLOPE_SAMPLES
    assert np.var(out) == pytest.approx((1 + q) ** 2 + q * q, rel=0.02)
    f, pxx = signal.welch(out, fs=1000.0, nperseg=4096)
    assert np.mean(pxx[(f > 0.5) & (f < 2)]) == pytest.approx(2e-3, rel=0.15)   # DC gain 1


def test_preload_leaves_small_tilts_alone_and_its_odd_lines_are_as_computed():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    f_y = G0 * np.sin(AMP * np.sin(W * t))
    err = g - rate
    small = np.abs(f_y) < SWING.PRELOAD
    assert np.all(err[small] == 0) and small.mean() > 0.2
    big = np.abs(f_y) > SWING.PRELOAD + 0.1
    assert np.allclose(err[big] / (f_y[big] - np.sign(f_y[big]) * SWING.PRELOAD), gy)
    cols = [h(j * W * t) for j in range(1, 40, 2) for h in (np.sin, np.cos)]
    assert np.linalg.norm(fit(err, cols)) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.02)


def test_two_range_blend_hands_over_to_a_noisier_mis_scaled_channel():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    t, gyro = noisy_run()
    rate = AMP * W * np.cos(W * t)

    def stand(x):
        return AMP * np.sin(W * x), AMP * W * np.cos(W * x)
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, stand(t)[0], stand, rng(14), **p)[1]
        low = np.abs(gyro) <= SWING.BLEND[0]
        assert np.array_equal(out[low], gyro[low])
        high = np.abs(gyro) >= SWING.BLEND[1]
        extra = out[high] - gyro[high] - p['gain'] * rate[high]
        assert np.std(extra) == pytest.approx(S_N, rel=0.02) and abs(extra.mean()) < 1e-4
        assert fold_lines(out - gyro) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_nonlinearity', p), rel=0.1)


def test_push_pull_mismatch_puts_a_quadrature_2f_line_on_the_slope_of_abs_rate():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    t, gyro = noisy_run()
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, None, None, None, **p)[1]
        m = SWING.SLOPE_SAMPLES
        mag = np.abs(gyro)
        assert np.allclose((out - gyro)[m:], -p['tau'] * (mag[m:] - mag[:-m]) * 100.0)
        assert fold_lines(out - gyro) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_asymmetry', p), rel=0.08)
        k = t > 1
        cols = (np.cos(2 * W * t[k]), np.sin(2 * W * t[k]), np.ones(k.sum()))
        e2, a2 = fit((out - gyro)[k], cols)[:2], fit(np.abs(gyro)[k], cols)[:2]
        angle = np.degrees(np.angle(complex(*e2)) - np.angle(complex(*a2))) % 360
        assert angle == pytest.approx(90.0, abs=3.0)          # -tau d/dt: a quarter period on


def test_dejitter_leaves_a_running_mean_of_exponential_latencies():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    mean = levels[1]['mean']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(15), mean=mean)
    e = out[2] - t
    assert np.all(np.diff(out[2]) > 0) and np.array_equal(out[0], t)
    m = SWING.DEJITTER
    assert abs(e.mean()) < 0.02 * mean and np.var(e) == pytest.approx(mean ** 2 / m, rel=0.05)
    for lag in (8, 16, 40):
        r = np.mean((e[:-lag] - e.mean()) * (e[lag:] - e.mean())) / np.var(e)
        assert r == pytest.approx(max(0.0, 1 - lag / m), abs=0.02)       # a triangle
    assert stats.skew(e) == pytest.approx(2 / np.sqrt(m), rel=0.25)
    f = np.linspace(-500, 500, 400001)
    assert np.trapezoid(SWING.dejitter_psd(f, mean, 1000.0), f) == pytest.approx(
        mean ** 2 / m, rel=1e-3)


def test_warming_led_grows_an_atan2_offset_error_of_the_line_period():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    o = 0.05
    phi = np.linspace(-0.3, 0.3, 200001)
    err = SWING.offset_error(phi, o)
    u, v = SWING.LINES * (phi + SWING.MOUNT), SWING.LINES * (phi + SWING.MOUNT + err)
    assert np.allclose(np.sin(v) * np.cos(u) - np.cos(v) * (np.sin(u) + o), 0, atol=1e-12)
    assert np.max(np.abs(err)) == pytest.approx(np.arcsin(o) / SWING.LINES, rel=1e-3)
    p = levels[1]
    t, rate, (_, _, te, enc) = swing(fn, p, 600.0)
    phi = AMP * np.sin(W * t)
    got = enc - phi
    assert np.allclose(got, SWING.offset_error(phi, SWING.led_offset(t, p['offset'])),
                       atol=1e-15)
    amp = [np.max(np.abs(got[(t > a) & (t < a + 5)])) for a in (10.0, 240.0, 590.0)]
    want = [p['offset'] * (1 - np.exp(-(a + 5) / 240.0)) / SWING.LINES for a in (10, 240, 590)]
    assert amp == pytest.approx(want, rel=0.05)                          # the LED warming
    zs = [SWING.detectability('encoder_cyclic_error', q) for q in levels]
    assert zs[0] / zs[2] == pytest.approx(levels[0]['offset'] / levels[2]['offset'], rel=0.02)


def test_both_harnesses_take_set_l_by_held_out_l(monkeypatch):
    check_harnesses('l', SHAPES, SWING_SHAPES, monkeypatch)
