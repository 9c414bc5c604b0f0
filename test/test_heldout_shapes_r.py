# Held-out set R (bench/validate_diagnosis_heldout_r.py, static, and
# bench/validate_diagnosis_swing_heldout_r.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out r. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT,
                            G0, load_set, N_ARW, noisy_run, rng, SIG, STATIC_NAMES, swing, W,
                            white)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('r')


def acf(y, lags):
    y = y - y.mean()
    return np.array([np.mean(y[:-k] * y[k:]) for k in lags]) / np.mean(y * y)


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_zero_levels_leave_the_record_unchanged():
    x = white(20000, 2)
    for name, p in [('internal_lowpass', {'theta': 0.0}), ('vibration', {'a': 0.0}),
                    ('temperature_drift', {'amplitude': 0.0}), ('bias_instability', {'b': 0.0}),
                    ('rate_random_walk', {'k': 0.0}), ('resonance', {'sigma': 0.0}),
                    ('stale_samples', {'mu': 0.0})]:
        assert np.allclose(SHAPES[name][0](x.copy(), rng(3), **p), x, rtol=0, atol=1e-15), name


def test_tracker_is_the_fading_memory_filter_with_a_lifted_middle_band():
    fn, levels = SHAPES['internal_lowpass']
    theta = 0.5
    x = rng(4).standard_normal(2 ** 20)
    y = fn(x.copy(), rng(5), theta=theta)
    b, a = STATIC.tracker_coeffs(theta)
    assert np.allclose(y[2000:], signal.lfilter(b, a, x)[2000:], atol=1e-9)
    assert b.sum() / a.sum() == pytest.approx(1.0)                           # DC gain 1
    ramp = 0.3 + 0.01 * np.arange(3000)
    assert np.allclose(fn(ramp, rng(5), theta=theta)[100:], ramp[100:], atol=1e-9)   # no lag
    f, h = signal.freqz(b, a, worN=2048, fs=1 / DT)
    assert 1.05 < np.abs(h).max() < 1.07 and np.abs(h[-1]) < 0.6              # peak, then below
    assert acf(y, [1])[0] == pytest.approx(STATIC.tracker_r1(theta), abs=0.005)
    for th in (0.05, 0.1):
        assert STATIC.tracker_r1(th) == pytest.approx(2 * th * th, rel=0.1)
    n = 720000
    assert STATIC.detectability('internal_lowpass', levels[2], DT, SIG, N_ARW) == \
        pytest.approx(STATIC.tracker_r1(levels[2]['theta']) * np.sqrt(n))


def test_bus_crosstalk_spikes_at_fixed_slots_with_lines_at_sample_rate_fractions():
    fn, levels = SHAPES['vibration']
    n = 100000
    y = fn(np.zeros(n), rng(6), a=1.0)
    g = rng(6)
    mag, baro = g.integers(STATIC.MAG_EVERY), g.integers(STATIC.BARO_EVERY)
    k = np.arange(n)
    assert np.array_equal(y, 1.0 * (k % 4 == mag) + STATIC.BARO_RATIO * (k % 5 == baro))
    spec = np.abs(np.fft.rfft(y - y.mean())) / n
    f = np.fft.rfftfreq(n, DT)
    on = spec > 1e-9
    assert set(np.round(f[on], 6)) == {20.0, 25.0, 40.0, 50.0}
    assert y.mean() == pytest.approx(1 / 4 + STATIC.BARO_RATIO / 5, rel=1e-3)


def test_stress_relaxation_is_a_stretched_exponential_from_power_on():
    fn, levels = SHAPES['temperature_drift']
    y = fn(np.zeros(720000), rng(7), amplitude=1.0)
    t = np.arange(720000) * DT + rng(7).uniform(0, 60)
    assert np.allclose(y, 1 - np.exp(-(t / STATIC.KWW_S) ** STATIC.KWW_BETA), atol=1e-12)
    assert np.all(np.diff(y) > 0) and np.all(np.diff(y, 2) < 1e-15)          # rising, concave
    assert STATIC.kww(STATIC.KWW_S, 1.0) == pytest.approx(1 - np.exp(-1))
    assert STATIC.kww(7200.0, 1.0) == pytest.approx(0.9, abs=0.01)
    expo = 1 - np.exp(-7200.0 / STATIC.KWW_S)                               # an exponential's
    assert STATIC.kww(7200.0, 1.0) < expo - 0.09
    assert STATIC.kww(1.0, 1.0) > 20 * (1 - np.exp(-1.0 / STATIC.KWW_S))     # steep at first


