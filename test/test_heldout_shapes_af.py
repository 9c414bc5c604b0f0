# Held-out set AF (bench/validate_diagnosis_swing_heldout_af.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4, and the swing harness reaches the set by
# --held-out af. THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AF."""
import bench_script

from heldout_common import AMP, G0, stand_of, W
from heldout_common import rng, S_N, swing, swing_set_tests, unit_stamp_errors

import numpy as np

import pytest

from scipy import signal

SWING = bench_script.load('validate_diagnosis_swing_heldout_af')
SHAPES = SWING.shapes(1000.0)
BIAS = -0.58 * np.pi / 180.0                              # the preset's x-gyro bias, rad/s
OFF = {'time_delay': {'d': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'e': 0.0}, 'scale_factor_asymmetry': {'kappa': 0.0},
       'timestamp_jitter': {'sigma': 0.0}, 'encoder_cyclic_error': {'a': 0.0}}


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)


def test_reanchored_stamps_are_late_by_random_piecewise_constant_latencies():
    """Check the latency: constant between Poisson re-anchorings, uniform levels, mean d."""
    fn, levels = SHAPES['time_delay']
    t = np.arange(900000) * 1e-3
    angle, rate = stand_of(5.0)(t)
    d = 4e-4                                         # 2 d < 0.9 ms: no bunching at all
    dwell, level_sets, means = [], [], []
    for seed in range(40):
        ti, g, te, enc = fn(t, rate.copy(), t.copy(), angle.copy(), stand_of(5.0), rng(seed),
                            d=d)
        assert np.array_equal(g, rate) and np.array_equal(te, t)
        assert np.array_equal(enc, angle)
        lat = ti - t
        assert lat.min() >= -1e-12 and lat.max() <= 2 * d + 1e-12
        jumps = np.flatnonzero(np.abs(np.diff(lat)) > 1e-12) + 1
        edges = np.r_[0, jumps, t.size]
        for s0, s1 in zip(edges[:-1], edges[1:]):                  # constant in between
            assert np.ptp(lat[s0:s1]) < 1e-12
        level_sets.append(lat[edges[:-1]])
        dwell.append(np.diff(t[jumps]))
        means.append(lat.mean())
    dwell, lv = np.concatenate(dwell), np.concatenate(level_sets)
    assert dwell.size > 900
    assert dwell.mean() == pytest.approx(SWING.DWELL_S, rel=0.1)               # Poisson
    assert np.std(dwell) == pytest.approx(SWING.DWELL_S, rel=0.15)            # exponential
    assert lv.mean() == pytest.approx(d, rel=0.05)
    assert np.var(lv) == pytest.approx(d * d / 3, rel=0.12)                   # uniform
    assert np.histogram(lv, bins=4, range=(0, 2 * d))[0].min() > 0.8 * lv.size / 4
    assert np.mean(means) == pytest.approx(d, rel=0.06)
    assert 0.10 < np.std(means) / d < 0.20                                  # the docstring's 0.15
    # A re-anchoring that shortens the latency by more than 0.9 ms bunches the next stamps.
    t2 = np.arange(200000) * 1e-3
    ti = fn(t2, t2 * 0, t2.copy(), t2 * 0, stand_of(5.0), rng(3), d=levels[1]['d'])[0]
    step, lat = np.diff(ti), ti - t2
    assert np.all(step >= 1e-4 - 1e-12) and np.any(np.abs(step - 1e-4) < 1e-12)   # bunched
    assert lat.min() >= -1e-12 and lat.max() <= 2 * levels[1]['d'] + 1e-12
    short = step < 1e-3 - 1e-9                      # only in the few samples after a drop
    assert 0 < short.sum() < 1e-3 * step.size


