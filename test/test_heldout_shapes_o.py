# Held-out set O (bench/validate_diagnosis_heldout_o.py, static, and
# bench/validate_diagnosis_swing_heldout_o.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out o. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT,
                            fold_lines, G0, load_set, N_ARW, noisy_run, rng, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('o')


def acf(y, lags):
    y = y - y.mean()
    return np.array([np.mean(y[:-k] * y[k:]) for k in lags]) / np.mean(y * y)


def runs(flag):
    """Lengths (samples) of the True runs and of the False runs of a boolean series."""
    edges = np.flatnonzero(np.diff(flag.astype(int))) + 1
    parts = np.split(flag, edges)[1:-1]                     # whole runs only
    return ([p.size for p in parts if p[0]], [p.size for p in parts if not p[0]])


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_follower_rises_fast_falls_slow_and_rectifies_noise():
    fn, levels = SHAPES['internal_lowpass']
    tau = 0.04
    a_up, a_dn = np.exp(-DT / (STATIC.RISE * tau)), np.exp(-DT / tau)
    step = fn(np.r_[0.0, np.ones(5), np.zeros(5)], rng(1), tau=tau)
    assert step[1] == pytest.approx(1 - a_up) and step[5] == pytest.approx(1 - a_up ** 5)
    assert step[6] == pytest.approx(step[5] * a_dn) and step[10] == pytest.approx(
        step[5] * a_dn ** 5)
    x = rng(2).standard_normal(2 ** 20)
    y = fn(x.copy(), rng(3), tau=tau)
    prev = np.r_[x[0], y[:-1]]
    a = np.where(x > prev, a_up, a_dn)
    assert np.allclose(y, prev + (1 - a) * (x - prev), atol=1e-12)
    assert np.mean(y) > 0.1 and stats.skew(y) > 0.1                 # rises win: rectified
    assert np.allclose(fn(np.full(1000, 0.003), rng(4), tau=tau), 0.003)
    small = 4e-3                                                    # a_dn 0.08, a_up ~ 0
    ys = fn(x.copy(), rng(5), tau=small)
    assert acf(ys, [1])[0] == pytest.approx(STATIC.follower_r1(small, DT), abs=0.01)


def test_spindle_is_a_tone_then_an_exponential_coast_down():
    fn, levels = SHAPES['vibration']
    n = 720000
    y = fn(np.zeros(n), rng(6), amplitude=1.0)
    g = rng(6)
    t_off = g.uniform(*STATIC.OFF_SPAN) * n * DT
    t = np.arange(n) * DT
    assert np.allclose(y, STATIC.coast(t, 1.0, t_off, g.uniform(0, 2 * np.pi)), atol=1e-9)
    on = t < t_off
    f, p = signal.welch(y[on], fs=1 / DT, nperseg=2 ** 12)
    assert f[np.argmax(p)] == pytest.approx(STATIC.SPIN_HZ, abs=0.05)
    assert np.mean(y[on] ** 2) == pytest.approx(0.5, rel=1e-3)      # constant amplitude
    after = ~on
    crossings = np.sum(np.diff(np.sign(y[after])) != 0)
    rest = n * DT - t_off
    want = 2 * STATIC.SPIN_HZ * STATIC.COAST_S * (1 - np.exp(-rest / STATIC.COAST_S))
    assert crossings == pytest.approx(want, rel=0.01)               # revolutions left
    for s in (150.0, 300.0):                                        # envelope ~ speed^2
        k = (t > t_off + s - 1) & (t < t_off + s + 1)
        envelope = np.exp(-2 * s / STATIC.COAST_S)
        assert np.sqrt(2 * np.mean(y[k] ** 2)) == pytest.approx(envelope, rel=0.03)
    z = STATIC.detectability('vibration', levels[0], DT, SIG, N_ARW)
    s = STATIC.coast(t, levels[0]['amplitude'], 0.4 * n * DT)
    assert z == pytest.approx(np.std(s) * np.sqrt(n) / SIG, rel=1e-9)