def test_adsorption_is_a_poisson_count_with_logarithmic_memory():
    fn, levels = SHAPES['bias_instability']
    b = 1.0
    ys = [fn(np.zeros(2 ** 20), rng(10 + i), b=b) for i in range(6)]
    m = STATIC.ADS_MEAN
    counts = np.concatenate(ys) * np.sqrt(m) / b + m
    assert np.allclose(counts, np.round(counts), atol=1e-9) and counts.min() >= 0   # a lattice
    assert counts.mean() == pytest.approx(m, abs=0.6)
    vals, freq = np.unique(np.round(counts), return_counts=True)
    pois = stats.poisson.pmf(vals, m)
    assert freq[:10] / counts.size == pytest.approx(pois[:10], abs=0.03)
    assert stats.skew(counts) > 0.2
    for lag in (1, 100, 1000, 10000):
        got = np.mean([np.mean(v[:-lag] * v[lag:]) for v in ys])             # the known mean 0
        assert got == pytest.approx(float(STATIC.adsorption_cov(lag * DT, b)), rel=0.2), lag
    c = STATIC.adsorption_cov(np.array([1.0, 10.0, 100.0]), 1.0)
    assert np.diff(c) == pytest.approx(np.diff(c)[0], rel=0.01)             # log in the lag
    ex = np.mean([avar(v, [1000])[0] for v in ys])
    want = STATIC.cov_avar(lambda u: STATIC.adsorption_cov(u, b), 1000 * DT)[0]
    assert ex == pytest.approx(want, rel=0.3)


def test_loose_screw_is_flat_then_a_gaussian_walk():
    fn, levels = SHAPES['rate_random_walk']
    k, n = 1e-4, 720000
    y = fn(np.zeros(n), rng(20), k=k)
    on = int(rng(20).uniform(0, STATIC.ONSET) * n)
    d = np.diff(np.r_[0.0, y])
    assert np.all(d[:on] == 0) and np.all(d[on:] != 0) and on < STATIC.ONSET * n
    assert np.std(d[on:]) == pytest.approx(k * np.sqrt(DT), rel=0.01)
    assert abs(stats.kurtosis(d[on:])) < 0.05
    ons = [np.argmax(fn(np.zeros(10000), rng(30 + i), k=k) != 0) for i in range(200)]
    assert np.max(ons) < 5000 and np.mean(ons) == pytest.approx(2500, rel=0.15)


def test_discharges_ramp_up_and_drop_by_half_with_an_exponential_correlation():
    fn, levels = SHAPES['gauss_markov']
    sd, tc = 1.0, 1.0
    mean = sd * np.sqrt((1 + STATIC.DROP) / (1 - STATIC.DROP))
    y = fn(np.zeros(2 ** 20), rng(40), sd=sd, tc=tc)
    q = y + mean
    d = np.diff(q)
    up = np.isclose(d, mean / tc * DT, rtol=0, atol=1e-9)
    assert np.mean(up) > 0.97 and np.all(d[~up] < 0)                        # ramps and drops
    drops = np.flatnonzero(~up)
    assert np.mean(~up) * 1 / DT == pytest.approx(2 / tc, rel=0.1)           # rate 2 / tc
    ratio = (q[drops + 1] - mean / tc * DT * 0.5) / q[drops]
    assert np.median(ratio) == pytest.approx(STATIC.DROP, abs=0.02)
    assert q.min() > 0 and stats.skew(y) > 0.1
    ys = np.array([fn(np.zeros(2 ** 20), rng(41 + i), sd=sd, tc=tc) for i in range(4)])
    assert ys.mean() == pytest.approx(0.0, abs=0.05) and ys.var() == pytest.approx(1, rel=0.05)
    got = [np.mean([np.mean(v[:-lag] * v[lag:]) for v in ys]) for lag in (50, 100, 300)]
    assert got == pytest.approx(np.exp(-np.array([0.5, 1.0, 3.0])), abs=0.04)


