# Held-out set M (bench/validate_diagnosis_heldout_m.py, static, and
# bench/validate_diagnosis_swing_heldout_m.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out m. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT,
                            fold_lines, G0, load_set, N_ARW, rng, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('m')


def line(y, t, f):
    """Amplitude of the sine of frequency ``f`` (Hz) fitted to ``y``."""
    cols = np.c_[np.cos(2 * np.pi * f * t), np.sin(2 * np.pi * f * t), np.ones_like(t)]
    return float(np.hypot(*np.linalg.lstsq(cols, y, rcond=None)[0][:2]))


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_warming_pole_smooths_heavily_at_first_and_not_at_all_at_the_end():
    fn, levels = SHAPES['internal_lowpass']
    a = levels[1]['a']
    assert np.allclose(fn(np.full(5000, 0.003), rng(1), a=a), 0.003, rtol=1e-12)   # DC gain 1
    x = rng(2).standard_normal(720000)
    y = fn(x.copy(), rng(3), a=a)
    t0 = rng(3).uniform(0, 60)
    ak = STATIC.pole_track(a, x.size, DT, t0)
    assert np.allclose(y[1:] - ak[1:] * y[:-1], (1 - ak[1:]) * x[1:], atol=1e-12)
    assert ak[0] == pytest.approx(a * np.exp(-t0 / 900.0))
    early, late = y[:20000], y[-100000:]
    v = (1 - ak) / (1 + ak)                                        # local output variance
    assert np.mean(early[1:] * early[:-1]) / np.mean(early ** 2) == pytest.approx(
        np.average(ak[1:20000], weights=v[:19999]), abs=0.02)
    assert abs(np.mean(late[1:] * late[:-1]) / np.mean(late ** 2)) < 0.01
    assert np.max(np.abs(late - x[-100000:])) < 0.01               # the pole has faded
    pooled = np.sum(y[1:] * y[:-1]) / np.sum(y * y)
    assert pooled == pytest.approx(STATIC.pooled_r1(a, x.size, DT, t0), abs=3 / np.sqrt(x.size))


def test_buffeting_is_a_gaussian_continuum_with_the_von_karman_slope():
    fn, _ = SHAPES['vibration']
    ys = np.array([fn(np.zeros(2 ** 19), rng(4 + i), amplitude=1.0) for i in range(3)])
    assert np.std(ys) == pytest.approx(1.0, rel=0.02)
    assert abs(stats.kurtosis(ys.ravel())) < 0.05 and abs(stats.skew(ys.ravel())) < 0.02
    f, p = signal.welch(ys, fs=1 / DT, nperseg=4096)
    p = p.mean(axis=0)
    want = STATIC.gust_psd(f, 1.0, DT)
    for lo in (0.5, 1.5, 3.0, 6.0, 12.0, 24.0):
        band = (f >= lo) & (f < 2 * lo)
        assert np.mean(p[band]) == pytest.approx(np.mean(want[band]), rel=0.08), lo
    k = (f > 15) & (f < 45)
    slope = np.polyfit(np.log(f[k]), np.log(p[k]), 1)[0]
    assert slope == pytest.approx(np.polyfit(np.log(f[k]), np.log(want[k]), 1)[0], abs=0.1)
    assert -1.7 < slope < -1.4                                      # -5/3, lifted by the 3 Hz HP
    share = np.convolve(p, np.ones(41), 'valid') / np.sum(p)       # any 1 Hz band's share
    assert np.max(share) < 0.15 and np.sum(p[f > 10]) > 0.25 * np.sum(p)   # broad, no line
    assert np.max(p) < 20 * np.median(p[(f > 1) & (f < 45)])


