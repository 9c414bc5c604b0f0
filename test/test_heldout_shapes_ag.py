# Held-out set AG (bench/validate_diagnosis_swing_heldout_ag.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4 and the levels are the solved ones, and the
# swing harness finds the set (by bench/heldout_sets). THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AG."""
import bench_script

from heldout_common import AMP, G0, swing_runner, W
from heldout_common import rng, S_N, solved_levels_test, swing_set_tests, unit_stamp_errors

import numpy as np

import pytest

from scipy import signal, special

SWING = bench_script.load('validate_diagnosis_swing_heldout_ag')
SETS = bench_script.load('heldout_sets')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'d': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'e': 0.0}, 'scale_factor_asymmetry': {'a': 0.0},
       'timestamp_jitter': {'sigma': 0.0}, 'encoder_cyclic_error': {'a': 0.0}}
run = swing_runner(SHAPES)


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)

# the quick shapes' solves only
test_levels_are_the_solved_ones = solved_levels_test(
    SWING, ['g_sensitivity', 'scale_factor_nonlinearity', 'scale_factor_asymmetry'])


def test_playout_buffer_follows_the_worst_recent_latency():
    """Check the buffer's recursion, its release, its mean d and its extreme-value law."""
    fn, levels = SHAPES['time_delay']
    a = np.exp(-1e-3 / SWING.BUFFER_S)
    ell = rng(1).exponential(1e-4, 20000)
    last, want = 0.0, []
    for v in ell.tolist():                                   # D_k = max(a D_(k-1), ell_k)
        last = max(a * last, v)
        want.append(last)
    assert np.allclose(SWING.playout(ell, 1e-3), want, rtol=1e-12, atol=0)
    d = levels[1]['d']
    means, pooled = [], []
    for seed in range(12):
        t, angle, rate, x, (ti, g, te, enc) = run('time_delay', {'d': d}, 900.0, seed=seed)
        assert np.array_equal(g, x) and np.array_equal(te, t) and np.array_equal(enc, angle)
        lat = ti - t
        ratio = lat[1:] / lat[:-1]
        assert lat.min() > 0 and np.all(ratio >= a * (1 - 1e-9))          # released at a
        jumps = ratio > a * (1 + 1e-9)
        assert 2.0 < jumps.sum() / 900.0 < 4.5                       # ~3 new worst a second
        means.append(lat.mean())
        pooled.append(lat[::2000])                                  # 2 s apart: independent
    assert np.mean(means) == pytest.approx(d, rel=0.01)              # gain 6.23 (closed form)
    assert np.std(means) / d < 0.02
    # The law of D / m against the product formula, summed term by term.
    m = d / SWING.playout_gain(1e-3)
    pooled = np.sort(np.concatenate(pooled)) / m
    j = np.arange(200000) * 1e-3 / SWING.BUFFER_S
    for q in (4.0, 5.5, 6.5, 8.0, 10.0):
        cdf = np.exp(np.sum(np.log1p(-np.exp(-q * np.exp(j)))))
        assert np.searchsorted(pooled, q) / pooled.size == pytest.approx(cdf, abs=0.035), q
    assert SWING.playout_gain(1e-3) == pytest.approx(6.23, abs=0.005)
    assert np.std(pooled) / np.mean(pooled) == pytest.approx(0.18, abs=0.02)