def test_single_track_error_is_white_and_heavy_near_the_track_extremes():
    fn, levels = SHAPES['quantization']
    q = levels[1]['q']
    assert np.allclose(STATIC.single_track(np.linspace(0, 5 * q, 1001), q, 0.0), 0, atol=1e-15)
    x = white(2 ** 20, 50)
    y = fn(x.copy(), rng(51), q=q)
    theta = np.cumsum(x) * DT
    err = np.cumsum(y) * DT - theta
    noise = STATIC.TRACK_NOISE * rng(51).standard_normal(x.size)
    assert np.allclose(err, STATIC.single_track(theta, q, noise), atol=1e-12)
    psi, m, v = STATIC.track_moments(q)
    assert np.var(err) == pytest.approx(v.mean() + np.var(m), rel=0.05)
    phase = np.mod(2 * np.pi * theta / q, 2 * np.pi)
    near = np.abs(np.cos(phase)) < 0.1
    far = np.abs(np.cos(phase)) > 0.9
    assert np.std(err[near]) > 3 * np.std(err[far])                      # heteroscedastic
    assert np.std(err[far]) == pytest.approx(STATIC.TRACK_NOISE * q / (2 * np.pi), rel=0.1)
    assert np.all(np.abs(acf(err, [1, 2, 5])) < 0.05)                       # nearly white
    rel = STATIC.track_excess(q, DT, N_ARW)
    ex = avar(y, [1])[0] / avar(x, [1])[0] - 1
    assert ex == pytest.approx(rel[0], rel=0.1)
    assert len(np.unique(np.round(np.diff(np.r_[0, y]) / 1e-9))) > 1000      # no staircase


def test_pulsating_bracket_rings_up_in_strokes_with_the_free_modes_mean_psd():
    fn, levels = SHAPES['resonance']
    sigma, n = 1.0, 2 ** 20
    ys = [fn(np.zeros(n), rng(60 + i), sigma=sigma) for i in range(4)]
    assert np.mean([np.var(v) for v in ys]) == pytest.approx(sigma ** 2, rel=0.05)
    f, p = signal.welch(np.array(ys), fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.mode_psd(f, sigma, DT)
    band = np.abs(f - STATIC.MODE_HZ) < 3
    assert np.mean(p.mean(axis=0)[band]) / np.mean(want[band]) == pytest.approx(1, abs=0.1)
    assert f[np.argmax(p.mean(axis=0))] == pytest.approx(STATIC.MODE_HZ, abs=0.3)
    y = ys[0]
    phase = np.mod(np.arange(n) * DT / STATIC.PUMP_S + rng(60).uniform(), 1.0)
    cyc = np.array([np.var(y[(phase >= lo) & (phase < lo + 0.1)]) for lo in np.arange(0, 1, .1)])
    assert cyc.max() > 3 * cyc.min()                                         # cyclostationary
    assert np.argmax(cyc) * 0.1 < STATIC.STROKE + 0.15                        # rings in strokes


def test_latest_value_logger_repeats_loses_and_reorders():
    fn, levels = SHAPES['stale_samples']
    n = 720000
    x = white(n, 70)
    for p in levels:
        y = fn(x.copy(), rng(71), **p)
        src = STATIC.recorded(n, p['mu'], DT, rng(71))
        assert np.array_equal(y, x[src])
        rep = np.mean(np.diff(src) == 0)
        want = STATIC.repeat_probability(p['mu'], DT)
        assert rep == pytest.approx(want, rel=0.1 if want > 0.01 else 0.25), p
        assert np.mean(np.diff(y) == 0) == pytest.approx(rep, rel=1e-3)
        lost = 1 - np.unique(src).size / n
        assert lost == pytest.approx(rep, rel=0.05)
    src = STATIC.recorded(n, levels[1]['mu'], DT, rng(72))
    assert np.mean(np.diff(src) < 0) > 0.01                                  # out of order
    arrive = np.arange(n) * DT + STATIC.BASE_S + rng(72).exponential(levels[1]['mu'], n)
    ticks = np.arange(n) * DT + STATIC.LAG_S
    late = src[:20]
    assert np.all(arrive[src[20:]] <= ticks[20:] + 1e-12) and np.all(late >= 0)
    for k in rng(73).integers(20, n, 200):                                 # the latest arrival
        assert arrive[src[k]] == arrive[arrive <= ticks[k]].max()
    assert STATIC.repeat_probability(0.0, DT) == 0.0
    assert STATIC.repeat_probability(levels[2]['mu'], DT) == pytest.approx(
        np.exp(-(STATIC.LAG_S - STATIC.BASE_S) / levels[2]['mu']), rel=0.01)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)
    for name, (fn, levels) in SWING_SHAPES.items():
        a = swing(fn, levels[0], 10.0)[2]
        b = swing(fn, levels[0], 10.0)[2]
        assert all(np.array_equal(u, v) for u, v in zip(a, b)), name          # reproducible