def test_radial_spreading_is_the_line_source_solution_rising_as_log_t():
    fn, levels = SHAPES['temperature_drift']
    amp = levels[1]['amplitude']
    y = fn(np.zeros(720000), rng(5), amplitude=amp)
    t = np.arange(720000) * DT + rng(5).uniform(0, 60)
    assert np.allclose(y, amp * special.exp1(300.0 / t), rtol=1e-12, atol=0)
    assert np.all(np.diff(y) >= 0) and y[0] < 2e-3 * amp              # a dead time, then a rise
    slope = np.gradient(y, np.log(t))                                  # per e-fold of time
    late = t > 2000
    assert np.allclose(slope[late], amp * np.exp(-300.0 / t[late]), rtol=1e-3)
    assert y[-1] - y[360000] == pytest.approx(amp * np.log(t[-1] / t[360000]), rel=0.08)

    def temp(r, tt):                                 # T = E1(r^2 / (4 alpha t)), alpha = 1
        return special.exp1(r * r / (4 * tt))
    r, tt, h = np.sqrt(1200.0), 500.0, 1e-2
    dt_ = (temp(r, tt + h) - temp(r, tt - h)) / (2 * h)
    lap = ((temp(r + h, tt) - 2 * temp(r, tt) + temp(r - h, tt)) / h ** 2
           + (temp(r + h, tt) - temp(r - h, tt)) / (2 * h * r))
    assert dt_ == pytest.approx(lap, rel=1e-4)                       # 2-D diffusion, radial
    s = STATIC.spreading(np.arange(720000) * DT + 30.0, amp)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(s) * np.sqrt(720000) / SIG, rel=1e-9)


