# Held-out set P (bench/validate_diagnosis_heldout_p.py, static, and
# bench/validate_diagnosis_swing_heldout_p.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out p. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_swing_set, DT, G0, load_set,
                            N_ARW, noisy_run, rng, S_LINE, SIG, STATIC_NAMES, swing, W)
import numpy as np
import pytest
from scipy import special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('p')
LSB = 0.05 * np.pi / 180.0


def acf(y, lags):
    y = y - y.mean()
    return np.array([np.mean(y[:-k] * y[k:]) for k in lags]) / np.mean(y * y)


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    assert sorted(SHAPES) == sorted(STATIC_NAMES + ['stale_samples'])
    for name, (fn, levels) in SHAPES.items():
        weak, strong, edge = [STATIC.detectability(name, p, DT, SIG, N_ARW) for p in levels]
        assert 3.5 <= edge <= 4.5 and 2.5 * edge < weak < strong, (name, edge, weak, strong)
        for p in levels:
            g = rng(1)
            x = SIG * g.standard_normal(20000) + 0.003
            y = fn(x.copy(), g, **p)
            assert y.shape == x.shape and np.all(np.isfinite(y)), name
            assert not np.allclose(y, x, rtol=0, atol=1e-12), name


def test_busy_hub_averages_two_samples_in_a_random_share_of_slots():
    fn, levels = SHAPES['internal_lowpass']
    q = 0.3
    x = rng(2).standard_normal(2 ** 20)
    y = fn(x.copy(), rng(3), q=q)
    busy = rng(3).uniform(size=x.size) < q
    busy[0] = False
    assert np.array_equal(y[~busy], x[~busy])
    assert np.allclose(y[busy], (x[busy] + x[np.flatnonzero(busy) - 1]) / 2)
    assert np.mean(busy) == pytest.approx(q, abs=0.005)
    r = acf(y, [1, 2, 5])
    assert r[0] == pytest.approx(q / 2, abs=0.005) and np.all(np.abs(r[1:]) < 0.005)
    n = 720000
    assert STATIC.detectability('internal_lowpass', levels[2], DT, SIG, N_ARW) == \
        pytest.approx(levels[2]['q'] / 2 * np.sqrt(n))


def test_belt_compressor_is_a_frequency_modulated_tone_with_bessel_sidebands():
    fn, levels = SHAPES['vibration']
    n = 100000                                                      # 1000 s: lines on bins
    y = fn(np.zeros(n), rng(4), amplitude=1.0)
    g = rng(4)
    t = np.arange(n) * DT
    assert np.allclose(y, STATIC.belt_tone(t, 1.0, g.uniform(0, 2 * np.pi),
                                           g.uniform(0, 2 * np.pi)), atol=1e-9)
    assert np.mean(y ** 2) == pytest.approx(0.5, rel=1e-3)
    spec = 2 * np.abs(np.fft.rfft(y)) / n
    f = np.fft.rfftfreq(n, DT)
    for k in range(-3, 4):
        i = np.argmin(np.abs(f - (STATIC.PUMP_HZ + k * STATIC.BELT_HZ)))
        assert spec[i] == pytest.approx(abs(special.jv(k, STATIC.BELT_INDEX)), abs=2e-3), k
    dev = STATIC.BELT_INDEX * STATIC.BELT_HZ
    outside = np.abs(f - STATIC.PUMP_HZ) > dev + 3 * STATIC.BELT_HZ
    assert np.sum(spec[outside] ** 2) < 0.01 * np.sum(spec ** 2)    # Carson's band


def test_battery_drift_is_convex_and_accelerating():
    fn, levels = SHAPES['temperature_drift']
    y = fn(np.zeros(720000), rng(5), amplitude=1.0)
    t = np.arange(720000) * DT + rng(5).uniform(0, 600)
    assert np.allclose(y, STATIC.battery(t, 1.0), atol=1e-12)
    assert np.all(np.diff(y) > 0) and np.all(np.diff(y, 2) > -1e-12)
    assert STATIC.battery(STATIC.T_BAT / 2, 1.0) == pytest.approx(3.0)
    slope = np.diff(y) / DT
    assert slope[-1] / slope[0] == pytest.approx(((1 - t[0] / STATIC.T_BAT)
                                                  / (1 - t[-1] / STATIC.T_BAT)) ** 3, rel=1e-3)