def test_phase_change_sink_holds_a_plateau_between_two_rises():
    fn, levels = SHAPES['temperature_drift']
    t_melt = -STATIC.WARM_S * np.log(1 - STATIC.MELT)
    tt = np.array([0.0, t_melt, t_melt + 900, t_melt + STATIC.MELT_S, t_melt + STATIC.MELT_S
                   + STATIC.WARM_S])
    want = [0.0, 0.4, 0.4, 0.4, 1 - 0.6 * np.exp(-1)]
    assert STATIC.pcm_warm(tt, 1.0) == pytest.approx(want, abs=1e-12)
    y = fn(np.zeros(720000), rng(7), amplitude=1.0)
    t = np.arange(720000) * DT + rng(7).uniform(0, 60)
    assert np.allclose(y, STATIC.pcm_warm(t, 1.0), atol=1e-12)
    assert np.all(np.diff(y) >= 0)
    slope = np.diff(y) / DT
    near = np.abs(t[1:] - t_melt) < 1.0
    kink = 0.6 / STATIC.WARM_S
    assert slope[near & (t[1:] < t_melt)].min() == pytest.approx(kink, rel=0.01)   # kink in
    end = t_melt + STATIC.MELT_S
    assert np.all(slope[(t[1:] > t_melt + 1) & (t[1:] < end - 1)] == 0)     # the arrest
    assert slope[(t[1:] > end) & (t[1:] < end + 1)].max() == pytest.approx(
        kink, rel=0.01)                                                      # kink out


