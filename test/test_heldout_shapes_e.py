# Held-out set E (bench/validate_diagnosis_heldout_e.py, static, and
# bench/validate_diagnosis_swing_heldout_e.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out e. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            flicker_band_psd, INC, load_set, N_ARW, S_LINE, SIG, stand, swing, W)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('e')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


@pytest.mark.parametrize('ratio', [0.85, 0.96, 0.9953])
def test_stale_reads_repeat_samples_keep_values_and_lag1_is_the_duplicate_share(ratio):
    fn, _ = SHAPES['internal_lowpass']
    x = np.random.default_rng(2).standard_normal(400000)
    y = fn(x.copy(), np.random.default_rng(3), ratio=ratio)
    j = np.searchsorted(x, y, sorter=np.argsort(x))
    src = np.argsort(x)[j]                                   # which input sample was read
    assert np.all(x[src] == y) and set(np.diff(src)) <= {0, 1}
    assert np.mean(np.diff(src) == 0) == pytest.approx(1 - ratio, abs=2e-4)
    assert np.var(y) == pytest.approx(np.var(x), rel=0.01)
    assert np.corrcoef(y[:-1], y[1:])[0, 1] == pytest.approx(1 - ratio, abs=0.005)


def test_compressor_tone_runs_40_percent_of_each_600_s_cycle_restarting_its_phase():
    fn, _ = SHAPES['vibration']
    n = 360000
    y = fn(np.zeros(n), np.random.default_rng(4), amplitude=1.0, freq=24.2)
    on = y != 0.0
    assert np.mean(on) == pytest.approx(STATIC.DUTY, abs=0.005)
    edges = np.flatnonzero(np.diff(on.astype(int)) == 1)
    assert np.allclose(np.diff(edges) * DT, STATIC.CYCLE, atol=0.02)
    t = np.arange(n) * DT
    phases = []
    for e in edges[:4]:
        seg = slice(e + 10, e + 20000)
        c = fit(y[seg], (np.sin(2 * np.pi * 24.2 * t[seg]), np.cos(2 * np.pi * 24.2 * t[seg])))
        assert np.hypot(*c) == pytest.approx(1.0, rel=1e-6)
        phases.append(np.arctan2(c[1], c[0]))
    assert np.ptp(phases) > 0.3                             # a new phase at every start


def test_turnover_is_a_parabola_with_its_vertex_mid_record_and_the_stated_curvature_z():
    fn, levels = SHAPES['temperature_drift']
    n, amp = 720000, levels[2]['amplitude']
    u = 2 * np.arange(n) / n - 1                          # (t - T / 2) / (T / 2)
    p2 = (3 * u * u - 1) / 2
    for seed in range(3):
        y = fn(np.zeros(n), np.random.default_rng(seed), amplitude=amp)
        c = np.polyfit(u, y, 3)
        assert abs(c[0]) < 1e-12 and c[1] == pytest.approx(amp, rel=1e-6)
        assert 0.3 * n <= np.argmin(y) <= 0.7 * n
        z = (y @ p2) / np.sqrt(p2 @ p2) / SIG              # curvature component, any vertex
        assert z == pytest.approx(STATIC.detectability('temperature_drift', levels[2], DT, SIG,
                                                       N_ARW), rel=0.01)


def test_tilted_flicker_psd_slope_and_level_and_allan_from_its_psd():
    fn, _ = SHAPES['bias_instability']
    ys, f, p, sel = flicker_band_psd(fn)
    assert np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0] == pytest.approx(-0.8, abs=0.06)
    assert np.median(p[sel] / STATIC.flicker_psd(f[sel], 1.0, DT)) == pytest.approx(1, rel=0.1)
    for m in (100, 1000):
        a = np.mean([avar(y, [m])[0] for y in ys])
        assert a == pytest.approx(STATIC.psd_avar(lambda q: STATIC.flicker_psd(q, 1.0, DT),
                                                  [m * DT], DT)[0], rel=0.2)


def test_heater_walk_ramps_at_plus_minus_v_flips_at_poisson_times_and_diffuses_at_k2():
    fn, _ = SHAPES['rate_random_walk']
    y = fn(np.zeros(4_000_000), np.random.default_rng(6), k=1.0)
    v = 1.0 / np.sqrt(2 * STATIC.FLIP_TC)
    slope = np.diff(y) / DT
    assert np.allclose(np.abs(slope), v, rtol=1e-6)
    assert np.mean(np.diff(np.sign(slope)) != 0) == pytest.approx(DT / (2 * STATIC.FLIP_TC),
                                                                  rel=0.1)
    m = np.array([100, 40000])
    expect = STATIC.psd_avar(lambda f: STATIC.heater_psd(f, 1.0), m * DT, DT)
    av = avar(y, m)
    assert av[1] == pytest.approx(expect[1], rel=0.35)
    assert av[1] == pytest.approx(m[1] * DT / 3, rel=0.4)           # K^2 tau / 3 at long tau
    assert av[0] == pytest.approx(expect[0], rel=0.2) and av[0] < 0.2 * m[0] * DT / 3


