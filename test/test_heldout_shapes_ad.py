# Held-out set AD (bench/validate_diagnosis_heldout_ad.py, static only): the generators do what
# their docstring claims, and the static harness reaches the set by --held-out ad. THE
# GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import avar, check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import linalg, signal, special

AD = bench_script.load('validate_diagnosis_heldout_ad')
SHAPES = AD.shapes(DT, SIG, N_ARW)


def test_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(AD, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_static_harness_takes_the_set_by_its_letter(monkeypatch):
    static = bench_script.load('validate_diagnosis')
    assert 'ad' in static.held_out_letters()
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', 'ad'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]


def test_cable_node_is_a_half_order_roll_off_with_unit_dc_gain():
    fn, levels = SHAPES['internal_lowpass']
    tau = levels[1]['tau']
    step = fn(np.r_[0.0, np.ones(999)], rng(1), tau=tau)        # the held step at k = 1
    t = np.arange(1, 1000) * DT
    assert step[1:] == pytest.approx(1 - special.erfcx(np.sqrt(t / tau)), abs=1e-9)
    x = white(2 ** 18, 1)
    y = fn(x.copy(), rng(1), **levels[1])
    f, px = signal.welch(x, fs=1 / DT, nperseg=4096)
    _, py = signal.welch(y, fs=1 / DT, nperseg=4096)
    fg, g2 = AD.warburg_gain2(tau, DT)
    for hz in (0.5, 5.0, 25.0, 49.0):
        assert np.interp(hz, f, py / px) == pytest.approx(np.interp(hz, fg, g2), rel=0.05)
    w = 2 * np.pi * fg[1:2000] * tau                            # the continuous law below 0.2 Hz
    assert g2[1:2000] == pytest.approx(1 / (1 + np.sqrt(2 * w) + w), rel=2e-3)
    fg, g2 = AD.warburg_gain2(levels[2]['tau'], DT)
    loss = [1 - np.interp(hz, fg, g2) for hz in (0.05, 0.2, 0.8)]
    assert loss[1] / loss[0] == pytest.approx(2.0, rel=0.05)     # sqrt(f), not f^2
    assert loss[2] / loss[1] == pytest.approx(2.0, rel=0.05)


def test_lift_runs_are_silent_between_and_never_above_the_cruise_frequency():
    fn, levels = SHAPES['vibration']
    ys = [fn(np.zeros(720000), rng(2 + j), amplitude=1.0) for j in range(4)]
    y = np.concatenate(ys)
    on = y != 0
    assert np.quantile(np.abs(y), 0.995) <= 1.0 and 0.07 < on.mean() < 0.13  # 10 % on
    f, p = signal.welch(y, fs=1 / DT, nperseg=8192)
    assert p[f > AD.TRIP_HZ + 1].sum() < 1e-3 * p.sum()
    fy, y2 = AD.hoist_psd1(DT)
    want = 2 * y2 / AD.TRIP_EVERY
    assert y.var() == pytest.approx(np.trapezoid(want, fy), rel=0.2)
    band = (fy > AD.TRIP_HZ - 1) & (fy < AD.TRIP_HZ + 1)
    assert np.trapezoid(want[band], fy[band]) > 0.9 * np.trapezoid(want, fy)
    # a cruise: the rate crosses zero at twice TRIP_HZ
    starts = np.flatnonzero(np.diff(on.astype(int)) == 1) + 1
    ends = np.flatnonzero(np.diff(on.astype(int)) == -1) + 1
    ends = ends[ends > starts[0]][:starts.size - 1]
    length = (ends - starts[:ends.size]) * DT
    longest = np.argmax(np.where(length <= 2 * AD.RAMP_S + AD.CRUISE_S[1], length, 0))  # one run
    run = y[starts[longest]:ends[longest]]
    mid = run[int(AD.RAMP_S / DT) + 50:-int(AD.RAMP_S / DT) - 50]
    crossings = np.sum(np.diff(np.sign(mid)) != 0)
    assert crossings / (mid.size * DT) == pytest.approx(2 * AD.TRIP_HZ, rel=0.02)


def test_thermostat_cycles_are_drawn_afresh_and_the_die_lags_inside_the_swing():
    times, levels = AD.room_cycle(0.0, 4e6, rng(3))
    spell = np.diff(times)
    heat, cool = spell[levels[:-1] < 0], spell[levels[:-1] > 0]
    assert heat.mean() == pytest.approx(AD.HEAT_S, rel=0.03)
    assert cool.mean() == pytest.approx(AD.COOL_S, rel=0.03)
    assert heat.std() / heat.mean() == pytest.approx(AD.CYCLE_CV, rel=0.08)
    fn, levels = SHAPES['temperature_drift']
    a = levels[1]['amplitude']
    y = fn(np.zeros(720000 * 5), rng(4), **levels[1]) / a
    assert np.abs(y).max() < 1 and y.std() == pytest.approx(0.35, abs=0.04)
    up = np.flatnonzero((y[:-1] < y.mean()) & (y[1:] >= y.mean())) * DT
    period = np.diff(up)
    assert period.mean() == pytest.approx(AD.HEAT_S + AD.COOL_S, rel=0.1)
    assert period.std() / period.mean() > 0.12                  # not a periodic cycle


def test_landscape_defect_revisits_its_sites_and_relaxes_as_its_modes_say():
    q, b = AD.landscape()
    assert b.size == AD.BARRIER_TAUS.size + 1
    assert b.mean() == pytest.approx(0.0, abs=1e-12) and np.mean(b * b) == pytest.approx(1.0)
    rates, w = AD.landscape_modes()
    assert w.sum() == pytest.approx(1.0, abs=1e-9) and rates.size == AD.BARRIER_TAUS.size
    for u in (0.1, 10.0, 1000.0):                               # the modes are the chain's
        want = b @ linalg.expm(q * u) @ b / b.size
        assert np.sum(w * np.exp(-rates * u)) == pytest.approx(want, rel=1e-6, abs=1e-12)
    y = AD.landscape_walk(2 ** 18, 1.0, DT, rng(5))
    assert np.all(np.isin(np.unique(y), b))                     # it revisits the same levels
    site = np.argmin(np.abs(y[:, None] - b[None, :]), axis=1)
    assert np.all(np.abs(np.diff(site)) <= 2)                   # hops between neighbours
    stay = linalg.expm(q * DT).diagonal()
    for i in np.flatnonzero(np.bincount(site[:-1], minlength=b.size) > 3000):
        was = site[:-1] == i
        assert np.mean(site[1:][was] == i) == pytest.approx(stay[i], abs=0.02), i
    tau = np.geomspace(0.1, 720, 40)
    slope = np.diff(np.log(AD.landscape_avar(tau, 1.0))) / np.diff(np.log(tau)) / 2
    assert -0.11 < slope.min() and slope.max() < 0.15            # 1/f-like over four decades


def test_norton_creep_walks_at_long_tau_with_bursts_at_short_tau():
    k = 1e-5
    ys = [SHAPES['rate_random_walk'][0](np.zeros(2 ** 20), rng(6 + j), k=k) for j in range(4)]
    for tau in (1.0, 100.0):
        want = AD.psd_avar(lambda f: AD.norton_psd(f, k), np.array([tau]), DT)[0]
        got = np.mean([avar(y, int(tau / DT)) for y in ys])
        assert got == pytest.approx(want, rel=0.3), tau
    walk = AD.psd_avar(lambda f: AD.norton_psd(f, k), np.array([1.0, 72.0]), DT) / (
        k * k * np.array([1.0, 72.0]) / 3)
    assert walk[0] < 0.5 and walk[1] == pytest.approx(1.0, abs=0.01)
    inc = np.concatenate([np.diff(y[::100]) for y in ys])
    assert np.mean(inc ** 4) / np.mean(inc ** 2) ** 2 > 10       # Gaussian walk: 3


def test_belt_field_has_a_cauchy_correlation_and_an_exponential_spectrum():
    fn, levels = SHAPES['gauss_markov']
    tc = 1.0
    ys = [fn(np.zeros(2 ** 21), rng(7 + j), sd=1.0, tc=tc) for j in range(3)]
    assert np.mean([y.std() for y in ys]) == pytest.approx(1.0, rel=0.03)
    rho = [np.mean([np.mean(y[:-m] * y[m:]) / np.mean(y * y) for y in ys])
           for m in (int(tc / DT), int(2 * tc / DT))]
    assert rho == pytest.approx([0.5, 0.2], abs=0.03)            # first order: 0.37, 0.14
    f, p = signal.welch(np.array(ys), fs=1 / DT, nperseg=2 ** 14)
    band = (f > 0.05) & (f < 1.0)
    slope = np.polyfit(f[band], np.log(p.mean(axis=0)[band]), 1)[0]
    assert slope == pytest.approx(-2 * np.pi * tc, rel=0.1)
    want = AD.belt_psd(0.3, 1.0, tc)
    assert np.interp(0.3, f, p.mean(axis=0)) == pytest.approx(want, rel=0.1)


def test_two_pitch_words_lie_on_both_lattices_and_the_error_is_their_mean():
    fn, levels = SHAPES['quantization']
    q = levels[1]['q']
    x = white(400000, 8)
    y = fn(x.copy(), rng(8), **levels[1])
    words = 2 * y * DT / q                                      # i + j PITCH
    j = np.arange(-40, 41)[:, None]
    resid = np.min(np.abs(words - j * AD.PITCH - np.round(words - j * AD.PITCH)), axis=0)
    assert np.all(resid < 1e-6)
    e = np.cumsum(y - x) * DT
    assert e.max() - e.min() <= (1 + AD.PITCH) * q / 2 + 1e-12
    assert e.var() == pytest.approx((1 + AD.PITCH ** 2) * q * q / 48, rel=0.1)
    assert e.var() == pytest.approx(sum(AD.floor_acov(p, 0, DT, N_ARW) for p in (
        q, AD.PITCH * q)) / 4, rel=0.1)


def test_rail_band_is_flat_between_horned_edges():
    f_m, share = AD.rail_modes()
    assert f_m.size == (AD.BAYS + 1) // 2 and share.sum() == pytest.approx(1.0)
    assert f_m.min() == pytest.approx(AD.BAY_HZ, rel=1e-3)
    assert f_m.max() == pytest.approx(AD.BAND_HZ, rel=1e-3)
    fn, levels = SHAPES['resonance']
    y = fn(np.zeros(2 ** 20), rng(9), sigma=1.0)
    assert y.std() == pytest.approx(1.0, rel=0.05)
    f, p = signal.welch(y, fs=1 / DT, nperseg=8192)
    outside = (f < AD.BAY_HZ - 1) | (f > AD.BAND_HZ + 1)
    assert p[outside].sum() < 0.05 * p.sum()
    mid = p[(f > 21) & (f < 27)].mean()
    assert p[(f > 17) & (f < 18)].mean() > 1.8 * mid and p[(f > 30) & (f < 31)].mean() > 1.4 * mid
    band = (f > 19) & (f < 29)
    assert np.mean(p[band]) == pytest.approx(np.mean(AD.rail_psd(1.0, DT)(f[band])), rel=0.1)


def test_low_power_mode_holds_blocks_of_three_after_quiet_spells_until_a_loud_conversion():
    fn, levels = SHAPES['stale_samples']
    th = levels[1]['th']
    x = white(720000, 10)
    idx = AD.low_power_index(x, th)
    assert np.array_equal(fn(x.copy(), rng(10), **levels[1]), x[idx])
    k = np.arange(x.size)
    lag = k - idx
    assert set(np.unique(lag)) == {0, 1, 2, 3}
    held = np.flatnonzero(lag > 0)
    assert np.all(np.abs(x[idx[held]]) < th)                   # the held conversions were quiet
    starts = held[lag[held] == 1] - 1                           # the conversions held over
    first = starts[np.r_[True, np.diff(starts) != AD.LOW_EVERY]]
    for s0 in first[:200]:                                      # each spell after QUIET_N quiet
        assert np.all(np.abs(x[s0 - AD.QUIET_N:s0]) < th)
    ends = starts[np.r_[np.diff(starts) != AD.LOW_EVERY, True]] + AD.LOW_EVERY
    ends = ends[ends < x.size]
    assert np.all(np.abs(x[ends]) >= th) and np.all(lag[ends] == 0)   # a loud wake
    assert held.size / x.size == pytest.approx(AD.low_power_share(th, SIG, 0.003), rel=0.08)