def test_envelope_flicker_is_rayleigh_with_the_hypergeometric_autocovariance():
    fn, _ = SHAPES['bias_instability']
    assert STATIC.envelope_cov(0.0, 1.0) == pytest.approx(1.0, rel=1e-9)
    assert STATIC.envelope_cov(1e9, 1.0) == pytest.approx(0.0, abs=1e-9)
    ys = np.array([fn(np.zeros(2 ** 19), rng(10 + i), b=1.0) for i in range(6)])
    low = -np.sqrt(np.pi / 2) / np.sqrt(2 - np.pi / 2)
    assert ys.min() >= low - 1e-12 and np.min(ys) < low + 0.3      # bounded below, reached
    assert stats.skew(ys.ravel()) == pytest.approx(0.63, abs=0.2)
    for lag in (0.05, 1.0, 10.0):
        k = int(lag / DT)
        got = np.mean([np.mean((v[:-k] - v.mean()) * (v[k:] - v.mean())) for v in ys])
        assert got == pytest.approx(float(STATIC.envelope_cov(lag, 1.0)), abs=0.1), lag
    tau = np.geomspace(0.2, 300, 7)
    want = STATIC.cov_avar(lambda u: STATIC.envelope_cov(u, 1.0), tau)
    assert abs(np.polyfit(np.log(tau), np.log(want), 1)[0]) < 0.3   # near a flicker floor
    for m in (100, 1000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        assert got == pytest.approx(STATIC.cov_avar(lambda u: STATIC.envelope_cov(u, 1.0),
                                                    m * DT)[0], rel=0.3)


def test_dac_walk_sits_on_a_lattice_and_chatters_at_each_crossing():
    fn, _ = SHAPES['rate_random_walk']
    k = 1e-4
    lsb = k * np.sqrt(STATIC.DAC_S)
    y = fn(np.zeros(720000), rng(20), k=k)
    bias, walk = STATIC.dac_walk(720000, k, DT, rng(20))
    assert np.array_equal(y, bias)
    assert np.allclose(y / lsb, np.round(y / lsb), atol=1e-9)
    assert np.ptp(bias - walk) <= lsb * (1 + 1e-9)                  # within half an LSB
    steps = np.diff(y)[np.diff(y) != 0]
    assert np.allclose(np.abs(steps), lsb)                          # one LSB at a time
    assert np.mean(steps[1:] == -steps[:-1]) > 0.8                  # mostly undone: chatter
    ys = [fn(np.zeros(720000), rng(21 + i), k=k) for i in range(16)]
    for m in (10000, 40000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        assert got == pytest.approx(k * k * m * DT / 3, rel=0.25), m


def test_fan_gated_convection_is_silent_between_gaussian_spells():
    fn, levels = SHAPES['gauss_markov']
    tc = 1.0
    y = fn(np.zeros(2 ** 22), rng(30), sd=1.0, tc=tc)
    on = y != 0
    assert np.mean(on) == pytest.approx(STATIC.FAN_SHARE, abs=0.04)
    ons, offs = runs(on)
    assert np.mean(ons) * DT == pytest.approx(STATIC.FAN_ON, rel=0.15)
    assert np.std(y[on]) == pytest.approx(1.0, rel=0.05)
    assert abs(stats.kurtosis(y[on])) < 0.3                         # Gaussian while on
    assert stats.kurtosis(y) == pytest.approx(3 / STATIC.FAN_SHARE - 3, rel=0.2)
    for lag in (50, 100, 300):
        want = sum(v * np.exp(-lag * DT / t) for v, t in STATIC.fan_terms(1.0, tc))
        got = np.mean(y[:-lag] * y[lag:])
        assert got == pytest.approx(want, abs=0.02), lag


def test_log_dpcm_sends_powers_of_two_and_leaves_a_relative_angle_error():
    fn, levels = SHAPES['quantization']
    n = 2 ** 20
    x = SIG * rng(40).standard_normal(n) + STATIC.BIAS
    theta = np.cumsum(x) * DT
    for p, ms in ((levels[0], (1, 10)), (levels[2], (1,))):       # the edge's m = 10: noisy
        y = fn(x.copy(), rng(41), **p)
        sent = y * DT
        code = p['k'] * np.log2(np.abs(sent))
        assert np.allclose(code, np.round(code), atol=1e-6)         # every word a log code
        err = np.cumsum(sent) - theta
        v = x * DT - np.r_[0.0, err[:-1]]
        half = 2.0 ** (0.5 / p['k'])
        assert np.all(np.abs(err) <= (half - 1) * np.abs(v) * (1 + 1e-6) + 1e-15)
        ex = avar(y, list(ms)) - avar(x, list(ms))
        for m, got in zip(ms, ex):
            want = 3 * STATIC.log_c0(p['k'], DT, SIG) / (m * DT) ** 2
            assert got == pytest.approx(want, rel=0.1), (p, m)
        assert np.corrcoef(err, x)[0, 1] > 0                        # a small gain


def test_loaded_mount_sweeps_down_at_a_fixed_rms():
    fn, _ = SHAPES['resonance']
    n = 720000
    y = fn(np.zeros(n), rng(50), sigma=1.0)
    seg = int(600 / DT)
    for part, t_mid in ((y[:seg], 300.0), (y[-seg:], n * DT - 300.0)):
        assert np.std(part) == pytest.approx(1.0, rel=0.08)
        f, p = signal.welch(part, fs=1 / DT, nperseg=2 ** 12)
        assert f[np.argmax(p)] == pytest.approx(STATIC.hopper_freq(t_mid, n * DT), abs=0.7)
    assert STATIC.hopper_freq(n * DT, n * DT) == pytest.approx(20.0, rel=0.01)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.loaded_psd(f, 1.0, DT, n * DT)
    for lo, hi in ((20, 23), (24, 28), (29, 32)):
        k = (f > lo) & (f < hi)
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.15), lo
    lo, hi = (f > 21) & (f < 22), (f > 29) & (f < 30)
    assert np.mean(p[lo]) / np.mean(p[hi]) == pytest.approx((29.5 / 21.5) ** 3, rel=0.2)
    _, width = STATIC.band_excess(lambda v: STATIC.loaded_psd(v, 1.0, DT, n * DT), DT, SIG)
    assert width > 4 * STATIC.HOPPER_HZ / STATIC.HOPPER_Q            # many line widths


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_interleaving_skew_delays_every_other_sample():
    fn, levels = SWING_SHAPES['time_delay']
    d = levels[1]['d']
    t, rate, (ti, g, te, _) = swing(fn, levels[1], 20.0)
    assert np.array_equal(ti, t) and np.array_equal(te, t)
    assert np.array_equal(g[::2], rate[::2])
    assert np.allclose(g[1::2], AMP * W * np.cos(W * (t[1::2] - d)), atol=1e-12)
    err = g - rate
    lag = -np.sum(err * np.gradient(rate, t)) / np.sum(np.gradient(rate, t) ** 2)
    assert lag == pytest.approx(d / 2, rel=0.02)                    # the mean delay
    spec = np.abs(np.fft.rfft(err)) ** 2
    f = np.fft.rfftfreq(t.size, 1e-3)
    low, image = np.sum(spec[f < 5]), np.sum(spec[f > 495])
    assert image == pytest.approx(low, rel=0.05)                    # an image at Nyquist


def test_quadrature_leak_is_a_g_sensitivity_of_wandering_sign():
    fn, levels = SWING_SHAPES['g_sensitivity']
    c = levels[1]['c']
    t = np.arange(900000) * 1e-3
    stand = (lambda s: (AMP * np.sin(W * s), AMP * W * np.cos(W * s)))
    rate = stand(t)[1]
    _, g, _, _ = fn(t, rate.copy(), t, t, stand, rng(60), c=c)
    f_y = G0 * np.sin(AMP * np.sin(W * t))
    u = SWING.gauss_markov(t.size, SWING.LEAK_TC, 1e-3, rng(60))
    assert np.allclose(g - rate, c * u * f_y, atol=1e-15)
    assert acf(u, [int(SWING.LEAK_TC * 1000)])[0] == pytest.approx(np.exp(-1), abs=0.15)
    assert np.sum(np.diff(np.sign(u)) != 0) >= 2                    # changes sign in a run
    f = SWING.leak_grid(W, 1000.0)
    total = np.trapezoid(SWING.leak_psd(f, c, AMP, W), f)
    assert total == pytest.approx(c * c * np.mean(f_y ** 2), rel=0.03)


def test_overflow_wraps_only_beyond_the_range():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    t, gyro = noisy_run()
    for p in levels[:2]:
        r = p['r']
        _, out, _, _ = fn(t, gyro.copy(), t, t, None, rng(1), **p)
        err = out - gyro
        assert np.all(np.abs(out) <= r)
        assert np.array_equal(np.abs(err) < 1e-9, np.abs(gyro) < r)
        hit = np.abs(err) > 1e-9
        assert np.allclose(err[hit], -2 * r * np.sign(gyro[hit]))
        assert fold_lines(err, kmin=2) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_nonlinearity', p), rel=0.1), r
    assert 0 < np.mean(np.abs(gyro) > levels[0]['r']) < 0.01        # weak: noise peaks only


def test_noisy_driver_half_adds_gain_noise_on_negative_rates_only():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    t = np.arange(900000) * 1e-3
    stand = (lambda s: (AMP * np.sin(W * s), AMP * W * np.cos(W * s)))
    rate = stand(t)[1]
    s_n = S_LINE / np.sqrt(2 / 900.0) * np.sqrt(1000.0)
    gyro = rate + s_n * rng(70).standard_normal(t.size)
    p = levels[0]
    _, out, _, _ = fn(t, gyro.copy(), t, t, stand, rng(71), **p)
    err = out - gyro
    assert np.all(err[rate >= 0] == 0)
    neg = rate < -0.1
    assert np.std(err[neg] / rate[neg]) == pytest.approx(p['eps'], rel=0.02)
    assert abs(np.mean(err[neg] / rate[neg])) < 3 * p['eps'] / np.sqrt(neg.sum())
    r = out - rate
    k = rate < 0
    stat = np.sum(rate[k] ** 2 * (r[k] ** 2 - s_n ** 2)) / (
        s_n ** 2 * np.sqrt(2 * np.sum(rate[k] ** 4)))
    assert stat == pytest.approx(SWING.detectability('scale_factor_asymmetry', p), rel=0.1)


def test_stepping_daemon_holds_the_stamp_error_between_poisson_steps():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    sigma = levels[0]['sigma']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(80), sigma=sigma)
    e = out[2] - t
    assert np.all(np.diff(out[2]) > 0) and np.array_equal(out[0], t)
    jumps = np.flatnonzero(np.diff(e) != 0)
    assert jumps.size == pytest.approx(900 / SWING.HOLD_S, rel=0.05)
    holds = np.diff(jumps) * 1e-3
    assert np.mean(holds) == pytest.approx(SWING.HOLD_S, rel=0.05)
    assert np.std(holds) == pytest.approx(np.mean(holds), rel=0.1)  # exponential holds
    assert np.std(e[jumps + 1]) == pytest.approx(sigma, rel=0.05)
    want = np.exp(-np.array([0.1, 0.2]) / SWING.HOLD_S)
    assert acf(e, [100, 200]) == pytest.approx(want, abs=0.03)
    f, pw = signal.welch(e, fs=1000.0, nperseg=2 ** 14)
    for lo, hi in ((0.2, 1.0), (2.0, 6.0), (20.0, 60.0)):
        k = (f > lo) & (f < hi)
        assert np.mean(pw[k]) == pytest.approx(np.mean(2 * SWING.step_psd(f[k], sigma)),
                                               rel=0.15), lo


def test_backlash_lags_the_stand_by_the_play_in_the_direction_of_motion():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    b = levels[1]['b']
    t, rate, (_, _, te, enc) = swing(fn, levels[1], 20.0)
    angle = AMP * np.sin(W * t)
    err = enc - angle
    assert np.array_equal(te, t) and np.all(np.abs(err) <= b + 1e-15)
    settled = (t > 2.6) & (np.abs(angle) < 0.5 * AMP)               # mid-swing, after a turn
    assert np.allclose(err[settled], -b * np.sign(rate[settled]), atol=1e-15)
    top = np.argmax(angle[:5000])                                   # first turning point
    flat = enc[top:top + 5000]
    held = np.flatnonzero(np.abs(flat - flat[0]) > 1e-15)[0]
    assert angle[top] - angle[top + held] == pytest.approx(2 * b, rel=0.02)
    zs = [SWING.detectability('encoder_cyclic_error', q) for q in levels]
    assert zs[2] < zs[0] < zs[1]


def test_both_harnesses_take_set_o_by_held_out_o(monkeypatch):
    check_harnesses('o', SHAPES, SWING_SHAPES, monkeypatch)