def test_kangaroo_holds_gaussian_levels_between_poisson_hops_exponential_correlation():
    fn, _ = SHAPES['gauss_markov']
    y = fn(np.zeros(2_000_000), np.random.default_rng(7), sigma=2.0, tc=0.8)
    hops = np.diff(y) != 0
    assert np.mean(hops) == pytest.approx(DT / 0.8, rel=0.03)
    levels = y[np.r_[True, hops]]
    assert np.std(levels) == pytest.approx(2.0, rel=0.03)
    assert abs(stats.skew(levels)) < 0.1 and abs(stats.kurtosis(levels)) < 0.15
    assert np.corrcoef(y[:-80], y[80:])[0, 1] == pytest.approx(np.exp(-1), abs=0.03)
    m = int(1.89 * 0.8 / DT)
    assert avar(y, [m])[0] == pytest.approx(STATIC.gm_avar(m * DT, 2.0, 0.8), rel=0.1)


@pytest.mark.parametrize('step', [1.65, 4.0, 6.0])
def test_interpolation_error_is_periodic_in_the_angle_and_its_allan_excess_as_stated(step):
    fn, _ = SHAPES['quantization']
    rng = np.random.default_rng(8)
    x = SIG * rng.standard_normal(400000)
    step, depth = step * INC, 0.1
    y = fn(x.copy(), np.random.default_rng(9), step=step, depth=depth)
    theta = np.r_[0.0, np.cumsum(x)] * DT
    e = np.r_[0.0, np.cumsum(y - x)] * DT                  # angle error less its start value
    offset = np.random.default_rng(9).uniform(0, step)
    truth = STATIC.interp_error(theta + offset, step, depth)
    assert np.allclose(e, truth - truth[0], atol=1e-12)
    assert np.var(truth) == pytest.approx((depth * step) ** 2 * (1 + 4 / 9) / 2, rel=0.03)
    for m in (1, 4):
        ex = (avar(y, [m]) - avar(x, [m]))[0] * (m * DT) ** 2
        assert ex == pytest.approx(STATIC.interp_excess(m, step, depth, INC), rel=0.12)


def test_limit_cycle_constant_envelope_lorentzian_width_and_arcsine_marginal():
    fn, _ = SHAPES['resonance']
    f0, q = 14.5, 40.0
    y = fn(np.zeros(800000), np.random.default_rng(10), sigma=1.5, freq=f0, q=q)
    assert np.std(y) == pytest.approx(1.5, rel=0.02)
    assert np.abs(y).max() <= 1.5 * np.sqrt(2) + 1e-12
    assert stats.kurtosis(y) == pytest.approx(-1.5, abs=0.05)      # arcsine, not Gaussian
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 14)
    half = np.abs(f - f0) <= f0 / q / 2
    assert p[half].sum() / p.sum() == pytest.approx(0.5, abs=0.06)
    near = np.abs(f - f0) < 1.0
    assert np.sum(f[near] * p[near]) / np.sum(p[near]) == pytest.approx(f0, abs=0.02)


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


@pytest.mark.parametrize('fn_hz', [20.0, 64.0, 335.0])
def test_isolator_delays_the_motion_by_two_zeta_over_wn_and_rings_underdamped(fn_hz):
    fn, _ = SWING_SHAPES['time_delay']
    t, rate, (_, g, _, _) = swing(fn, {'fn': fn_hz})
    c = fit(g, (np.cos(W * t), np.sin(W * t)))
    wn = 2 * np.pi * fn_hz
    d = np.arctan2(2 * SWING.ZETA * W * wn, wn * wn - W * W) / W
    assert np.arctan2(c[1], c[0]) / W == pytest.approx(d, rel=0.01)
    assert d == pytest.approx(2 * SWING.ZETA / wn, rel=0.01)
    assert np.hypot(*c) == pytest.approx(AMP * W, rel=1e-4)
    if fn_hz < 30:                                        # the peak is resolved at 1 kHz
        out = fn(t, np.zeros(t.size), t, t, lambda s: (s, 1.0 * (s >= 1.0)), None, fn=fn_hz)[1]
        overshoot = (out + (t >= 1.0)).max() - 1.0
        zeta = SWING.ZETA
        assert overshoot == pytest.approx(np.exp(-np.pi * zeta / np.sqrt(1 - zeta ** 2)),
                                          rel=0.02)


