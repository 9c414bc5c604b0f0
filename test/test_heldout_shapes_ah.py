# Held-out set AH (bench/validate_diagnosis_swing_heldout_ah.py, swing only): the generators do
# what their docstring claims, the edges sit at z ~ 4 and the levels are the solved ones, and the
# swing harness finds the set (by bench/heldout_sets). THE GENERATORS only, never the diagnosis.
"""Generator tests of held-out swing set AH."""
import bench_script

from heldout_common import AMP, G0, lines, swing_runner, W
from heldout_common import rng, S_N, solved_levels_test, swing_set_tests

import numpy as np

import pytest

from scipy import signal

SWING = bench_script.load('validate_diagnosis_swing_heldout_ah')
SETS = bench_script.load('heldout_sets')
SHAPES = SWING.shapes(1000.0)
OFF = {'time_delay': {'s': 0.0}, 'g_sensitivity': {'gy': 0.0},
       'scale_factor_nonlinearity': {'k': 0.0}, 'scale_factor_asymmetry': {'k': 0.0},
       'timestamp_jitter': {'m': 0.0}, 'encoder_cyclic_error': {'a': 0.0}}
run = swing_runner(SHAPES)


(test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
 test_off_levels_leave_the_run_unchanged) = swing_set_tests(SWING, OFF)

# all but the delay's (a slow solve)
test_levels_are_the_solved_ones = solved_levels_test(
    SWING, ['g_sensitivity', 'scale_factor_nonlinearity', 'scale_factor_asymmetry',
            'timestamp_jitter', 'encoder_cyclic_error'])


@pytest.mark.parametrize('level', [0, 1])
def test_link_levels_are_the_solved_ones_to_their_last_digit(level):
    """Check the slow link's weak and strong slots: z = 25, 100 lie within one last digit."""
    s = SHAPES['time_delay'][1][level]['s']
    unit = 10.0 ** (np.floor(np.log10(s)) - 2)
    lo, hi = (SWING.detectability('time_delay', {'s': s + d * unit}) for d in (-1, 1))
    assert lo < SWING.TARGETS[level] < hi


def test_retrying_link_serves_in_order_and_loses_in_the_null():
    """Check the queue against its recursion, the loss law by tilt and whole-slot retries."""
    fn, levels = SHAPES['time_delay']
    s = levels[1]['s']
    t, angle, rate, x, (ti, g, te, enc) = run('time_delay', {'s': s}, 20.0, noise=S_N)
    assert np.array_equal(g, x) and np.array_equal(te, t) and np.array_equal(enc, angle)
    fails = rng(10).geometric(1.0 - SWING.loss(angle)) - 1           # the generator's draws
    done, want = -np.inf, []
    for tk, kk in zip(t.tolist(), fails.tolist()):       # done_k = max(t_k, done) + s (1 + K)
        done = max(tk, done) + s * (1 + kk)
        want.append(done - s)
    assert np.allclose(ti, want, rtol=0, atol=1e-12)
    assert np.all(np.diff(ti) >= s * (1 - 1e-9)) and np.all(ti >= t - 1e-12)
    assert SWING.loss(np.array([SWING.PHI_NULL]))[0] == pytest.approx(SWING.P_NULL)
    assert SWING.loss(np.array([-0.3, 0.0]))[0] == pytest.approx(SWING.P_FLOOR, abs=1e-9)
    # At the edge the queue is mostly empty: a sample whose predecessor was through in time is
    # late by K whole slots, K geometric with the loss at its tilt.
    s = levels[2]['s']
    t, angle, rate, x, out = run('time_delay', {'s': s}, 900.0, seed=3)
    lat = out[0] - t
    free = np.r_[False, out[0][:-1] + s <= t[1:] + 1e-12]
    k = lat[free] / s
    assert np.allclose(k, np.round(k), atol=1e-6) and free.mean() > 0.8
    p = SWING.loss(angle[free])
    for lo, hi in ((-0.4, 0.1), (0.15, 0.2), (0.22, 0.26), (0.26, 0.3), (0.32, 0.36)):
        band = (angle[free] >= lo) & (angle[free] < hi)
        share = np.mean(k[band] > 0.5)
        assert share == pytest.approx(np.mean(p[band]), abs=0.01 + 0.05 * share), (lo, hi)
        assert np.mean(k[band]) == pytest.approx(np.mean(p[band] / (1 - p[band])), rel=0.06)


