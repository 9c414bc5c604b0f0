# Held-out sets T, U, V, W, X, Y and Z (bench/validate_diagnosis_heldout_{t,u,v,w,x,y,z}.py,
# static only): the generators do what their docstrings claim, and the static harness reaches
# them by --held-out t / u / v / w / x / y / z. THE GENERATORS only, never the diagnosis.
import bench_script
from heldout_common import check_static_set, DT, N_ARW, rng, SIG, STATIC_NAMES, white
import numpy as np
import pytest
from scipy import signal

SETS = {k: bench_script.load(f'validate_diagnosis_heldout_{k}') for k in 'tuvwxyz'}
SHAPES = {k: m.shapes(DT, SIG, N_ARW) for k, m in SETS.items()}


def kurtosis(y):
    y = y - y.mean()
    return float(np.mean(y ** 4) / np.mean(y ** 2) ** 2 - 3.0)


@pytest.mark.parametrize('letter', sorted(SETS))
def test_set_covers_the_catalogue_edges_at_z4_levels_ordered_outputs_finite(letter):
    check_static_set(SETS[letter], SHAPES[letter], STATIC_NAMES + ['stale_samples'],
                     reproducible=True)


@pytest.mark.parametrize('letter', sorted(SETS))
def test_static_harness_takes_the_set_by_its_letter(monkeypatch, letter):
    static = bench_script.load('validate_diagnosis')
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', letter])
    assert sorted(seen[0]) == sorted(SHAPES[letter])


def test_t_ring_buffer_replays_blocks_of_16_with_no_lag_1_repeat():
    fn, levels = SHAPES['t']['stale_samples']
    x = white(200000, 3)
    y = fn(x.copy(), rng(3), **levels[1])
    lag16 = np.mean(y[16:] == y[:-16])
    assert np.mean(y[1:] == y[:-1]) == 0.0
    assert lag16 == pytest.approx(levels[1]['eps'], rel=0.25)


def test_u_swept_fan_is_a_flat_band_with_a_constant_envelope():
    fn, levels = SHAPES['u']['vibration']
    x = np.zeros(2 ** 18)
    y = fn(x.copy(), rng(4), **levels[1])
    f, p = signal.welch(y, fs=1.0 / DT, nperseg=8192)
    band = f[p > 0.1 * p.max()]
    assert band.min() > 19.5 and band.max() < 24.0 and band.max() - band.min() > 2.0
    assert kurtosis(y) == pytest.approx(-1.5, abs=0.05)    # a sinusoid's, whatever its sweep


def test_u_radio_holds_come_in_whole_packets_of_five():
    fn, levels = SHAPES['u']['stale_samples']
    x = white(200000, 5)
    y = fn(x.copy(), rng(5), **levels[1])
    held = np.concatenate([[False], y[1:] == y[:-1]])
    edges = np.diff(np.concatenate([[0], held.astype(int), [0]]))
    runs = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    assert runs.size > 50 and np.all(runs % 5 == 0)


def test_v_rotors_make_six_lines_at_the_intermodulation_frequencies():
    fn, levels = SHAPES['v']['vibration']
    y = fn(np.zeros(2 ** 18), rng(6), **levels[1])
    f, p = signal.welch(y, fs=1.0 / DT, nperseg=16384)
    peaks, _ = signal.find_peaks(p, height=1e-4 * p.max())
    found = np.sort(f[peaks])
    f1, f2 = 23.1, 23.1 * 17.0 / 29.0
    want = np.sort([f1, f2, 2 * f1, 2 * f2, f1 - f2, f1 + f2])
    assert found.size == 6 and np.allclose(found, want, atol=0.02)


def test_v_clock_repeats_a_share_m_over_pi():
    fn, levels = SHAPES['v']['stale_samples']
    x = white(720000, 7)
    y = fn(x.copy(), rng(7), **levels[1])
    assert np.mean(y[1:] == y[:-1]) == pytest.approx(levels[1]['m'] / np.pi, rel=0.1)


def test_x_notch_cuts_a_hole_and_keeps_dc_and_nyquist():
    fn, levels = SHAPES['x']['internal_lowpass']
    y = fn(white(2 ** 18, 8), rng(8), **levels[1])
    f, p = signal.welch(y, fs=1.0 / DT, nperseg=4096)
    near = [p[np.argmin(np.abs(f - hz))] / (2 * SIG ** 2 * DT) for hz in (29.3, 5.0, 49.0)]
    assert near[0] < 0.05 and near[1:] == pytest.approx([1.0, 1.0], abs=0.1)


