# The held-out effect generators (bench/validate_diagnosis_heldout_b.py, static, and
# bench/validate_diagnosis_swing_heldout.py, swing) do what their docstrings claim. This checks
# THE GENERATORS on short synthetic records, never the diagnosis.
import bench_script
import numpy as np
import pytest
from scipy import signal, special, stats

DT = 0.01
N_ARW = 2.4 * np.pi / 180.0 / 60.0
SIG = N_ARW / np.sqrt(DT)
STATIC = bench_script.load('validate_diagnosis_heldout_b')
SWING = bench_script.load('validate_diagnosis_swing_heldout')
SHAPES = STATIC.shapes(DT, SIG, N_ARW)
SWING_SHAPES = SWING.shapes(1000.0)
AMP, PERIOD = np.deg2rad(20.0), 5.0
W = 2 * np.pi / PERIOD


def _adev(y, m):
    c = np.r_[0.0, np.cumsum(y)]
    a = (c[m:] - c[:-m]) / m
    d = a[m:] - a[:-m]
    return np.sqrt(0.5 * np.mean(d * d))


def _stand(t):
    return AMP * np.sin(W * t), AMP * W * np.cos(W * t)


def test_static_set_covers_the_catalogue_and_levels_are_ordered():
    assert sorted(SHAPES) == sorted(['internal_lowpass', 'vibration', 'temperature_drift',
                                     'bias_instability', 'rate_random_walk', 'gauss_markov',
                                     'quantization', 'resonance'])
    for name, (fn, levels) in SHAPES.items():
        z = [STATIC.detectability(name, p, DT, SIG, N_ARW) for p in levels]
        weak, strong, edge = z
        assert 3.0 <= edge <= 6.0 and edge < weak < strong, (name, z)
        for p in levels:
            rng = np.random.default_rng(1)
            x = SIG * rng.standard_normal(20000) + 0.003
            y = fn(x.copy(), rng, **p)
            assert y.shape == x.shape and np.all(np.isfinite(y)), name
            assert not np.array_equal(y, x), name


def test_one_pole_lowpass_has_dc_gain_one_and_lag1_correlation_pole():
    fn, _ = SHAPES['internal_lowpass']
    assert fn(np.ones(50), None, pole=0.6) == pytest.approx(np.ones(50))
    y = fn(np.random.default_rng(2).standard_normal(200000), None, pole=0.3)
    assert np.corrcoef(y[:-1], y[1:])[0, 1] == pytest.approx(0.3, abs=0.01)


def test_harmonic_vibration_lines_and_rms():
    fn, _ = SHAPES['vibration']
    n = 100000                                  # 1000 s: whole periods of 8.7 Hz
    y = fn(np.zeros(n), np.random.default_rng(3), amplitude=1.0, freq=8.7)
    assert np.std(y) == pytest.approx(np.sqrt((1 + 1 / 4 + 1 / 9) / 2), rel=1e-3)
    t = np.arange(n) * DT
    for k in (1, 2, 3):
        cols = np.c_[np.sin(2 * np.pi * k * 8.7 * t), np.cos(2 * np.pi * k * 8.7 * t)]
        c = np.linalg.lstsq(cols, y, rcond=None)[0]
        assert np.hypot(*c) == pytest.approx(1.0 / k, rel=1e-3)


def test_vibration_welch_line_height_is_the_one_its_detectability_assumes():
    fn, _ = SHAPES['vibration']
    rng = np.random.default_rng(13)
    L = STATIC.WELCH_L
    y = fn(rng.standard_normal(8 * L), rng, amplitude=0.2, freq=8.7)
    f, p = signal.welch(y, fs=1 / DT, window='hann', nperseg=L, noverlap=0)
    k = np.argmin(np.abs(f - 8.7))
    floor = np.median(p[(f > 1.0) & (f < 8.0)])
    expected = STATIC.scalloping(8.7 * L * DT) ** 2 * 0.2 ** 2 * L / 6
    assert p[k] / floor - 1.0 == pytest.approx(expected, rel=0.15)


def test_ramp_warmup_is_linear_and_saturates():
    fn, _ = SHAPES['temperature_drift']
    y = fn(np.zeros(30000), None, amplitude=2.0, t_r=120.0)
    assert y[0] == 2.0 and y[6000] == pytest.approx(1.0) and not np.any(y[12000:])
    assert np.all(np.diff(y) <= 0)


