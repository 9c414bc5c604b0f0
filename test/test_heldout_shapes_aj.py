# Held-out set AJ (bench/validate_diagnosis_swing_heldout_aj.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4 and the levels are the solved ones, and the
# swing harness finds the set (by bench/heldout_sets). THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AJ."""
import bench_script

from heldout_common import AMP, G0, lines, swing_runner, W
from heldout_common import period_z_ratio, rng, S_N, solved_levels_test, swing_set_tests

import numpy as np

import pytest

from scipy import signal, stats

SWING = bench_script.load('validate_diagnosis_swing_heldout_aj')
SETS = bench_script.load('heldout_sets')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'d': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'k2': 0.0}, 'scale_factor_asymmetry': {'a': 0.0},
       'timestamp_jitter': {'sigma': 0.0}, 'encoder_cyclic_error': {'a': 0.0}}
run = swing_runner(SHAPES)


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)

test_levels_are_the_solved_ones = solved_levels_test(SWING)


def test_flushes_make_the_stamps_late_intermittently():
    """Check the latency d inside the flushes only, their timing, the order and the mean."""
    d = SHAPES['time_delay'][1][1]['d']
    starts, means = [], []
    for seed in range(4):
        t, angle, rate, x, (ti, g, te, enc) = run('time_delay', {'d': d}, 120.0,
                                                  noise=S_N, seed=seed)
        assert np.array_equal(g, x) and np.array_equal(te, t) and np.array_equal(enc, angle)
        u = rng(seed).uniform(0.0, 11.3)
        inside = np.mod(t - u, 11.3) < 2.6
        want = t + d * inside
        for k in np.flatnonzero(np.diff(inside.astype(int)) < 0) + 1:   # kept in order
            j = k
            while want[j] < want[j - 1] + 1e-4:
                want[j] = want[j - 1] + 1e-4
                j += 1
        assert np.allclose(ti, want, rtol=0, atol=1e-12)
        assert np.all(np.diff(ti) >= 1e-4 * (1 - 1e-9))
        lat = ti - t
        on = np.flatnonzero(np.diff(inside.astype(int)) > 0) + 1
        off = np.flatnonzero(np.diff(inside.astype(int)) < 0) + 1
        assert np.allclose(np.diff(t[on]), 11.3, atol=1.5e-3)              # every 11.3 s
        assert np.allclose(t[off[off > on[0]][:on.size - 1]] - t[on[:-1]], 2.6, atol=1.5e-3)
        assert np.allclose(lat[inside], d, rtol=1e-9)                  # d late in a flush
        held = np.abs(ti - (t + d * inside)) > 1e-9                 # held back for order
        assert np.all((lat[held] > 0) & (lat[held] < d)) and not np.any(held & inside)
        assert np.all(np.abs(lat[~inside & ~held]) < 1e-9) and np.mean(held) < 0.005
        starts.append(u)
        means.append(np.mean(inside))
    assert SWING.flush_mean(d) == pytest.approx(0.2301 * d, rel=1e-3)   # docstring
    assert np.mean(means) == pytest.approx(2.6 / 11.3, abs=0.03)
    firsts = []
    t = np.arange(12000) * 1e-3
    for seed in range(300):                                 # the first flush: uniform phase
        gate = SWING.flush_gate(t, rng(seed))
        rise = np.flatnonzero(np.diff(gate.astype(int)) > 0)
        firsts.append(t[rise[0] + 1] if rise.size else 0.0)
    assert stats.kstest(np.array(firsts) / 11.3, 'uniform').pvalue > 1e-3
    assert period_z_ratio(SWING, 'time_delay') == pytest.approx(4.0, rel=0.01)


