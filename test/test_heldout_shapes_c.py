# Held-out set C (bench/validate_diagnosis_heldout_c.py, static, and
# bench/validate_diagnosis_swing_heldout_c.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out c. THE GENERATORS only, never the diagnosis.
# (A file of its own: test_heldout_shapes.py, which checks set B, would pass the 420-line limit.)
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            flicker_band_psd, load_set, N_ARW, SIG, stand, swing, W)
import numpy as np
import pytest
from scipy import signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('c')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


@pytest.mark.parametrize('cutoff', [0.3, 0.6, 0.9955])
def test_butterworth_dc_gain_one_lag1_and_half_power_at_cutoff(cutoff):
    fn, _ = SHAPES['internal_lowpass']
    assert fn(np.ones(50), None, cutoff=cutoff) == pytest.approx(np.ones(50))
    y = fn(np.random.default_rng(2).standard_normal(400000), None, cutoff=cutoff)
    assert np.corrcoef(y[:-1], y[1:])[0, 1] == pytest.approx(STATIC.lag1(cutoff), abs=0.005)
    if cutoff < 0.99:
        b, a = signal.butter(2, cutoff)
        assert abs(signal.freqz(b, a, [np.pi * cutoff])[1][0]) ** 2 == pytest.approx(0.5)


def test_fan_tone_rms_and_its_power_stays_in_the_stated_band():
    fn, _ = SHAPES['vibration']
    y = fn(np.zeros(400000), np.random.default_rng(3), amplitude=1.0, freq=4.3, wander=0.01)
    assert np.std(y) == pytest.approx(np.sqrt(0.5), rel=0.01)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 16)
    band = np.abs(f - 4.3) <= 2.5 * 0.01 * 4.3
    assert p[band].sum() / p.sum() > 0.95
    spread = np.sqrt(np.sum(p * (f - 4.3) ** 2) / p.sum())       # the wander, ~ 0.043 Hz
    assert 0.5 * 0.043 < spread < 1.5 * 0.043


def test_thermostat_is_periodic_hysteretic_and_its_line_is_the_detectability_one():
    fn, levels = SHAPES['temperature_drift']
    amp = levels[0]['amplitude']
    n = 720000
    y = fn(np.zeros(n), np.random.default_rng(4), amplitude=amp)
    k = int(STATIC.THERMO_PERIOD / DT)
    assert np.abs(y[2 * k:] - y[k:-k]).max() < 5e-3 * amp        # periodic after one cycle
    assert np.abs(y).max() < amp
    assert np.mean(np.diff(y[k:]) == 0.0) > 0.1                   # the play operator holds
    t = np.arange(n) * DT
    cols = (np.sin(2 * np.pi * t / STATIC.THERMO_PERIOD),
            np.cos(2 * np.pi * t / STATIC.THERMO_PERIOD), np.ones(n))
    lines = [np.hypot(*fit(fn(np.zeros(n), np.random.default_rng(s), amplitude=amp), cols)[:2])
             for s in range(8)]
    assert np.mean(lines) == pytest.approx(STATIC.fundamental(amp, DT, n), rel=0.03)
    assert np.min(lines) > 0.8 * np.mean(lines)


def test_telegraph_sum_flicker_psd_slope_minus_one_and_allan_floor():
    fn, _ = SHAPES['bias_instability']
    ys, f, p, sel = flicker_band_psd(fn)
    assert np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0] == pytest.approx(-1.0, abs=0.1)
    assert np.median(p[sel] * np.pi * f[sel]) == pytest.approx(1.0, rel=0.15)   # B^2 / (pi f)
    for m in (10, 100, 1000):
        adev = np.mean([np.sqrt(avar(y, [m])[0]) for y in ys])
        assert adev == pytest.approx(0.664, rel=0.15)


def test_intermittent_walk_diffuses_at_k_squared_in_episodes():
    fn, _ = SHAPES['rate_random_walk']
    y = fn(np.zeros(4_000_000), np.random.default_rng(6), k=1.0)
    d = np.diff(y)
    assert np.mean(d * d) / DT == pytest.approx(1.0, rel=0.15)
    block = d[:d.size // 10000 * 10000].reshape(-1, 10000).var(axis=1) / DT   # 100 s blocks
    assert np.percentile(block, 90) / np.percentile(block, 10) > 4.0      # 1.8 vs 0.2 K^2
    m = np.array([5000, 80000])
    a = avar(y, m)
    assert a[1] == pytest.approx(80000 * DT / 3, rel=0.35)
    assert np.log(a[1] / a[0]) / np.log(16.0) == pytest.approx(1.0, abs=0.2)


def test_popcorn_two_levels_correlation_and_allan():
    fn, _ = SHAPES['gauss_markov']
    y = fn(np.zeros(2_000_000), np.random.default_rng(7), sigma=2.0, tc=0.2)
    assert set(np.unique(y)) == {-2.0, 2.0}
    assert np.corrcoef(y[:-20], y[20:])[0, 1] == pytest.approx(np.exp(-1), abs=0.02)
    m = int(1.89 * 0.2 / DT)
    assert avar(y, [m])[0] == pytest.approx(STATIC.gm_avar(m * DT, 2.0, 0.2), rel=0.05)


@pytest.mark.parametrize('c', [0.29, 3.0])
def test_dithered_counter_angle_error_uniform_white_and_allan_excess(c):
    fn, _ = SHAPES['quantization']
    rng = np.random.default_rng(8)
    x = SIG * rng.standard_normal(200000) + 0.003
    step = c * N_ARW * np.sqrt(DT)
    y = fn(x, rng, step=step)
    e = np.cumsum(y - x) * DT
    v = step ** 2 / 12
    assert np.var(e) == pytest.approx(v, rel=0.05)
    assert abs(np.corrcoef(e[:-1], e[1:])[0, 1]) < 0.03
    assert np.ptp(e) <= step * (1 + 1e-9)
    excess = (avar(y, [1])[0] - avar(x, [1])[0]) / (3 * v / DT ** 2)
    assert excess == pytest.approx(1.0, abs=0.1)


def test_split_mode_pair_rms_and_two_peaks():
    fn, _ = SHAPES['resonance']
    y = fn(np.zeros(400000), np.random.default_rng(9), sigma=1.5, freq=33.0, q=30.0)
    assert np.std(y) == pytest.approx(1.5, rel=0.05)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 13)
    for target in (33.0 * 0.98, 33.0 * 1.02):
        near = np.abs(f - target) < 0.25
        assert f[near][np.argmax(p[near])] == pytest.approx(target, abs=0.15)
    mid = np.argmin(np.abs(f - 33.0))
    assert p[mid] < 0.7 * p[np.abs(f - 33.0 * 0.98) < 0.25].max()        # a dip between


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