def test_voss_flicker_psd_slope_minus_one_and_allan_floor():
    fn, _ = SHAPES['bias_instability']
    rng = np.random.default_rng(4)
    ys = np.array([fn(np.zeros(2 ** 17), rng, b=1.0) for _ in range(4)])
    f, p = signal.welch(ys, fs=1 / DT, nperseg=2 ** 14)
    p = p.mean(axis=0)
    sel = (f >= 0.05) & (f <= 5.0)                      # two decades
    slope = np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0]
    assert slope == pytest.approx(-1.0, abs=0.1)
    assert np.median(p[sel] * np.pi * f[sel]) == pytest.approx(1.0, rel=0.15)   # B^2/(pi f)
    for m in (10, 100, 1000):
        assert np.mean([_adev(y, m) for y in ys]) == pytest.approx(0.664, rel=0.15)


def test_jump_walk_diffuses_at_k_squared_and_allan_slope_half():
    fn, _ = SHAPES['rate_random_walk']
    y = fn(np.zeros(4_000_000), np.random.default_rng(5), k=1.0, hold=30.0)
    assert np.count_nonzero(np.diff(y)) == pytest.approx(4e6 * DT / 30.0, rel=0.1)
    m = 10000
    d = y[m:] - y[:-m]
    assert np.mean(d * d) / (m * DT) == pytest.approx(1.0, rel=0.2)
    slope = np.log(_adev(y, 80000) / _adev(y, 5000)) / np.log(16.0)
    assert slope == pytest.approx(0.5, abs=0.12)


def test_gauss_markov_sd_and_correlation_time():
    fn, _ = SHAPES['gauss_markov']
    y = fn(np.zeros(4_000_000), np.random.default_rng(6), sigma=2.0, tc=3.0)
    assert np.std(y) == pytest.approx(2.0, rel=0.05)
    assert np.corrcoef(y[:-300], y[300:])[0, 1] == pytest.approx(np.exp(-1), abs=0.04)
    m = int(1.89 * 3.0 / DT)                    # the Allan bump used by detectability
    assert _adev(y, m) ** 2 == pytest.approx(STATIC.gm_avar(m * DT, 2.0, 3.0), rel=0.1)


@pytest.mark.parametrize('c', [0.26, 1.0])
def test_dnl_counter_angle_error_variance_and_allan_excess(c):
    fn, _ = SHAPES['quantization']
    rng = np.random.default_rng(7)
    x = SIG * rng.standard_normal(200000) + 0.003
    step = c * N_ARW * np.sqrt(DT)
    y = fn(x, rng, step=step, dnl=0.3)
    assert np.allclose(y / (step / DT), np.round(y / (step / DT)))     # whole counts
    e = np.cumsum(x - y) * DT
    v = step ** 2 * (1 / 12 + 0.3 ** 2 / 3)
    assert np.var(e) == pytest.approx(v, rel=0.05)
    assert np.ptp(e) <= 1.6 * step + 1e-15
    excess = (_adev(y, 1) ** 2 - _adev(x, 1) ** 2) / (3 * v / DT ** 2)
    assert excess == pytest.approx(1.0, abs=0.2)


def test_burst_resonance_rms_peak_and_non_gaussian():
    fn, _ = SHAPES['resonance']
    y = fn(np.zeros(400000), np.random.default_rng(8), sigma=1.5, freq=21.5, q=25.0, rate=1.0)
    assert np.std(y) == pytest.approx(1.5, rel=0.1)
    assert stats.kurtosis(y) > 3.0
    f, p = signal.welch(y, fs=1 / DT, nperseg=4096)
    assert f[np.argmax(p)] == pytest.approx(21.5, abs=0.1)


def _swing(fn, p, duration=60.0):
    t = np.arange(int(duration * 1000)) * 1e-3
    angle, rate = _stand(t)
    return t, rate, fn(t, rate.copy(), t.copy(), angle.copy(), _stand,
                       np.random.default_rng(9), **p)


def _fit(y, t, cols):
    return np.linalg.lstsq(np.c_[tuple(cols)], y, rcond=None)[0]


def test_swing_set_covers_the_catalogue_levels_ordered_outputs_finite():
    assert sorted(SWING_SHAPES) == sorted(['time_delay', 'g_sensitivity',
                                           'scale_factor_nonlinearity', 'scale_factor_asymmetry',
                                           'timestamp_jitter', 'encoder_cyclic_error'])
    for name, (fn, levels) in SWING_SHAPES.items():
        weak, strong, edge = [SWING.detectability(name, p) for p in levels]
        assert 3.0 <= edge <= 6.0 and edge < weak < strong, name
        for p in levels:
            t, rate, out = _swing(fn, p, 20.0)
            assert len(out) == 4 and all(a.shape == t.shape and np.all(np.isfinite(a))
                                         for a in out), name
            assert np.all(np.diff(out[2]) > 0) and np.all(np.diff(out[0]) > 0), name


