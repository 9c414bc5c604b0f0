# Held-out set AK (bench/validate_diagnosis_swing_heldout_ak.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4 and the levels are the solved ones, and the
# swing harness finds the set (by bench/heldout_sets). THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AK."""
import bisect

import bench_script

from heldout_common import AMP, G0, lines, swing_runner, W
from heldout_common import period_z_ratio, rng, S_N, solved_levels_test, swing_set_tests

import numpy as np

import pytest

from scipy import signal, stats

SWING = bench_script.load('validate_diagnosis_swing_heldout_ak')
SETS = bench_script.load('heldout_sets')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'m': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'k3': 0.0}, 'scale_factor_asymmetry': {'a': 0.0},
       'timestamp_jitter': {'tick': 0.0}, 'encoder_cyclic_error': {'a': 0.0}}
run = swing_runner(SHAPES)


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)

test_levels_are_the_solved_ones = solved_levels_test(SWING)


def test_stalling_logger_stamps_bursts_of_latency():
    """Check the reader by hand, the bursts' start, drain and area, the stalls' statistics."""
    m = SHAPES['time_delay'][1][1]['m']
    for seed in range(2):
        t, angle, rate, x, (ti, g, te, enc) = run('time_delay', {'m': m}, 60.0,
                                                  noise=S_N, seed=seed)
        assert np.array_equal(g, x) and np.array_equal(te, t) and np.array_equal(enc, angle)
        p = np.r_[t[0] - 1e-3 * np.arange(10000, 0, -1), t]
        starts, ends = SWING.stalls(p[0], p[-1], m, rng(seed))
        assert np.all(starts[1:] > ends[:-1]) and np.all(ends > starts)   # merged
        want, last = [], -np.inf
        for pk in p.tolist():                                   # the reader, by hand
            r = max(pk, last + 1e-3 / 8)
            j = bisect.bisect_right(starts.tolist(), r) - 1
            if j >= 0 and r < ends[j]:
                r = float(ends[j])
            want.append(r)
            last = r
        assert np.allclose(ti, want[10000:], rtol=0, atol=1e-9)
        lat = ti - t
        assert np.all(lat >= 0) and np.all(np.diff(ti) >= 1e-3 / 8 * (1 - 1e-9))
        busy = lat > 1e-9
        assert 0 < np.mean(busy) < 0.2
        step = np.diff(lat)[busy[1:] & busy[:-1]]                # draining at 1 - 1 / 8
        assert np.median(step) == pytest.approx(-0.875e-3, rel=1e-6)
        for s, e in zip(starts, ends):                          # S late at a stall's start
            k = np.searchsorted(t, s)
            if 0 < k < t.size and lat[k - 1] < 1e-9:
                assert lat[k] == pytest.approx(max(e - t[k], 0.0), abs=1e-9)
    t = np.arange(3000) * 1e-3                                  # one stall's area
    lat = SWING.read_times(t, 1e-3, np.array([0.5]), np.array([0.6])) - t
    assert np.sum(lat) * 1e-3 == pytest.approx(0.1 ** 2 * 8 / 14, rel=0.01)
    assert lat.max() == pytest.approx(0.1, abs=1e-3) and np.all(lat[t > 0.5 + 0.8 / 7] < 1e-9)
    starts, ends = SWING.stalls(0.0, 40000.0, 0.005, rng(3))      # Poisson, exponential
    assert stats.kstest(np.diff(starts) / 4.0, 'expon').pvalue > 1e-3
    assert stats.kstest((ends - starts) / 0.005, 'expon').pvalue > 1e-3
    assert SWING.stall_mean(m) == pytest.approx(0.2857 * m ** 2, rel=1e-3)   # docstring
    t = np.arange(900000) * 1e-3                            # the mean: the bursts' area
    starts, ends = SWING.stalls(t[0] - 10.0, t[-1], m, rng(7))
    lat = SWING.stall_stamps(t, m, rng(7)) - t
    area = np.sum((ends - starts) ** 2) * 8 / 14 / (t[-1] - t[0] + 10.0)
    assert np.mean(lat) == pytest.approx(area, rel=0.03)
    assert np.mean(lat) == pytest.approx(SWING.stall_mean(m), rel=0.3)
    assert period_z_ratio(SWING, 'time_delay') == pytest.approx(4.0, rel=0.01)


