# Held-out set K (bench/validate_diagnosis_heldout_k.py, static, and
# bench/validate_diagnosis_swing_heldout_k.py, swing): the generators do what their docstrings
# claim, and both harnesses reach them by --held-out k. THE GENERATORS only, never the diagnosis.
from heldout_common import (AMP, avar, check_harnesses, check_static_set, check_swing_set, DT, fit,
                            flicker_band_psd, fold_lines, G0, load_set, N_ARW, noisy_run,
                            octave_ratios, rng, S_LINE, SIG, swing, W)
import numpy as np
import pytest
from scipy import integrate, signal, special, stats

STATIC, SWING, SHAPES, SWING_SHAPES = load_set('k')


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_jitter_gate_smooths_small_changes_passes_large_ones_with_the_solved_lag1():
    fn, levels = SHAPES['internal_lowpass']
    s = levels[0]['s']
    x = SIG * rng(3).standard_normal(2 ** 20)
    y = fn(x.copy(), rng(4), s=s)
    d = x[1:] - y[:-1]
    small = np.abs(d) < s
    assert y[0] == x[0] and 0.2 < small.mean() < 0.8
    assert np.allclose(y[1:][small], y[:-1][small] + 0.25 * d[small], rtol=0, atol=1e-15)
    assert np.array_equal(y[1:][~small], x[1:][~small])                 # large ones pass
    assert np.allclose(fn(x + 0.003, rng(4), s=s) - 0.003, y, rtol=0, atol=1e-12)
    yc = y - y.mean()
    r1 = np.mean(yc[1:] * yc[:-1]) / np.mean(yc * yc)
    assert r1 == pytest.approx(STATIC.gate_lag1(s / SIG), abs=0.004)    # 0.061, sd 0.001
    assert STATIC.gate_lag1(12.0) == pytest.approx(0.75, abs=0.005)     # a one-pole of 0.75
    assert STATIC.gate_lag1(0.05) < 1e-4


def test_shaker_sweeps_an_octave_a_minute_at_constant_acceleration_spreading_its_power():
    fn, levels = SHAPES['vibration']
    a, n = levels[1]['amplitude'], int(4 * STATIC.CYCLE / DT)
    y = fn(np.zeros(n), rng(6), amplitude=a)
    f = STATIC.sweep_freq(np.arange(n) * DT + rng(6).uniform(0, STATIC.CYCLE))
    an = signal.hilbert(y)
    inst = np.diff(np.unwrap(np.angle(an))) / (2 * np.pi * DT)
    core = slice(3000, -3000)
    assert np.allclose(inst[core], (f[1:] + f[:-1])[core] / 2, atol=0.05)
    assert np.allclose(np.abs(an)[core], (a * 10.0 / f)[core], rtol=0.02)     # a 1 / f rate
    g = np.geomspace(10.0, 40.0, 200)
    assert np.allclose(np.diff(np.log2(STATIC.sweep_freq(np.linspace(0, 120, 200)))),
                       np.diff(np.linspace(0, 120, 200))[0] / 60.0)           # octave a minute
    total = integrate.trapezoid(STATIC.sweep_psd(g, a), g)
    assert np.mean(y * y) == pytest.approx(total, rel=0.01)
    fw, p = signal.welch(y, fs=1 / DT, nperseg=4096)
    for lo, hi in ((10, 14), (14, 20), (20, 28), (28, 40)):
        k, h = (fw >= lo) & (fw < hi), np.linspace(lo, hi, 400)
        assert np.sum(p[k]) * fw[1] == pytest.approx(
            integrate.trapezoid(STATIC.sweep_psd(h, a), h), rel=0.1)
    assert np.sum(p[(fw < 9) | (fw > 41)]) * fw[1] < 0.01 * total            # no line