def test_lognormal_flicker_is_the_exponential_of_a_gaussian_one_over_f():
    fn, _ = SHAPES['bias_instability']
    s = STATIC.LOGNORMAL
    y = fn(np.zeros(2 ** 20), rng(6), b=1.0)
    g = STATIC.barrier(2 ** 20, DT, rng(6))
    sd = np.sqrt(np.exp(s * s) * np.expm1(s * s))
    assert np.allclose(y, (np.exp(s * g) - np.exp(s * s / 2)) / sd, atol=1e-12)
    tau = np.geomspace(0.1, 700, 9)
    exact = STATIC.cov_avar(lambda u: STATIC.flicker_cov(u, 1.0, 1e-4), tau)
    gm = sum(STATIC.gm_avar(tau, 1 / np.sqrt(11), tc) for tc in STATIC.FLICKER_TAUS)
    assert np.allclose(exact, gm, rtol=1e-3)                      # s -> 0: the Gaussian sum
    want = STATIC.cov_avar(lambda u: STATIC.flicker_cov(u, 1.0), tau)
    slope = np.polyfit(np.log(tau[2:7]), np.log(want[2:7]), 1)[0]
    assert abs(slope) < 0.15                                       # a flicker floor
    ys = [fn(np.zeros(2 ** 20), rng(20 + i), b=1.0) for i in range(6)]
    for m in (100, 1000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        assert got == pytest.approx(STATIC.cov_avar(lambda u: STATIC.flicker_cov(u, 1.0),
                                                    m * DT)[0], rel=0.3)
    r = rng(7)
    first = np.array([fn(np.zeros(2), r, b=1.0)[0] for _ in range(3000)])   # stationary law
    g0 = np.log(first * sd + np.exp(s * s / 2)) / s
    assert abs(np.mean(g0)) < 0.06 and np.var(g0) == pytest.approx(1.0, rel=0.08)
    assert stats.kstest(g0, 'norm').pvalue > 0.01                  # exp of a Gaussian
    assert abs(np.mean(first)) < 0.08 and np.var(first) == pytest.approx(1.0, rel=0.25)
    assert np.mean([stats.skew(v) for v in ys]) > 1.5              # skewed, not Gaussian


def test_crackling_slips_are_poisson_with_pareto_sizes_and_a_walks_allan_variance():
    fn, _ = SHAPES['rate_random_walk']
    ys = [fn(np.zeros(2 ** 21), rng(30 + i), k=1.0) for i in range(4)]
    steps = np.concatenate([np.diff(y) for y in ys])
    size = np.abs(steps[steps != 0])
    xm = 1.0 / np.sqrt(STATIC.CRACK_RATE * 3.0)
    assert size.size / (4 * 2 ** 21 * DT) == pytest.approx(STATIC.CRACK_RATE, rel=0.03)
    assert np.quantile(size, 0.01) > 0.9 * xm
    for x, rel in ((2.0, 0.06), (4.0, 0.15)):                      # P(|s| > x xm) = x^-3
        assert np.mean(size > x * xm) == pytest.approx(x ** -3.0, rel=rel)
    assert stats.kurtosis(steps[steps != 0]) > 10                  # heavy tails
    win = int(100 / DT)
    counts = np.concatenate([(np.diff(y) != 0)[:y.size // win * win - win].reshape(-1, win)
                             .sum(axis=1) for y in ys])
    assert counts.var() / counts.mean() == pytest.approx(1.0, abs=0.25)   # no clustering
    for m in (100, 3000):
        got = np.mean([avar(y, [m])[0] for y in ys])
        assert got == pytest.approx(STATIC.walk_avar(m, np.sqrt(DT)), rel=0.3)


def test_popcorn_sits_low_and_bursts_up_a_tenth_of_the_time_with_exponential_correlation():
    fn, _ = SHAPES['gauss_markov']
    tc, p = 0.5, STATIC.POP_UP
    y = fn(np.zeros(2 ** 21), rng(8), sd=1.0, tc=tc)
    levels = np.unique(np.round(y, 9))
    assert levels == pytest.approx([-np.sqrt(p / (1 - p)), np.sqrt((1 - p) / p)])
    up = y > 0
    assert np.mean(up) == pytest.approx(p, abs=0.01)
    assert np.std(y) == pytest.approx(1.0, rel=0.05)
    assert stats.skew(y) == pytest.approx((1 - 2 * p) / np.sqrt(p * (1 - p)), rel=0.1)
    for lag in (25, 50, 100):
        assert np.mean(y[:-lag] * y[lag:]) / np.mean(y * y) == pytest.approx(
            np.exp(-lag * DT / tc), abs=0.03)
    edges = np.flatnonzero(np.diff(up.astype(int)))
    runs = np.diff(edges) * DT
    first_up = up[edges[0] + 1]
    ups, downs = (runs[0::2], runs[1::2]) if first_up else (runs[1::2], runs[0::2])
    assert np.mean(ups) == pytest.approx(tc / (1 - p), rel=0.1)
    assert np.mean(downs) == pytest.approx(tc / p, rel=0.1)


def test_float32_angle_rounds_to_a_spacing_set_by_the_accumulated_angle():
    fn, levels = SHAPES['quantization']
    for theta in (1.0, 240.0, 300.0, 2000.0, 20000.0):
        assert STATIC.float_spacing(theta) == np.spacing(np.float32(theta))
    n = 2 ** 21
    x = SIG * rng(9).standard_normal(n) + 0.003
    for p in levels:
        y = fn(x.copy(), rng(10), **p)
        theta = p['theta0'] + np.cumsum(x) * DT
        read = np.r_[np.float32(p['theta0']), theta.astype(np.float32)].astype(float)
        assert np.allclose(y, np.diff(read) / DT, rtol=0, atol=1e-9)
        ex = avar(y, [1, 10]) - avar(x, [1, 10])
        for m, got in zip((1, 10), ex):
            want = STATIC.float_excess(m, p['theta0'], DT, N_ARW, n) * N_ARW ** 2 / (m * DT)
            assert got == pytest.approx(want, rel=0.12, abs=0.002 * N_ARW ** 2 / DT)
    y = fn(x.copy(), rng(10), theta0=250.0)                        # crosses 256 rad
    theta = 250.0 + np.cumsum(x) * DT
    err = np.cumsum(x - y) * DT
    below, above = err[theta < 255.9], err[theta > 256.1]
    assert np.std(above) / np.std(below) == pytest.approx(2.0, rel=0.05)   # the step doubles


def test_cable_modes_form_a_harmonic_comb_with_inverse_square_shares():
    fn, _ = SHAPES['resonance']
    y = fn(np.zeros(2 ** 21), rng(11), sigma=1.0)
    assert np.std(y) == pytest.approx(1.0, rel=0.05)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.cable_psd(f, 1.0, DT)
    power = []
    for c in STATIC.CABLE_HZ:
        k = np.abs(f - c) < 1.5
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.2), c
        power.append(np.sum(p[np.abs(f - c) < 3.0]))
        assert f[k][np.argmax(p[k])] == pytest.approx(c, abs=0.15)
    assert np.array(power) / power[0] == pytest.approx(1 / np.arange(1, 5) ** 2, rel=0.15)
    assert STATIC.CABLE_HZ / STATIC.CABLE_HZ[0] == pytest.approx([1, 2, 3, 4])


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_fifo_race_repeats_older_samples_a_share_p_of_the_time():
    fn, levels = SWING_SHAPES['time_delay']
    for p in levels[:2]:
        t, rate, (ti, g, te, _) = swing(fn, p, 120.0)
        k = t > 1
        c = np.linalg.lstsq(np.c_[-AMP * W * W * np.sin(W * t[k]), np.cos(W * t[k])],
                            (g - rate)[k], rcond=None)[0]
        assert -c[0] == pytest.approx(4e-3 * p['p'], rel=0.03)     # mean delay 4 p samples
        assert np.array_equal(ti, t) and np.array_equal(te, t)
    p = levels[1]['p']
    noise = rng(12).standard_normal(2 ** 20)
    t = np.arange(noise.size) * 1e-3
    out = fn(t, noise, t, np.zeros_like(t), None, rng(13), p=p)[1]
    same, old = out == noise, out == np.r_[np.full(4, noise[0]), noise[:-4]]
    assert np.all(same | old) and np.mean(old[4:]) == pytest.approx(p, abs=0.01)
    assert np.var(out) == pytest.approx(np.var(noise), rel=0.01)    # values repeated, not mixed
    r4 = np.mean(out[4:] * out[:-4]) / np.var(out)
    assert r4 == pytest.approx(p * (1 - p), abs=0.01)               # duplicates 4 apart


def test_coarse_compensation_leaves_a_zero_mean_sawtooth_in_specific_force():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 60.0)
    f_y = G0 * np.sin(AMP * np.sin(W * t))
    err = g - rate
    step = SWING.COMP_STEP
    assert np.max(np.abs(err)) <= gy * step / 2 * (1 + 1e-9)
    assert np.allclose(err, gy * (f_y - step * np.round(f_y / step)), atol=1e-15)
    assert abs(np.polyfit(f_y, err, 1)[0]) < 0.05 * gy              # no net g-sensitivity
    jumps = np.sum(np.abs(np.diff(err)) > 0.5 * gy * step)
    assert jumps == pytest.approx(12 * 12, abs=2)                  # six edges a half swing
    assert fold_lines(err, kmin=1) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.02)