def test_extrapolating_compensation_leaves_the_curvature():
    """Check the extrapolation by hand, ramps and steady tilts, its line at f, sidebands."""
    gy = SHAPES['g_sensitivity'][1][1]['gy']
    phases = []
    for seed in range(3):
        t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 12.0, noise=S_N, seed=seed)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
        u = rng(seed).uniform(0.0, 0.93)
        phases.append(u)
        want = []
        for tk in t.tolist():
            j = np.floor((tk - u) / 0.93)
            t1, t0 = u + j * 0.93, u + (j - 1) * 0.93
            f1, f0 = (G0 * np.sin(AMP * np.sin(W * v)) for v in (t1, t0))
            want.append(gy * (G0 * np.sin(AMP * np.sin(W * tk)) - f1 - (tk - t1) * (f1 - f0)
                              / 0.93))
        err = out[1] - x
        assert np.allclose(err, want, rtol=0, atol=1e-12)
        fresh = np.mod(t - u, 0.93) < 1e-3                        # nil at each message
        assert np.abs(err[fresh]).max() < 0.01 * np.abs(err).max()
    assert np.ptp(phases) > 0.1
    t = np.arange(5000) * 1e-3
    for f_of in (lambda v: 0.3 + 0.2 * v, lambda v: np.full_like(v, 2.0)):   # ramp, steady
        assert np.abs(SWING.extrapolated_error(t, f_of, gy, 0.31)).max() < 1e-15
    for period, mag, ahead in ((5.0, 0.514, 126.7), (2.5, 1.502, 75.1)):
        w = 2 * np.pi / period
        x = w * 0.93
        h = (1 - (1 - np.exp(-1j * x)) / (1j * x)
             - (1 - np.exp(-1j * x)) * (np.exp(-1j * x) * (1 + 1j * x) - 1) / x ** 2)
        assert abs(h) == pytest.approx(mag, abs=0.002)              # docstring
        assert np.degrees(np.angle(h)) == pytest.approx(ahead, abs=0.1)
        t = np.arange(int(93 * period * 1000)) * 1e-3               # 500 messages
        f = G0 * np.sin(AMP * np.sin(w * t))
        err = SWING.extrapolated_error(t, lambda v: G0 * np.sin(AMP * np.sin(w * v)), 1.0,
                                       0.2)
        per = int(period * 1000)
        c, raw = lines(err, per), lines(f, per)
        assert abs(c[1] / raw[1]) == pytest.approx(abs(h), rel=0.005)
        assert np.angle(c[1] / raw[1] / h) == pytest.approx(0.0, abs=0.005)
        if period == 5.0:
            locked = np.tile(np.fft.irfft(c * per, per), t.size // per)
            assert np.sum(locked ** 2) / np.sum(err ** 2) == pytest.approx(0.66, abs=0.03)
    assert period_z_ratio(SWING, 'g_sensitivity') == pytest.approx(2.54, abs=0.02)


def test_ac_coupled_compressor_compresses_the_filtered_rate():
    """Check the coupling by hand, a steady rate and a step, its gain and phase, the 3f line."""
    k3 = SHAPES['scale_factor_nonlinearity'][1][1]['k3']
    t, angle, rate, x, out = run('scale_factor_nonlinearity', {'k3': k3}, 20.0, noise=S_N)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    a = np.exp(-1e-3)
    pre = AMP * W * np.cos(W * (t[0] - 1e-3 * np.arange(10000, 0, -1)))
    low, want = pre[0], []
    for v in np.r_[pre, rate].tolist():
        low = a * low + (1 - a) * v
        want.append(-k3 * (v - low) ** 3)
    assert np.allclose(out[1] - x, want[10000:], rtol=1e-7, atol=1e-15)

    def steady(u):
        return 0.1 * u, np.full_like(u, 0.1)

    def step(u):
        return 0.0 * u, np.where(u >= 5.0, 0.3, 0.0)
    t = np.arange(10000) * 1e-3
    fn = SHAPES['scale_factor_nonlinearity'][0]
    assert np.abs(fn(t, t * 0, t, t * 0, steady, rng(0), k3=k3)[1]).max() < 1e-30   # none
    err = fn(t, t * 0, t, t * 0, step, rng(0), k3=k3)[1]
    assert np.all(err[t < 5.0] == 0)
    assert err[6000] == pytest.approx(-k3 * (0.3 * np.exp(-1.0)) ** 3, rel=0.01)
    for period, gain, ahead in ((5.0, 0.782, 38.5), (2.5, 0.929, 21.7)):
        w = 2 * np.pi / period
        t = np.arange(int(4 * period * 1000)) * 1e-3
        v = SWING.ac_coupled(t, lambda u: AMP * w * np.cos(w * u))
        per, rate = int(period * 1000), AMP * w * np.cos(w * t)
        c, r = lines(v, per), lines(rate, per)
        assert abs(c[1] / r[1]) == pytest.approx(gain, abs=0.001)
        assert np.degrees(np.angle(c[1] / r[1])) == pytest.approx(ahead, abs=0.1)
        e, m = lines(SWING.ac_error(v, k3), per), lines(-k3 * rate ** 3, per)
        assert abs(e[3] / m[3]) == pytest.approx(gain ** 3, rel=0.002)
        assert np.degrees(np.angle(e[3] / m[3])) == pytest.approx(3 * ahead, abs=0.3)
    assert k3 * (0.782 * AMP * W) ** 2 == pytest.approx(0.0142, rel=0.01)   # docstring
    assert period_z_ratio(SWING, 'scale_factor_nonlinearity') == pytest.approx(9.44, abs=0.05)


def test_hunting_trim_flips_the_negative_gain_every_swing():
    """Check the trim by hand, both phases, the flip per swing, its half-integer lines."""
    a = SHAPES['scale_factor_asymmetry'][1][1]['a']
    phases = set()
    for seed in range(6):
        t, angle, rate, x, out = run('scale_factor_asymmetry', {'a': a}, 20.0, noise=S_N,
                                     seed=seed)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
        b = int(rng(seed).integers(2))
        phases.add(b)
        j, was, want = 0, False, []
        for v in rate.tolist():
            j += v < 0 and not was
            was = v < 0
            want.append((-1) ** (j + b) * a * v if v < 0 else 0.0)
        err = out[1] - x
        assert np.allclose(err, want, rtol=1e-12, atol=1e-15)
    assert phases == {0, 1}
    assert np.all(err[rate >= 0] == 0)
    neg = rate < -0.01
    gains = np.round(err[neg] / (a * rate[neg]), 6)
    assert set(np.abs(gains)) == {1.0}
    halves = np.split(gains, np.flatnonzero(np.diff(gains) != 0) + 1)   # one sign a half
    assert len(halves) == 4 and all(np.ptp(h) == 0 for h in halves)
    assert all(h[0] == -k[0] for h, k in zip(halves[:-1], halves[1:]))
    c = lines(err, 10000)                                  # two swings: f / 2 per line
    assert np.abs(c[2:200:2]).max() < 1e-9 * np.abs(c).max()   # no swing harmonic
    assert abs(c[1]) > 0.1 * a * AMP * W and abs(c[3]) > 0.1 * a * AMP * W
    assert period_z_ratio(SWING, 'scale_factor_asymmetry') == pytest.approx(2.0, rel=1e-3)


def test_fractional_n_clock_shapes_the_jitter_blue():
    """Check the errors by hand, their law, correlation, bounded sum, PSD and Welch bands."""
    fn, levels = SHAPES['timestamp_jitter']
    tick = levels[1]['tick']
    n = 2 ** 17
    t = np.arange(n) * 1e-3
    errs = []
    for seed in range(4):
        out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(40 + seed), tick=tick)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], np.sin(W * t))
        assert np.all(np.diff(out[2]) > 0)
        e = out[2] - t
        q = rng(40 + seed).random(n + 1)
        assert np.allclose(e, tick * (q[1:] - q[:-1]), rtol=0, atol=1e-13)
        assert np.abs(e).max() < tick and np.abs(np.cumsum(e)).max() < tick   # no drift
        errs.append(e)
    e = np.concatenate(errs) / tick
    assert stats.kstest(e[::7], 'triang', args=(0.5, -1.0, 2.0)).pvalue > 1e-3
    assert np.std(e) == pytest.approx(1 / np.sqrt(6), rel=0.01)         # 0.408 tick
    for lag, want in ((1, -0.5), (2, 0.0), (3, 0.0), (7, 0.0)):
        got = np.mean([np.corrcoef(u[:-lag], u[lag:])[0, 1] for u in errs])
        assert got == pytest.approx(want, abs=0.01), lag
    f = np.linspace(-500.0, 500.0, 200001)
    psd = SWING.mash_psd(f, tick, 1000.0)
    assert np.trapezoid(psd, f) == pytest.approx(tick ** 2 / 6, rel=1e-4)
    assert psd[0] == pytest.approx(2 * tick ** 2 / 6 / 1000.0, rel=1e-9)   # Nyquist: 2x white
    assert SWING.mash_psd(0.0, tick, 1000.0) == 0
    fw, pxx = signal.welch(np.array(errs), fs=1000.0, nperseg=4096, return_onesided=True)
    pxx = pxx.mean(axis=0)
    for lo, hi in ((5.0, 60.0), (100.0, 250.0), (400.0, 499.0)):
        band = (fw >= lo) & (fw < hi)
        grid = np.linspace(lo, hi, 20001)
        want = 2 * np.trapezoid(SWING.mash_psd(grid, tick, 1000.0), grid)
        assert np.sum(pxx[band]) * (fw[1] - fw[0]) == pytest.approx(want, rel=0.1), (lo, hi)
    assert period_z_ratio(SWING, 'timestamp_jitter') == pytest.approx(1.84, abs=0.02)