@pytest.mark.parametrize('d', [2e-4, 1e-3, 4e-3])
def test_iir_delay_cos_component_is_minus_a_w_d(d):
    fn, _ = SWING_SHAPES['time_delay']
    t, rate, (_, g, _, _) = _swing(fn, {'delay_s': d})
    angle = np.r_[0.0, np.cumsum((g[1:] + g[:-1]) / 2) * 1e-3]       # trapezoid
    m = t > 1.0
    c = _fit((angle - _stand(t)[0])[m], t[m],
             (np.sin(W * t[m]), np.cos(W * t[m]), np.ones(m.sum()), t[m]))
    assert c[1] == pytest.approx(-AMP * W * d, rel=0.05)


def test_g_by_g_fundamental_in_phase_with_angle():
    fn, levels = SWING_SHAPES['g_sensitivity']
    t, rate, (_, g, _, _) = _swing(fn, levels[0])
    c = _fit(g - rate, t, (np.sin(W * t), np.cos(W * t)))
    assert c[0] == pytest.approx(levels[0]['k'] * SWING.G0 ** 2 * special.j1(2 * AMP), rel=1e-3)
    assert abs(c[1]) < 1e-6 * abs(c[0])


def test_knee_third_harmonic_closed_form():
    fn, _ = SWING_SHAPES['scale_factor_nonlinearity']
    t, rate, (_, g, _, _) = _swing(fn, {'s': -0.04})
    err = g - rate
    assert np.all(err[np.abs(rate) <= SWING.KNEE] == 0.0)
    c = _fit(err, t, (np.cos(3 * W * t), np.sin(3 * W * t)))
    big_w = AMP * W
    thk = np.arccos(SWING.KNEE / big_w)
    a3 = 4 / np.pi * big_w * -0.04 * (0.5 * (np.sin(2 * thk) / 2 + np.sin(4 * thk) / 4)
                                      - SWING.KNEE / big_w * np.sin(3 * thk) / 3)
    assert c[0] == pytest.approx(a3, rel=1e-3)


def test_erf_asymmetry_scale_factors_and_two_f_line():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = _swing(fn, levels[1])
    hi = np.abs(rate) > 2.5 * SWING.ASYM_WIDTH
    assert np.allclose(g[hi & (rate > 0)] / rate[hi & (rate > 0)], 1 + a, atol=1e-6 * a)
    assert np.allclose(g[hi & (rate < 0)] / rate[hi & (rate < 0)], 1 - a, atol=1e-6 * a)
    c = _fit(g - rate, t, (np.cos(2 * W * t), np.sin(2 * W * t), np.ones(t.size)))
    assert c[0] == pytest.approx(a * SWING.harmonic(
        lambda r: r * special.erf(r / SWING.ASYM_WIDTH), AMP * W, 2), rel=1e-3)


def test_wandering_stamp_error_sd_and_smooth_correlation():
    fn, _ = SWING_SHAPES['timestamp_jitter']
    t, _, (_, _, te, _) = _swing(fn, {'sigma_s': 1e-3}, 600.0)
    e = te - t
    assert np.std(e) == pytest.approx(1e-3, rel=0.15)
    lag = int(SWING.JITTER_TC * 1000)
    # Second-order Gauss-Markov: correlation (1 + 1) e^-1 at one stage time; smooth at 1 ms.
    assert np.corrcoef(e[:-lag], e[lag:])[0, 1] == pytest.approx(2 / np.e, abs=0.08)
    assert np.std(np.diff(e)) < 0.01 * np.std(e)


def test_cyclic_error_second_and_fourth_harmonics_on_512_lines():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    a2 = levels[0]['a2']
    t, _, (_, _, _, enc) = _swing(fn, levels[0], 20.0)
    phi = _stand(t)[0]
    x = SWING.LINES * phi
    c = _fit(enc - phi, t, (np.sin(2 * x), np.cos(2 * x), np.sin(4 * x), np.cos(4 * x),
                            np.sin(x), np.cos(x)))
    assert np.hypot(c[0], c[1]) == pytest.approx(a2, rel=1e-6)
    assert np.hypot(c[2], c[3]) == pytest.approx(a2 / 2, rel=1e-6)
    assert np.hypot(c[4], c[5]) < 1e-6 * a2
