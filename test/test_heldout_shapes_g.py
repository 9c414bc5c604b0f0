# Held-out set G (bench/validate_diagnosis_heldout_g.py, static, and
# bench/validate_diagnosis_swing_heldout_g.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out g. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            INC, load_set, N_ARW, S_LINE, SIG, stand, swing, W)
import numpy as np
import pytest
from scipy import signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('g')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


@pytest.mark.parametrize('t', [0.0, 1.5])
def test_spike_filter_swaps_in_the_median_only_past_the_threshold_lag1_as_computed(t):
    fn, _ = SHAPES['internal_lowpass']
    x = np.random.default_rng(2).standard_normal(400000)
    y = fn(x.copy(), None, thresh=t)
    med = np.median(np.c_[x[:-2], x[1:-1], x[2:]], axis=1)
    hit = np.abs(x[1:-1] - med) > t
    assert np.array_equal(y[1:-1][hit], med[hit])
    assert np.array_equal(y[1:-1][~hit], x[1:-1][~hit])
    assert y[0] == x[0] and y[-1] == x[-1] and np.mean(hit) > 0.02
    assert np.corrcoef(y[:-1], y[1:])[0, 1] == pytest.approx(STATIC.spike_lag1(t), abs=0.006)


def test_knock_train_is_periodic_and_its_lines_are_the_rings_fourier_transform():
    fn, _ = SHAPES['vibration']
    f0, per = 31.2, int(round(STATIC.KNOCK_PERIOD / DT))
    y = fn(np.zeros(80000), np.random.default_rng(3), amplitude=1.0, freq=f0)
    assert np.allclose(y[per:], y[:-per], atol=1e-12)
    t = np.arange(y.size) * DT
    t0 = np.random.default_rng(3).uniform(0, STATIC.KNOCK_PERIOD)    # the train's phase
    for k in (20, 25, 30):
        f = k / STATIC.KNOCK_PERIOD
        c = fit(y, (np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)))
        fa = f + np.arange(-3000, 3001) / DT                  # the lines sampling folds onto f
        line = 2 * abs(np.sum(STATIC.knock_spectrum(fa, f0) * np.exp(2j * np.pi * fa * t0)))
        assert np.hypot(*c) == pytest.approx(line / STATIC.KNOCK_PERIOD, rel=1e-3)
        assert line == pytest.approx(2 * abs(STATIC.knock_spectrum(f, f0)), rel=0.2)
    f, amp = STATIC.knock_lines(f0, DT)                  # phase-averaged power of each line
    fa = f[:, None] + np.arange(-3000, 3001)[None, :] / DT
    assert np.allclose(amp, 2 * np.sqrt(np.sum(np.abs(STATIC.knock_spectrum(fa, f0)) ** 2,
                                               axis=1)) / STATIC.KNOCK_PERIOD, rtol=1e-3)
    tt = np.arange(per) * DT                 # brute force: the last 40 knocks' rings summed
    rings = sum(np.exp(-(tt + j * STATIC.KNOCK_PERIOD) / STATIC.KNOCK_DECAY)
                * np.sin(2 * np.pi * f0 * (tt + j * STATIC.KNOCK_PERIOD)) for j in range(40))
    assert np.allclose(STATIC.knock_wave(tt, f0), rings, atol=1e-9)


def test_gradient_pulse_is_the_rate_of_a_logistic_ambient_step():
    fn, levels = SHAPES['temperature_drift']
    amp, n = levels[1]['amplitude'], 720000
    y = fn(np.zeros(n), None, amplitude=amp)
    t = np.arange(n) * DT
    w = STATIC.GRAD_WIDTH
    ambient = 1.0 / (1.0 + np.exp(-(t - STATIC.GRAD_AT) / w))
    assert np.allclose(y, amp * 4 * w * np.gradient(ambient, DT), atol=1e-6 * amp)
    assert y.max() == pytest.approx(amp, rel=1e-6) and y[-1] < 1e-6 * amp
    assert np.sum(y) * DT == pytest.approx(amp * 4 * w, rel=1e-3)   # the step's size
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(y) * np.sqrt(n) / SIG, rel=1e-9)


def test_held_flicker_steps_only_at_register_updates_and_its_allan_is_the_held_1_over_f():
    fn, _ = SHAPES['bias_instability']
    n, per = 2 ** 21, int(round(STATIC.HOLD / DT))
    y = fn(np.zeros(n), np.random.default_rng(4), b=1.0)
    steps = np.flatnonzero(np.diff(y)) + 1
    assert np.all(np.diff(steps) == per)
    held = y[steps[0]::per]
    w = signal.fftconvolve(held, STATIC.frac_kernel(held.size, -0.5))[:held.size]
    assert np.std(w[10:]) == pytest.approx(1.0, rel=0.05)              # the white drive
    assert abs(np.corrcoef(w[10:-1], w[11:])[0, 1]) < 0.06
    psd = lambda f: STATIC.held_flicker_psd(f, 1.0)                      # noqa: E731
    for m in (per, 8 * per):
        assert avar(y, [m])[0] == pytest.approx(STATIC.psd_avar(psd, [m * DT], DT)[0],
                                                rel=0.25)
    assert STATIC.held_flicker_psd(1e-6, 1.0) == pytest.approx(1 / (np.pi * 1e-6), rel=1e-6)