def test_sagging_head_modulates_the_cyclic_error_with_tilt():
    """Check the error's formula, its tilt envelope, its frequency, none on the level."""
    a = SHAPES['encoder_cyclic_error'][1][1]['a']
    t, angle, rate, x, out = run('encoder_cyclic_error', {'a': a}, 20.0)
    assert np.array_equal(out[0], t) and np.array_equal(out[1], x)
    e = out[3] - angle
    assert np.allclose(e, a * np.sin(angle) * np.sin(5760 * angle + 1.1), rtol=1e-9,
                       atol=1e-15)
    assert np.all(np.abs(e) <= a * np.abs(np.sin(angle)) * (1 + 1e-12))
    assert np.abs(e).max() == pytest.approx(a * np.sin(AMP), rel=5e-3)    # 0.342 a
    assert np.sin(AMP) == pytest.approx(0.342, abs=5e-4)
    level = np.abs(angle) < 1e-4
    assert np.abs(e[level]).max() < 1.01e-4 * a
    t15 = np.arcsin(0.75) / W                                   # at 15 deg, rising
    window = np.abs(t - t15) < 0.05
    spec = np.abs(np.fft.rfft(e[window] * np.hanning(window.sum()), 8192))
    freq = np.fft.rfftfreq(8192, 1e-3)
    assert freq[np.argmax(spec)] == pytest.approx(266.0, abs=6.0)
    assert 5760 * AMP * W / (2 * np.pi) == pytest.approx(402.0, abs=0.5)   # docstring
    assert 2 * np.pi / 5760 * 180 / np.pi * 3600 == pytest.approx(225.0, abs=0.1)

    def rest(u):
        return np.zeros_like(u), np.zeros_like(u)
    t = np.arange(2000) * 1e-3
    enc = SHAPES['encoder_cyclic_error'][0](t, t * 0, t.copy(), np.zeros(t.size), rest,
                                            rng(0), a=a)[3]
    assert np.all(enc == 0)                                      # none at rest on the level
    assert period_z_ratio(SWING, 'encoder_cyclic_error') == pytest.approx(0.974, abs=0.01)


def test_swing_harness_finds_set_ak():
    """Check that the held-out set list the harness offers includes ak, by its file alone."""
    assert 'ak' in SETS.letters('validate_diagnosis_swing_heldout', 'b')
    assert SETS.module('validate_diagnosis_swing_heldout', 'ak', 'b') == SWING.__name__
