# Held-out set I (bench/validate_diagnosis_heldout_i.py, static, and
# bench/validate_diagnosis_swing_heldout_i.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out i. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            flicker_band_psd, load_set, N_ARW, octave_ratios, S_LINE, SIG, swing,
                            W)
import numpy as np
import pytest
from scipy import signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('i')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_frame_smoother_is_zero_phase_unit_gain_and_reset_at_every_frame_edge():
    fn, _ = SHAPES['internal_lowpass']
    a, f = 0.5, STATIC.FRAME
    start = int(np.random.default_rng(3).integers(f))
    assert np.allclose(fn(np.full(10 * f, 2.0), np.random.default_rng(3), a=a), 2.0)
    x = np.zeros(10 * f)
    mid = start + 4 * f + f // 2                        # the middle of a whole frame
    x[mid] = 1.0
    y = fn(x, np.random.default_rng(3), a=a)
    frame = slice(start + 4 * f, start + 5 * f)
    assert np.count_nonzero(y) == f and np.all(y[frame] > 0)           # that frame only
    k = np.arange(1, 6)
    assert np.allclose(y[mid - k], y[mid + k], rtol=0.05)               # (nearly) symmetric
    assert y[mid - 1] > 0.3 * y[mid]                                    # the past answers
    w = np.random.default_rng(4).standard_normal(f * 20000)
    y = fn(w.copy(), np.random.default_rng(5), a=0.15)
    s = int(np.random.default_rng(5).integers(f))
    r1 = y[:-1] * y[1:]
    edge = (np.arange(r1.size) - s + 1) % f == 0                        # pairs across an edge
    assert abs(np.mean(r1[edge])) < 0.02
    assert np.mean(r1) / np.mean(y * y) == pytest.approx(STATIC.frame_lag1(0.15), abs=0.005)


def test_fan_hops_among_three_speeds_with_amplitude_as_speed_squared():
    fn, _ = SHAPES['vibration']
    n = 2 * 10 ** 6
    y = fn(np.zeros(n), np.random.default_rng(6), amplitude=1.0)
    z = signal.hilbert(y)
    inst = np.diff(np.unwrap(np.angle(z))) / (2 * np.pi * DT)
    inst = inst[1000:-1000]
    env = np.abs(z)[1001:-1000]
    fan = np.array(STATIC.FAN_HZ)
    near = np.abs(inst[:, None] - fan[None, :]) < 0.05
    share = near.mean(axis=0)
    assert share.sum() > 0.9 and np.all(share > 0.15)                    # one speed at a time
    for j, f in enumerate(fan):
        assert np.median(env[near[:, j]]) == pytest.approx((f / fan[1]) ** 2, rel=0.02)
    hops = np.flatnonzero(np.diff(np.argmax(near, axis=1)[near.any(axis=1)]))
    assert 40 < hops.size < 130                                          # ~83 at 240 s


def test_diffusive_warming_rises_from_zero_with_an_inverse_square_root_tail():
    fn, levels = SHAPES['temperature_drift']
    a, n = levels[1]['amplitude'], 720000
    y = fn(np.zeros(n), np.random.default_rng(7), amplitude=a)
    t0 = np.random.default_rng(7).uniform(0, STATIC.POWER_ON)
    t = np.arange(n) * DT + t0
    assert np.allclose(y, a * special.erfc(np.sqrt(STATIC.DIFFUSE_T / t)), rtol=1e-12)
    assert y[0] < 1e-3 * a and np.all(np.diff(y) >= 0)
    tail = (a - y[-1]) * np.sqrt(t[-1]) / (2 * a * np.sqrt(STATIC.DIFFUSE_T / np.pi))
    assert tail == pytest.approx(1.0, rel=0.03)                          # 1 / sqrt(t), no tau
    s = STATIC.diffusive(np.arange(n) * DT, a)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(s) * np.sqrt(n) / SIG, rel=1e-9)


def test_diffusion_flicker_has_the_modes_psd_one_over_f_in_band_flat_below():
    fn, _ = SHAPES['bias_instability']
    ys, f, pxx, band = flicker_band_psd(fn)
    want = STATIC.slab_psd(f[band], 1.0, DT)
    ratio = octave_ratios(f, pxx, band, want)
    assert np.allclose(ratio, 1.0, atol=0.2), ratio
    assert np.mean(pxx[band] / want) == pytest.approx(1.0, abs=0.06)
    g = np.geomspace(1e-3, 3.0, 20)
    slope = np.polyfit(np.log(g), np.log(STATIC.slab_psd(g, 1.0, DT)), 1)[0]
    assert slope == pytest.approx(-1.0, abs=0.05)
    assert STATIC.slab_psd(1e-3, 1.0, DT) * np.pi * 1e-3 == pytest.approx(1.0, rel=0.1)
    assert STATIC.slab_psd(1e-6, 1.0, DT) / STATIC.slab_psd(1e-5, 1.0, DT) < 1.5    # flat
    a = np.mean([avar(y, [100])[0] for y in ys])
    assert a == pytest.approx(STATIC.psd_avar(
        lambda h: STATIC.slab_psd(h, 1.0, DT), 1.0, DT)[0], rel=0.3)