def test_railed_walk_is_a_walk_folded_between_rails_and_its_modes_sum_to_the_uniform():
    fn, _ = SHAPES['rate_random_walk']
    n, k = 8_000_000, 1.0
    y = fn(np.zeros(n), np.random.default_rng(6), k=k)
    half = k * np.sqrt(STATIC.BOUND_TIME)
    rng = np.random.default_rng(6)
    walk = rng.uniform(-half, half) + np.cumsum(rng.standard_normal(n)) * k * np.sqrt(DT)
    assert np.abs(y).max() <= half * (1 + 1e-12)
    seg = np.floor((walk + half) / (2 * half))                 # mirror image the walk is in
    same = seg[1:] == seg[:-1]
    sign = np.where(seg % 2 == 0, 1.0, -1.0)[1:]
    assert np.allclose(np.diff(y)[same], (sign * np.diff(walk))[same], atol=1e-9)
    assert np.allclose(y[seg % 2 == 0], (walk - seg * 2 * half)[seg % 2 == 0], atol=1e-9)
    sd, tc = STATIC.reflected_modes(k, half, 9999)
    assert np.sum(sd ** 2) == pytest.approx(half * half / 3, rel=1e-6)   # uniform variance
    assert np.var(y) == pytest.approx(half * half / 3, rel=0.3)
    m = np.array([100, 30000])
    expect = sum(STATIC.gm_avar(m * DT, s, c) for s, c in zip(sd[:50], tc[:50]))
    assert np.allclose(avar(y, m), expect, rtol=0.3)
    assert expect[0] == pytest.approx(m[0] * DT / 3, rel=0.02)          # a walk at short tau


def test_squared_ou_is_chi_square_and_exponentially_correlated_with_half_its_time():
    fn, _ = SHAPES['gauss_markov']
    sigma, tc = 2.0, 0.8
    y = fn(np.zeros(2_000_000), np.random.default_rng(7), sigma=sigma, tc=tc)
    q2 = y / (sigma / np.sqrt(2)) + 1
    assert q2.min() >= 0 and q2.min() < 1e-4
    assert np.std(y) == pytest.approx(sigma, rel=0.04)
    assert stats.skew(y) == pytest.approx(2 * np.sqrt(2), rel=0.1)
    lag = int(tc / DT)
    assert np.corrcoef(y[:-lag], y[lag:])[0, 1] == pytest.approx(np.exp(-1), abs=0.03)
    m = int(1.89 * tc / DT)
    assert avar(y, [m])[0] == pytest.approx(STATIC.gm_avar(m * DT, sigma, tc), rel=0.1)


@pytest.mark.parametrize('hyst', [0.22, 2.0, 8.0])
def test_schmitt_counter_holds_within_its_band_and_its_allan_excess_is_the_chains(hyst):
    fn, _ = SHAPES['quantization']
    step, h = INC / 24, hyst * INC / 24
    x = SIG * np.random.default_rng(8).standard_normal(300000)
    y = fn(x.copy(), np.random.default_rng(9), step=step, hyst=h)
    rng = np.random.default_rng(9)
    theta = np.r_[0.0, np.cumsum(x)] * DT + (rng.integers(2 ** 20) + rng.uniform()) * step
    read = np.floor(theta[0] / step) * step + np.r_[0.0, np.cumsum(y)] * DT
    e = theta - read
    assert e[1:].min() >= -h * (1 + 1e-6) - 1e-15 and e.max() < step + h + 1e-12
    for i in (5, 77, 1234):                                    # one step of the chain's map
        assert STATIC.schmitt_map(e[i - 1] + theta[i] - theta[i - 1], step, h) == \
            pytest.approx(e[i], abs=1e-12)
    for m in (1, 4):
        ex = (avar(y, [m]) - avar(x, [m]))[0] * (m * DT) ** 2
        assert ex == pytest.approx(STATIC.schmitt_excess(m, step, h, INC), rel=0.12)


