# Held-out set Q (bench/validate_diagnosis_heldout_q.py, static only: no swing set Q): the
# generators do what their docstrings claim, and the static harness reaches them by
# --held-out q. THE GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import avar, check_static_set, DT, N_ARW, rng, SIG
import numpy as np
import pytest
from scipy import linalg, signal, stats

STATIC = bench_script.load('validate_diagnosis_heldout_q')
SHAPES = STATIC.shapes(DT, SIG, N_ARW)
N2H = 720000                                        # samples in the harness's 2 h record


def acf(y, lags):
    y = y - y.mean()
    return np.array([np.mean(y[:-k] * y[k:]) for k in lags]) / np.mean(y * y)


def test_static_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(STATIC, SHAPES)


def test_static_harness_takes_set_q_by_held_out_q(monkeypatch):
    harness = bench_script.load('validate_diagnosis')
    assert 'q' in harness.held_out_letters()
    seen = []
    monkeypatch.setattr(harness, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    harness.main(['--held-out', 'q'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]
    for name, (fn, levels) in SHAPES.items():                       # through make_record
        x = harness.make_record([(name, 1)], 3000, 5, shapes=SHAPES)
        assert x.shape == (3000,) and np.all(np.isfinite(x)), name
        assert np.array_equal(x, harness.make_record([(name, 1)], 3000, 5, shapes=SHAPES))


RANDOM = ['vibration', 'temperature_drift', 'bias_instability', 'rate_random_walk',
          'gauss_markov', 'resonance']
ZERO = {'internal_lowpass': {'tau': 1e-6}, 'vibration': {'amplitude': 0.0},
        'temperature_drift': {'amplitude': 0.0}, 'bias_instability': {'b': 0.0},
        'rate_random_walk': {'k': 0.0}, 'gauss_markov': {'sd': 0.0, 'tc': 2.0},
        'quantization': {'q': 1e-13}, 'resonance': {'sigma': 0.0}}


def test_every_shape_is_reproducible_per_seed_keeps_length_and_vanishes_at_zero_level():
    x = SIG * rng(1).standard_normal(30000) + 0.003
    for name, (fn, levels) in SHAPES.items():
        for p in levels:
            a, b = fn(x.copy(), rng(2), **p), fn(x.copy(), rng(2), **p)
            assert a.shape == x.shape and np.array_equal(a, b), name
            other = fn(x.copy(), rng(3), **p)
            assert (not np.allclose(a, other)) == (name in RANDOM), name
        clean = fn(x.copy(), rng(2), **ZERO[name])                   # the clean limit
        assert np.allclose(clean, x, rtol=0, atol=1e-9), name


def test_rc_line_is_a_diffusive_lowpass_with_a_dead_time():
    fn, levels = SHAPES['internal_lowpass']
    tau = 0.05
    m = 200                                                          # a 200-cell RC ladder
    a = (np.diag(np.full(m, -2.0)) + np.diag(np.ones(m - 1), 1) + np.diag(np.ones(m - 1), -1))
    a[-1, -1] = -1.0                                                 # open at the ADC end
    a *= m * m / tau
    for u in (0.1, 0.3, 1.0, 2.0):
        far = 1 - (linalg.expm(a * u * tau) @ np.ones(m))[-1]
        assert far == pytest.approx(float(STATIC.line_step(u * tau, tau)), abs=0.005), u
    edge = STATIC.line_step(tau * np.array([1 - 1e-9, 1 + 1e-9]), tau)
    assert edge[0] == pytest.approx(edge[1], abs=1e-8)                # the two series agree
    one_pole = 1 - np.exp(-0.05 * 2.43)                              # same 3 dB corner
    assert STATIC.line_step(0.05 * tau, tau) < 0.005 < one_pole / 20  # a dead time
    assert abs(1 / np.cosh(np.sqrt(2j * np.pi * 0.387))) ** 2 == pytest.approx(0.5, abs=0.01)
    h = STATIC.line_kernel(tau, DT)
    assert np.all(h >= 0) and np.sum(h) == pytest.approx(1.0, abs=1e-10)
    step = fn(np.r_[np.zeros(10), np.ones(100)], rng(1), tau=tau)
    assert np.allclose(step[10:], STATIC.line_step((np.arange(100) + 1) * DT, tau), atol=1e-12)
    assert np.all(np.diff(step) >= -1e-15) and step.max() <= 1 + 1e-12   # no overshoot
    x = rng(2).standard_normal(2 ** 20)
    y = fn(x.copy(), rng(3), tau=tau)
    assert acf(y, [1])[0] == pytest.approx(STATIC.line_r1(tau, DT), abs=0.005)
    assert np.var(y) == pytest.approx(np.sum(h * h), rel=0.02)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    assert np.mean(p[f > 40]) < 0.01 * np.mean(p[f < 1])            # a low-pass
    for fk in (1.0, 3.0, 6.0):                                       # the line's own response
        hd = np.sum(h * np.exp(-2j * np.pi * fk * DT * np.arange(h.size)))
        line = 1 / np.cosh(np.sqrt(2j * np.pi * fk * tau)) * np.sinc(fk * DT)   # and the hold
        assert abs(hd) == pytest.approx(abs(line), rel=0.02), fk
    edge_tau = levels[2]['tau']
    assert STATIC.detectability('internal_lowpass', levels[2], DT, SIG, N_ARW) == \
        pytest.approx(STATIC.line_r1(edge_tau, DT) * np.sqrt(N2H))
    assert 0.387 / edge_tau > 0.5 / DT                               # edge corner above Nyquist


def test_hunting_servo_rocks_at_a_trapezoid_rate_with_odd_harmonics_only():
    fn, levels = SHAPES['vibration']
    n = 100000
    y = fn(np.zeros(n), rng(4), amplitude=1.0)
    t = np.arange(n) * DT
    assert np.allclose(y, STATIC.hunt(t, 1.0, rng(4).uniform(0, 2 * np.pi)), atol=1e-12)
    assert np.abs(y).max() <= 1 + 1e-12
    assert np.mean(np.abs(y) > 1 - 1e-9) == pytest.approx(1 - STATIC.HUNT_RAMP, abs=0.01)
    assert np.mean(y ** 2) == pytest.approx(1 - 2 * STATIC.HUNT_RAMP / 3, rel=2e-3)
    m = 20000                                                        # one period, finely
    w = STATIC.hunt(np.arange(m) / m / STATIC.HUNT_HZ, 1.0)
    c = 2 * np.abs(np.fft.rfft(w)) / m
    for k in range(1, 10):
        assert c[k] == pytest.approx(STATIC.hunt_line(k, 1.0), abs=2e-4), k
    assert c[1] > 1.2 and c[3] > 0.3 and np.all(c[2:20:2] < 1e-6)    # odd harmonics only
    angle = np.cumsum(y) * DT                                        # a rounded triangle
    period = 1 / STATIC.HUNT_HZ
    swing = period / 2 * (1 - STATIC.HUNT_RAMP / 2)
    assert np.ptp(angle) == pytest.approx(swing, rel=0.05)
    z = STATIC.detectability('vibration', levels[1], DT, SIG, N_ARW)
    want = levels[1]['amplitude'] * np.sqrt(1 - 2 * STATIC.HUNT_RAMP / 3) * np.sqrt(N2H) / SIG
    assert z == pytest.approx(want, rel=1e-3)


def test_heat_soak_rises_as_the_square_root_of_time_without_settling():
    fn, levels = SHAPES['temperature_drift']
    y = fn(np.zeros(N2H), rng(7), amplitude=1.0)
    t = np.arange(N2H) * DT + rng(7).uniform(0, 60)
    assert np.allclose(y, np.sqrt(t / STATIC.SOAK_S), atol=1e-12)
    assert STATIC.soak(STATIC.SOAK_S, 1.0) == pytest.approx(1.0)
    assert STATIC.soak(4000.0, 1.0) == pytest.approx(2 * STATIC.soak(1000.0, 1.0))
    assert np.all(np.diff(y) > 0) and np.all(np.diff(y, 2) < 1e-15)  # rising, concave
    k = t > 100
    assert np.polyfit(np.log(t[k]), np.log(y[k]), 1)[0] == pytest.approx(0.5, abs=1e-6)
    slope = np.diff(y) / DT
    assert slope[-1] / slope[0] == pytest.approx(np.sqrt(t[0] / t[-1]), rel=0.01)
    late = np.diff(y[-360000::60000])                                # still rising at the end
    assert np.all(late > 0.01)


def test_warming_flicker_grows_from_a_ninth_of_its_hot_variance():
    fn, _ = SHAPES['bias_instability']
    assert STATIC.drive_variance(0.0) == pytest.approx(1 / 9)
    assert STATIC.drive_variance(1e7) == pytest.approx(1.0)
    assert STATIC.drive_variance(STATIC.HEAT_S) == pytest.approx(1 / 9 + 8 / 9 * (1 - np.e ** -1))
    t0 = 30.0
    tt = np.arange(N2H) * DT + t0
    assert STATIC.mean_drive(N2H * DT, t0) == pytest.approx(np.mean(STATIC.drive_variance(tt)),
                                                            rel=1e-4)
    ys = [fn(np.zeros(N2H), rng(10 + i), b=1.0) for i in range(4)]
    g = rng(10)
    start = g.uniform(0, 60)
    assert np.allclose(ys[0], STATIC.warming_flicker(N2H, DT, start, g))
    early = np.mean([np.var(np.diff(y[:6000:10])) for y in ys])      # 0.1 s increments
    late = np.mean([np.var(np.diff(y[-60000::10])) for y in ys])
    want = np.mean(STATIC.drive_variance(np.arange(6000) * DT + 30)) / STATIC.drive_variance(
        6900.0)
    assert early / late == pytest.approx(want, rel=0.2)
    unit = STATIC.cov_avar(lambda u: STATIC.flicker_cov(u, 1.0), np.geomspace(0.3, 300, 7))
    assert abs(np.polyfit(np.log(np.geomspace(0.3, 300, 7)), np.log(unit), 1)[0]) < 0.3
    hot = np.mean([avar(y[-180000:], [100])[0] for y in ys])        # last half hour, 1 s
    assert hot == pytest.approx(STATIC.cov_avar(lambda u: STATIC.flicker_cov(u, 1.0), 1.0)[0]
                                * STATIC.drive_variance(6300.0), rel=0.2)
    for m in (100, 1000):
        got = np.mean([avar(y, [m])[0] for y in ys])
        want = STATIC.cov_avar(lambda u: STATIC.flicker_cov(u, 1.0), m * DT)[0]
        assert got == pytest.approx(want * STATIC.mean_drive(N2H * DT), rel=0.25), m


def test_ratchet_steps_once_a_cycle_and_rests_through_the_cool_half():
    fn, _ = SHAPES['rate_random_walk']
    k = 1e-4
    y = fn(np.zeros(N2H), rng(20), k=k)
    assert np.array_equal(y, STATIC.ratchet(N2H, k, DT, rng(20)))
    u = np.mod(np.arange(N2H) * DT + rng(20).uniform(0, STATIC.CYCLE_S), STATIC.CYCLE_S)
    half = STATIC.CYCLE_S / 2
    cool = (u > half + DT) & (u < STATIC.CYCLE_S - DT)
    assert np.all(np.diff(y)[cool[1:]] == 0)                        # flat treads
    assert np.all(np.diff(y)[(u[1:] > DT) & (u[1:] < half - DT)] != 0)  # smooth risers
    hs = int(half / DT)
    starts = np.flatnonzero(np.diff(u) < 0) + 1                     # cycle starts
    for s in starts[:-1]:                                            # raised-cosine risers
        before, after = y[s - 1], y[s + hs + 1]
        assert np.allclose(y[s:s + hs + 1], before + (after - before) * STATIC.riser(
            u[s:s + hs + 1]), rtol=0, atol=1e-15)
    ys = [fn(np.zeros(N2H), rng(21 + i), k=k) for i in range(32)]
    steps = []
    for i, v in enumerate(ys):
        ui = np.mod(np.arange(N2H) * DT + rng(21 + i).uniform(0, STATIC.CYCLE_S),
                    STATIC.CYCLE_S)
        starts = np.flatnonzero(np.diff(ui) < 0) + 1
        starts = starts[starts + hs + 1 < N2H]
        steps += list(v[starts + hs + 1] - v[starts - 1])
    assert np.std(steps) == pytest.approx(k * np.sqrt(STATIC.CYCLE_S), rel=0.1)
    tau_long = 20 * STATIC.CYCLE_S
    assert STATIC.ratchet_avar(tau_long, k)[0] == pytest.approx(k * k * tau_long / 3, rel=0.05)
    assert STATIC.ratchet_avar(1.0, k)[0] < 0.05 * k * k / 3       # smooth at short tau
    for m in (1000, 30000, 60000):
        got = np.mean([avar(v, [m])[0] for v in ys])
        assert got == pytest.approx(STATIC.ratchet_avar(m * DT, k)[0], rel=0.3), m


def test_load_bursts_are_a_lagged_busy_telegraph_bounded_and_skewed():
    fn, levels = SHAPES['gauss_markov']
    tc, n = 1.0, 2 ** 21
    y = fn(np.zeros(n), rng(30), sd=1.0, tc=tc)
    g = rng(30)
    means = [tc / STATIC.BUSY, tc / (1 - STATIC.BUSY)]
    busy = STATIC.dwell_states(n, DT, means, int(g.uniform() < STATIC.BUSY), g)
    assert np.mean(busy) == pytest.approx(STATIC.BUSY, abs=0.02)
    a = np.exp(-DT / (STATIC.LAG * tc))
    v = signal.lfilter([1 - a], [1.0, -a], busy.astype(float), zi=[a * busy[0]])[0]
    assert np.allclose(y, (v - STATIC.BUSY) / STATIC.load_sd())
    idle, hot = -STATIC.BUSY / STATIC.load_sd(), (1 - STATIC.BUSY) / STATIC.load_sd()
    assert idle - 1e-9 <= y.min() < idle + 0.05 and y.max() <= hot + 1e-9   # bounded, reached
    assert np.std(y) == pytest.approx(1.0, rel=0.05) and abs(np.mean(y)) < 0.05
    assert stats.skew(y) > 0.8                                       # bursts upwards
    for lag in (0.2, 0.5, 1.0, 3.0):
        k = int(round(lag / DT))
        got = np.mean((y[:-k] - y.mean()) * (y[k:] - y.mean()))
        assert got == pytest.approx(float(STATIC.load_cov(lag, 1.0, tc)), abs=0.03), lag
    assert STATIC.load_cov(0.0, 1.0, tc) == pytest.approx(1.0)
    ex = [avar(fn(np.zeros(n), rng(31 + i), sd=1.0, tc=tc), [100, 300]) for i in range(3)]
    want = (STATIC.gm_avar(np.array([1.0, 3.0]), 1.0, tc)
            - STATIC.LAG * STATIC.gm_avar(np.array([1.0, 3.0]), 1.0, STATIC.LAG * tc)) / (
        1 - STATIC.LAG)
    assert np.mean(ex, axis=0) == pytest.approx(want, rel=0.15)


def test_pipelined_carry_leaves_a_triangular_lag1_angle_error():
    fn, levels = SHAPES['quantization']
    n = 2 ** 20
    x = SIG * rng(40).standard_normal(n) + 0.003
    theta = np.cumsum(x) * DT
    for p in (levels[1], levels[2]):
        q = p['q']
        y = fn(x.copy(), rng(41), q=q)
        words = y * DT / q
        assert np.allclose(words, np.round(words), atol=1e-6)       # a q / dt lattice
        e, sent = np.zeros(5000), np.zeros(5000)
        for k in range(5000):                                        # the pipeline itself
            u = x[k] * DT - (e[k - 2] if k >= 2 else 0.0)
            sent[k] = q * np.round(u / q)
            e[k] = sent[k] - u
        assert np.allclose(y[:5000] * DT, sent, rtol=0, atol=1e-12)
        err = np.cumsum(y) * DT - theta
        assert np.allclose(err[:5000], e + np.r_[0.0, e[:-1]], atol=1e-12)
        assert np.abs(err).max() <= q * (1 + 1e-6)
        assert np.var(err) == pytest.approx(q * q / 6, rel=0.03)
        assert stats.kurtosis(err) == pytest.approx(-0.6, abs=0.05)  # sum of two uniforms
        assert acf(err, [1, 2, 5]) == pytest.approx([0.5, 0.0, 0.0], abs=0.01)
        v = q * q / 12
        ex = avar(y, [1, 10]) - avar(x, [1, 10])
        assert ex[0] == pytest.approx(2 * v / DT ** 2, rel=0.1)
        assert ex[1] == pytest.approx(6 * v / (10 * DT) ** 2, rel=0.2)
        f, pe = signal.welch(y - x, fs=1 / DT, nperseg=2 ** 10)
        ends = max(np.mean(pe[f < 2]), np.mean(pe[f > 48]))           # nil at DC and Nyquist
        assert np.mean(pe[(f > 22) & (f < 28)]) > 30 * ends


def test_bracket_has_a_peak_a_notch_above_it_and_a_broadband_floor():
    fn, levels = SHAPES['resonance']
    n = 2 ** 20
    y = fn(np.zeros(n), rng(50), sigma=1.0)
    assert np.std(y) == pytest.approx(1.0, rel=0.03)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 12)
    want = STATIC.bracket_psd(f, 1.0, DT)
    for lo, hi in ((1, 10), (20, 23), (23, 25), (30, 35), (36, 39), (42, 49)):
        k = (f > lo) & (f < hi)
        assert np.mean(p[k]) == pytest.approx(np.mean(want[k]), rel=0.1), lo
    assert f[np.argmax(p)] == pytest.approx(STATIC.BRACKET_HZ, abs=0.3)
    fine = np.linspace(26, 49, 23001)
    g = STATIC.bracket_gain2(fine, DT)
    notch = fine[np.argmin(g)]
    assert notch == pytest.approx(STATIC.BRACKET_HZ / np.sqrt(1 - STATIC.PARTICIPATION),
                                  abs=0.5)
    assert g.min() < 0.01 and STATIC.bracket_gain2([1.0], DT)[0] == pytest.approx(1.0, abs=0.01)
    assert np.mean(p[(f > 36.5) & (f < 38.5)]) < 0.02 * np.mean(p[f < 10])   # the notch
    w0, zeta = 2 * np.pi * STATIC.BRACKET_HZ, 1 / (2 * STATIC.BRACKET_Q)
    s = 2j * np.pi * np.array([1.0, 10.0, 23.7])                     # the analog form, in band
    analog = np.abs(1 - STATIC.PARTICIPATION * s * s / (s * s + 2 * zeta * w0 * s + w0 * w0))
    digital = STATIC.bracket_gain2([1.0, 10.0, 23.7], DT)
    assert digital[:2] == pytest.approx(analog[:2] ** 2, rel=0.02)
    assert digital[2] == pytest.approx(analog[2] ** 2, rel=0.15)     # the peak, q ~ 15