def test_smoothed_compensation_leaves_a_high_passed_g_sensitivity():
    """Check the one-pole recursion, nothing at a steady tilt, the gain i w tau / (1 + i w tau)."""
    fn, levels = SHAPES['g_sensitivity']
    gy = levels[1]['gy']
    t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 20.0, noise=S_N)
    a = np.exp(-1e-3 / SWING.ACC_TAU)
    f = G0 * np.sin(angle)
    lp, want = f[0], []
    for v in f.tolist():
        lp = a * lp + (1 - a) * v
        want.append(gy * (v - lp))
    assert np.allclose(out[1] - x, want, rtol=1e-9, atol=1e-15)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)

    def tilted(u):                                     # 0.3 rad, then 0.5 rad from 2 s on
        return np.where(u < 2.0, 0.3, 0.5), np.zeros_like(u)
    res = fn(t, t * 0, t.copy(), t * 0, tilted, rng(0), gy=gy)[1]
    assert np.all(res[t < 2.0] == 0)                                 # none for a steady tilt
    late = t >= 2.0
    step = gy * G0 * (np.sin(0.5) - np.sin(0.3))
    assert np.allclose(res[late], step * a ** (np.arange(late.sum()) + 1), rtol=1e-9)
    for period, inphase, ahead in ((5.0, 0.5, 0.5), (2.5, 0.8, 0.4), (10.0, 0.2, 0.4)):
        t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 12 * period, period=period)
        w = 2 * np.pi / period
        keep = t >= 2 * period                                       # settled, whole periods
        th = w * t[keep]
        cols = np.c_[np.sin(th), np.cos(th), np.sin(3 * th), np.cos(3 * th), np.sin(5 * th),
                     np.cos(5 * th)]
        c = np.linalg.lstsq(cols, (out[1] - x)[keep], rcond=None)[0]
        got = (c[0] + 1j * c[1]) / (gy * 2 * G0 * special.j1(AMP))
        wt = w * SWING.ACC_TAU
        assert got == pytest.approx(1j * wt / (1 + 1j * wt), rel=2e-3), period
        assert got.real == pytest.approx(inphase, abs=0.01)                # docstring shares
        assert got.imag == pytest.approx(ahead, abs=0.01)


def explicit_trap(w, step, u):
    """Return the trap's occupancy sample by sample (``trap_states``' docstring)."""
    up, down = SWING.trap_rates(w, step)
    s = [bool(u[0] < up[0] / (up[0] + down[0]))]
    for k in range(1, len(w)):
        s.append(bool(u[k] >= down[k]) if s[-1] else bool(u[k] < up[k]))
    return np.array(s)


def test_telegraph_trap_follows_the_rate_and_bends_the_mean_response():
    """Check the chain against its recursion, its law at fixed rates and its mean on a swing."""
    fn, levels = SHAPES['scale_factor_nonlinearity']
    e = levels[1]['e']
    t, angle, rate, x, out = run('scale_factor_nonlinearity', {'e': e}, 20.0, noise=S_N)
    u = rng(10).random(t.size)                                       # the generator's draws
    s = SWING.trap_states(rate, 1e-3, u)
    assert np.array_equal(s, explicit_trap(rate, 1e-3, u))
    assert np.array_equal(out[1], x - e * s * rate) and 0.2 < s.mean() < 0.8
    half, width = SWING.TRAP_HALF, SWING.TRAP_W
    for w0 in (0.15, 0.25, 0.32):
        c, em = SWING.trap_rates(np.array([w0]), 1e-3)
        s = SWING.trap_states(np.full(600000, w0), 1e-3, rng(5).random(600000))
        share = 1 / (1 + np.exp(-2 * (w0 - half) / width))       # lambda_c / (lambda_c + e)
        assert s.mean() == pytest.approx(share, abs=0.015 + 0.05 * share), w0
        flips = np.flatnonzero(np.diff(s.astype(int))) + 1
        runs = np.diff(flips)
        full = runs[::2] if s[flips[0]] else runs[1::2]              # occupied dwells
        assert full.mean() == pytest.approx(1 / em[0], rel=0.1), w0    # geometric, 1 / e_k
    assert SWING.trap_rates(np.array([0.0]), 1e-3)[0][0] == pytest.approx(
        -np.expm1(-SWING.TRAP_HZ * 1e-3 * np.exp(-half / width)))
    # On the swing: the chain's mean occupancy (master equation) against 300 periods.
    per = 5000
    t = np.arange(300 * per) * 1e-3
    rate = AMP * W * np.cos(W * t)
    emp = SWING.trap_states(rate, 1e-3, rng(6).random(t.size)).reshape(-1, per).mean(axis=0)
    mean = SWING.trap_mean(rate[:per], 1e-3)
    assert np.abs(emp.reshape(-1, 250).mean(axis=1) - mean.reshape(-1, 250).mean(axis=1)
                  ).max() < 0.02
    assert mean.min() == pytest.approx(0.0075, abs=0.001) and mean.max() > 0.97   # docstring
    lines = [np.linalg.norm(np.fft.rfft(-e * p * rate[:per])[2:61]) for p in (emp, mean)]
    assert lines[0] == pytest.approx(lines[1], rel=0.03)
    quasi = 1 / (1 + np.exp(-2 * (np.abs(rate[:per]) - half) / width))   # it follows the rate
    assert np.abs(mean - quasi).max() < 0.1 and np.abs(mean - quasi).mean() < 0.02