def test_retrying_link_mean_latency_follows_the_backlog_law():
    """Check ``arq_mean`` against runs at the weak level, the period and the amplitude."""
    s = SHAPES['time_delay'][1][0]['s']
    per = 5000
    mean = SWING.arq_mean(AMP * np.sin(W * np.arange(per) * 1e-3), s, 1e-3)
    got = np.mean([(run('time_delay', {'s': s}, 900.0, seed=seed)[4][0]
                    - np.arange(900000) * 1e-3).reshape(-1, per).mean(axis=0)
                   for seed in range(3)], axis=0)
    assert got.mean() == pytest.approx(mean.mean(), rel=0.04)
    binned = [u.reshape(-1, 250).mean(axis=1) for u in (got, mean)]
    assert np.abs(binned[0] - binned[1]).max() < 0.08 * binned[1].max()
    assert mean.max() == pytest.approx(5.65e-3, rel=0.01) and mean.mean() < 0.1 * mean.max()
    tilt = AMP * np.sin(W * np.argmax(mean) * 1e-3)                   # it backs up in the null
    assert abs(tilt - SWING.PHI_NULL) < 2 * SWING.NULL_SD
    # A swing of 6 deg never reaches the null: the floor's whole-slot retries alone.
    amp = np.deg2rad(6.0)
    t, angle, rate, x, out = run('time_delay', {'s': s}, 300.0, amp=amp, seed=4)
    p = SWING.loss(angle)
    assert np.mean(out[0] - t) == pytest.approx(s * np.mean(p / (1 - p)), rel=0.05)
    assert np.mean(p / (1 - p)) < 0.04
    # At 2.5 s the null is crossed twice as fast: less backs up in it.
    fast = SWING.arq_mean(AMP * np.sin(2 * W * np.arange(2500) * 1e-3), s, 1e-3)
    assert fast.max() < 0.8 * mean.max()


def test_failover_drops_the_compensation_once_in_mid_run():
    """Check nothing before the failover, the raw g_y f_y after, its spread and its z."""
    gy = SHAPES['g_sensitivity'][1][1]['gy']
    shares = []
    for seed in range(12):
        t, angle, rate, x, out = run('g_sensitivity', {'gy': gy}, 100.0, noise=S_N, seed=seed)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
        err = out[1] - x
        start = np.flatnonzero(err != 0)[0]
        assert np.all(err[:start] == 0)
        assert np.allclose(err[start:], gy * G0 * np.sin(angle[start:]), rtol=1e-9, atol=1e-15)
        shares.append(t[start] / t[-1])
    assert min(shares) >= 0.45 - 1e-3 and max(shares) <= 0.55 + 1e-3
    assert np.std(shares) > 0.015                                    # drawn per run
    n_arw, amp, enc, w, s = bench_script.load('heldout_detect').swing_scales(5.0, 900.0)
    t = np.arange(900000) * 1e-3
    bias = gy * G0 * np.sin(AMP * np.sin(W * t))
    zs = [SWING.rate_z(bias * (t >= share * t[-1]), AMP * W * np.cos(W * t), n_arw, 1000.0)
          for share in (0.45, 0.5, 0.55)]
    assert zs[1] == pytest.approx(SWING.detectability('g_sensitivity', {'gy': gy}), rel=1e-3)
    assert zs[0] / zs[1] == pytest.approx(1.05, abs=0.01)             # docstring: 0.95-1.05
    assert zs[2] / zs[1] == pytest.approx(0.95, abs=0.01)