def test_swing_zero_levels_leave_the_run_unchanged():
    for name, p in [('time_delay', {'c': 0.0}), ('g_sensitivity', {'c': 0.0}),
                    ('scale_factor_nonlinearity', {'sigma_u': 0.0}),
                    ('scale_factor_asymmetry', {'a': 0.0}), ('timestamp_jitter', {'m': 0.0}),
                    ('encoder_cyclic_error', {'r': 0.0})]:
        t, rate, out = swing(SWING_SHAPES[name][0], p, 10.0)
        want = (t, rate, t, AMP * np.sin(W * t))
        assert all(np.allclose(a, b, rtol=0, atol=1e-12) for a, b in zip(out, want)), name


def test_interrupt_backlog_stamps_late_by_the_speed():
    fn, levels = SWING_SHAPES['time_delay']
    c = levels[1]['c']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    assert np.array_equal(g, rate) and np.array_equal(te, t)
    late = ti - t
    assert np.allclose(late, c * np.abs(rate), atol=1e-15)
    assert late.max() == pytest.approx(c * AMP * W, rel=1e-4)
    turn = np.abs(np.cos(W * t)) < 1e-3
    assert np.all(late[turn] < 1e-3 * late.max())
    assert np.all(np.diff(ti) > 0)


def test_wavy_suspension_is_a_fixed_smooth_residual_of_a_linear_calibration():
    fn, levels = SWING_SHAPES['g_sensitivity']
    c = levels[1]['c']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    f_y = G0 * np.sin(AMP * np.sin(W * t))
    assert np.allclose(g - rate, SWING.waviness(f_y, c), atol=1e-15)
    angle = AMP * np.sin(W * t)
    other = fn(t, rate.copy(), t.copy(), angle, lambda s: (AMP * np.sin(W * s),
                                                           AMP * W * np.cos(W * s)), rng(99), c=c)
    assert np.array_equal(other[1], g)                                       # one sensor
    u = np.linspace(-1, 1, 20001)
    r = SWING.waviness(u * G0, 1.0)
    assert np.sqrt(np.mean(r * r)) == pytest.approx(1.0, rel=1e-6)
    assert np.allclose(np.polyfit(u, r, 1), 0, atol=1e-9)                   # calibrated line out
    spec = np.abs(np.fft.rfft((g - rate)[5000:10000])) / 5000
    assert spec[1] > 0 and spec[2] > 0.05 * spec[1] and spec[3] > 0.05 * spec[1]
    assert np.all(np.abs(np.diff(r, 2)) < 1e-4)                             # smooth


