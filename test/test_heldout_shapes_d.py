# Held-out set D (bench/validate_diagnosis_heldout_d.py, static, and
# bench/validate_diagnosis_swing_heldout_d.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out d. THE GENERATORS only, never the diagnosis.
from gyro_char.allan.expected import markov_avar
from gyro_char.sim.config import BenchConfig
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            flicker_band_psd, load_set, N_ARW, SIG, stand, swing, W)
import numpy as np
import pytest
from scipy import signal, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('d')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


@pytest.mark.parametrize('cutoff', [0.45, 0.7, 0.9975])
def test_decimation_fir_linear_phase_negative_lobes_dc_one_and_lag1(cutoff):
    fn, _ = SHAPES['internal_lowpass']
    h = STATIC.fir(cutoff)
    assert h.size == 15 and np.allclose(h, h[::-1]) and h.min() < 0       # linear phase
    assert fn(np.ones(50), None, cutoff=cutoff) == pytest.approx(np.ones(50))
    imp = fn(np.r_[0.0, 1.0, np.zeros(40)], None, cutoff=cutoff)
    assert np.argmax(imp) == 1 + 7                                        # 7-sample delay
    y = fn(np.random.default_rng(2).standard_normal(400000), None, cutoff=cutoff)
    assert np.corrcoef(y[:-1], y[1:])[0, 1] == pytest.approx(STATIC.lag1(cutoff), abs=0.005)


def test_gearbox_mesh_line_and_sidebands_at_mesh_plus_minus_shaft():
    fn, _ = SHAPES['vibration']
    y = fn(np.zeros(100000), np.random.default_rng(3), amplitude=1.0, shaft=2.35, teeth=11)
    t = np.arange(y.size) * DT
    for f, a in ((25.85, 1.0), (25.85 - 2.35, 0.3), (25.85 + 2.35, 0.3)):
        c = fit(y, (np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)))
        assert np.hypot(*c) == pytest.approx(a, rel=0.01), f
    assert np.abs(y).max() <= 1.6 + 1e-9
    shaft = int(round(1 / 2.35 / DT * 20))                 # 20 turns, 851.06 samples: ~periodic
    assert np.std(y[shaft:] - y[:-shaft]) < 0.1


def test_draught_steps_mid_record_through_the_thermal_lag():
    fn, levels = SHAPES['temperature_drift']
    amp, n = levels[0]['amplitude'], 720000
    for seed in range(4):
        y = fn(np.zeros(n), np.random.default_rng(seed), amplitude=amp)
        k0 = np.argmax(y > 0)
        assert 0.35 * n - 2 <= k0 <= 0.65 * n + 1 and np.all(y[:k0] == 0.0)
        lag = int(STATIC.DRAUGHT_LAG / DT)
        assert y[k0 + lag] == pytest.approx(amp * (1 - np.exp(-1)), rel=0.01)
        assert y[-1] == pytest.approx(amp, rel=1e-3)
    t1 = 0.5 * n * DT                                    # mean-difference z at the mid step
    z_mid = (amp * (1 - STATIC.DRAUGHT_LAG / t1)) / (N_ARW * np.sqrt(2 / t1))
    assert STATIC.detectability('temperature_drift', levels[0], DT, SIG, N_ARW) == \
        pytest.approx(z_mid, rel=0.05)


def test_fractal_shot_flicker_psd_minus_one_allan_floor_and_bursty():
    fn, _ = SHAPES['bias_instability']
    ys, f, p, sel = flicker_band_psd(fn)
    assert np.polyfit(np.log(f[sel]), np.log(p[sel]), 1)[0] == pytest.approx(-1.0, abs=0.1)
    assert np.median(p[sel] * np.pi * f[sel]) == pytest.approx(1.0, rel=0.15)   # B^2 / (pi f)
    for m in (100, 1000):
        adev = np.mean([np.sqrt(avar(y, [m])[0]) for y in ys])
        assert adev == pytest.approx(0.664, rel=0.15)
    d = np.diff(ys[0])
    assert np.mean(np.abs(d) > 10.0) == pytest.approx(STATIC.SHOT_RATE * DT, rel=0.15)
    assert stats.kurtosis(d) > 50                          # sparse events, not Gaussian


def test_lagged_walk_is_smooth_and_diffuses_at_k_squared():
    fn, _ = SHAPES['rate_random_walk']
    y = fn(np.zeros(4_000_000), np.random.default_rng(6), k=1.0)
    d = np.diff(y)
    a = np.exp(-DT / STATIC.WALK_LAG)
    assert np.corrcoef(d[:-1], d[1:])[0, 1] == pytest.approx(a, abs=2e-3)   # C^1: lagged
    m = np.array([100, 80000])
    av = avar(y, m)
    tau = m * DT
    expect = tau / 3 - markov_avar(tau, STATIC.WALK_LAG)
    assert av[1] == pytest.approx(expect[1], rel=0.35)
    assert av[0] < 0.3 * tau[0] / 3                          # the lag hides it at 1 s