def test_still_gated_reference_holds_through_the_motion():
    """Check the hold by hand, its lead and lines at 20 deg, the turning points, small swings."""
    gy = SHAPES['g_sensitivity'][1][1]['gy']
    t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 20.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    f = G0 * np.sin(angle)
    ref, want = 0.0, []
    for fk, wk in zip(f.tolist(), rate.tolist()):
        if abs(wk) < 0.05:
            ref = fk
        want.append(gy * (fk - ref))
    err = out[1] - x
    assert np.allclose(err, want, rtol=1e-9, atol=1e-15)
    assert np.all(err[np.abs(rate) < 0.05] == 0)                  # nil while still
    assert np.mean(np.abs(rate) < 0.05) == pytest.approx(2 / np.pi * np.arcsin(0.05 / (AMP * W)),
                                                         abs=1e-3)
    held = G0 * np.sin(AMP * np.sqrt(1 - (0.05 / (AMP * W)) ** 2))
    assert held == pytest.approx(3.333, abs=1e-3)                      # docstring
    assert np.abs(err).max() == pytest.approx(2 * gy * held, rel=1e-3)
    mid = (np.abs(angle) < 1e-3) & (t > 1.0)                          # at mid-swing: -held
    assert np.allclose(np.abs(err[mid] - gy * f[mid]), gy * held, rtol=1e-3)
    c, raw = lines(err[t >= 5.0], 5000), lines(gy * f[t >= 5.0], 5000)
    assert abs(c[1] / raw[1]) == pytest.approx(1.52, abs=0.005)
    assert np.degrees(np.angle(c[1] / raw[1])) == pytest.approx(56.0, abs=0.5)   # ahead
    assert abs(c[3] / c[1]) == pytest.approx(0.28, abs=0.005)
    assert np.abs(c[2:40:2]).max() < 1e-9 * abs(c[1])                  # odd lines only
    small = run('g_sensitivity', {'gy': gy}, 10.0, amp=np.deg2rad(2.2))
    assert np.all(small[4][1] == small[3])                  # always still: none
    wide = run('g_sensitivity', {'gy': gy}, 10.0, amp=np.deg2rad(2.4))
    assert np.ptp(wide[4][1] - wide[3]) > 0.1 * gy
    assert np.degrees(0.05 / W) == pytest.approx(2.28, abs=0.01)
    assert period_z_ratio(SWING, 'g_sensitivity') == pytest.approx(1.057, abs=0.01)


def test_chopped_front_end_carries_the_quadratic_to_nyquist():
    """Check the re-signed k2 w^2, both chopper phases, no low lines, its power at Nyquist."""
    k2 = SHAPES['scale_factor_nonlinearity'][1][1]['k2']
    phases = set()
    for seed in range(6):
        t, angle, rate, x, out = run('scale_factor_nonlinearity', {'k2': k2}, 20.0,
                                     noise=S_N, seed=seed)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
        err = out[1] - x
        b = rng(seed).integers(2)
        sign = np.where((np.arange(t.size) + b) % 2 == 0, 1.0, -1.0)
        assert np.allclose(err, sign * k2 * rate ** 2, rtol=1e-9, atol=1e-15)
        phases.add(int(b))
    assert phases == {0, 1}
    k = np.arange(t.size)                                          # alternating signs
    assert set(k[err > 0] % 2) == {b} and set(k[err < 0] % 2) == {1 - b}
    c = lines(err, 5000)
    assert np.abs(c[:200]).max() < 1e-9 * np.abs(err).max()       # nothing at the lines
    assert abs(c[2500]) > 0.3 * k2 * (AMP * W) ** 2                  # at Nyquist
    spec = np.abs(np.fft.rfft(err)) ** 2
    freq = np.fft.rfftfreq(err.size, 1e-3)
    assert spec[freq < 400].sum() < 1e-12 * spec.sum()
    assert np.mean(err ** 2) == pytest.approx(3 / 8 * k2 ** 2 * (AMP * W) ** 4, rel=1e-3)
    assert k2 * AMP * W == pytest.approx(6.8e-3, rel=0.01)           # docstring: 0.68 %
    assert period_z_ratio(SWING, 'scale_factor_nonlinearity') == pytest.approx(4.0, rel=0.01)


