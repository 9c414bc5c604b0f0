# Held-out set S (bench/validate_diagnosis_heldout_s.py, static only: no swing set S): the
# generators do what their docstrings claim, and the static harness reaches them by
# --held-out s. THE GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import avar, check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import signal, stats

STATIC = bench_script.load('validate_diagnosis_heldout_s')
SHAPES = STATIC.shapes(DT, SIG, N_ARW)
N2H = 720000                                        # samples in the harness's 2 h record


def acf(y, lags):
    y = y - y.mean()
    return np.array([np.mean(y[:-k] * y[k:]) for k in lags]) / np.mean(y * y)


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_zero_levels_leave_the_record_unchanged():
    x = white(20000, 2)
    for name, p in [('internal_lowpass', {'tau': 0.0}), ('vibration', {'amplitude': 0.0}),
                    ('temperature_drift', {'amplitude': 0.0}), ('bias_instability', {'b': 0.0}),
                    ('rate_random_walk', {'k': 0.0}), ('gauss_markov', {'sd': 0.0, 'tc': 2.0}),
                    ('resonance', {'sigma': 0.0}), ('stale_samples', {'delta': 0.0})]:
        assert np.allclose(SHAPES[name][0](x.copy(), rng(3), **p), x, rtol=0, atol=1e-15), name
    clean = SHAPES['quantization'][0](x.copy(), rng(3), q=1e-13)          # the clean limit
    assert np.allclose(clean, x, rtol=0, atol=1e-9)