def test_fan_warmup_follows_the_lumped_die_with_its_thermostat_and_kinks():
    fn, levels = SHAPES['temperature_drift']
    amp, n = levels[1]['amplitude'], 720000
    y = fn(np.zeros(n), rng(7), amplitude=amp)
    t = np.arange(n) * DT + rng(7).uniform(0, STATIC.POWER_ON)

    def hit(_, temp):                                   # the fan's thermostat
        return temp[0] - STATIC.FAN_ON
    hit.terminal = True
    warm = integrate.solve_ivp(lambda _, temp: (1 - temp) / STATIC.WARM_TAU, (0, 9000), [0.0],
                               events=hit, rtol=1e-10, atol=1e-12, dense_output=True)
    t_on = warm.t_events[0][0]
    cool = integrate.solve_ivp(lambda _, temp: (STATIC.FAN_LEVEL - temp) / STATIC.FAN_TAU,
                               (t_on, 9000), [STATIC.FAN_ON], rtol=1e-10, atol=1e-12,
                               dense_output=True)
    model = np.where(t < t_on, warm.sol(np.minimum(t, t_on))[0],
                     cool.sol(np.maximum(t, t_on))[0])
    assert np.allclose(y, amp * model, rtol=0, atol=1e-6 * amp)
    assert t_on == pytest.approx(600 * np.log(2.5), rel=1e-6)
    k = np.searchsorted(t, t_on)
    slope = np.diff(y) / DT
    assert slope[k - 5] == pytest.approx(amp / 1500, rel=0.01)
    assert slope[k + 5] == pytest.approx(-amp / (200 / 0.3), rel=0.01)      # the kink
    assert y[-1] == pytest.approx(0.3 * amp, rel=1e-6)
    s = STATIC.fan_warmup(np.arange(n) * DT, amp)
    assert STATIC.detectability('temperature_drift', levels[1], DT, SIG, N_ARW) == \
        pytest.approx(np.std(s) * np.sqrt(n) / SIG, rel=1e-9)


def test_nulled_flicker_is_an_integrating_loops_residual_one_over_f_above_the_corner():
    fn, _ = SHAPES['bias_instability']
    ys, f, pxx, band = flicker_band_psd(fn)
    want = STATIC.nulled_flicker_psd(f[band], 1.0, DT)
    ratio = octave_ratios(f, pxx, band, want)
    assert np.allclose(ratio, 1.0, atol=0.2), ratio
    for lo, hi, slope in ((1e-6, 1e-5, 1.0), (0.02, 2.0, -1.0)):
        g = np.geomspace(lo, hi, 20)
        got = np.polyfit(np.log(g), np.log(STATIC.nulled_flicker_psd(g, 1.0, DT)), 1)[0]
        assert got == pytest.approx(slope, abs=0.1)
    n = 5000                                                          # the loop, step by step
    q = np.convolve(rng(5).standard_normal(n), STATIC.flicker_kernel(n))[:n]
    held, out = 0.0, np.empty(n)
    for k in range(n):
        out[k] = q[k] - held
        held += DT / STATIC.NULLING_TAU * out[k]
    assert np.allclose(fn(np.zeros(n), rng(5), b=1.0), out, rtol=1e-9, atol=1e-9)
    a = np.mean([avar(y, [1000])[0] for y in ys])
    assert a == pytest.approx(STATIC.psd_avar(
        lambda h: STATIC.nulled_flicker_psd(h, 1.0, DT), 10.0, DT)[0], rel=0.3)


def test_ratchet_slips_one_way_creeps_back_and_walks_with_skewed_steps():
    fn, _ = SHAPES['rate_random_walk']
    n, lam = 720000, STATIC.SLIPS_PER_S
    beta = 1.0 / np.sqrt(2 * lam)
    ys = [fn(np.zeros(n), rng(30 + i), k=1.0) for i in range(4)]
    inc = np.concatenate([np.diff(y) for y in ys])
    creep = np.isclose(inc, -lam * DT * beta, rtol=0, atol=1e-12)
    assert np.mean(~creep) == pytest.approx(1 - np.exp(-lam * DT), rel=0.08)
    assert np.all(inc[~creep] > -lam * DT * beta)                          # slips one way
    assert np.mean(inc[~creep] + lam * DT * beta) == pytest.approx(beta, rel=0.1)
    steps = np.concatenate([np.diff(y[::1000]) for y in ys])                # 10 s steps
    assert abs(np.mean(steps)) < 0.1 * np.std(steps)
    assert np.var(steps) == pytest.approx(10.0, rel=0.2)                    # K^2 tau, K = 1
    assert stats.skew(steps) == pytest.approx(6 / 2 ** 1.5 / np.sqrt(lam * 10), rel=0.35)
    for m in (100, 3000):
        got = np.mean([avar(y, [m])[0] for y in ys])
        assert got == pytest.approx(STATIC.walk_avar(m, np.sqrt(DT)), rel=0.25)