def test_gamma_ou_skewed_one_sided_exponential_correlation_and_allan():
    fn, _ = SHAPES['gauss_markov']
    y = fn(np.zeros(2_000_000), np.random.default_rng(7), sigma=2.0, tc=1.5)
    assert abs(np.mean(y)) < 0.05 and np.std(y) == pytest.approx(2.0, rel=0.03)
    assert stats.skew(y) == pytest.approx(2 / np.sqrt(STATIC.GAMMA_SHAPE), rel=0.1)
    a, lam = np.exp(-DT / 1.5), STATIC.GAMMA_SHAPE / 1.5
    m0 = lam * DT * 2.0 * np.sqrt((1 - a * a) / (2 * lam * DT)) / (1 - a)   # removed mean
    jump = (y[1:] + m0) - a * (y[:-1] + m0)            # decay between events, jumps upward
    assert y.min() > -m0 and jump.min() > -1e-9
    assert np.mean(jump > 1e-9) == pytest.approx(lam * DT, rel=0.05)
    assert np.corrcoef(y[:-150], y[150:])[0, 1] == pytest.approx(np.exp(-1), abs=0.03)
    m = int(1.89 * 1.5 / DT)
    assert avar(y, [m])[0] == pytest.approx(STATIC.gm_avar(m * DT, 2.0, 1.5), rel=0.1)


@pytest.mark.parametrize('c', [0.155, 1.2])
def test_noise_shaping_second_difference_of_a_bounded_white_error_and_allan(c):
    fn, _ = SHAPES['quantization']
    rng = np.random.default_rng(8)
    x = SIG * rng.standard_normal(200000) + 0.003
    step = c * SIG
    y = fn(x.copy(), rng, step=step)
    assert np.allclose(np.round(y / step), y / step)
    e = np.cumsum(np.cumsum(y - x))                       # (1 - z^-1)^2 e = y - x, e_-1 = 0
    v = step ** 2 / 12
    assert np.abs(e).max() <= step / 2 * (1 + 1e-6)
    assert np.var(e) == pytest.approx(v, rel=0.05)
    assert abs(np.corrcoef(e[:-1], e[1:])[0, 1]) < 0.03
    ex = avar(y, [1, 4]) - avar(x, [1, 4])
    assert ex[0] == pytest.approx(10 * v, rel=0.1)
    assert ex[1] == pytest.approx(6 * v / 16, rel=0.15)


def test_duffing_mode_rms_and_line_shifted_up_by_two_kappa(monkeypatch):
    fn, _ = SHAPES['resonance']
    f0, q = 27.5, 30.0

    def centroid(kappa):
        monkeypatch.setattr(STATIC, 'KAPPA', kappa)
        y = fn(np.zeros(400000), np.random.default_rng(9), sigma=1.5, freq=f0, q=q)
        f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 13)
        near = np.abs(f - f0) < 8.0
        return np.std(y), np.sum(f[near] * p[near]) / np.sum(p[near]), f, p

    sd0, c0, _, _ = centroid(0.0)
    sd, c, f, p = centroid(0.02)
    assert sd0 == pytest.approx(1.5, rel=0.05) and sd == pytest.approx(1.5, rel=0.05)
    assert c - c0 == pytest.approx(2 * 0.02 * f0, rel=0.15)
    lo = f0 - f0 / (2 * q)
    band = (f >= lo) & (f <= lo + f0 / q + 2 * 0.02 * f0)
    assert 0.4 < p[band].sum() / p.sum() < 0.75              # about half in the stated band


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


@pytest.mark.parametrize('taps', [4, 17, 65])
def test_decimation_fir_delays_the_motion_by_half_its_length(taps):
    fn, _ = SWING_SHAPES['time_delay']
    h = SWING.fir_taps(taps)
    assert np.allclose(h, h[::-1]) and h.sum() == pytest.approx(1.0)
    t, rate, (_, g, _, _) = swing(fn, {'taps': taps})
    angle = np.r_[0.0, np.cumsum((g[1:] + g[:-1]) / 2) * 1e-3]
    c = fit(angle - stand(t)[0], (np.sin(W * t), np.cos(W * t), np.ones(t.size), t))
    assert c[1] == pytest.approx(-AMP * W * (taps - 1) / (2 * SWING.FS_INT), rel=0.02)