def test_blanked_compensation_shows_the_raw_g_sensitivity_in_the_self_test_windows_only():
    """Check the windows (0.9 s every 7.3 s, phase per run) and the raw g_y f_y inside."""
    fn, levels = SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    starts = []

    def tilted(u):                              # never level: f_y never 0, the gate seen whole
        return 0.6 + 0.2 * np.sin(W * u), 0.2 * W * np.cos(W * u)
    for seed in (1, 2):
        t = np.arange(100000) * 1e-3
        angle, rate = tilted(t)
        out = fn(t, rate.copy(), t.copy(), angle.copy(), tilted, rng(seed), gy=gy)
        extra = out[1] - rate
        on = extra != 0
        assert np.allclose(extra[on], gy * G0 * np.sin(angle[on]), rtol=1e-12, atol=1e-15)
        up = np.flatnonzero(on[1:] & ~on[:-1]) + 1
        down = np.flatnonzero(~on[1:] & on[:-1]) + 1
        assert up.size >= 12 and np.allclose(np.diff(t[up]), SWING.SELFTEST_S, atol=1.5e-3)
        ends = np.searchsorted(down, up)
        full = ends < down.size
        length = t[down[ends[full]]] - t[up[full]]
        assert np.allclose(length, SWING.SELFTEST_ON, atol=1.5e-3)
        duty = on[up[0]:up[-1]].mean()                                   # whole cycles
        assert duty == pytest.approx(SWING.SELFTEST_ON / SWING.SELFTEST_S, rel=0.01)
        starts.append(t[up[0]])
    assert abs(starts[0] - starts[1]) > 0.01                          # a phase of its own
    # The rate-domain z: independent of the window's phase, and the angle-domain matched z
    # where the residual closes (a plain linear g-sensitivity).
    n_arw, amp, enc, w, _ = SWING.swing_scales(5.0, 900.0)
    t = np.arange(900000) * 1e-3
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    zs = [SWING.rate_z(gy * G0 * np.sin(phi) * SWING.selftest_gate(t, p), rate, n_arw, 1000.0)
          for p in np.linspace(0, SWING.SELFTEST_S, 6)[:-1]]
    assert np.ptp(zs) < 0.015 * np.mean(zs)
    plain = 1e-5 * G0 * np.sin(phi)
    want = SWING.matched_z(SWING.fitted_residual(plain, t, phi, 1000.0), 1000.0, n_arw,
                           SWING.encoder_floor(enc, 1000.0, amp * w))
    assert SWING.rate_z(plain, rate, n_arw, 1000.0) == pytest.approx(want, rel=0.01)


def explicit_flags(x, m):
    """Return the range flags of readings ``x`` by the state machine, one reading at a time."""
    out, coarse, quiet = [], False, 0
    for v in np.abs(x).tolist():
        out.append(coarse)
        if not coarse:
            if v > SWING.R_UP:
                coarse, quiet = True, 0
        else:
            quiet = quiet + 1 if v <= SWING.R_DN else 0
            if quiet == m:
                coarse = False
    return np.array(out)


def test_auto_range_enters_on_the_first_loud_reading_and_leaves_after_the_hold():
    """Check the range logic against a state machine, its chain against a Monte Carlo."""
    fn, levels = SHAPES['scale_factor_nonlinearity']
    e = levels[1]['e']
    m = int(round(SWING.HOLD_S * 1000))
    for period in (5.0, 2.5):
        t = np.arange(20000) * 1e-3
        angle, rate = stand_of(period)(t)
        x = rate + BIAS + S_N * rng(4).standard_normal(t.size)
        out = fn(t, x.copy(), t.copy(), angle, stand_of(period), rng(5), e=e)
        h = explicit_flags(x, m)
        assert np.array_equal(SWING.range_flags(x, 1e-3), h)
        assert np.array_equal(out[1], x * (1 + e * h)) and np.array_equal(out[0], t)
        enter = np.flatnonzero(h[1:] & ~h[:-1])            # the reading that switched
        leave = np.flatnonzero(~h[1:] & h[:-1])            # the last coarse sample
        peaks = 2 * int(20 / period)                  # the run starts and ends at a peak
        assert leave.size == peaks and enter.size == peaks + 1         # once a peak, each way
        assert np.all(enter[:-1] < leave) and np.all(leave < enter[1:])
        assert np.all(np.abs(x[enter]) > SWING.R_UP)
        assert all(np.all(np.abs(x[k - m + 1:k + 1]) <= SWING.R_DN) for k in leave)
        early = (SWING.R_UP - np.abs(rate[enter[1:]] + BIAS)) / S_N    # not the run's start
        if period == 5.0:
            assert 1.3 < early.mean() < 2.3                  # about 1.8 noise sd early
    # The chain's P(h) against the generator's flags over 200 noisy periods.
    per = 5000
    t = np.arange(200 * per) * 1e-3
    rate = AMP * W * np.cos(W * t)
    x = rate + BIAS + S_N * rng(6).standard_normal(t.size)
    emp = SWING.range_flags(x, 1e-3).reshape(-1, per)[2:].mean(axis=0)
    mean = rate[:per] + BIAS
    chain = SWING.range_chain(mean, S_N, m)
    assert np.abs(emp.reshape(-1, 100).mean(axis=1) - chain.reshape(-1, 100).mean(axis=1)
                  ).max() < 0.04
    assert chain.mean() == pytest.approx(0.59, abs=0.01)
    lines = [np.linalg.norm(np.fft.rfft(p * mean)[2:61]) for p in (emp, chain)]
    assert lines[0] == pytest.approx(lines[1], rel=0.03)
    fast = AMP * 2 * W * np.cos(2 * W * np.arange(2500) * 1e-3) + BIAS
    chain = SWING.range_chain(fast, S_N, m)
    assert chain.mean() == pytest.approx(0.89, abs=0.01) and chain.min() < 1e-6   # 2.5 s