def test_blower_markov_has_exponential_correlation_and_a_variance_cycling_with_the_blower():
    fn, _ = SHAPES['gauss_markov']
    tc, n = 0.5, 2 ** 21
    y = fn(np.zeros(n), rng(8), sd=1.0, tc=tc)
    t = np.arange(n) * DT + rng(8).uniform(0, STATIC.HVAC_S)
    assert np.std(y) == pytest.approx(1.0, rel=0.05)
    for lag in (10, 25, 50):
        r = np.mean(y[:-lag] * y[lag:]) / np.mean(y * y)
        assert r == pytest.approx(np.exp(-lag * DT / tc), abs=0.03)
    cyc = np.floor(np.mod(t / STATIC.HVAC_S, 1.0) * 8).astype(int)
    var = np.array([np.mean(y[cyc == k] ** 2) for k in range(8)])
    a2 = np.exp(-2 * DT / tc)
    lag = (1 - a2) / (1 - a2 * np.exp(-2j * np.pi * DT / STATIC.HVAC_S))   # variance's lag
    mid = 2 * np.pi * (np.arange(8) + 0.5) / 8
    want = 1 + 0.9 * np.abs(lag) * np.sin(mid + np.angle(lag)) * np.sinc(1 / 8)
    assert np.allclose(var, want, atol=0.08), (var, want)
    assert var.max() / var.min() > 8
    assert stats.kurtosis(y) == pytest.approx(3 * 0.9 ** 2 / 2, abs=0.25)   # a scale mixture


def test_fallback_reads_whole_fringes_in_spells_with_the_computed_allan_excess():
    fn, levels = SHAPES['quantization']
    n, d = 2 ** 21, STATIC.COARSE_S / (STATIC.COARSE_S + STATIC.LOCKED_S)
    x = SIG * rng(9).standard_normal(n) + 0.003
    for p in levels[:2]:
        step = p['step']
        y = fn(x.copy(), rng(10), **p)
        r = rng(10)
        start = r.uniform(0, step)
        mask = STATIC.two_state(n, DT, STATIC.COARSE_S, STATIC.LOCKED_S, r) > 0
        theta = start + np.cumsum(x) * DT
        read = start * (1 - mask[0]) + np.cumsum(y) * DT
        whole = read[mask] / step
        assert np.allclose(whole, np.round(whole), rtol=0, atol=1e-6)       # whole fringes
        assert np.allclose(read[~mask], theta[~mask], rtol=0, atol=1e-9)
        assert np.all((theta - read > -1e-9) & (theta - read < step + 1e-9))
        ex = avar(y, [1, 10]) - avar(x, [1, 10])
        for m, got in zip((1, 10), ex):
            want = STATIC.fallback_excess(m, step, DT, N_ARW) * N_ARW ** 2 / (m * DT)
            assert got == pytest.approx(want * mask.mean() / d, rel=0.12)
    spells = np.diff(np.flatnonzero(np.diff(mask.astype(int))))
    assert 0.08 < mask.mean() < 0.3 and spells.size > 40


def resonance_psd(f, f0, q):
    """Continuous second-order mode's PSD shape (an unaliased mode)."""
    return 1 / ((f0 ** 2 - f ** 2) ** 2 + (f * f0 / q) ** 2)


@pytest.mark.parametrize('freq, q, alias, mirrored', [(172.0, 15.0, 28.0, True),
                                                      (137.0, 20.0, 37.0, False)])