def test_torquer_hysteresis_is_a_play_loop_on_the_true_rate():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    e = levels[1]['e']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 60.0)
    loop = (g - rate) / e
    h = SWING.PLAY
    assert np.all(np.abs(loop - rate) <= h + 1e-12)
    k = t > 5
    rising, falling = np.gradient(rate) > 0, np.gradient(rate) < 0
    follow = np.abs(np.abs(loop - rate) - h) < 1e-12
    assert np.allclose(loop[k & rising & follow], rate[k & rising & follow] - h)
    assert np.allclose(loop[k & falling & follow], rate[k & falling & follow] + h)
    held = k & ~follow
    both = held[1:] & held[:-1]
    assert np.mean(held) > 0.1 and np.all(np.abs(np.diff(loop)[both]) < 1e-12)
    err = (g - rate)[t >= 5]
    assert fold_lines(err, kmin=2) / S_LINE == pytest.approx(
        SWING.detectability('scale_factor_nonlinearity', levels[1]), rel=0.02)
    spec = np.abs(np.fft.rfft(err[:50000].reshape(-1, 5000).mean(axis=0)))
    assert np.max(spec[2:40:2]) < 1e-6 * np.max(spec[3:40:2])        # odd lines only


def test_chopped_driver_moves_the_2f_line_to_chop_sidebands():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    sign = (g - rate) / (a * np.abs(rate))
    ok = np.abs(rate) > 1e-3
    assert np.allclose(np.abs(sign[ok]), 1.0) and np.mean(sign[ok] > 0) == pytest.approx(
        SWING.DUTY, abs=0.01)
    mag = np.abs(rate)
    base = line(a * mag, t, 2 / 5.0)
    assert line(g - rate, t, 2 / 5.0) / base == pytest.approx(2 * SWING.DUTY - 1, abs=0.01)
    side = base / 2 * 4 / np.pi * np.sin(np.pi * SWING.DUTY)
    for f in (2 / 5.0 + 1 / SWING.CHOP_S, 1 / SWING.CHOP_S - 2 / 5.0):
        assert line(g - rate, t, f) == pytest.approx(side, rel=0.03)


