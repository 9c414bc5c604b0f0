# Held-out set AB (bench/validate_diagnosis_heldout_ab.py, static only): the generators do what
# their docstring claims, and the static harness reaches the set by --held-out ab. THE
# GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import signal

AB = bench_script.load('validate_diagnosis_heldout_ab')
SHAPES = AB.shapes(DT, SIG, N_ARW)


def test_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite():
    check_static_set(AB, SHAPES, STATIC_NAMES + ['stale_samples'], reproducible=True)


def test_static_harness_takes_the_set_by_its_letter(monkeypatch):
    static = bench_script.load('validate_diagnosis')
    assert 'ab' in static.held_out_letters()
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', 'ab'])
    assert sorted(seen[0]) == sorted(SHAPES)
    assert seen[0]['quantization'][1] == SHAPES['quantization'][1]


def test_front_end_memory_correlates_every_other_sample_and_dips_at_a_quarter_rate():
    fn, levels = SHAPES['internal_lowpass']
    r = levels[1]['r']                                      # 0.3
    x = white(2 ** 18, 1)
    y = fn(x.copy(), rng(1), **levels[1])
    u = y - y.mean()
    rho = [np.mean(u[:-m] * u[m:]) / np.mean(u * u) for m in (1, 2, 4)]
    assert rho == pytest.approx([0.0, r, r * r], abs=0.01)
    f, px = signal.welch(x, fs=1 / DT, nperseg=4096)
    _, py = signal.welch(y, fs=1 / DT, nperseg=4096)
    gain = [np.interp(hz, f, py / px) for hz in (0.5, 25.0, 49.5)]
    assert gain == pytest.approx([1.0, ((1 - r) / (1 + r)) ** 2, 1.0], rel=0.06)


def test_cogging_ripple_repeats_each_stroke_and_piles_up_below_its_top_frequency():
    fn, levels = SHAPES['vibration']
    y = fn(np.zeros(2 ** 16), rng(2), **levels[1])
    m = int(round(AB.STROKE_S / DT))
    assert np.allclose(y[m:], y[:-m], atol=1e-9 * levels[1]['amplitude'])
    assert abs(y[:m].sum()) * DT < 1e-9                     # the bench angle returns each stroke
    f, p = signal.periodogram(y, fs=1 / DT)
    above = p[f > AB.RIPPLE_HZ + 1].sum() / p.sum()
    horn = p[(f > AB.RIPPLE_HZ - 4) & (f <= AB.RIPPLE_HZ)].sum()
    middle = p[(f > 12) & (f <= 16)].sum()
    assert above < 0.01 and horn > 2 * middle


def test_crystal_cubic_peaks_and_dips_where_the_warm_up_crosses_its_turns():
    fn, levels = SHAPES['temperature_drift']
    a = levels[0]['amplitude']
    y = fn(np.zeros(720000), rng(3), **levels[0])
    t = np.arange(y.size) * DT
    top = np.argmax(y[t < 900])
    low = np.argmin(np.where((t > 900) & (t < 4000), y, np.inf))     # a local minimum
    # turning points at u = 0.3 and 0.8 of the warm-up, 321 s and 1449 s after power-on; the
    # record starts 0-60 s after it
    assert 321 - 61 < t[top] < 321 + 1 and 1449 - 61 < t[low] < 1449 + 1
    assert y[top] - y[low] == pytest.approx(a, rel=1e-6)
    assert y[-1] / a == pytest.approx(AB.cubic(1.0), rel=5e-3)


def test_packets_correlate_as_one_and_a_half_order_and_are_one_sided():
    fn, levels = SHAPES['gauss_markov']
    tc = 1.0
    y = fn(np.zeros(2 ** 21), rng(4), sd=1.0, tc=tc)
    assert y.mean() == pytest.approx(0.0, abs=0.03) and y.std() == pytest.approx(1.0, rel=0.04)
    rho = [np.mean(y[:-m] * y[m:]) / np.mean(y * y) for m in (int(tc / DT), int(2 * tc / DT))]
    assert rho == pytest.approx([1.5 * np.exp(-1), 2 * np.exp(-2)], abs=0.025)
    assert y.min() >= -AB.PACKETS * 1.0 / np.sqrt(2 * AB.PACKETS) - 1e-9   # never below empty
    assert np.mean(y ** 3) > 0.5                            # skewed upwards


def test_wandering_readout_keeps_the_count_lattice_and_a_correlated_angle_error():
    fn, levels = SHAPES['quantization']
    q = levels[1]['q']
    x = white(400000, 5)
    y = fn(x.copy(), rng(5), **levels[1])
    words = y * DT / q
    assert np.allclose(words, np.round(words), atol=1e-6)
    e = np.cumsum(y - x) * DT
    e = e - e.mean()
    assert e.std() == pytest.approx(q * np.sqrt(AB.READ_SD ** 2 + 1 / 12), rel=0.1)
    lag = int(AB.READ_S / DT)
    rho = np.mean(e[:-lag] * e[lag:]) / np.mean(e * e)
    assert rho == pytest.approx(np.exp(-1) * AB.READ_SD ** 2 / (AB.READ_SD ** 2 + 1 / 12),
                                abs=0.06)


def test_play_wave_holds_through_the_slot_and_the_mount_matches_its_psd():
    assert np.all(AB.play_wave(0.5 * AB.PLAY, np.linspace(0, 7, 50)) == 0.0)
    wave = AB.play_wave(3.0, np.linspace(0, 2 * np.pi, 4001))
    assert wave.max() - wave.min() == pytest.approx(2 * (3.0 - AB.PLAY), rel=1e-6)
    d1 = AB.play_harmonics([3.0], 1)[0, 1]
    assert np.angle(d1) < -0.05                             # the bracket lags the plate
    fn, levels = SHAPES['resonance']
    sigma = levels[1]['sigma']
    y = fn(np.zeros(2 ** 20), rng(6), **levels[1])
    assert y.std() == pytest.approx(sigma, rel=0.08)
    f, p = signal.welch(y, fs=1 / DT, nperseg=2048)
    band = np.abs(f - AB.MODE_HZ) < 0.5
    assert np.mean(p[band]) == pytest.approx(np.mean(AB.play_psd(sigma, DT)(f[band])),
                                             rel=0.12)


def test_glitch_gate_holds_only_rejected_jumps_at_its_stationary_share():
    fn, levels = SHAPES['stale_samples']
    gate = levels[1]['gate']
    x = white(300000, 7)
    y = fn(x.copy(), rng(7), **levels[1])
    held = y != x
    assert np.all(np.abs(np.diff(y)[~held[1:]]) <= gate)   # every published sample passed
    assert np.all(np.abs(x[1:][held[1:]] - y[:-1][held[1:]]) > gate)
    assert np.all(y[1:][held[1:]] == y[:-1][held[1:]])
    assert held.mean() == pytest.approx(AB.gate_share(gate, SIG), rel=0.06)
