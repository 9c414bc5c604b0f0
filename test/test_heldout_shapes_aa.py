# Held-out set AA (bench/validate_diagnosis_heldout_aa.py, static only): the generators do what
# their docstring claims, and the static harness reaches the set by --held-out aa. THE
# GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import signal

AA = bench_script.load('validate_diagnosis_heldout_aa')
SHAPES = AA.shapes(DT, SIG, N_ARW)


def test_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(AA, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_static_harness_takes_the_set_by_its_letter(monkeypatch):
    static = bench_script.load('validate_diagnosis')
    assert 'aa' in static.held_out_letters()
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', 'aa'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]


def test_mode_split_channel_peaks_below_its_split_and_is_causal():
    fn, levels = SHAPES['internal_lowpass']
    x = white(2 ** 18, 1)
    y = fn(x.copy(), rng(1), **levels[1])                  # a 30 Hz split
    f, px = signal.welch(x, fs=1 / DT, nperseg=4096)
    _, py = signal.welch(y, fs=1 / DT, nperseg=4096)
    gain = [np.interp(hz, f, py / px) for hz in (5.0, 29.15, 49.9)]
    assert gain == pytest.approx([1.05, 4.75, 0.36], rel=0.05)
    impulse = np.zeros(8192)
    impulse[4096] = 1.0
    h = fn(impulse, rng(1), **levels[1])
    assert np.max(np.abs(h[:4090])) < 1e-9 and abs(h.sum() - 1.0) < 1e-6


def test_two_step_defect_dwells_are_erlang_2_and_its_correlation_turns_negative():
    fn, levels = SHAPES['gauss_markov']
    p = levels[0]                                           # sd 5e-4 rad/s, tc 2 s
    y = fn(np.zeros(2 ** 21), rng(2), **p)
    assert np.unique(np.round(y / p['sd'], 12)).tolist() == [-1.0, 1.0]
    edges = np.flatnonzero(np.diff(y) != 0)
    dwell = np.diff(edges) * DT
    assert dwell.mean() == pytest.approx(2 * p['tc'], rel=0.05)
    assert dwell.std() / dwell.mean() == pytest.approx(np.sqrt(0.5), abs=0.04)
    u = y / p['sd']
    rho = [np.mean(u[:-m] * u[m:]) for m in (int(p['tc'] / DT), int(2.36 * p['tc'] / DT))]
    assert rho == pytest.approx([np.exp(-1) * np.cos(1), -0.067], abs=0.03)


def test_keyframes_touch_one_sample_in_ten_and_keep_the_angle_within_half_a_step():
    fn, levels = SHAPES['quantization']
    q = levels[1]['q']
    x = white(200000, 3)
    y = fn(x.copy(), rng(3), **levels[1])
    touched = np.flatnonzero(np.abs(y - x) > 1e-12)
    assert touched.size > 0.09 * x.size / AA.KEY_EVERY
    assert np.unique(touched % AA.KEY_EVERY).size == 1
    angle_error = np.cumsum(y - x) * DT
    assert np.max(np.abs(angle_error)) <= q / 2 * (1 + 1e-6)


def test_chain_sits_on_the_eleven_levels_of_a_product_of_ten_switches():
    fn, levels = SHAPES['bias_instability']
    y = fn(np.zeros(200000), rng(4), b=1.0)
    product = y * np.sqrt(AA.chain_var()) + 1
    eps, sites = AA.SITE_EPS, AA.SITE_TAUS.size
    lattice = (1 + eps) ** np.arange(sites + 1) * (1 - eps) ** (sites - np.arange(sites + 1))
    assert np.isclose(product[:, None], lattice[None, :], rtol=1e-9).any(axis=1).all()
    assert np.unique(np.round(product, 9)).size > 5


def test_leaking_driver_holds_grow_e_fold_every_grow_s():
    fn, levels = SHAPES['stale_samples']
    x = white(720000, 5)
    y = fn(x.copy(), rng(5), **levels[1])
    held = (y[1:] == y[:-1]) & (x[1:] != x[:-1])
    quarter = held.size // 4
    late, early = held[-quarter:].mean(), held[:quarter].mean()
    assert late / early == pytest.approx(np.exp(3 * quarter * DT / AA.GROW_S), rel=0.1)
    assert held.mean() == pytest.approx(AA.held_share(levels[1]['p0'], DT, x.size * DT),
                                        rel=0.05)
