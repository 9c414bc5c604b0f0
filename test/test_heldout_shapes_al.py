# Held-out set AL (bench/validate_diagnosis_heldout_al.py, static only): the generators do what
# their docstring claims, and the static harness reaches the set by --held-out al. THE
# GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import avar, check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import signal

AL = bench_script.load('validate_diagnosis_heldout_al')
SHAPES = AL.shapes(DT, SIG, N_ARW)


def test_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(AL, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_static_harness_takes_the_set_by_its_letter(monkeypatch):
    static = bench_script.load('validate_diagnosis')
    assert 'al' in static.held_out_letters()
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', 'al'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]


def test_fft_rate_correction_is_a_brick_wall_at_the_sensors_nyquist():
    fn, levels = SHAPES['internal_lowpass']
    e = levels[1]['e']
    x = white(2 ** 18, 1)
    y = fn(x.copy(), rng(1), e=e)
    assert y.var() == pytest.approx(x[:int(round(x.size * (1 - e)))].var(), rel=1e-9)
    p = np.abs(np.fft.rfft(y - y.mean())) ** 2
    f = np.fft.rfftfreq(y.size, DT)
    top = (1 - e) / (2 * DT)
    assert p[f > top + 0.01].sum() < 1e-20 * p.sum()          # nil above, no transition band
    band = (f > 1) & (f < top - 0.01)
    level = p[band].mean() / (y.size * SIG ** 2)
    assert level == pytest.approx(1 / (1 - e), rel=0.01)      # the variance kept
    assert AL.resample_z(levels[2]['e'], DT, 7200.0) == pytest.approx(4.0, abs=0.01)


def test_panel_tone_flips_phase_and_leaves_no_carrier():
    n = 2 ** 20
    ys = [AL.flip_wave(n, DT, rng(20 + j)) for j in range(4)]
    rho, a = np.exp(-2 * DT / AL.DWELL_S), np.exp(-DT / AL.RING_S)
    state_var = (1 - a) / (1 + a) * (1 + a * rho) / (1 - a * rho)
    assert state_var == pytest.approx(0.963, abs=0.002)
    assert np.mean([y.var() for y in ys]) == pytest.approx(state_var / 2, rel=0.03)
    t = np.arange(n) * DT
    for y in ys:                                             # demodulated at the tone: +-1 spells
        c = 2 * signal.lfilter(np.ones(100) / 100, [1.0], y * np.exp(-2j * np.pi * AL.FLIP_HZ * t))
        phase = np.angle(c[200::100] * np.conj(c[200]))
        held = np.abs(c[200::100]) > 0.9
        near = np.minimum(np.abs(phase), np.pi - np.abs(phase))[held]
        assert np.all(near < 0.1)                           # one of two states, half a turn apart
        flips = np.mean(np.abs(phase[held]) > np.pi / 2)
        assert 0.2 < flips < 0.8                            # both states visited
    f, p = signal.welch(np.array(ys), fs=1 / DT, nperseg=2 ** 16)
    p = p.mean(axis=0)
    half = 1 / (np.pi * AL.DWELL_S)
    inner = np.abs(f - AL.FLIP_HZ) < half
    outer = (np.abs(f - AL.FLIP_HZ) > 4 * half) & (np.abs(f - AL.FLIP_HZ) < 0.5)
    want = AL.flip_ratio(f, 1.0, DT, 1.0) * 2 * DT           # the exact one-sided PSD, unit A
    assert np.trapezoid(p[inner], f[inner]) == pytest.approx(
        np.trapezoid(want[inner], f[inner]), rel=0.15)
    assert np.trapezoid(p[outer], f[outer]) == pytest.approx(
        np.trapezoid(want[outer], f[outer]), rel=0.25)


def test_oven_cycle_grows_out_of_nothing_and_saturates():
    fn, levels = SHAPES['temperature_drift']
    n = 720000
    y = fn(np.zeros(n), rng(3), amplitude=1.0)
    t = np.arange(n) * DT
    r = rng(3)
    onset = r.uniform(*AL.ONSET) * n * DT
    assert 1800 <= onset <= 3600
    assert np.abs(y[t < onset - 3 * AL.GROW_S]).max() < 0.05          # a few per cent at first
    late = y[t > onset + 3 * AL.GROW_S]
    assert np.abs(late).max() == pytest.approx(1.0, abs=0.01)        # saturated at A
    ups = np.flatnonzero((late[:-1] < 0) & (late[1:] >= 0)) * DT
    assert np.diff(ups).mean() == pytest.approx(AL.PERIOD_S, rel=0.01)
    env = np.abs(signal.hilbert(y))
    k0, k1 = (int((onset + d) / DT) for d in (-AL.GROW_S, 0.0))
    assert env[k1] / env[k0] == pytest.approx(np.sqrt((1 + np.e ** 2) / 2), rel=0.1)


def test_retrim_bounds_the_flicker_with_steps_that_cut_its_slow_part():
    n = 720000
    g = AL.unit_flicker(n, DT, rng(4))
    assert g.std() == pytest.approx(1.0, abs=0.2)
    y = SHAPES['bias_instability'][0](np.zeros(n), rng(4), b=1.0)
    assert np.array_equal(y, AL.retrim(g, AL.TRIM_W))
    assert np.abs(y).max() <= AL.TRIM_W + 1e-12
    resets = np.flatnonzero(y == 0.0)
    assert 120 < resets.size < 300                                    # ~190 in 2 h
    assert np.all(np.abs(g[resets[1:]] - g[resets[1:] - 1] + y[resets[1:] - 1]) > AL.TRIM_W)
    assert y.std() == pytest.approx(0.76, abs=0.08)
    tau = np.array([9.15, 56.0, 340.0])
    free, cut = (np.sqrt(AL.block_avar(v, DT, tau)) for v in (g, y))
    assert cut[0] > 1.1 * free[0] and cut[1] < 0.9 * free[1] and cut[2] < 0.6 * free[2]


def test_washboard_hops_are_whole_spacings_and_walk_at_long_tau(monkeypatch):
    k = 1e-5
    ys = [AL.washboard(2 ** 20, k, DT, rng(5 + j)) for j in range(3)]
    for tt in (1.0, 100.0):
        want = AL.washboard_avar(np.array([tt]), k, DT)[0]
        got = np.mean([avar(y, int(tt / DT)) for y in ys])
        assert got == pytest.approx(want, rel=0.3), tt
    monkeypatch.setattr(AL, 'RATTLE', 0.0)
    y = AL.washboard(2 ** 20, k, DT, rng(5))
    steps = np.diff(y) / (k * np.sqrt(AL.HOP_S))
    assert np.allclose(steps, np.round(steps), atol=1e-6)             # a lattice of hops
    moved = np.abs(np.round(steps)) > 0
    assert moved.mean() == pytest.approx(1 - np.exp(-DT / AL.HOP_S), rel=0.1)


def test_jammed_filler_has_a_compressed_exponential_correlation():
    fn, levels = SHAPES['gauss_markov']
    tc = 1.0
    ys = [fn(np.zeros(2 ** 20), rng(7 + j), sd=1.0, tc=tc) for j in range(3)]
    assert np.mean([y.std() for y in ys]) == pytest.approx(1.0, rel=0.05)
    rho = [np.mean([np.mean(y[:-m] * y[m:]) / np.mean(y * y) for y in ys])
           for m in (int(tc / DT), int(2 * tc / DT))]
    assert rho == pytest.approx([np.exp(-1), np.exp(-2 ** 1.5)], abs=0.03)  # 0.37, 0.059
    for tt in (0.5, 5.0):
        want = AL.compressed_avar(np.array([tt]), 1.0, tc, DT)[0]
        got = np.mean([avar(y, int(tt / DT)) for y in ys])
        assert got == pytest.approx(want, rel=0.15), tt


def test_two_speed_errors_are_whole_cycles_on_about_one_sample_in_eighty():
    fn, levels = SHAPES['quantization']
    cycle = levels[1]['cycle']
    x = white(400000, 8)
    y = fn(x.copy(), rng(8), cycle=cycle)
    e = np.cumsum(y - x) * DT                                # the read angle's error
    whole = np.round(e / cycle)
    fine = e - whole * cycle
    assert np.all(np.abs(fine) <= cycle / AL.FINE + 1e-12)   # the rest is the fine floor
    assert np.mean(whole != 0) == pytest.approx(0.0124, rel=0.1)
    assert np.mean(whole ** 2) == pytest.approx(AL.ambiguity_moment(), rel=0.1)
    assert abs(np.corrcoef(whole[:-1], whole[1:])[0, 1]) < 0.02   # independent samples
    assert AL.ambiguity_moment() == pytest.approx(0.0124, abs=2e-4)


def test_tank_lines_sit_at_the_sloshing_frequencies():
    f_n, share = AL.slosh_modes()
    assert f_n == pytest.approx([1.30, 2.61, 3.39, 4.01, 4.54, 5.02], abs=0.01)
    assert share.sum() == pytest.approx(1.0) and share[0] == pytest.approx(0.84, abs=0.01)
    fn, levels = SHAPES['resonance']
    y = fn(np.zeros(2 ** 20), rng(9), sigma=1.0)
    assert y.std() == pytest.approx(1.0, rel=0.1)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2 ** 15)
    for fm in f_n[:3]:
        near = np.abs(f - fm) < 0.3
        assert f[near][np.argmax(p[near])] == pytest.approx(fm, abs=0.02)
    assert p[f > 6].sum() < 0.01 * p.sum()
    band = (f > 2.4) & (f < 2.8)
    assert np.trapezoid(p[band], f[band]) == pytest.approx(
        np.trapezoid(AL.slosh_psd(1.0, DT)(f[band]), f[band]), rel=0.25)


def test_log_flushes_hold_the_tick_after_each_full_buffer():
    fn, levels = SHAPES['stale_samples']
    buf = levels[1]['buffer']
    x = white(720000, 10)
    idx = AL.flush_index(x, buf)
    assert np.array_equal(fn(x.copy(), rng(10), **levels[1]), x[idx])
    held = np.flatnonzero(idx != np.arange(x.size))
    assert np.all(idx[held] == held - 1)
    cum = np.cumsum(AL.LINE_CHARS + (x < 0))
    assert np.all(cum[held - 1] // buf > np.r_[0, cum][held - 1] // buf)   # a buffer filled
    assert held.size / x.size == pytest.approx(AL.flush_share(buf, SIG, 0.003), rel=0.01)
    gaps = np.diff(held)
    assert gaps.mean() == pytest.approx(buf / (AL.LINE_CHARS + 0.34), rel=0.01)
    assert gaps.min() < gaps.max()                           # jittered by the signs