def test_self_heated_half_reads_low_by_its_own_temperature_growing_from_cold():
    """Check the one-pole temperature, the one-sided gain and its settled, swing-set size."""
    fn, levels = SHAPES['scale_factor_asymmetry']
    kappa = levels[1]['kappa']
    t = np.arange(20000) * 1e-3
    angle, rate = stand_of(5.0)(t)
    a = np.exp(-1e-3 / SWING.HEAT_S)
    temp, want = 0.0, []
    for v in rate.tolist():
        temp = a * temp + (1 - a) * max(-v, 0.0)
        want.append(temp)
    assert np.allclose(SWING.heating(t, rate), want, rtol=1e-10, atol=1e-15)
    for period in (5.0, 2.5):
        t = np.arange(900000) * 1e-3
        angle, rate = stand_of(period)(t)
        noisy = rate + S_N * rng(7).standard_normal(t.size)
        out = fn(t, noisy.copy(), t.copy(), angle, stand_of(period), rng(8), kappa=kappa)[1]
        err = out - noisy
        assert np.all(err[rate >= 0] == 0) and np.all(err[rate < -1e-3] > 0)
        neg = rate < -0.2
        drop = err[neg] / -rate[neg]                        # the negative half's gain drop
        settled = kappa * 2 * AMP * (2 * np.pi / period) / (2 * np.pi)     # kappa W / pi
        assert drop[:20].max() < 0.01 * settled                          # cold at the start
        assert drop[-200:].mean() == pytest.approx(settled, rel=0.03)     # settled at 900 s
        t_mid = t[neg][np.argmin(np.abs(t[neg] - SWING.HEAT_S))]
        grown = drop[np.argmin(np.abs(t[neg] - t_mid))]
        assert grown == pytest.approx(settled * (1 - np.exp(-1)), rel=0.05)    # HEAT_S
        if period == 5.0:
            settled_5 = settled
    assert settled == pytest.approx(2 * settled_5)                   # twice at 2.5 s