@pytest.mark.parametrize('window', [3.8e-4, 2e-3, 8e-3])
def test_integrate_and_dump_delays_by_half_the_window(window):
    fn, _ = SWING_SHAPES['time_delay']
    t, rate, (_, g, _, _) = swing(fn, {'window_s': window})
    angle = np.r_[0.0, np.cumsum((g[1:] + g[:-1]) / 2) * 1e-3]
    c = fit(angle - stand(t)[0], (np.sin(W * t), np.cos(W * t), np.ones(t.size), t))
    assert c[1] == pytest.approx(-AMP * W * window / 2, rel=0.02)


def test_viscoelastic_g_amplitude_and_lag():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1])
    m = t > 2.0
    c = fit((g - rate)[m], (np.sin(W * t[m]), np.cos(W * t[m])))
    assert np.hypot(*c) == pytest.approx(gy * SWING.G0 * 2 * special.j1(AMP)
                                         / np.hypot(1, W * SWING.G_LAG), rel=0.01)
    assert np.arctan2(-c[1], c[0]) == pytest.approx(np.arctan(W * SWING.G_LAG), abs=0.01)


def test_range_switch_gain_step_and_third_harmonic():
    fn, _ = SWING_SHAPES['scale_factor_nonlinearity']
    t, rate, (_, g, _, _) = swing(fn, {'e': 0.02})
    err = g - rate
    hi = np.abs(rate) > SWING.RANGE_SWITCH
    assert np.all(err[~hi] == 0.0) and np.allclose(err[hi], 0.02 * rate[hi])
    c = fit(err, (np.cos(3 * W * t), np.sin(3 * W * t)))
    assert c[0] == pytest.approx(0.02 * SWING.harmonic(
        lambda r: r * (np.abs(r) > SWING.RANGE_SWITCH), AMP * W, 3), rel=0.01)


def test_comparator_asymmetry_gains_and_second_harmonic():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1])
    assert np.allclose(g - rate, a * np.abs(rate - SWING.COMPARATOR))
    c = fit(g - rate, (np.cos(2 * W * t), np.sin(2 * W * t), np.ones(t.size)))
    assert c[0] == pytest.approx(a * SWING.harmonic(lambda r: np.abs(r - SWING.COMPARATOR),
                                                    AMP * W, 2), rel=1e-3)


def test_latency_zero_mean_stated_variance_one_sided_heavy_tail():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    m = levels[0]['mean_s']
    t, _, (_, _, te, _) = swing(fn, levels[0], 600.0)
    e = te - t
    sd = np.sqrt(SWING.latency_moments(m)[1])
    assert sd == pytest.approx(3.13 * m, rel=0.01)
    assert abs(np.mean(e)) < 0.05 * sd
    assert np.std(e) == pytest.approx(sd, rel=0.1)
    assert stats.skew(e) > 3.0 and e.min() >= -1.45 * m - 1e-3


def test_triangle_cyclic_error_odd_harmonics_on_360_lines():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    a = levels[0]['a']
    t, _, (_, _, _, enc) = swing(fn, levels[0], 20.0)
    phi = stand(t)[0]
    assert np.abs(enc - phi).max() == pytest.approx(a, rel=1e-3)
    x = SWING.LINES * phi + 0.9
    c = fit(enc - phi, tuple(f(k * x) for k in (1, 2, 3) for f in (np.sin, np.cos)))
    assert np.hypot(c[0], c[1]) == pytest.approx(8 * a / np.pi ** 2, rel=0.01)
    assert np.hypot(c[2], c[3]) < 1e-2 * a                        # no even harmonics
    assert np.hypot(c[4], c[5]) == pytest.approx(8 * a / (9 * np.pi ** 2), rel=0.02)


def test_both_harnesses_take_set_c_by_held_out_c(monkeypatch):
    check_harnesses('c', SHAPES, SWING_SHAPES, monkeypatch)