def test_aliased_mode_folds_to_its_image_with_the_computed_spectrum(freq, q, alias, mirrored):
    fn, _ = SHAPES['resonance']
    y = fn(np.zeros(2 ** 20), rng(11), sigma=1.0, freq=freq, q=q)
    assert np.std(y) == pytest.approx(1.0, rel=0.03)
    f, pxx = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.aliased_psd(f, 1.0, freq, q, DT)
    assert np.allclose(pxx[2:-1], want[2:-1], rtol=0.3)
    for band in ((f > 2) & (f < 15), (f > alias - 5) & (f < alias + 5)):
        assert np.mean(pxx[band]) == pytest.approx(np.mean(want[band]), rel=0.06)
    assert f[np.argmax(pxx)] == pytest.approx(alias, abs=0.5)
    g = np.linspace(0, 0.5 / DT, 200001)
    assert integrate.trapezoid(STATIC.aliased_psd(g, 1.0, freq, q, DT), g) == \
        pytest.approx(1.0, rel=1e-3)                                      # the images sum to 1
    side = STATIC.aliased_psd(alias + 8, 1.0, freq, q, DT) / STATIC.aliased_psd(
        alias - 8, 1.0, freq, q, DT)
    base = resonance_psd(alias + 8, alias, alias / (freq / q)) / resonance_psd(
        alias - 8, alias, alias / (freq / q))
    high, low = [np.mean(pxx[np.abs(f - alias - s) < 1]) for s in (8, -8)]
    if mirrored:                                              # steep side down, unlike a mode
        assert base < 1 < side and high > low


def test_swing_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_swing_set(SWING, SWING_SHAPES)


def test_notch_delays_the_motion_below_it_and_cuts_a_hole_in_the_noise():
    fn, levels = SWING_SHAPES['time_delay']
    for p in levels:
        t, rate, (ti, g, te, _) = swing(fn, p, 60.0)
        delay = 1 / (2 * np.pi * p['notch_hz'] * p['q'])                  # analog, low f
        c = fit((g - rate)[5000:], (AMP * W * W * np.sin(W * t[5000:]), np.cos(W * t[5000:])))
        assert c[0] == pytest.approx(delay, rel=0.04) and abs(c[1]) < 2e-3 * AMP * W
        assert np.array_equal(ti, t) and np.array_equal(te, t)
    p = levels[0]
    noise = rng(12).standard_normal(2 ** 18)
    t = np.arange(noise.size) * 1e-3
    out = fn(t, noise, t, np.zeros_like(t), None, None, **p)[1]
    f, pxx = signal.welch(out, fs=1000.0, nperseg=4096)
    at = np.argmin(np.abs(f - p['notch_hz']))
    assert pxx[at] < 0.01 * np.median(pxx) and np.median(pxx) == pytest.approx(2e-3, rel=0.05)
    zs = [SWING.detectability('time_delay', q) for q in levels]
    delays = [1 / (q['notch_hz'] * q['q']) for q in levels]
    assert zs[0] / zs[2] == pytest.approx(delays[0] / delays[2], rel=0.05)


def test_creep_relaxes_to_twice_with_a_nearly_constant_loss_angle_and_its_lines():
    fn, levels = SWING_SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    assert SWING.creep(np.ones(30000), 1.0)[-1] == pytest.approx(2.0, rel=1e-6)
    first = 1 + np.mean(1 - np.exp(-1e-3 / SWING.CREEP_TAUS))            # one step of each
    assert SWING.creep(np.ones(10), 1e-3)[0] == pytest.approx(first, rel=1e-12)
    lags = []
    for period in (2.5, 5.0, 10.0):
        w = 2 * np.pi / period

        def stand(x, w=w):
            return AMP * np.sin(w * x), AMP * w * np.cos(w * x)
        t, rate, (_, g, _, _) = swing(fn, levels[1], 300.0, stand)
        k = t > 100
        c = fit((g - rate)[k], (np.sin(w * t[k]), np.cos(w * t[k]), np.sin(3 * w * t[k]),
                                np.cos(3 * w * t[k])))
        lags.append(np.degrees(np.arctan2(-c[1], c[0])))
        cont = 1 + np.mean(1 / (1 + 1j * w * SWING.CREEP_TAUS))              # continuous time
        line = np.abs(cont) * 2 * special.j1(AMP) * G0 * gy          # f_y's fundamental
        assert np.hypot(c[0], c[1]) == pytest.approx(line, rel=0.02)
        assert lags[-1] == pytest.approx(-np.degrees(np.angle(cont)), abs=0.1)
    assert np.ptp(lags) < 0.6 and min(lags) > 4.5                       # a constant loss
    t, rate, (_, g, _, _) = swing(fn, levels[1], 900.0)
    k = t > 100
    cols = [h(j * W * t[k]) for j in (1, 3, 5) for h in (np.sin, np.cos)]
    assert np.linalg.norm(fit((g - rate)[k], cols)) / S_LINE == pytest.approx(
        SWING.detectability('g_sensitivity', levels[1]), rel=0.02)