def test_cracked_strand_reads_the_negative_half_low_past_the_crack_only():
    """Check the gate (negative rate, tilt past 6 deg), its duty and its lines in closed form."""
    a = SHAPES['scale_factor_asymmetry'][1][1]['a']
    crack = SWING.PHI_CRACK
    for deg in (20.0, 10.0, 5.0):
        amp = np.deg2rad(deg)
        t, angle, rate, x, out = run('scale_factor_asymmetry', {'a': a}, 20.0, amp=amp)
        err = out[1] - x
        on = (rate < 0) & (angle > crack)
        assert np.array_equal(err != 0, on)
        assert np.allclose(err[on], -2 * a * rate[on], rtol=1e-9, atol=1e-17)    # low by 2 a
        want = (np.pi / 2 - np.arcsin(crack / amp)) / (2 * np.pi) if amp > crack else 0.0
        assert on.mean() == pytest.approx(want, abs=1e-3), deg
    assert (np.pi / 2 - np.arcsin(crack / AMP)) / (2 * np.pi) == pytest.approx(0.201, abs=1e-3)
    # The 2f and 3f lines against the integral over the gated arc, pi / 2 < theta < theta_c.
    t, angle, rate, x, out = run('scale_factor_asymmetry', {'a': a}, 20.0)
    c = np.fft.rfft(out[1] - x) / t.size
    th0, th1 = np.pi / 2, np.pi - np.arcsin(crack / AMP)
    for k in (2, 3):
        def part(th):
            return (np.exp(1j * (1 - k) * th) / (2j * (1 - k))
                    - np.exp(-1j * (1 + k) * th) / (2j * (1 + k)))
        line = -2 * a * AMP * W / np.pi * (part(th1) - part(th0))
        assert 2 * abs(c[4 * k]) == pytest.approx(abs(line), rel=5e-3), k
    zs = [SWING.detectability('scale_factor_asymmetry', {'a': a}, period_s=p) for p in (5, 2.5)]
    assert zs[1] == pytest.approx(2 * zs[0], rel=1e-3)             # |w| doubles, the gate stays