def test_autozero_walk_restarts_from_zero_every_900_s_allan_as_its_covariance():
    fn, _ = SHAPES['rate_random_walk']
    n, period = 10 ** 6, int(STATIC.AUTOZERO / DT)
    ys = [fn(np.zeros(n), np.random.default_rng(30 + i), q=1.0) for i in range(8)]
    zero = np.flatnonzero(ys[0] == 0.0)
    assert np.all(np.diff(zero) == period) and zero.size >= n // period
    d = np.diff(ys[0])
    jumps = np.abs(d) > 6
    assert np.array_equal(np.flatnonzero(jumps) + 1, zero[zero > 0])   # only at re-zeroings
    assert np.std(d[~jumps]) == pytest.approx(1.0, rel=0.01)
    for m in (100, 3000):
        got = np.mean([avar(y, [m])[0] for y in ys])
        want = STATIC.cov_avar(lambda ell: STATIC.autozero_cov(ell, 1.0, period), m)
        assert got == pytest.approx(want, rel=0.25)


def test_product_is_symmetric_leptokurtic_and_exponentially_correlated():
    fn, _ = SHAPES['gauss_markov']
    tc, n = 0.1, 2 ** 21
    y = fn(np.zeros(n), np.random.default_rng(8), amplitude=1.0, tc=tc)
    assert np.std(y) == pytest.approx(1.0, rel=0.03)
    assert abs(stats.skew(y)) < 0.15 and stats.kurtosis(y) == pytest.approx(6.0, rel=0.15)
    for lag in (5, 10, 20):
        r = np.mean(y[:-lag] * y[lag:]) / np.mean(y * y)
        assert r == pytest.approx(np.exp(-lag * DT / tc), abs=0.02)


def test_vernier_reads_on_the_fine_grid_with_a_sawtooth_of_its_gain_error():
    fn, levels = SHAPES['quantization']
    p = levels[1]
    q, g = p['step'], p['gain']
    x = SIG * np.random.default_rng(9).standard_normal(400000)
    y = fn(x.copy(), np.random.default_rng(10), **p)
    theta0 = np.random.default_rng(10).uniform(0, q)              # the angle before x[0]
    theta = theta0 + np.r_[0.0, np.cumsum(x)] * DT
    read = theta[0] + STATIC.vernier_error(theta[0], q, g) + np.r_[0.0, np.cumsum(y)] * DT
    cell = q / STATIC.FINE
    k = np.round(read / cell)
    assert np.allclose(read, k * cell, atol=1e-6 * cell)                # on the fine grid
    e = read - theta
    r = np.mod(theta, q)
    assert np.polyfit(r, e, 1)[0] == pytest.approx(g, abs=0.01)         # sawtooth slope g
    assert np.max(np.abs(e - g * r)) <= cell / 2 * (1 + 1e-6)
    ex = avar(y, [1, 10]) - avar(x, [1, 10])
    for m, got in zip((1, 10), ex):
        want = STATIC.vernier_excess(m, q, g, DT, N_ARW) * N_ARW ** 2 / (m * DT)
        assert got == pytest.approx(want, rel=0.15)


def test_demodulated_mode_has_first_order_skirts_and_the_computed_spectrum():
    fn, _ = SHAPES['resonance']
    n, f0, q = 2 ** 20, 35.0, 35.0 / 3
    y = fn(np.zeros(n), np.random.default_rng(11), sigma=1.0, freq=f0, q=q)
    assert np.std(y) == pytest.approx(1.0, rel=0.05) and abs(stats.kurtosis(y)) < 0.1
    f, pxx = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.complex_pole_psd(f, 1.0, f0, q, DT)
    for band in ((f > 1) & (f < 10), (f > 30) & (f < 40)):
        assert np.mean(pxx[band]) == pytest.approx(np.mean(want[band]), rel=0.06)
    assert np.allclose(pxx[1:-1], want[1:-1], rtol=0.3)
    r, th = np.exp(-np.pi * f0 * DT / q), 2 * np.pi * f0 * DT           # a real 2nd-order mode
    fa = np.linspace(0, 50, 100001)
    real = np.abs(signal.freqz([1], [1, -2 * r * np.cos(th), r * r], worN=fa, fs=100)[1]) ** 2
    real /= np.trapezoid(real, fa)                                       # unit variance
    low = (f > 1) & (f < 10)
    assert np.mean(pxx[low]) > 1.8 * np.mean(np.interp(f[low], fa, real))   # the plateau
    assert f[np.argmax(pxx)] == pytest.approx(f0, abs=0.5)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_allpass_delays_the_motion_and_leaves_the_noise_white():
    fn, levels = SWING_SHAPES['time_delay']
    d = levels[1]['delay']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    late = AMP * W * np.cos(W * (t - d))
    k = slice(2000, None)
    assert np.max(np.abs(g[k] - late[k])) < 1e-3 * np.max(np.abs(rate - late))
    assert np.array_equal(ti, t) and np.array_equal(te, t)
    w = np.random.default_rng(12).standard_normal(2 ** 20)
    y = SWING.allpass(w, 2.3)
    assert np.std(y) == pytest.approx(1.0, rel=0.01)
    f, pxx = signal.welch(y, fs=1000.0, nperseg=1024)
    assert np.allclose(pxx[1:-1], 2e-3, rtol=0.2)                       # flat: all-pass