def test_peak_detector_holds_the_largest_recent_rate():
    """Check the detector's recursion, its release, the gain drop and its held-peak lines."""
    fn, levels = SHAPES['scale_factor_nonlinearity']
    k = levels[1]['k']
    t, angle, rate, x, out = run('scale_factor_nonlinearity', {'k': k}, 20.0, noise=S_N)
    a = np.exp(-1e-3 / SWING.RELEASE_S)
    held, want = 0.0, []
    for v in rate.tolist():
        held = max(abs(v), a * held)
        want.append(held)
    assert np.allclose(SWING.peak_envelope(rate, 1e-3), want, rtol=1e-9, atol=0)
    assert np.allclose(out[1], x - k * np.array(want) * rate, rtol=0, atol=1e-15)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)

    def stepped(u):                                        # 0.4 rad/s, then 0.1 rad/s from 2 s
        return 0.4 * u + np.where(u < 2.0, 0.0, -0.3 * (u - 2.0)), np.where(u < 2.0, 0.4, 0.1)
    t, angle, rate, x, out = run('scale_factor_nonlinearity', {'k': k}, 8.0, stand=stepped)
    gain = (out[1] - x) / rate
    assert np.allclose(gain[t < 2.0], -k * 0.4, rtol=1e-9)          # steady: k |w| off the gain
    caught = 2.0 + SWING.RELEASE_S * np.log(4.0)
    late = (t >= 2.0) & (t < caught - 0.01)
    assert np.allclose(gain[late], -k * 0.4 * a ** ((t[late] - 2.0) * 1000 + 1), rtol=1e-6)
    assert np.allclose(gain[t > caught + 0.01], -k * 0.1, rtol=1e-9)   # released to the rate
    for period, floor, lag, fifth in ((5.0, 0.58, -8.0, 0.25), (2.5, 0.73, -21.0, 0.38)):
        t, angle, rate, x, out = run('scale_factor_nonlinearity', {'k': k}, 6 * period,
                                     period=period)
        held = SWING.peak_envelope(rate, 1e-3)[t >= 2 * period]
        assert held.min() / (AMP * 2 * np.pi / period) == pytest.approx(floor, abs=0.005)
        c = lines((out[1] - x)[t >= 2 * period], int(period * 1000))
        assert np.abs(c[2:40:2]).max() < 1e-6 * np.abs(c[3])         # odd lines only
        assert np.degrees(np.angle(-c[3])) == pytest.approx(lag, abs=1.0)   # lagging
        assert abs(c[5] / c[3]) == pytest.approx(fifth, abs=0.01)
    t = np.arange(5000) * 1e-3
    memoryless = lines(-np.abs(AMP * W * np.cos(W * t)) * AMP * W * np.cos(W * t), 5000)
    held = lines(-SWING.peak_envelope(np.tile(AMP * W * np.cos(W * t), 3), 1e-3)[10000:]
                 * AMP * W * np.cos(W * t), 5000)
    assert abs(held[3]) == pytest.approx(0.6 * abs(memoryless[3]), abs=0.02 * abs(held[3]))
    zs = [SWING.detectability('scale_factor_nonlinearity', {'k': k}, period_s=p)
          for p in (5.0, 2.5)]
    assert zs[1] / zs[0] == pytest.approx(2.74, abs=0.02)


def test_sagging_mass_parts_the_gains_with_the_tilt():
    """Check the gains 1 +- k g (1 - cos phi), the even lines, the peak's phase and scaling."""
    k = SHAPES['scale_factor_asymmetry'][1][1]['k']
    t, angle, rate, x, out = run('scale_factor_asymmetry', {'k': k}, 20.0, noise=S_N)
    part = k * G0 * (1 - np.cos(angle))
    assert np.allclose(out[1] - x, np.sign(rate) * part * rate, rtol=1e-9, atol=1e-15)
    assert np.array_equal(out[0], t) and np.array_equal(out[3], angle)
    assert part.max() == pytest.approx(k * G0 * (1 - np.cos(AMP)), rel=1e-6)
    assert k * G0 * (1 - np.cos(AMP)) == pytest.approx(0.0315, abs=5e-4)    # docstring: 3.2 %
    err = out[1] - x
    c = lines(err, 5000)
    assert np.abs(c[1:40:2]).max() < 1e-9 * np.abs(c[2])              # even lines only
    th = np.mod(W * t, np.pi)
    peak = th[np.argmax(err)]
    assert min(peak, np.pi - peak) == pytest.approx(np.arctan(np.sqrt(2)), abs=0.02)
    assert np.abs(err[np.abs(angle) < 1e-3]).max() < 1e-4 * err.max()    # none on the level
    half = run('scale_factor_asymmetry', {'k': k}, 20.0, amp=AMP / 2)
    ratio = np.linalg.norm(lines(half[4][1] - half[3], 5000)[2:61]) / np.linalg.norm(c[2:61])
    assert ratio == pytest.approx(1 / 8, rel=0.01)                     # the amplitude cubed
    zs = [SWING.detectability('scale_factor_asymmetry', {'k': k}, period_s=p)
          for p in (5.0, 2.5)]
    assert zs[1] == pytest.approx(2 * zs[0], rel=1e-3)