def test_tilt_hysteresis_is_backlash_and_its_lag_does_not_depend_on_the_period():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    phases = []
    for per in (5.0, 2.5):
        w = 2 * np.pi / per

        def at(t, w=w):
            return AMP * np.sin(w * t), AMP * w * np.cos(w * t)
        t, rate, (_, g, _, _) = swing(fn, levels[1], 20.0, at)
        f_y = SWING.G0 * np.sin(at(t)[0])
        b = (g - rate) / gy
        assert np.abs(b - f_y).max() <= SWING.PLAY * (1 + 1e-9)
        assert np.mean(np.diff(b) == 0.0) > 0.05                  # it holds at turnarounds
        m = t > per
        c = fit(b[m], (np.sin(w * t[m]), np.cos(w * t[m])))
        phases.append(np.arctan2(-c[1], c[0]))
        if per == 5.0:
            z = np.hypot(*c) * gy / (BenchConfig.from_preset('adis16405').noise[
                'gyro_x']['N'] * np.sqrt(2 / 900.0))
            assert z == pytest.approx(SWING.detectability('g_sensitivity', levels[1]), rel=0.01)
    assert phases[0] > 0.05 and phases[1] == pytest.approx(phases[0], abs=1e-3)


def test_lock_in_dead_band_square_root_edge_and_third_harmonic():
    fn, _ = SWING_SHAPES['scale_factor_nonlinearity']
    w_l = 0.03
    t, rate, (_, g, _, _) = swing(fn, {'w_l': w_l})
    inside = np.abs(rate) < w_l
    assert inside.any() and np.all(g[inside] == 0.0)
    out = ~inside
    assert np.allclose(g[out] ** 2, rate[out] ** 2 - w_l ** 2)
    assert np.all(np.sign(g[out]) == np.sign(rate[out]))
    fast = np.abs(rate) > 0.4
    assert np.allclose(g[fast] - rate[fast], -w_l ** 2 / (2 * rate[fast]), rtol=0.02)
    c = fit(g - rate, (np.cos(3 * W * t), np.sin(3 * W * t)))
    s = BenchConfig.from_preset('adis16405').noise['gyro_x']['N'] * np.sqrt(2 / 900.0)
    assert np.hypot(*c) / s == pytest.approx(
        SWING.detectability('scale_factor_nonlinearity', {'w_l': w_l}), rel=0.01)


def test_schmitt_asymmetry_switches_late_after_each_reversal_and_second_harmonic():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    a = levels[1]['a']
    t, rate, (_, g, _, _) = swing(fn, levels[1])
    state = np.round((g - rate) / (a * rate), 6)
    big = np.abs(rate) > SWING.SCHMITT
    assert np.all(state[big] == np.sign(rate[big]))
    rising = (np.abs(rate) < SWING.SCHMITT) & (np.gradient(rate) > 0) & (rate > 0)
    assert rising.any() and np.all(state[rising] == -1.0)           # still the old gain
    c = fit(g - rate, (np.cos(2 * W * t), np.sin(2 * W * t), np.ones(t.size)))
    s = BenchConfig.from_preset('adis16405').noise['gyro_x']['N'] * np.sqrt(2 / 900.0)
    assert np.hypot(c[0], c[1]) / s == pytest.approx(
        SWING.detectability('scale_factor_asymmetry', levels[1]), rel=0.01)
    assert abs(c[1]) > 1e-3 * abs(c[0])                  # the late switch has a sin part
    assert c[2] < 0.997 * 2 * a * AMP * W / np.pi        # and loses DC against a |w|


def test_sync_sawtooth_stamp_error_period_span_and_zero_mean():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    delta = levels[1]['delta']
    t, _, (_, _, te, _) = swing(fn, levels[1])
    e = te - t
    assert abs(np.mean(e)) < 1e-3 * delta
    assert np.ptp(e) == pytest.approx(delta * SWING.SYNC, rel=1e-2)
    assert np.allclose(e[1000:], e[:-1000], atol=1e-12)            # period: the 1 s sync
    jumps = np.diff(e) < -0.5 * delta * SWING.SYNC
    assert jumps.sum() == 59 or jumps.sum() == 60
    assert np.allclose(np.diff(e)[~jumps], delta * 1e-3)


def test_per_revolution_disk_error_eccentricity_and_four_lobes():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    a = levels[1]['a']
    t, _, (_, _, _, enc) = swing(fn, levels[1], 20.0)
    phi = stand(t)[0]
    c = fit(enc - phi, (np.sin(phi), np.cos(phi), np.sin(4 * phi), np.cos(4 * phi)))
    assert np.hypot(c[0], c[1]) == pytest.approx(2 * a, rel=1e-6)
    assert np.hypot(c[2], c[3]) == pytest.approx(a, rel=1e-6)
    z5 = SWING.detectability('encoder_cyclic_error', levels[1])
    z25 = SWING.detectability('encoder_cyclic_error', levels[1], period_s=2.5)
    assert z25 == pytest.approx(2 * z5, rel=0.02)       # an angle error: rate lines x 2


def test_both_harnesses_take_set_d_by_held_out_d(monkeypatch):
    check_harnesses('d', SHAPES, SWING_SHAPES, monkeypatch)