def test_interference_is_a_bounded_sine_of_a_flicker_phase():
    fn, _ = SHAPES['bias_instability']
    assert STATIC.interference_cov(0.0, 1.0) == pytest.approx(1.0, rel=1e-9)
    ys = np.array([fn(np.zeros(2 ** 19), rng(10 + i), b=1.0) for i in range(4)])
    s2 = STATIC.PHASE_SD ** 2
    bound = 1 / np.sqrt(np.exp(-s2) * np.sinh(s2))
    assert np.abs(ys).max() <= bound + 1e-12 and np.abs(ys).max() > 0.99 * bound
    assert np.std(ys) == pytest.approx(1.0, rel=0.1)
    assert stats.kurtosis(ys.ravel()) < -0.5                         # arcsine-like, flat
    for lag in (0.05, 1.0, 10.0):
        k = int(lag / DT)
        got = np.mean([np.mean((v[:-k] - v.mean()) * (v[k:] - v.mean())) for v in ys])
        assert got == pytest.approx(float(STATIC.interference_cov(lag, 1.0)), abs=0.12), lag
    for m in (100, 1000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        want = STATIC.cov_avar(lambda u: STATIC.interference_cov(u, 1.0), m * DT)[0]
        assert got == pytest.approx(want, rel=0.3), m


def test_barrier_walk_is_log_normal_with_steps_growing_with_the_level():
    fn, _ = SHAPES['rate_random_walk']
    k = 1e-4
    d = k * np.sqrt(STATIC.LOG_S)
    y = fn(np.zeros(720000), rng(20), k=k)
    bias, walk = STATIC.barrier_walk(720000, k, DT, rng(20))
    assert np.array_equal(y, bias) and np.all(y > -d)               # the current stays > 0
    local = k * np.sqrt(DT) * np.exp(walk[:-1] / d)
    assert np.std(np.diff(y) / local) == pytest.approx(1.0, rel=0.01)
    ends = [fn(np.zeros(720000), rng(21 + i), k=k)[-1] for i in range(60)]
    assert stats.skew(ends) > 0.5                                   # skewed upwards


def test_trap_cluster_is_an_exponentially_correlated_lattice():
    fn, levels = SHAPES['gauss_markov']
    tc = 1.0
    y = fn(np.zeros(2 ** 21), rng(30), sd=1.0, tc=tc)
    m = STATIC.TRAPS
    lev = y * np.sqrt(m)
    assert np.allclose(lev, np.round(lev)) and np.all(np.abs(lev) <= m)
    vals, counts = np.unique(np.round(lev), return_counts=True)
    assert vals.size == m + 1
    want = special.comb(m, (vals + m) / 2) / 2 ** m
    assert counts / y.size == pytest.approx(want, abs=0.02)         # binomial marginal
    assert np.var(y) == pytest.approx(1.0, rel=0.05)
    assert acf(y, [50, 100, 300]) == pytest.approx(np.exp(-np.array([0.5, 1.0, 3.0])),
                                                   abs=0.03)


def test_gateway_rounds_twice_and_leaves_a_white_angle_error():
    fn, levels = SHAPES['quantization']
    n = 2 ** 20
    x = SIG * rng(40).standard_normal(n) + STATIC.BIAS
    theta = np.cumsum(x) * DT
    for p in (levels[0], levels[2]):
        y = fn(x.copy(), rng(41), **p)
        out = np.cumsum(y) * DT
        step = p['q'] * STATIC.GATE_R
        assert np.allclose(out / step, np.round(out / step), atol=1e-6)
        err = out - theta
        assert np.var(err) == pytest.approx(STATIC.gateway_var(p['q']), rel=0.05)
        assert np.all(np.abs(acf(err, [1, 2, 10])) < 0.05)           # nearly white
        ex = avar(y, [1]) - avar(x, [1])
        assert ex[0] == pytest.approx(3 * STATIC.gateway_var(p['q']) / DT ** 2, rel=0.1)


def test_snubbed_mount_clips_the_angle_and_keeps_the_bussgang_gain():
    fn, levels = SHAPES['resonance']
    n = 2 ** 20
    y = fn(np.zeros(n), rng(50), sigma=1.0)
    phi, lim = STATIC.mode_angle(n, 1.0, DT, rng(50))
    free = np.diff(phi) / DT
    assert np.allclose(y, np.diff(np.clip(phi, -lim, lim)) / DT)
    assert np.std(free) == pytest.approx(1.0, rel=0.03)
    assert lim == pytest.approx(STATIC.STOP * np.std(phi), rel=0.03)
    on = np.abs(phi) >= lim
    assert np.mean(on) == pytest.approx(1 - special.erf(STATIC.STOP / np.sqrt(2)), abs=0.02)
    gain = np.sum(y * free) / np.sum(free * free)
    assert gain == pytest.approx(special.erf(STATIC.STOP / np.sqrt(2)), abs=0.02)
    kappa = special.erf(STATIC.STOP / np.sqrt(2))
    assert kappa ** 2 < np.var(y) < kappa                              # plus distortion


def test_housekeeping_freezes_repeat_periodic_bursts():
    fn, levels = SHAPES['stale_samples']
    freeze, period = 0.05, 3.0
    n = 360000
    x = SIG * rng(60).standard_normal(n) + 0.003
    y = fn(x.copy(), rng(61), freeze=freeze, period=period)
    held = STATIC.frozen(n, freeze, period, DT, rng(61).uniform(0, period))
    assert np.array_equal(y[~held], x[~held])
    rep = np.diff(y) == 0
    assert np.array_equal(rep, held[1:])
    starts = np.flatnonzero(held[1:] & ~held[:-1]) + 1
    assert np.allclose(np.diff(starts) * DT, period, atol=DT)       # periodic bursts
    lengths = np.diff(np.r_[np.flatnonzero(np.diff(held.astype(int)) != 0), n - 1])[::2]
    assert np.all(np.abs(lengths[:-1] - freeze / DT) <= 1)          # of ~F / dt repeats
    assert np.all(y[starts] == x[starts - 1])                       # the sample before
    assert np.mean(held) == pytest.approx(freeze / period, rel=0.05)
    q0 = STATIC.repeat_share(SIG)
    xr, yr = np.round(x / LSB), np.round(y / LSB)
    assert np.mean(np.diff(xr) == 0) == pytest.approx(q0, rel=0.05)
    assert np.mean(np.diff(yr) == 0) == pytest.approx(q0 + np.mean(held) * (1 - q0), rel=0.05)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_backlog_delay_grows_linearly_through_the_run():
    fn, levels = SWING_SHAPES['time_delay']
    d = levels[1]['d']
    t = np.arange(900000) * 1e-3
    stand = (lambda s: (AMP * np.sin(W * s), AMP * W * np.cos(W * s)))
    rate = stand(t)[1]
    ti, g, te, _ = fn(t, rate.copy(), t.copy(), t.copy(), stand, rng(1), d=d)
    assert np.array_equal(ti, t) and np.array_equal(te, t)
    err = g - rate
    acc = np.gradient(rate, t)
    for lo in (0.0, 300.0, 600.0):
        k = (t >= lo) & (t < lo + 100)
        lag = -np.sum(err[k] * acc[k]) / np.sum(acc[k] ** 2)
        assert lag == pytest.approx(d * (lo + 50) / SWING.QUEUE_S, rel=0.02), lo
    t20, rate20, (_, g20, _, _) = swing(fn, levels[1], 20.0)
    assert np.sum(np.abs(np.diff(g20)) > 1) == 0                    # still follows the swing


def test_softening_flexure_is_cubic_in_tilt_with_odd_lines_only():
    fn, levels = SWING_SHAPES['g_sensitivity']
    c = levels[1]['c']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    f_y = G0 * np.sin(AMP * np.sin(W * t))
    assert np.allclose(g - rate, c * f_y ** 3 / G0 ** 2, atol=1e-15)
    period = g[5000:10000] - rate[5000:10000]
    spec = np.abs(np.fft.rfft(period)) / 5000
    assert spec[1] > 0 and spec[3] > 0.01 * spec[1]
    assert np.all(spec[2:12:2] < 1e-9 * spec[1])                    # no even lines
    small = SWING.flexure(np.array([1e-3]), c)[0]
    assert small == pytest.approx(c * G0 * 1e-9, rel=1e-3)          # nil for small tilts


def test_mismatched_companding_is_odd_and_exact_at_zero_and_full_scale():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    e = levels[0]['e']
    w = np.linspace(-SWING.W_FS, SWING.W_FS, 2001)
    out = SWING.compand(w, e)
    assert np.allclose(SWING.compand(w, 0.0), w, rtol=1e-12, atol=1e-12)
    assert np.allclose(out, -out[::-1]) and out[1000] == 0
    assert out[-1] == pytest.approx(SWING.W_FS, rel=1e-12)
    assert np.max(np.abs(out - w)) > 1e-3
    t, gyro = noisy_run()
    _, g, _, _ = fn(t, gyro.copy(), t, t, None, rng(1), e=e)
    assert np.allclose(g, SWING.compand(gyro, e))
    assert np.std(g - gyro) < 0.1 * np.std(gyro)                    # follows the swing


def test_soaking_half_acts_only_after_each_reversal_to_negative():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    assert np.all(err[rate >= 0] == 0)
    rev = np.flatnonzero((rate[1:] < 0) & (rate[:-1] >= 0)) + 1
    assert rev.size == 4
    for r in rev[:3]:
        for s in (1, 400, 800):
            k = r + s
            assert err[k] / rate[k] == pytest.approx(a * np.exp(-s * 1e-3 / SWING.SOAK_S),
                                                     rel=1e-6)


def test_core_migrations_make_a_two_level_telegraph_stamp_error():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    delta = levels[1]['delta']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(80), delta=delta)
    e = out[2] - t
    assert np.all(np.diff(out[2]) > 0) and np.array_equal(out[0], t)
    assert np.allclose(np.abs(e), delta / 2)
    flips = np.sum(np.diff(e) != 0)
    assert flips == pytest.approx(900 / SWING.MIGRATE_S, rel=0.15)
    tau = SWING.MIGRATE_S / 2
    assert acf(e, [500, 1000]) == pytest.approx(np.exp(-np.array([0.5, 1.0]) / tau),
                                                abs=0.12)