def test_interpolated_stamps_are_exact_at_the_captures_and_scatter_between():
    """Check zero error at the captures, the variance along the block, Gaussianity and PSD."""
    fn, levels = SHAPES['timestamp_jitter']
    sigma = levels[1]['sigma']
    x = unit_stamp_errors(fn, sigma, 20, runs=8)
    pos = np.arange(x.shape[1]) % SWING.ANCHOR
    assert np.all(x[:, pos == 0] == 0)                                  # captured: exact
    share = pos / SWING.ANCHOR
    for k in range(1, SWING.ANCHOR):
        want = 1 + (1 - share[k]) ** 2 + share[k] ** 2
        assert np.mean(x[:, pos == k] ** 2) == pytest.approx(want, rel=0.04), k
    unit = (x / np.sqrt(1 + (1 - share) ** 2 + share ** 2))[:, pos != 0]
    assert np.mean(unit ** 4) / np.mean(unit ** 2) ** 2 == pytest.approx(3.0, rel=0.03)
    b1, b2 = x[:, pos == 8], x[:, pos == 24]                  # same block: shared captures
    assert np.mean(b1 * b2) == pytest.approx(0.75 * 0.25 + 0.25 * 0.75, abs=0.04)
    acv = [np.mean(x[:, :x.shape[1] - k] * x[:, k:]) for k in range(2 * SWING.ANCHOR + 1)]
    assert np.allclose(acv, SWING.anchored_acv(), atol=0.02)
    assert SWING.anchored_acv()[0] == pytest.approx(np.mean(1 + (1 - share) ** 2 + share ** 2
                                                            - 2 * (pos == 0)), rel=1e-9)
    f, pxx = signal.welch(x * sigma, fs=1000.0, nperseg=4096)
    want = 2 * SWING.anchored_psd(f, sigma, 1000.0)                      # one-sided
    for lo in (2.0, 5.0, 20.0, 31.0, 60.0, 150.0, 400.0):
        band = (f >= lo) & (f < lo * 1.5)
        assert pxx.mean(axis=0)[band].mean() == pytest.approx(want[band].mean(), rel=0.05), lo
    grid = np.linspace(-500, 500, 100001)
    assert np.trapezoid(SWING.anchored_psd(grid, sigma, 1000.0), grid) == pytest.approx(
        sigma ** 2 * SWING.anchored_acv()[0], rel=1e-6)


def test_learning_head_sheds_its_error_with_the_distance_travelled():
    """Check the static error at rest and each harmonic's decay with the periods travelled."""
    a = SHAPES['encoder_cyclic_error'][1][1]['a']
    lines = SWING.LEARN_LINES

    def still(u):
        return np.full_like(u, 0.1), np.zeros_like(u)
    t = np.arange(20000) * 1e-3
    enc = SHAPES['encoder_cyclic_error'][0](t, t * 0, t.copy(), np.full(t.size, 0.1), still,
                                            rng(0), a=a)[3]
    static = a * sum(r * np.sin(k * lines * 0.1 + p) for k, r, p, _ in SWING.LEARN)
    assert np.allclose(enc - 0.1, static, rtol=1e-12)                     # at rest: no learning
    for period in (5.0, 2.5):
        t, angle, rate, x, out = run('encoder_cyclic_error', {'a': a}, 900.0, period=period)
        assert np.array_equal(out[0], t) and np.array_equal(out[1], x)
        assert np.array_equal(out[2], t)
        e, u = out[3] - angle, lines * angle
        per_s = 4 * AMP * lines / (2 * np.pi) / period           # periods travelled a second
        for mid in (50.0, 300.0, 600.0, 850.0):
            win = np.abs(t - mid) <= period / 2
            cols = np.c_[np.sin(u[win]), np.cos(u[win]), np.sin(2 * u[win]), np.cos(2 * u[win])]
            c = np.linalg.lstsq(cols, e[win], rcond=None)[0]
            for k, r, p, big in SWING.LEARN:
                got = np.hypot(c[2 * k - 2], c[2 * k - 1])
                assert got == pytest.approx(a * r * np.exp(-per_s * mid / big), rel=0.01), k
                assert np.arctan2(c[2 * k - 1], c[2 * k - 2]) == pytest.approx(p, abs=0.01)
    assert 4 * AMP * lines / (2 * np.pi) == pytest.approx(333.3, abs=0.1)
    assert np.exp(-180 * 333.33 / SWING.LEARN[0][3]) == pytest.approx(0.135, abs=0.001)


def test_swing_harness_finds_set_ag():
    """Check that the held-out set list the harness offers includes ag, by its file alone."""
    assert 'ag' in SETS.letters('validate_diagnosis_swing_heldout', 'b')
    assert SETS.module('validate_diagnosis_swing_heldout', 'ag', 'b') == SWING.__name__