def test_x_half_carry_rate_error_has_lag_1_correlation_minus_0_4():
    fn, levels = SHAPES['x']['quantization']
    x = white(400000, 9)
    err = fn(x.copy(), rng(9), **levels[0]) - x
    err = err - err.mean()
    assert np.mean(err[1:] * err[:-1]) / np.mean(err * err) == pytest.approx(-0.4, abs=0.02)


def test_x_failed_checks_hold_negative_words_far_more_often():
    fn, levels = SHAPES['x']['stale_samples']
    x = white(400000, 10)
    y = fn(x.copy(), rng(10), **levels[1])
    held = y != x
    negative = np.round(x / (0.05 * np.pi / 180.0)) < 0
    eps = levels[1]['eps']
    assert np.mean(held[negative]) > 10 * eps and np.mean(held[~negative]) < 5 * eps
    assert np.mean(held) == pytest.approx(SETS['x'].crc_share(eps, SIG), rel=0.05)


def test_y_ping_pong_holds_fall_on_one_parity_only():
    fn, levels = SHAPES['y']['stale_samples']
    x = white(200000, 11)
    y = fn(x.copy(), rng(11), **levels[1])
    held = np.flatnonzero(y != x)
    assert held.size > 1000 and np.unique(held % 2).size == 1
    assert np.all(y[held] == x[held - 1])
    assert held.size / x.size == pytest.approx(levels[1]['p'] / 2, rel=0.1)


def test_y_pulled_fan_is_a_one_sided_comb_below_the_compressor():
    fn, levels = SHAPES['y']['vibration']
    y = fn(np.zeros(2 ** 18), rng(12), **levels[1])
    f = np.fft.rfftfreq(y.size, DT)
    p = np.abs(np.fft.rfft(y)) ** 2
    share = [p[np.abs(f - hz) < 0.05].sum() / p.sum() for hz in (26.30, 26.06, 25.82)]
    assert share == pytest.approx([0.25, 0.56, 0.14], abs=0.03)
    assert p[f > 26.42].sum() < 1e-3 * p.sum()


def test_z_bearing_peaks_widen_with_the_harmonic_order_as_a_renewal_train_does():
    fn, levels = SHAPES['z']['vibration']
    y = fn(np.zeros(2 ** 19), rng(13), **levels[1])
    f = np.fft.rfftfreq(y.size, DT)
    p = np.abs(np.fft.rfft(y)) ** 2
    dense = np.linspace(1e-6, 0.5 / DT, 2000001)
    want = SETS['z'].bearing_psd(1.0, DT)(dense)

    def core(freq, power, k):       # the share of a harmonic's +-0.5 Hz within +-0.05 Hz
        near = np.abs(freq - k * SETS['z'].BPFO_HZ)
        return power[near < 0.05].sum() / power[near < 0.5].sum()
    got = [core(f, p, k) for k in (2, 3, 4, 5, 6)]
    assert got == pytest.approx([core(dense, want, k) for k in (2, 3, 4, 5, 6)], rel=0.1)
    assert got[0] > 0.55 and got[-1] < 0.3 and np.all(np.diff(got) < 0)


def test_z_loads_sit_on_a_poisson_lattice_and_decorrelate_exactly_at_2_tc():
    fn, levels = SHAPES['z']['gauss_markov']
    p, on = levels[0], SETS['z'].LOADS
    y = fn(np.zeros(2 ** 22), rng(14), **p)
    count = y / p['sd'] * np.sqrt(on) + on
    assert np.allclose(count, np.round(count), rtol=0, atol=1e-9) and count.min() >= 0
    assert [np.mean(count), np.var(count)] == pytest.approx([on, on], rel=0.05)
    lag = int(round(p['tc'] / DT))
    rho = [np.mean(y[:-m] * y[m:]) / np.mean(y * y) for m in (lag, 2 * lag, 3 * lag)]
    assert rho[0] == pytest.approx(0.5, abs=0.04) and max(abs(rho[1]), abs(rho[2])) < 0.04


def test_z_send_on_delta_sends_nothing_or_at_least_delta_and_loses_no_angle():
    fn, levels = SHAPES['z']['quantization']
    delta = levels[0]['delta']
    x = white(400000, 15)
    y = fn(x.copy(), rng(15), **levels[0])
    sent = y != 0
    unsent_angle = np.cumsum(x - y) * DT
    assert np.all(np.abs(unsent_angle) < delta * (1 + 1e-6))
    assert np.all(np.abs(y[sent]) * DT >= delta * (1 - 1e-9))
    assert np.mean(sent) == pytest.approx(SETS['z'].delta_kernel(delta, DT, SIG)[4], rel=0.02)