def test_clipped_carrier_is_the_clip_describing_function_with_lines_as_computed():
    fn, levels = SWING_SHAPES['scale_factor_nonlinearity']
    full = levels[1]['full']
    ph = np.arange(200000) * 2 * np.pi / 200000
    for w in (0.1, 0.59, 0.61, 0.8, 1.5, 10.0):                         # units of full
        carrier = w * full * np.cos(ph) + SWING.QUAD * full * np.sin(ph)
        demod = 2 * np.mean(np.clip(carrier, -full, full) * np.cos(ph))
        assert demod == pytest.approx(float(SWING.carrier_clip(w * full, full)), abs=1e-6)
        assert (w < 0.6) == (float(SWING.carrier_clip(w * full, full)) == w * full)
    assert float(SWING.carrier_clip(1e5, full)) == pytest.approx(4 * full / np.pi, rel=1e-4)
    t, gyro = noisy_run()
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, AMP * np.sin(W * t), None, None, **p)[1]
        assert np.allclose(out, SWING.carrier_clip(gyro, p['full']), rtol=1e-12)
        assert fold_lines(out - gyro) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_nonlinearity', p), rel=0.08)


def test_oven_cycled_asymmetry_is_a_abs_w_with_a_triangular_coefficient():
    fn, levels = SWING_SHAPES['scale_factor_asymmetry']
    t, gyro = noisy_run()
    for p in levels[:2]:
        out = fn(t, gyro.copy(), t, AMP * np.sin(W * t), None, rng(14), **p)[1]
        ok = np.abs(gyro) > 1e-3
        factor = (out - gyro)[ok] / (p['a'] * np.abs(gyro[ok]))
        assert factor.max() == pytest.approx(1.8, abs=1e-3) and \
            factor.min() == pytest.approx(0.2, abs=1e-3)
        full = (out - gyro) / (p['a'] * np.maximum(np.abs(gyro), 1e-30))
        assert np.allclose(full[120000:][ok[120000:] & ok[:-120000]],
                           full[:-120000][ok[120000:] & ok[:-120000]], atol=1e-9)  # 120 s
        slope = np.abs(np.diff(full[ok][::97]) / np.diff(t[ok][::97]))
        assert np.median(slope) == pytest.approx(4 * 0.8 / 120, rel=0.01)   # a triangle
        mean = np.mean(full[ok])
        assert fold_lines(out - gyro) / S_LINE == pytest.approx(
            SWING.detectability('scale_factor_asymmetry', p) * mean, rel=0.08)
    win = 20000                                                           # 20 s windows
    err = (out - gyro)[:len(t) // win * win].reshape(-1, win)
    tw = t[:win]
    line = [np.hypot(*fit(e, (np.cos(2 * W * tw), np.sin(2 * W * tw), np.ones(win)))[:2])
            for e in err]
    fac = full[:len(t) // win * win].reshape(-1, win)
    assert np.corrcoef(line, [np.median(v) for v in fac])[0, 1] > 0.9


def test_busy_host_stamps_late_in_clustered_spells_with_the_computed_spectrum():
    fn, levels = SWING_SHAPES['timestamp_jitter']
    busy = levels[1]['busy']
    t = np.arange(900000) * 1e-3
    out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(15), busy=busy)
    e = out[2] - t
    assert np.all(np.diff(out[2]) > 0) and np.array_equal(out[0], t)
    assert abs(np.mean(e)) < 0.03 * busy                               # mean calibrated out
    d = SWING.BUSY_S / (SWING.BUSY_S + SWING.QUIET_S)
    lat = e + (d * busy + (1 - d) * SWING.QUIET) / 2
    step = float(np.median(np.diff(t)))
    on = STATIC.two_state(t.size, step, SWING.BUSY_S, SWING.QUIET_S, rng(15)) > 0
    spread = np.where(on, busy, SWING.QUIET)
    assert np.all((lat > -1e-12) & (lat < spread + 1e-12))
    assert stats.kstest(lat / spread, 'uniform').pvalue > 0.01
    spells = np.diff(np.flatnonzero(np.diff(on.astype(int))))
    assert on.mean() == pytest.approx(d, rel=0.3) and spells.size > 200
    f = np.linspace(-500, 500, 400001)
    assert integrate.trapezoid(SWING.bursty_psd(f, busy, 1000.0), f) == pytest.approx(
        np.var(e), rel=0.15)
    for lag in (100, 300):                                             # clustered: slow part
        cov = np.mean((e[:-lag] - e.mean()) * (e[lag:] - e.mean()))
        tc = 1 / (1 / SWING.BUSY_S + 1 / SWING.QUIET_S)
        assert cov == pytest.approx(((busy - SWING.QUIET) / 2) ** 2 * d * (1 - d)
                                    * np.exp(-lag * 1e-3 / tc), rel=0.35)


def test_ruled_disk_error_is_a_closed_sum_of_pitch_errors_linear_between_lines():
    fn, levels = SWING_SHAPES['encoder_cyclic_error']
    e = SWING.disk_errors()
    assert e[0] == 0 and abs(e[-1]) < 1e-12 and np.sqrt(np.mean(e[:-1] ** 2)) == \
        pytest.approx(1.0, rel=1e-12)
    pitch = np.diff(e)
    z = (pitch - pitch.mean()) / pitch.std()
    assert stats.kstest(z, 'norm').pvalue > 0.01 and abs(np.mean(z[1:] * z[:-1])) < 0.05
    ring = e[:-1]
    sf = [np.mean((np.roll(ring, -lag) - ring) ** 2) for lag in (1, 4, 16)]
    assert sf[1] / sf[0] == pytest.approx(4, rel=0.15) and sf[2] / sf[0] == pytest.approx(
        16 * (1 - 16 / 4096) / (1 - 1 / 4096), rel=0.25)                 # a walk, not white
    rms = levels[1]['rms']
    t, rate, (_, _, _, enc) = swing(fn, levels[1], 20.0)
    phi = AMP * np.sin(W * t)
    assert np.allclose(enc - phi, SWING.disk_error(phi, rms), rtol=0, atol=1e-15)
    idx = np.arange(-200, 200) + int(round(SWING.MOUNT / (2 * np.pi) * 4096))
    at_lines = idx * 2 * np.pi / 4096 - SWING.MOUNT                      # the lines' angles
    assert np.allclose(SWING.disk_error(at_lines, rms), rms * e[idx], rtol=0, atol=1e-12 * rms)
    mid = SWING.disk_error(at_lines[:-1] + np.pi / 4096, rms)
    assert np.allclose(mid, rms * (e[idx[:-1]] + e[idx[:-1] + 1]) / 2, atol=1e-12 * rms)
    zs = [SWING.detectability('encoder_cyclic_error', p) for p in levels]
    assert zs[0] / zs[2] == pytest.approx(levels[0]['rms'] / levels[2]['rms'], rel=1e-6)


def test_both_harnesses_take_set_k_by_held_out_k(monkeypatch):
    check_harnesses('k', SHAPES, SWING_SHAPES, monkeypatch)