def test_static_harness_takes_set_s_by_held_out_s(monkeypatch):
    harness = bench_script.load('validate_diagnosis')
    assert 's' in harness.held_out_letters()
    seen = []
    monkeypatch.setattr(harness, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    harness.main(['--held-out', 's'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]
    for name, (fn, levels) in SHAPES.items():                       # through make_record
        x = harness.make_record([(name, 1)], 3000, 5, shapes=SHAPES)
        assert x.shape == (3000,) and np.all(np.isfinite(x)), name
        assert np.array_equal(x, harness.make_record([(name, 1)], 3000, 5, shapes=SHAPES))


def test_sense_bandwidth_filters_the_mechanical_share_onto_a_shelf():
    fn, levels = SHAPES['internal_lowpass']
    tau, n = 0.05, 2 ** 20
    m, e = STATIC.split_white(SIG * rng(4).standard_normal(n), SIG, rng(5))
    assert np.var(m) == pytest.approx(STATIC.MECH * SIG ** 2, rel=0.01)
    assert np.var(e) == pytest.approx((1 - STATIC.MECH) * SIG ** 2, rel=0.01)
    assert abs(np.corrcoef(m, e)[0, 1]) < 0.005                      # independent shares
    x = white(n, 6)
    y = fn(x.copy(), rng(7), tau=tau)
    mm, ee = STATIC.split_white(x, SIG, rng(7))
    a = np.exp(-DT / tau)
    assert np.allclose(y, signal.lfilter([1 - a], [1, -a], mm, zi=[a * mm[0]])[0] + ee)
    assert np.mean(y) == pytest.approx(np.mean(x), abs=3 * SIG / np.sqrt(n))   # DC gain 1
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.shelf_gain2(f, tau, DT) * 2 * SIG ** 2 * DT
    for lo, hi in ((0.1, 1), (2, 5), (10, 20), (40, 50)):
        k = (f > lo) & (f < hi)
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.05), lo
    top = np.mean(p[f > 40]) / (2 * SIG ** 2 * DT)                   # the shelf, not zero
    assert top == pytest.approx(1 - STATIC.MECH, abs=0.02)
    assert acf(y, [1])[0] == pytest.approx(STATIC.shelf_r1(tau, DT), abs=0.005)
    r1 = [STATIC.shelf_r1(t, DT) for t in (0.002, 0.015, 0.1, 1.0)]
    assert r1[1] > r1[2] > r1[3]                                     # saturates, then falls
    assert STATIC.detectability('internal_lowpass', levels[2], DT, SIG, N_ARW) == \
        pytest.approx(STATIC.shelf_r1(levels[2]['tau'], DT) * np.sqrt(N2H))


def test_generator_rocks_one_sine_a_firing_with_scattered_and_missing_cycles():
    fn, levels = SHAPES['vibration']
    amp, n = 1.0, N2H
    y = fn(np.zeros(n), rng(8), amplitude=amp)
    g = rng(8)
    t = np.arange(n) * DT
    phase = g.uniform()
    count = int(np.floor(STATIC.ENGINE_HZ * t[-1] + phase)) + 1
    amps = STATIC.cycle_amplitudes(count, amp, g)
    assert np.array_equal(y, STATIC.engine(t, amps, phase))
    u = STATIC.ENGINE_HZ * t + phase
    k = np.floor(u).astype(int)
    s = np.sin(2 * np.pi * (u - k))
    fit = np.bincount(k, y * s, count) / np.maximum(np.bincount(k, s * s, count), 1e-30)
    seen = np.bincount(k, np.abs(s) > 0.3, count) > 0                # cycles with a clear sample
    assert np.allclose(fit[seen], amps[seen], atol=1e-9)              # one sine a cycle
    silent = fit[seen] == 0
    assert np.mean(silent) == pytest.approx(STATIC.MISFIRE, abs=0.004)
    fired = fit[seen][~silent]
    assert np.mean(fired) == pytest.approx(amp, abs=0.002)
    assert np.std(fired) == pytest.approx(STATIC.CYCLE_CV * amp, rel=0.02)
    line = 2 * abs(np.mean(y * np.exp(-2j * np.pi * u)))               # the mean line
    assert line == pytest.approx(amp * (1 - STATIC.MISFIRE), rel=0.01)
    rest = y - amp * (1 - STATIC.MISFIRE) * s                          # the pedestal
    v = np.var(amps)
    assert np.var(rest) == pytest.approx(v * np.mean(s * s), rel=0.05)


def test_lagging_compensation_leaves_a_transient_that_returns_to_zero():
    fn, levels = SHAPES['temperature_drift']
    y = fn(np.zeros(N2H), rng(9), amplitude=1.0)
    t = np.arange(N2H) * DT + rng(9).uniform(0, 60)
    assert np.allclose(y, STATIC.lag_residual(t, 1.0), atol=1e-12)
    tt = np.arange(800000) * DT                                      # two lags from power-on
    a_d, a_s = np.exp(-DT / STATIC.DIE_S), np.exp(-DT / STATIC.SENSOR_S)
    die = signal.lfilter([1 - a_d], [1, -a_d], np.ones(tt.size))
    sensor = signal.lfilter([1 - a_s], [1, -a_s], die)
    assert np.allclose(die - sensor, STATIC.lag_bracket(tt + DT), atol=2e-4)
    peak = STATIC.lag_peak_time()
    assert peak == pytest.approx(tt[np.argmax(die - sensor)], abs=2.0)
    assert STATIC.lag_residual(peak, 1.0) == pytest.approx(1.0)
    assert y.max() == pytest.approx(1.0, abs=1e-6) and y[-1] < 0.002   # peak A, back to 0
    assert STATIC.lag_residual(0.0, 1.0) == 0.0
    i = np.argmax(y)
    assert np.all(np.diff(y[:i]) > 0) and np.all(np.diff(y[i + 1:]) < 0)


def test_landscape_levels_flip_and_reset_the_faster_ones_with_exponential_memory():
    fn, levels = SHAPES['bias_instability']
    w = STATIC.tree_rates()
    above = np.r_[np.cumsum(w[::-1])[::-1][1:], 0.0]
    assert np.all(w > 0)
    assert np.allclose(2 * w + above, 1 / STATIC.TREE_TAUS)
    n = 2 ** 20
    bits = STATIC.tree_bits(n, DT, rng(11))
    assert set(np.unique(bits)) == {-1, 1}
    y = fn(np.zeros(n), rng(11), b=1.0)
    assert np.allclose(y, bits.sum(axis=0) / np.sqrt(bits.shape[0]))   # a lattice
    b = bits.astype(float)
    for lv in (0, 2, 5):
        tau = STATIC.TREE_TAUS[lv]
        for lag in (max(1, int(round(tau / DT / 2))), int(round(tau / DT))):
            got = np.mean(b[lv, :-lag] * b[lv, lag:])
            assert got == pytest.approx(np.exp(-lag * DT / tau), abs=0.03), (lv, lag)
    change = np.diff(bits, axis=1) != 0
    for lv in (6, 8):                                                # a slow crossing resets
        hit = change[lv]
        assert np.all(np.abs(change[:3, hit].mean(axis=1) - 0.5) < 0.06), lv
        assert np.all(change[:3].mean(axis=1)[1:] < 0.15)
    ys = [fn(np.zeros(n), rng(12 + i), b=1.0) for i in range(3)]
    big_t = n * DT                                                   # a record's own variance
    u = np.linspace(0, big_t, 200001)
    kept = 1 - 2 / big_t ** 2 * np.trapezoid((big_t - u) * STATIC.landscape_cov(u, 1.0), u)
    assert np.mean([np.var(v) for v in ys]) == pytest.approx(kept, rel=0.1)
    for m in (10, 300):
        got = np.mean([avar(v, [m])[0] for v in ys])
        want = sum(STATIC.gm_avar(m * DT, 1 / np.sqrt(19), tt) for tt in STATIC.TREE_TAUS)
        assert got == pytest.approx(float(np.squeeze(want)), rel=0.2), m
    cov = STATIC.landscape_cov(np.geomspace(1, 100, 5), 1.0)
    assert np.diff(cov) == pytest.approx(np.diff(cov)[0], rel=0.15)  # ~ log in the lag: 1/f


def test_slips_recover_partly_so_the_walk_bends_to_a_lower_intensity():
    fn, levels = SHAPES['rate_random_walk']
    k = 1e-4
    y = fn(np.zeros(N2H), rng(20), k=k)
    a = np.exp(-DT / STATIC.RECOVER_S)
    assert np.all(np.diff(y) != 0)                                   # recovering between slips
    g = rng(20)
    burn = int(10 * STATIC.RECOVER_S / DT)
    count = g.poisson(STATIC.SLIP_RATE * DT, N2H + burn)
    steps = np.sqrt(count) * STATIC.slip_size(k) * g.standard_normal(N2H + burn)
    kern = (1 - STATIC.RECOVER) + STATIC.RECOVER * a ** np.arange(N2H + burn)
    want = signal.fftconvolve(steps, kern)[:N2H + burn]
    want = want[burn:] - (1 - STATIC.RECOVER) * np.cumsum(steps)[burn - 1]
    assert np.allclose(y, want, atol=1e-9 * np.abs(want).max())
    assert np.mean(count > 0) == pytest.approx(STATIC.SLIP_RATE * DT, rel=0.05)
    ys = [fn(np.zeros(N2H), rng(21 + i), k=k) for i in range(8)]
    short = np.mean([avar(v, [20])[0] for v in ys]) / (20 * DT / 3)   # intensity at 0.2 s
    long_ = np.mean([avar(v, [30000])[0] for v in ys]) / (300 / 3)    # at 300 s
    s2 = STATIC.SLIP_RATE * STATIC.slip_size(k) ** 2
    assert short == pytest.approx(s2, rel=0.1)
    assert long_ == pytest.approx(k * k, rel=0.35) and long_ < 0.25 * short   # bends down
    for m in (100, 3000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        assert got == pytest.approx(STATIC.slip_avar(m * DT, k)[0], rel=0.15), m


def test_switched_kinetics_keep_the_variance_and_switch_the_memory():
    fn, levels = SHAPES['gauss_markov']
    sd, tc, n = 1.0, 2.0, 2 ** 21
    ys, modes = zip(*[STATIC.kinetics(n, sd, tc, DT, rng(30 + i)) for i in range(3)])
    y = fn(np.zeros(n), rng(30), sd=sd, tc=tc)
    assert np.allclose(y, ys[0])
    allv = np.concatenate(ys)
    assert np.var(allv) == pytest.approx(1.0, rel=0.05)
    assert abs(stats.kurtosis(allv)) < 0.1 and abs(stats.skew(allv)) < 0.1   # Gaussian
    for mode in (0, 1):                                              # the memory switches
        num = den = 0.0
        for v, md in zip(ys, modes):
            k = np.flatnonzero((md[1:] == mode) & (md[:-1] == mode)) + 1
            num += np.sum(v[k] * v[k - 1])
            den += np.sum(v[k - 1] ** 2)
        want = np.exp(-DT / (tc * (STATIC.SLOW if mode else 1.0)))
        assert num / den == pytest.approx(want, abs=2e-4), mode
    assert np.mean(np.concatenate(modes)) == pytest.approx(0.5, abs=0.08)
    w, times = STATIC.kinetics_terms(tc)
    assert np.sum(w) == pytest.approx(1.0) and np.all(w > 0)
    assert times.min() < tc < times.max() < STATIC.SLOW * tc
    for lag in (50, 200, 800, 2000):
        got = np.mean([np.mean(v[:-lag] * v[lag:]) for v in ys])
        assert got == pytest.approx(float(STATIC.kinetics_cov(lag * DT, sd, tc)),
                                    abs=0.03), lag


def test_counted_vfc_keeps_the_angle_and_shows_idle_tones_when_coarse():
    fn, levels = SHAPES['quantization']
    n = 2 ** 20
    x = white(n, 40)
    theta = np.cumsum(x) * DT
    for p in levels:
        q = p['q']
        y = fn(x.copy(), rng(41), q=q)
        ph = rng(41).uniform()
        counts = np.round(y * DT / q + STATIC.VFC_NU)
        assert np.allclose(y * DT / q + STATIC.VFC_NU, counts, atol=1e-6)   # whole counts
        k = np.arange(1, n + 1)
        err = np.cumsum(y) * DT - theta
        want = -q * (np.mod(STATIC.VFC_NU * k + theta / q + ph, 1.0) - ph)
        assert np.allclose(err, want, atol=1e-9 + 1e-6 * q)         # -Q frac(psi): bounded
        rel = STATIC.vfc_excess(q, DT, N_ARW)
        ex = [avar(y, [m])[0] / avar(x, [m])[0] - 1 for m in (1, 10)]
        assert ex == pytest.approx(rel, rel=0.1), q
    q = levels[1]['q'] * 4                                           # coarse: idle tones
    y = fn(x.copy(), rng(42), q=q)
    f, pe = signal.welch(np.cumsum(y - x) * DT, fs=1 / DT, nperseg=2 ** 12)   # angle error
    nu = np.mod(STATIC.VFC_NU + 0.003 * DT / q, 1.0)
    tone = np.abs(f - nu / DT) < 0.5
    assert f[np.argmax(pe)] == pytest.approx(nu / DT, abs=0.1)
    assert np.mean(pe[tone]) > 30 * np.median(pe)
    small = fn(x.copy(), rng(42), q=levels[2]['q'])                   # fine: white error
    e = np.cumsum(small) * DT - theta
    assert np.all(np.abs(acf(e, [1, 2, 5])) < 0.02)
    assert np.var(e) == pytest.approx(levels[2]['q'] ** 2 / 12, rel=0.03)


def test_wire_loom_is_a_line_with_a_gaussian_profile_and_steep_skirts():
    fn, levels = SHAPES['resonance']
    n = 2 ** 20
    ys = [fn(np.zeros(n), rng(50 + i), sigma=1.0) for i in range(2)]
    assert np.mean([np.var(v) for v in ys]) == pytest.approx(1.0, rel=0.05)
    f, p = signal.welch(np.array(ys), fs=1 / DT, nperseg=2 ** 13)
    p = p.mean(axis=0)
    want = STATIC.loom_psd(f, 1.0, DT)
    for lo, hi in ((5, 15), (18, 19.5), (20, 22), (22.5, 24), (26, 30), (35, 45)):
        k = (f > lo) & (f < hi)
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.1), lo
    freqs = STATIC.wire_freqs()
    assert np.std(freqs) == pytest.approx(STATIC.WIRE_HZ * STATIC.WIRE_SPREAD, rel=0.1)
    fine = np.linspace(10, 32, 22001)
    prof = STATIC.loom_psd(fine, 1.0, DT)
    half = fine[prof >= prof.max() / 2]
    fwhm = half.max() - half.min()
    sd = STATIC.WIRE_HZ * STATIC.WIRE_SPREAD
    assert fwhm == pytest.approx(2.355 * sd, rel=0.15)                # a Gaussian's width
    peak = fine[np.argmax(prof)]
    lor = prof.max() / (1 + ((fine - peak) / (fwhm / 2)) ** 2)         # same width, Lorentzian
    far = np.abs(fine - peak) > 4 * sd
    assert np.mean(prof[far]) < 0.2 * np.mean(lor[far])               # steep skirts


def test_deadband_holds_quiet_values_and_never_publishes_a_small_step():
    fn, levels = SHAPES['stale_samples']
    x = white(N2H, 70)
    for p in levels:
        d = p['delta']
        y = fn(x.copy(), rng(71), **p)
        step = np.abs(np.diff(y))
        assert np.all((step == 0) | (step >= d))                    # no step below delta
        moved = np.r_[True, step > 0]
        assert np.array_equal(y[moved], x[moved])                    # published as read
        held = np.flatnonzero(~moved)
        assert np.all(np.abs(x[held] - y[held]) < d)                 # held within delta
        r = np.round(y / STATIC.LSB)
        share = np.mean(np.diff(r) == 0)
        assert share == pytest.approx(STATIC.deadband_share(d, SIG), abs=6e-4), d
    assert STATIC.deadband_share(0.0, SIG) == pytest.approx(STATIC.repeat_share(SIG), rel=1e-4)
    d = levels[1]['delta']                                           # value-dependent holds
    y = fn(x.copy(), rng(71), delta=d)
    hold = np.diff(y) == 0
    last = y[:-1]                                                    # the published value
    p_hold = stats.norm.cdf(last + d, 0.003, SIG) - stats.norm.cdf(last - d, 0.003, SIG)
    for lo, hi in ((-0.5, 0.5), (1.5, 2.5), (-2.5, -1.5)):            # in sd from the mean
        k = (last > 0.003 + lo * SIG) & (last < 0.003 + hi * SIG)
        assert np.mean(hold[k]) == pytest.approx(np.mean(p_hold[k]), rel=0.1), lo
    assert np.mean(p_hold[np.abs(last - 0.003) < SIG / 2]) > 3 * np.mean(
        p_hold[np.abs(last - 0.003) > 2 * SIG])                       # likelier where quiet
    v, pi = STATIC.deadband_law(d, SIG)                              # its stationary law
    dv = v[1] - v[0]
    assert np.sum(pi) * dv == pytest.approx(1.0)
    assert np.var(y) == pytest.approx(np.sum(pi * (v - 0.003) ** 2) * dv, rel=0.01)