def test_loop_peaking_shapes_the_sensors_own_noise_with_bodes_zero_log_integral():
    fn, levels = SHAPES['resonance']
    p = levels[1]
    b, a = STATIC.peaking(p['gain'], p['freq'], p['q'], DT)
    f = np.linspace(0, 0.5 / DT, 400001)
    mag2 = np.abs(signal.freqz(b, a, worN=f, fs=1 / DT)[1]) ** 2
    assert abs(np.trapezoid(np.log(mag2), f)) < 1e-4 * 0.5 / DT       # no net log gain
    assert np.sqrt(mag2.max()) == pytest.approx(p['gain'], rel=0.06)
    assert f[np.argmax(mag2)] == pytest.approx(p['freq'], abs=0.05)
    x = np.random.default_rng(11).standard_normal(2 ** 20)
    y = fn(x.copy(), None, **p)
    fw, px = signal.welch(x, fs=1 / DT, nperseg=2 ** 12)
    _, py = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    ratio = np.abs(signal.freqz(b, a, worN=fw, fs=1 / DT)[1]) ** 2
    near = np.abs(fw - p['freq']) < 3.0
    assert np.allclose(py[near] / px[near], ratio[near], rtol=0.1)
    assert np.mean(np.log(py / px)[1:-1]) == pytest.approx(0.0, abs=0.02)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_clock_skew_makes_the_gyro_late_by_a_delay_growing_through_the_run():
    fn, levels = SWING_SHAPES['time_delay']
    ppm = levels[1]['ppm']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 60.0)
    d = ti - t
    assert np.allclose(d, ppm * 1e-6 * t, rtol=0, atol=1e-12)
    assert np.array_equal(g, rate) and np.array_equal(te, t) and np.all(np.diff(ti) > 0)
    late = g - stand(ti)[1]                                    # the value is from ti - d
    acc = -AMP * W * W * np.sin(W * ti)
    assert np.allclose(late, -acc * d, atol=1e-3 * AMP * W * W * d.max())


def test_mass_stops_saturate_the_g_term_and_cut_its_fundamental():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    fy = SWING.G0 * np.sin(stand(t)[0])
    err = g - rate
    assert np.allclose(err, gy * SWING.SAT_FORCE * np.tanh(fy / SWING.SAT_FORCE), atol=1e-15)
    assert np.abs(err).max() < gy * SWING.SAT_FORCE
    small = np.abs(fy) < 0.05
    assert np.allclose(err[small], gy * fy[small], rtol=1e-3)      # linear for small force
    c = fit(err, (np.sin(W * t), np.cos(W * t), np.ones(t.size)))
    assert np.hypot(c[0], c[1]) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=1e-3)
    assert np.hypot(c[0], c[1]) < 0.9 * gy * 2 * SWING.G0 * special.jv(1, AMP)


def test_mode_crossing_is_a_local_bump_in_the_transfer_and_noise_smooths_it_as_computed():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    e0 = levels[1]['e0']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    far = np.abs(np.abs(rate) - SWING.BUMP_AT) > 10 * SWING.BUMP_WIDTH
    assert np.abs(err[far]).max() < 0.01 * e0 and np.abs(err).max() > 0.99 * e0
    assert np.allclose(err * np.sign(rate), np.abs(err))              # odd in the rate
    sn, w = 0.02, np.linspace(-0.4, 0.4, 9)
    noisy = w[:, None] + sn * np.random.default_rng(3).standard_normal((9, 200000))
    assert np.allclose(SWING.bump(noisy, 1.0).mean(axis=1), SWING.smoothed_bump(w, 1.0, sn),
                       atol=0.005)


def test_loose_contact_switches_the_asymmetry_on_and_off_with_exponential_dwells():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    ok = np.abs(rate) > 0.05
    state = (g - rate)[ok] / (a * np.abs(rate[ok]))
    assert np.allclose(state, np.round(state), atol=1e-9) and set(np.round(state)) == {0, 1}
    u = SWING.contact(10_000_000, DT, np.random.default_rng(4))
    dwell = np.diff(np.flatnonzero(np.diff(u))) * DT
    assert np.mean(dwell) == pytest.approx(SWING.CONTACT_DWELL, rel=0.1)
    assert np.std(dwell) / np.mean(dwell) == pytest.approx(1.0, abs=0.1)   # exponential
    assert np.mean(u) == pytest.approx(0.5, abs=0.05)


def test_double_buffer_stamps_alternate_early_and_late_a_nyquist_line():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    skew = levels[1]['skew']
    t, _, (_, _, te, _) = swing(fn, levels[1], 20.0)
    e = te - t
    assert np.allclose(np.abs(e), skew / 2, rtol=1e-6) and np.all(e[1:] * e[:-1] < 0)
    spec = np.abs(np.fft.rfft(e)) ** 2
    assert spec[-1] / spec.sum() > 1 - 1e-9 and np.all(np.diff(te) > 0)


def test_muxed_tracks_read_the_two_tracks_apart_and_err_at_twice_the_line_in_speed():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    skew = levels[1]['skew']
    t, rate, (_, _, _, enc) = swing(fn, levels[1], 20.0)
    phi = stand(t)[0]
    lines = SWING.SIGNAL_LINES
    u = lines * phi
    direct = np.arctan2(np.sin(lines * stand(t - skew / 2)[0]),
                        np.cos(lines * stand(t + skew / 2)[0]))
    assert np.allclose(enc - phi, np.angle(np.exp(1j * (direct - u))) / lines, atol=1e-10)
    eps = lines * rate * skew
    assert np.allclose((enc - phi) * lines, -eps / 2 * np.cos(2 * u), atol=np.abs(eps).max()
                       ** 2)
    slow = np.abs(rate) < 1e-3
    assert np.abs(enc - phi)[slow].max() < 1e-3 * skew


def test_both_harnesses_take_set_g_by_held_out_g(monkeypatch):
    check_harnesses('g', SHAPES, SWING_SHAPES, monkeypatch)