def test_dac_bit_errors_are_an_odd_staircase_calibrated_in_slope():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    su = levels[1]['sigma_u']
    lsb = SWING.DAC_FS / 2 ** SWING.DAC_BITS
    w = np.linspace(-SWING.DAC_FS, SWING.DAC_FS, 40001)
    e = SWING.dac_error(w, su)
    assert np.allclose(e, -e[::-1], atol=1e-15) and SWING.dac_error(0.0, su) == 0
    m = np.linspace(0, SWING.DAC_FS, 40001)
    em = SWING.dac_error(m, su)
    assert abs(np.sum(m * em)) < 1e-4 * np.sum(m * np.abs(em))              # slope calibrated
    codes = np.arange(40) * lsb
    table = SWING.dac_table(su)
    assert np.allclose(-SWING.dac_error(codes, su), table[:40] - su * SWING.DAC_SLOPE * codes)
    mid = SWING.dac_error(codes[:-1] + lsb / 2, su)
    assert np.allclose(mid, (SWING.dac_error(codes[:-1], su) + SWING.dac_error(codes[1:], su)) / 2)
    jump = np.abs(np.diff(table))
    assert jump[127] > 3 * np.median(jump)                       # the MSB's carry, 2 rad/s
    assert np.allclose(SWING.dac_error(w, 2 * su), 2 * e)
    t, gyro = noisy_run()
    _, g, _, _ = fn(t, gyro.copy(), t, t, None, rng(1), sigma_u=su)
    assert np.allclose(g, gyro + SWING.dac_error(gyro, su))
    assert np.std(g - gyro) < 0.05 * np.std(gyro)


def test_bootstrap_droops_through_each_negative_half():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    assert np.all(err[rate >= 0] == 0)
    rev = np.flatnonzero((rate[1:] < 0) & (rate[:-1] >= 0)) + 1
    assert rev.size == 4
    for r in rev[:3]:
        for s in (1, 1000, 2400):
            k = r + s
            assert err[k] / rate[k] == pytest.approx(-a * s * 1e-3 / SWING.DROOP_S, rel=1e-6)


def test_congested_link_delays_stamps_by_a_reflected_walk():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    m = levels[1]['m']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(80), m=m)
    e = out[2] - t
    assert np.array_equal(out[0], t) and np.all(np.diff(out[2]) > 0)
    mean, cov = SWING.queue_cov()
    assert e.mean() == pytest.approx(0, abs=0.1 * m)
    assert np.mean(e < -mean * m + 0.02 * m) == pytest.approx(0.18, abs=0.04)     # no wait
    assert stats.skew(e) > 1.0                                               # one-sided
    es = [SWING.link_backlog(t, m, rng(81 + i)) for i in range(4)]
    for lag in (1, 10, 50, 200):
        got = np.mean([np.mean((v[:-lag] - m * mean) * (v[lag:] - m * mean)) for v in es])
        assert got / m ** 2 == pytest.approx(cov[lag], abs=0.06), lag
    x = np.r_[0.0, rng(82).normal(-2 / SWING.QUEUE_TC, 2 / np.sqrt(SWING.QUEUE_TC), 999)]
    v = np.zeros(1000)
    for i in range(1, 1000):
        v[i] = max(0.0, v[i - 1] + x[i])
    s = np.cumsum(x)
    assert np.allclose(s - np.minimum.accumulate(np.minimum(s, 0)), v)        # Lindley


def test_led_crosstalk_is_a_line_periodic_error_carried_by_the_pwm():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    r = levels[1]['r']
    t, rate, (_, _, te, enc) = swing(fn, levels[1], 20.0)
    angle = AMP * np.sin(W * t)
    err = enc - angle
    ph = rng(10).uniform(0, 2 * np.pi)
    assert np.array_equal(te, t)
    assert np.allclose(err, SWING.crosstalk_error(angle, t, r, ph), atol=1e-15)
    first = r / SWING.ENC_LINES * np.sin(2 * np.pi * SWING.PWM_HZ * t + ph) * np.cos(
        SWING.ENC_LINES * angle)
    assert np.allclose(err, first, atol=0.05 * r / SWING.ENC_LINES)
    assert abs(err.mean()) < 0.02 * np.abs(err).max()
    still = np.full(2000, 0.1)
    e0 = SWING.crosstalk_error(still, t[:2000], r, ph)
    spec = np.abs(np.fft.rfft(e0))
    assert np.fft.rfftfreq(2000, 1e-3)[np.argmax(spec)] == pytest.approx(SWING.PWM_HZ, abs=1)


def test_both_harnesses_take_set_r_by_held_out_r(monkeypatch):
    check_harnesses('r', SHAPES, SWING_SHAPES, monkeypatch)