def test_bracketed_stamps_are_mostly_exact_and_symmetric_heavy_tailed():
    """Check the exact share, symmetry, variance, kurtosis, whiteness and the handlers' law."""
    fn, levels = SHAPES['timestamp_jitter']
    m = levels[1]['m']
    t = np.arange(2 ** 18) * 1e-3
    errs = []
    for seed in range(4):
        out = fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(20 + seed), m=m)
        assert np.array_equal(out[0], t) and np.array_equal(out[3], np.sin(W * t))
        assert np.all(np.diff(out[2]) > 0)
        errs.append(out[2] - t)
    e = np.concatenate(errs)
    q = SWING.IRQ_SHARE
    assert np.mean(e == 0) == pytest.approx((1 - q) ** 2, abs=0.002)
    assert np.abs(e).max() <= 0.45e-3 + 1e-12
    hit = e[e != 0]
    assert np.mean(hit > 0) == pytest.approx(0.5, abs=0.01)
    assert np.mean(e) == pytest.approx(0.0, abs=0.02 * np.std(e))
    assert np.var(e) == pytest.approx(SWING.irq_variance(m, 1e-3), rel=0.04)
    kurt = np.mean(e ** 4) / np.mean(e ** 2) ** 2
    assert 100 < kurt < 250                                            # docstring: ~160
    for lag in (1, 2, 5):
        r = np.mean([np.corrcoef(u[:-lag], u[lag:])[0, 1] for u in errs])
        assert abs(r) < 0.01, lag
    one = np.abs(hit) * 2                            # mostly single handlers: P, log-normal
    assert np.median(one) == pytest.approx(m, rel=0.05)
    quart = np.diff(np.quantile(np.log(one), [0.25, 0.75]))[0] / 1.349
    assert quart == pytest.approx(SWING.IRQ_SPREAD, rel=0.05)
    f, pxx = signal.welch(e, fs=1000.0, nperseg=4096)
    assert np.abs(pxx[1:] / (2 * SWING.irq_variance(m, 1e-3) / 1000.0) - 1).mean() < 0.1


def test_detent_rings_the_bracket_up_at_its_speed():
    """Check the static detent at rest, the bracket's response at steady speeds, the swing."""
    a = SHAPES['encoder_cyclic_error'][1][1]['a']
    pairs = SWING.DETENT_PAIRS

    def still(u):
        return np.full_like(u, 0.1), np.zeros_like(u)
    t = np.arange(5000) * 1e-3
    enc = SHAPES['encoder_cyclic_error'][0](t, t * 0, t.copy(), np.full(t.size, 0.1), still,
                                            rng(0), a=a)[3]
    assert np.allclose(enc - 0.1, a * np.sin(2 * pairs * 0.1 + SWING.DETENT_PHASE), rtol=1e-9)
    b, den = SWING.bracket_filter(1000.0)
    for f_hz in (10.0, SWING.BRACKET_HZ, 80.0):
        v = 2 * np.pi * f_hz / (2 * pairs)                          # the speed that drives f_hz

        def steady(u, v=v):
            return v * u, np.full_like(u, v)
        t, angle, rate, x, out = run('encoder_cyclic_error', {'a': a}, 6.0, stand=steady)
        late = t > 3.0
        u = 2 * np.pi * f_hz * t[late]
        c = np.linalg.lstsq(np.c_[np.sin(u), np.cos(u)], (out[3] - angle)[late], rcond=None)[0]
        gain = abs(signal.freqz(b, den, worN=[2 * np.pi * f_hz / 1000.0])[1][0])
        assert np.hypot(*c) == pytest.approx(a * gain, rel=1e-6), f_hz
    assert abs(signal.freqz(b, den, worN=[2 * np.pi * SWING.BRACKET_HZ / 1000.0])[1][0]) == (
        pytest.approx(1 / (2 * SWING.BRACKET_ZETA), rel=1e-6))
    for period, most in ((5.0, 7.8), (2.5, 5.4)):
        t, angle, rate, x, out = run('encoder_cyclic_error', {'a': a}, 4 * period, period=period)
        assert np.array_equal(out[0], t) and np.array_equal(out[1], x)
        e = (out[3] - angle)[t >= period]
        assert np.abs(e).max() / a == pytest.approx(most, abs=0.1), period
        speed = np.abs(rate[t >= period])[np.argmax(np.abs(e))]
        assert 0.15 < speed < 0.30                                 # near 0.245 rad/s, rung on
        turning = np.abs(rate[t >= period]) < 0.005
        assert np.abs(e[turning]).max() < (1.1 if period == 5.0 else 3.0) * a


def test_swing_harness_finds_set_ah():
    """Check that the held-out set list the harness offers includes ah, by its file alone."""
    assert 'ah' in SETS.letters('validate_diagnosis_swing_heldout', 'b')
    assert SETS.module('validate_diagnosis_swing_heldout', 'ah', 'b') == SWING.__name__