def test_forming_half_fades_with_negative_travel():
    """Check the envelope by hand, negative rates only, its e-fold times, even and odd lines."""
    a = SHAPES['scale_factor_asymmetry'][1][1]['a']
    t, angle, rate, x, out = run('scale_factor_asymmetry', {'a': a}, 30.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    q, want = 0.0, []
    for v in rate.tolist():
        q += max(-v, 0.0) * 1e-3
        want.append(a * np.exp(-q / SWING.FORM_Q) * v if v < 0 else 0.0)
    err = out[1] - x
    assert np.allclose(err, want, rtol=1e-9, atol=1e-15)
    assert np.all(err[rate >= 0] == 0) and np.all(err[rate < 0] < 0)
    c = lines(err[t >= 10.0] / SWING.forming(rate, 1e-3)[t >= 10.0], 5000)
    assert abs(c[2]) > 0.2 * abs(c[1]) and abs(c[3]) < 1e-3 * abs(c[1])   # a one-sided gain
    for period, fold in ((5.0, 286.5), (2.5, 143.2)):
        w = 2 * np.pi / period
        tt = np.arange(900000) * 1e-3
        env = SWING.forming(AMP * w * np.cos(w * tt), 1e-3)
        assert tt[np.argmin(np.abs(env - np.exp(-1)))] == pytest.approx(fold, rel=0.01)
        if period == 5.0:
            assert env[-1] == pytest.approx(0.043, abs=0.001)            # docstring
        assert np.all(np.diff(env) <= 0)
    assert period_z_ratio(SWING, 'scale_factor_asymmetry') == pytest.approx(1.74, abs=0.02)


def test_self_timed_daq_walks_between_syncs():
    """Check the walk by hand, its resets every frame, its variance ramp, covariance and PSD."""
    fn, levels = SHAPES['timestamp_jitter']
    sigma = levels[1]['sigma']
    m = SWING.FRAME
    n = 2 ** 17
    t = np.arange(n) * 1e-3
    errs = []
    for seed in range(4):
        out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(40 + seed), sigma=sigma)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], np.sin(W * t))
        assert np.all(np.diff(out[2]) > 0)
        e = out[2] - t
        r = rng(40 + seed)
        b = r.integers(m)
        steps = sigma / np.sqrt(m) * r.standard_normal(n)
        want, acc = [], 0.0
        for k in range(n):
            acc = 0.0 if (k == 0 or (k - b) % m == 0) else acc + steps[k]
            want.append(acc)
        assert np.allclose(e, want, rtol=0, atol=1e-12)
        assert np.all(e[np.arange(n) % m == b % m] == 0)               # reset at each sync
        errs.append(e[(b + m) % m:][:(n - m) // m * m])
    frames = np.concatenate([u.reshape(-1, m) for u in errs])
    assert np.allclose(frames.var(axis=0) / sigma ** 2, np.arange(m) / m, atol=0.012)
    e = np.concatenate(errs)
    assert np.std(e) / sigma == pytest.approx(0.661, rel=0.01)         # docstring
    f = np.linspace(-500.0, 500.0, 200001)
    psd = SWING.walk_psd(f, sigma, 1000.0)
    assert np.trapezoid(psd, f) == pytest.approx(7 / 16 * sigma ** 2, rel=1e-4)
    for lag in range(0, 10):                           # covariance, lag by lag
        acv = sigma ** 2 * max(m - 1 - lag, 0) * (m - lag) / (2 * m * m)
        assert np.trapezoid(psd * np.cos(2 * np.pi * f * lag / 1000.0), f) == (
            pytest.approx(acv, abs=1e-4 * sigma ** 2)), lag
        got = np.mean([np.mean(u[:u.size - lag] * u[lag:]) for u in errs])
        assert got == pytest.approx(acv, abs=0.01 * sigma ** 2), lag
    fw, pxx = signal.welch(np.array(errs), fs=1000.0, nperseg=4096, return_onesided=True)
    pxx = pxx.mean(axis=0)
    for lo, hi in ((1.0, 60.0), (100.0, 250.0), (400.0, 499.0)):
        band = (fw >= lo) & (fw < hi)
        grid = np.linspace(lo, hi, 20001)
        want = 2 * np.trapezoid(SWING.walk_psd(grid, sigma, 1000.0), grid)
        assert np.sum(pxx[band]) * (fw[1] - fw[0]) == pytest.approx(want, rel=0.1), (lo, hi)
    assert period_z_ratio(SWING, 'timestamp_jitter') == pytest.approx(2.67, abs=0.03)


def test_speed_dropped_correction_gates_the_cyclic_error():
    """Check the error by its formula, the gate's speeds and share, its frequency, still stand."""
    a = SHAPES['encoder_cyclic_error'][1][1]['a']
    t, angle, rate, x, out = run('encoder_cyclic_error', {'a': a}, 20.0)
    assert np.array_equal(out[0], t) and np.array_equal(out[1], x)
    e = out[3] - angle
    on, state = [], False
    for v in np.abs(rate).tolist():
        state = v >= 0.25 if state else v > 0.30
        on.append(state)
    on = np.array(on)
    assert np.allclose(e, np.where(on, a * np.sin(4096 * angle + SWING.GATE_PHASE), 0.0),
                       rtol=1e-9, atol=1e-15)
    up = np.flatnonzero(np.diff(on.astype(int)) > 0) + 1
    down = np.flatnonzero(np.diff(on.astype(int)) < 0) + 1
    assert np.all((np.abs(rate[up]) > 0.30) & (np.abs(rate[up - 1]) <= 0.30))
    assert np.all((np.abs(rate[down]) < 0.25) & (np.abs(rate[down - 1]) >= 0.25))
    assert np.mean(on[t >= 5.0]) == pytest.approx(0.567, abs=0.002)     # docstring
    fast = run('encoder_cyclic_error', {'a': a}, 10.0, period=2.5)
    assert np.mean(SWING.gate_flags(fast[2])) == pytest.approx(0.797, abs=0.003)
    window = np.abs(t - 5.0) < 0.06                                 # mid-swing at full speed
    spec = np.abs(np.fft.rfft(e[window] * np.hanning(window.sum())))
    freq = np.fft.rfftfreq(window.sum(), 1e-3)
    assert freq[np.argmax(spec)] == pytest.approx(286.0, abs=10.0)
    assert 4096 * 0.30 / (2 * np.pi) == pytest.approx(196.0, abs=0.5)
    slow = run('encoder_cyclic_error', {'a': a}, 10.0, amp=np.deg2rad(13.5))
    assert np.all(slow[4][3] == slow[1])                            # never fast enough
    brisk = run('encoder_cyclic_error', {'a': a}, 10.0, amp=np.deg2rad(14.0))
    assert np.abs(brisk[4][3] - brisk[1]).max() > 0.9 * a

    def still(u):
        return np.full_like(u, 0.1), np.zeros_like(u)
    t = np.arange(2000) * 1e-3
    enc = SHAPES['encoder_cyclic_error'][0](t, t * 0, t.copy(), np.full(t.size, 0.1), still,
                                            rng(0), a=a)[3]
    assert np.all(enc == 0.1)                                       # none at rest
    assert 2 * np.pi / 4096 * 180 / np.pi * 3600 == pytest.approx(316.4, abs=0.1)
    assert period_z_ratio(SWING, 'encoder_cyclic_error') == pytest.approx(1.05, abs=0.02)


def test_swing_harness_finds_set_aj():
    """Check that the held-out set list the harness offers includes aj, by its file alone."""
    assert 'aj' in SETS.letters('validate_diagnosis_swing_heldout', 'b')
    assert SETS.module('validate_diagnosis_swing_heldout', 'aj', 'b') == SWING.__name__