def test_moire_beat_is_periodic_in_angle_every_beat():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    a = levels[1]['a']
    t, rate, (_, _, te, enc) = swing(fn, levels[1], 20.0)
    angle = AMP * np.sin(W * t)
    err = enc - angle
    assert np.array_equal(te, t) and np.max(np.abs(err)) == pytest.approx(a, rel=1e-3)
    ph = rng(10).uniform(0, 2 * np.pi)
    assert np.allclose(err, SWING.moire(angle, a, ph), atol=1e-15)
    assert np.allclose(SWING.moire(angle + SWING.BEAT_RAD, a, ph), err, atol=1e-12)
    assert SWING.BEAT_RAD == pytest.approx(np.deg2rad(3.25), rel=0.01)


def test_swing_levels_scale_with_s_line():
    z = SWING.detectability('g_sensitivity', {'c': 1e-3})
    th = np.arange(4096) * 2 * np.pi / 4096
    c = np.fft.rfft(1e-3 * G0 * np.sin(AMP * np.sin(th)) ** 3) / th.size
    assert z == pytest.approx(2 * np.linalg.norm(c[1:61]) / S_LINE, rel=1e-6)


def test_both_harnesses_take_set_p_by_held_out_p(monkeypatch):
    check_harnesses('p', SHAPES, SWING_SHAPES, monkeypatch)