def test_bilinear_g_sensitivity_has_two_slopes_and_its_fundamental_is_the_stated_z():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0)
    f_y = SWING.G0 * np.sin(stand(t)[0])
    b = (g - rate) / gy
    for side in (f_y > 0.1, f_y < -0.1):
        slope = np.polyfit(f_y[side], b[side], 1)[0]
        assert slope == pytest.approx(1 + SWING.ONE_SIDE * np.sign(f_y[side][0]), rel=1e-9)
    c = fit(g - rate, (np.sin(W * t), np.cos(W * t), np.cos(2 * W * t), np.ones(t.size)))
    assert np.hypot(c[0], c[1]) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.01)
    assert -c[2] == pytest.approx(SWING.ONE_SIDE * gy * SWING.G0 * AMP * 4 / (3 * np.pi),
                                  rel=0.03)


def test_self_heating_is_a_lagged_cubic_with_the_stated_third_harmonic():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    k = levels[1]['k']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 30.0)
    gain = (g - rate) / (k * rate)
    ok = np.abs(rate) > 0.05
    lagged = SWING.lag(rate ** 2, SWING.HEAT_TAU, 1e-3)
    m = t > 3.0
    assert np.allclose(gain[ok & m], lagged[ok & m], rtol=0, atol=1e-3 * (AMP * W) ** 2)
    c = fit(g - rate, (np.cos(3 * W * t), np.sin(3 * W * t), np.cos(W * t), np.sin(W * t)))
    expect = k * (AMP * W) ** 3 / 4 / np.hypot(1, 2 * W * SWING.HEAT_TAU)
    assert np.hypot(c[0], c[1]) == pytest.approx(expect, rel=0.01)
    assert np.hypot(c[0], c[1]) / S_LINE == pytest.approx(
        SWING.detectability('scale_factor_nonlinearity', levels[1]), rel=0.01)


def test_after_effect_gain_relaxes_after_each_reversal_and_second_harmonic():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1], 30.0)
    state = (g - rate) / (a * rate)
    assert np.all(np.abs(state) <= 1 + 1e-9)
    rev = np.flatnonzero(np.diff(np.sign(rate)) > 0)[2]       # a rising zero crossing
    k = int(SWING.MAG_TAU * 1000)
    s0 = state[rev - 1]
    assert state[rev + k] - 1 == pytest.approx((s0 - 1) * np.exp(-1), rel=0.02)
    c = fit(g - rate, (np.cos(2 * W * t), np.sin(2 * W * t), np.ones(t.size)))
    assert np.hypot(c[0], c[1]) / S_LINE == pytest.approx(
        SWING.detectability('scale_factor_asymmetry', levels[1]), rel=0.02)


def test_packet_stamps_hold_a_uniform_error_for_ten_samples():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    h = levels[1]['h']
    t, _, (_, _, te, _) = swing(fn, levels[1])
    e = te - t
    change = np.flatnonzero(np.abs(np.diff(e)) > 1e-9)
    assert np.all(np.diff(change) == SWING.PACKET)
    blocks = e[change + 1]
    assert np.abs(blocks).max() <= h and abs(np.mean(blocks)) < 0.05 * h
    assert np.var(blocks) == pytest.approx(h * h / 3, rel=0.05)
    assert stats.kurtosis(blocks) == pytest.approx(-1.2, abs=0.1)   # uniform


def test_disk_graduation_errors_fixed_gaussian_and_linear_between_lines():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    sigma = levels[1]['sigma']
    t, _, (_, _, _, enc1) = swing(fn, levels[1], 20.0)
    phi = stand(t)[0]
    enc2 = fn(t, phi, t, phi.copy(), stand, np.random.default_rng(99), **levels[1])[3]
    assert np.array_equal(enc1, enc2)                     # the same disk in every run
    pitch = 2 * np.pi / SWING.LINES
    marks = np.arange(-100, 100) * pitch
    err = SWING.graduation(marks, sigma)
    assert np.std(SWING.disk()) == pytest.approx(1.0, rel=0.05)
    assert abs(np.corrcoef(err[:-1], err[1:])[0, 1]) < 0.2
    mid = SWING.graduation(marks[:-1] + pitch / 2, sigma)
    assert np.allclose(mid, (err[:-1] + err[1:]) / 2, atol=1e-15)
    assert np.allclose(enc1 - phi, SWING.graduation(phi, sigma), atol=1e-15)


def test_both_harnesses_take_set_e_by_held_out_e(monkeypatch):
    check_harnesses('e', SHAPES, SWING_SHAPES, monkeypatch)