def test_ringing_servo_stamp_error_is_a_resonant_gaussian_process():
    """Check the stamp error's sd, ringing autocorrelation, spectrum and noise gain."""
    fn, levels = SHAPES['timestamp_jitter']
    sigma = levels[1]['sigma']
    x = unit_stamp_errors(fn, sigma, 20)
    assert np.mean(x * x) == pytest.approx(1.0, rel=0.05)
    assert np.mean(x ** 4) / np.mean(x * x) ** 2 == pytest.approx(3.0, rel=0.05)   # Gaussian
    acf = [np.mean(x[:, :-k] * x[:, k:]) / np.mean(x * x) for k in (1, 20, 40)]
    assert acf[0] > 0.95 and acf[1] == pytest.approx(-0.52, abs=0.05) and acf[2] > 0.15
    f, pxx = signal.welch(x * sigma, fs=1000.0, nperseg=4096)
    want = 2 * SWING.servo_psd(f, sigma, 1000.0)                       # one-sided
    pm, wm = pxx.mean(axis=0), want
    for lo in (2.0, 6.0, 12.0, 20.0, 25.0, 32.0, 60.0, 150.0):
        band = (f >= lo) & (f < lo * 1.5)
        assert pm[band].mean() == pytest.approx(wm[band].mean(), rel=0.12), lo
    assert 23.0 < f[np.argmax(wm)] < 27.0
    assert wm.max() / wm[1] == pytest.approx(7.25, rel=0.05)              # the loop's peak
    grid = np.linspace(-500, 500, 200001)
    assert np.trapezoid(SWING.servo_psd(grid, sigma, 1000.0), grid) == pytest.approx(
        sigma ** 2, rel=1e-4)
    wn, z = 2 * np.pi * SWING.SERVO_HZ, SWING.SERVO_ZETA
    energy = SWING.servo_filter(1000.0)[2]                    # noise gain against the analog
    assert energy == pytest.approx(wn * (1 + 4 * z * z) / (4 * z) / 1000.0, rel=0.02)


def test_tracking_interpolator_passes_the_static_error_at_rest_and_cuts_it_at_speed():
    """Check the loop against its recursion, whole at the turning points, cut at speed."""
    fn, levels = SHAPES['encoder_cyclic_error']
    a = levels[1]['a']
    stand = stand_of(5.0)
    t = np.arange(2000) * 1e-3
    got = SWING.track_error(t, stand, a)
    ticks = np.arange(4 * (t.size - 1) + 1) * 2.5e-4
    meas = SWING.static_error(stand(ticks)[0], a).tolist()
    wn, tick = 2 * np.pi * SWING.TRACK_HZ, 2.5e-4
    kp, ki = 2 * SWING.TRACK_ZETA * wn, wn * wn
    psi, v, want = meas[0], 0.0, []
    for n, mn in enumerate(meas):
        if n % 4 == 0:
            want.append(psi)
        err = mn - psi
        v += tick * ki * err
        psi += tick * (v + kp * err)
    assert np.allclose(got, want, rtol=0, atol=1e-9 * a)
    t, rate, (ti, g, te, enc) = swing(fn, levels[1], 20.0)
    angle = AMP * np.sin(W * t)
    assert np.array_equal(ti, t) and np.array_equal(g, rate) and np.array_equal(te, t)
    e = enc - angle
    rest = (np.abs(rate) < 0.01) & (t > 1.0)
    assert rest.sum() > 100
    assert np.abs(e[rest] - SWING.static_error(angle[rest], a)).max() < 0.03 * a
    # At the rate's peak (t = 10 s) the line frequency stands still: each harmonic comes out
    # as the loop's response at k L phi_dot / 2 pi.
    win = np.abs(t - 10.0) <= 0.025
    u = SWING.TRACK_LINES * angle[win]
    cols = np.c_[np.sin(u), np.cos(u), np.sin(2 * u), np.cos(2 * u)]
    c = np.linalg.lstsq(cols, e[win], rcond=None)[0]
    b, den = SWING.track_loop(2.5e-4)
    for k, r, p in SWING.TRACK_HARMONICS:
        f = k * SWING.TRACK_LINES * AMP * W / (2 * np.pi)
        h = signal.freqz(b, den, worN=[2 * np.pi * f * 2.5e-4])[1][0]
        got = (c[2 * k - 2] + 1j * c[2 * k - 1]) / (a * r * np.exp(1j * p))
        assert abs(got) == pytest.approx(abs(h), rel=0.02), k
        assert np.angle(got / h) == pytest.approx(0.0, abs=0.03), k
    assert abs(h) < 0.35                                         # the second harmonic cut


def test_swing_harness_takes_set_af_by_held_out_af():
    """Check that the swing harness lists set af and loads the same shapes."""
    harness = bench_script.load('validate_diagnosis_swing')
    assert 'af' in harness.held_out_letters()
    got = harness.held_out_shapes(1000.0, 'af')
    assert sorted(got) == sorted(SHAPES)
    assert all(got[k][1] == SHAPES[k][1] for k in SHAPES)