def test_sync_servo_leaves_a_piecewise_linear_stamp_error_between_gaussian_nodes():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    sigma = levels[1]['sigma']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(15), sigma=sigma)
    e = out[2] - t
    assert np.all(np.diff(out[2]) > 0) and np.array_equal(out[0], t)
    kinks = np.flatnonzero(np.abs(np.diff(e, 2)) > 1e-9) + 1
    kinks = kinks[np.r_[True, np.diff(kinks) > 1]]
    assert kinks.size > 440 and np.all(np.isin(np.diff(kinks) % 2000, [0, 1, 1999]))
    assert np.var(e) == pytest.approx(2 / 3 * sigma ** 2, rel=0.12)   # nodes 2 s apart
    assert np.std(e[kinks]) == pytest.approx(sigma, rel=0.1)
    f = np.linspace(-50, 50, 400001)
    assert np.trapezoid(SWING.servo_psd(f, sigma), f) == pytest.approx(2 / 3 * sigma ** 2,
                                                                       rel=1e-3)
    fw, pw = signal.welch(e, fs=1000.0, nperseg=2 ** 16)
    k = (fw > 0.02) & (fw < 0.3)
    assert np.mean(pw[k]) == pytest.approx(np.mean(2 * SWING.servo_psd(fw[k], sigma)),
                                           rel=0.2)


def test_two_led_head_errs_by_a_wandering_amplitude_ratio():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    g = 0.01
    phi = np.linspace(-0.3, 0.3, 200001)
    err = SWING.ratio_error(phi, g)
    u, v = SWING.LINES * (phi + SWING.MOUNT), SWING.LINES * (phi + SWING.MOUNT + err)
    assert np.allclose(np.sin(v) * np.cos(u) - (1 + g) * np.sin(u) * np.cos(v), 0, atol=1e-12)
    assert np.allclose(err, g * np.sin(2 * u) / (2 * SWING.LINES), atol=0.01 * g / SWING.LINES)
    p = levels[1]
    t, rate, (_, _, te, enc) = swing(fn, p, 600.0)
    angle = AMP * np.sin(W * t)
    wander = p['gamma'] * SWING.led_wander(t.size, 1000.0, rng(10))
    assert np.allclose(enc - angle, SWING.ratio_error(angle, wander), atol=1e-15)
    w = SWING.led_wander(2 ** 23, 1000.0, rng(16))
    assert np.var(w) == pytest.approx(1.0, rel=0.25)
    lag = int(SWING.LED_TC * 1000)
    assert np.mean(w[lag:] * w[:-lag]) / np.mean(w * w) == pytest.approx(np.exp(-1), abs=0.15)
    zs = [SWING.detectability('encoder_cyclic_error', q) for q in levels]
    assert zs[0] / zs[2] == pytest.approx((levels[0]['gamma'] / levels[2]['gamma']) ** 2,
                                          rel=1e-6)


def test_both_harnesses_take_set_m_by_held_out_m(monkeypatch):
    check_harnesses('m', SHAPES, SWING_SHAPES, monkeypatch)
