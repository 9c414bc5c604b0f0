# Held-out set AC (bench/validate_diagnosis_heldout_ac.py, static only): the generators do what
# their docstring claims, and the static harness reaches the set by --held-out ac. THE
# GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import avar, check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import signal

AC = bench_script.load('validate_diagnosis_heldout_ac')
SHAPES = AC.shapes(DT, SIG, N_ARW)


def test_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(AC, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_static_harness_takes_the_set_by_its_letter(monkeypatch):
    static = bench_script.load('validate_diagnosis')
    assert 'ac' in static.held_out_letters()
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', 'ac'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]


def test_equaliser_is_all_pass_when_exact_and_a_peak_beside_a_dip_when_mis_stored():
    f = np.linspace(0.0, 0.5 / DT, 2001)
    assert np.allclose(AC.equaliser_gain2(f, 0.0, DT), 1.0, atol=1e-12)
    fn, levels = SHAPES['internal_lowpass']
    eps = levels[1]['eps']
    g2 = AC.equaliser_gain2(f, eps, DT)
    lo, hi = f[np.argmin(g2)], f[np.argmax(g2)]
    assert g2[0] == pytest.approx(1.0, abs=1e-9) and g2.min() < 0.9 and g2.max() > 1.1
    assert abs(lo - AC.EQ_HZ) < 6 and abs(hi - AC.EQ_HZ) < 6 and (lo - AC.EQ_HZ) * (
        hi - AC.EQ_HZ) < 0                                  # either side of the pole
    x = white(2 ** 18, 1)
    y = fn(x.copy(), rng(1), **levels[1])
    fw, px = signal.welch(x, fs=1 / DT, nperseg=2048)
    _, py = signal.welch(y, fs=1 / DT, nperseg=2048)
    for hz in (lo, hi, 5.0, 45.0):
        assert np.interp(hz, fw, py / px) == pytest.approx(
            AC.equaliser_gain2([hz], eps, DT)[0], rel=0.06)


def test_fan_rack_is_a_forest_of_fans_lines_inside_the_speed_spread():
    fn, levels = SHAPES['vibration']
    a = levels[1]['amplitude']
    y = fn(np.zeros(2 ** 17), rng(2), **levels[1])
    f, p = signal.periodogram(y, fs=1 / DT, window='blackmanharris')
    inside = (f > AC.FAN_LO - 0.05) & (f < AC.FAN_HI + 0.05)
    assert p[~inside].sum() < 1e-6 * p.sum()
    peaks, _ = signal.find_peaks(p, height=0.05 * p.max(), distance=5)
    assert len(peaks) >= AC.FANS - 4                        # a few fans may share a bin
    # the rms of FANS incommensurate lines, each a sinc(f dt)
    assert y.std() == pytest.approx(a * np.sqrt(AC.FANS / 2) * np.sinc(24.5 * DT), rel=0.1)


def test_turnover_square_doubles_the_cycle_mid_record_and_flips_its_fundamental():
    fn, levels = SHAPES['temperature_drift']
    a = levels[1]['amplitude']
    y = fn(np.zeros(720000), rng(3), **levels[1])
    t = np.arange(y.size) * DT
    assert y.min() >= 0.0 and y.max() <= a * (1 + AC.DRIFT / 2) ** 2 + 1e-12

    def lines(sl, k):
        w = 2 * np.pi * k / AC.CYCLE_S
        return np.linalg.lstsq(np.c_[np.sin(w * t[sl]), np.cos(w * t[sl]), np.ones(
            t[sl].size)], y[sl], rcond=None)[0][:2]
    first, mid, last = slice(0, 180000), slice(270000, 450000), slice(540000, 720000)
    assert np.hypot(*lines(mid, 2)) > 3 * np.hypot(*lines(mid, 1))
    assert np.dot(lines(first, 1), lines(last, 1)) < -0.5 * np.hypot(*lines(first, 1)) ** 2


def test_locked_defect_dwells_never_shorter_than_the_lock_and_its_psd_peaks():
    mean = 1.0
    s = AC.locked_switch(2 ** 21, mean, DT, rng(4))
    dwell = np.diff(np.flatnonzero(np.diff(s) != 0)) * DT
    assert dwell.min() >= AC.DEAD * mean - 2 * DT
    assert dwell.mean() == pytest.approx(mean, rel=0.02)
    assert dwell.std() == pytest.approx((1 - AC.DEAD) * mean, rel=0.08)
    f, p = signal.welch(s, fs=1 / DT, nperseg=2 ** 13)
    want = AC.locked_psd(f[1:], mean)
    assert f[1:][np.argmax(want)] == pytest.approx(1 / (2 * mean), rel=0.1)  # regular switching
    band = (f[1:] > 0.05) & (f[1:] < 2.0)
    assert np.mean(p[1:][band]) == pytest.approx(np.mean(want[band]), rel=0.05)
    assert p[1:][np.argmax(want)] == pytest.approx(want.max(), rel=0.15)


def test_slow_slips_walk_at_long_tau_and_are_smooth_at_short_tau():
    ks = 1e-5
    ys = [SHAPES['rate_random_walk'][0](np.zeros(2 ** 20), rng(5 + j), k=ks) for j in range(4)]
    for tau, tol in ((1.0, 0.3), (100.0, 0.3)):
        m = int(tau / DT)
        want = AC.psd_avar(lambda f: AC.slips_psd(f, ks), np.array([tau]), DT)[0]
        got = np.mean([avar(y, m) for y in ys])
        assert got == pytest.approx(want, rel=tol), tau
    assert AC.psd_avar(lambda f: AC.slips_psd(f, ks), np.array([1.0]), DT)[0] < 0.2 * ks ** 2 / 3
    step = np.concatenate([np.diff(y) for y in ys])
    assert np.max(np.abs(step)) < 0.1 * ks * np.sqrt(AC.SLIP_EVERY)  # no sudden step


def test_frozen_layer_correlates_as_a_gaussian_not_an_exponential():
    fn, levels = SHAPES['gauss_markov']
    tc = 1.0
    y = fn(np.zeros(2 ** 21), rng(6), sd=1.0, tc=tc)
    assert y.mean() == pytest.approx(0.0, abs=0.03) and y.std() == pytest.approx(1.0, rel=0.03)
    rho = [np.mean(y[:-m] * y[m:]) / np.mean(y * y) for m in (int(tc / DT), int(2 * tc / DT))]
    assert rho == pytest.approx([np.exp(-1), np.exp(-4)], abs=0.03)


def test_decoder_reads_whole_counts_whose_four_codes_follow_the_edges_widths():
    fn, levels = SHAPES['quantization']
    q = levels[1]['q']
    x = white(400000, 7)
    y = fn(x.copy(), rng(7), **levels[1])
    count = np.rint(np.cumsum(y) * DT / q)
    assert np.allclose(np.cumsum(y) * DT / q, count, atol=1e-6)
    share = np.sort(np.bincount((count % 4).astype(int), minlength=4) / count.size)
    widths = np.diff(np.r_[AC.EDGES, 4.0])
    assert share == pytest.approx(np.sort(widths) / 4, abs=0.01)
    assert share[-1] == pytest.approx(1.25 / 4, abs=0.01)          # the widest step, 1.25 Q
    e = np.cumsum(y - x) * DT
    assert e.var() == pytest.approx(AC.decoded_acov(q, 0, DT, N_ARW), rel=0.1)


def test_bracket_line_follows_the_upper_branch_then_the_lower_through_the_veering():
    fp, fm, c4, s4 = AC.veering(np.arange(0, 7200, 0.5))
    assert np.min(fp - fm) == pytest.approx(2 * AC.COUPLE, rel=1e-3)
    assert c4[np.argmin(fp - fm)] == pytest.approx(0.25, abs=0.01)
    fn, levels = SHAPES['resonance']
    sigma = levels[1]['sigma']
    y = fn(np.zeros(720000), rng(8), **levels[1])
    assert y.std() == pytest.approx(sigma * np.sqrt(np.mean(c4 + s4)), rel=0.08)

    def peak(a, b):
        f, p = signal.welch(y[int(a / DT):int(b / DT)], fs=1 / DT, nperseg=4096)
        return f[np.argmax(p)]
    early, late = AC.veering(np.array([60.0, 6000.0]), 30.0)[:2]
    assert peak(0, 200) == pytest.approx(AC.MODE_A, abs=0.6)
    assert peak(4000, 7200) == pytest.approx(late[1], abs=0.3)
    assert early[0] > AC.MODE_B + 1 > late[1] + 1


def test_bus_holds_every_fourth_read_in_bursts_at_the_beat_of_the_two_clocks():
    fn, levels = SHAPES['stale_samples']
    busy = levels[1]['busy']
    x = white(360000, 9)
    y = fn(x.copy(), rng(9), **levels[1])
    held = np.flatnonzero(y != x)
    assert np.all(y[held] == y[held - 1]) and np.all(np.diff(held) >= 4)
    period = AC.MAG_RATIO * DT * (1 + AC.CLOCK_ERR)
    assert held.size / x.size == pytest.approx(busy / period, rel=0.1)
    gaps = np.diff(held)
    assert np.mean(gaps == 4) > 0.95
    starts = held[np.r_[0, np.flatnonzero(gaps > 4) + 1]] * DT
    beat = AC.MAG_RATIO * DT / (4 * AC.CLOCK_ERR)
    assert np.diff(starts[1:]) == pytest.approx(beat, abs=0.1)