def test_settling_g_coefficient_relaxes_from_three_times_its_final_value():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    err = g - rate
    fy = 9.80665 * np.sin(AMP * np.sin(W * t))
    assert np.allclose(err, gy * (1 + 2 * np.exp(-t / 200.0)) * fy, rtol=1e-9, atol=1e-15)
    first = fit(err[:5000], (fy[:5000],))[0]
    last = fit(err[-5000:], (fy[-5000:],))[0]
    assert first == pytest.approx(3 * gy, rel=0.02) and last == pytest.approx(gy, rel=0.03)
    c = fit(err, (np.sin(W * t), np.cos(W * t)))
    assert np.hypot(*c) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.02)


def fold_lines(err, t, kmax=60):
    """Norm of lines 2..kmax of ``err`` folded over the 5 s swing period (1 kHz samples)."""
    m = 5000
    mean = err[:err.size // m * m].reshape(-1, m).mean(axis=0)
    return float(2 * np.linalg.norm(np.fft.rfft(mean)[2:kmax + 1] / m))


@pytest.mark.parametrize('name', ['scale_factor_nonlinearity', 'scale_factor_asymmetry'])
def test_clip_and_onset_lines_with_noise_as_computed(name):
    fn, levels = SWING_SHAPES[name]
    t = np.arange(900000) * 1e-3
    rate = AMP * W * np.cos(W * t)
    n_pre = S_LINE / np.sqrt(2 / 900.0)                                # the preset's N
    gyro = rate + n_pre * np.sqrt(1000.0) * np.random.default_rng(13).standard_normal(t.size)
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, AMP * np.sin(W * t), None, None, **p)[1]
        assert fold_lines(out - gyro, t) / S_LINE == pytest.approx(
            SWING.detectability(name, p), rel=0.08)


def test_clipping_is_a_hard_limit_and_the_onset_is_even_and_zero_below_it():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    fs = levels[1]['full_scale']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    assert np.max(np.abs(g)) == pytest.approx(fs, rel=1e-12)
    inside = np.abs(rate) < fs
    assert np.array_equal(g[inside], rate[inside]) and np.all(np.abs(g[~inside]) == fs)
    assert 0.05 < np.mean(~inside) < 0.5
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    err = g - rate
    assert np.all(err[np.abs(rate) < SWING.ONSET] == 0)
    assert np.allclose(err, a * np.maximum(np.abs(rate) - SWING.ONSET, 0), atol=1e-15)
    assert np.allclose(err[:10000], err[2500:12500], atol=1e-6 * a)      # even: w and -w
    assert np.max(err) == pytest.approx(a * (AMP * W - SWING.ONSET), rel=1e-4)


def test_ripple_moves_the_encoder_stamps_by_a_50_hz_sine():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    amp = levels[1]['amp']
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    e = te - t
    c = fit(e, (np.sin(2 * np.pi * 50 * t), np.cos(2 * np.pi * 50 * t)))
    assert np.hypot(*c) == pytest.approx(amp, rel=1e-9)
    assert np.max(np.abs(e - c[0] * np.sin(2 * np.pi * 50 * t) - c[1] * np.cos(
        2 * np.pi * 50 * t))) < 1e-9 * amp
    assert np.array_equal(ti, t) and np.array_equal(g, rate)
    zs = [SWING.detectability('timestamp_jitter', p) for p in levels]
    assert zs[0] / zs[2] == pytest.approx(levels[0]['amp'] / levels[2]['amp'], rel=1e-6)


def test_interleaved_graduation_errs_at_half_and_one_and_a_half_the_line_frequency():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    eps = levels[0]['eps']
    L = SWING.TRACK_LINES
    u = np.arange(2 ** 14) * 4 * np.pi / 2 ** 14                          # two signal periods
    e = SWING.track_error(u / L, eps, 0.3) * L
    h = np.abs(np.fft.rfft(e)) / u.size * 2
    assert h[1] > 0.3 * eps and h[3] > 0.3 * eps                          # u / 2, 3 u / 2
    assert np.max(np.delete(h, [1, 3])[:40]) < 0.02 * eps                  # nothing else
    approx = eps * (np.cos(u) * np.sin(u / 2 + 0.3) - np.sin(u) * np.sin(u / 2 + 0.3
                                                                         + np.pi / 4))
    assert np.allclose(e, approx, atol=0.02 * eps)
    t, rate, (_, _, _, enc) = swing(fn, levels[0], 20.0)
    err = enc - AMP * np.sin(W * t)
    assert np.max(np.abs(err)) == pytest.approx(np.max(np.abs(approx)) / L, rel=0.05)


def test_both_harnesses_take_set_i_by_held_out_i(monkeypatch):
    check_harnesses('i', SHAPES, SWING_SHAPES, monkeypatch)
