"""
What the held-out shape tests share: the bench numbers, the preset noise and the set checks.

Generators only, never the diagnosis: each set's own file checks its shapes' physics; here
are the checks every set passes (names, edge levels at z ~ 4, finite output, both harnesses
reach the set by ``--held-out LETTER``).
"""
import bench_script
from gyro_char.allan.kernel import overlapping_avar
from gyro_char.sim.config import BenchConfig
import numpy as np
import pytest
from scipy import signal

DT = 0.01
N_ARW = 2.4 * np.pi / 180.0 / 60.0
SIG = N_ARW / np.sqrt(DT)
AMP, PERIOD = np.deg2rad(20.0), 5.0
W = 2 * np.pi / PERIOD
G0 = 9.80665
INC = N_ARW * np.sqrt(DT)       # the static records' white-noise angle step per sample
# the preset gyro's per-sample noise at 1 kHz (its ARW, 1.89 deg/sqrt(h))
S_N = 1.890 * np.pi / 180.0 / 60.0 * np.sqrt(1000.0)
# sd of a fitted rate-residual sine on a 900 s swing run of the preset's gyro
S_LINE = BenchConfig.from_preset('adis16405').noise['gyro_x']['N'] * np.sqrt(2 / 900.0)
STATIC_NAMES = ['internal_lowpass', 'vibration', 'temperature_drift', 'bias_instability',
                'rate_random_walk', 'gauss_markov', 'quantization', 'resonance']
SWING_NAMES = ['time_delay', 'g_sensitivity', 'scale_factor_nonlinearity',
               'scale_factor_asymmetry', 'timestamp_jitter', 'encoder_cyclic_error']


def avar(y, m):
    return overlapping_avar(y, DT, m=m)[1]


def fit(y, cols):
    return np.linalg.lstsq(np.c_[tuple(cols)], y, rcond=None)[0]


def flicker_band_psd(fn, b=1.0):
    """Four 2^17-sample records of ``fn`` on zeros, their mean Welch PSD and its 0.05-5 Hz band."""
    rng = np.random.default_rng(5)
    ys = np.array([fn(np.zeros(2 ** 17), rng, b=b) for _ in range(4)])
    f, p = signal.welch(ys, fs=1 / DT, nperseg=2 ** 14)
    return ys, f, p.mean(axis=0), (f >= 0.05) & (f <= 5.0)


def octave_ratios(f, pxx, band, want):
    """Measured over exact PSD, averaged in each of the seven octaves of the 0.05-5 Hz band."""
    octave = np.floor(np.log2(f[band] / 0.05))
    return [np.mean(pxx[band][octave == k]) / np.mean(want[octave == k]) for k in range(7)]


def stand(t):
    return AMP * np.sin(W * t), AMP * W * np.cos(W * t)


def stand_of(period, amp=AMP):
    """Return the true (angle, rate) of a swing of ``amp`` rad and ``period`` seconds."""
    w = 2 * np.pi / period

    def stand_at(t):
        return amp * np.sin(w * t), amp * w * np.cos(w * t)
    return stand_at


def fold_lines(err, kmax=60, kmin=2):
    """Norm of lines kmin..kmax of ``err`` folded over the 5 s swing period (1 kHz samples)."""
    m = 5000
    mean = err[:err.size // m * m].reshape(-1, m).mean(axis=0)
    return float(2 * np.linalg.norm(np.fft.rfft(mean)[kmin:kmax + 1] / m))


def load_set(letter):
    """Return set ``letter``'s static and swing modules and their shapes at the bench numbers."""
    static = bench_script.load(f'validate_diagnosis_heldout_{letter}')
    swing = bench_script.load(f'validate_diagnosis_swing_heldout_{letter}')
    return static, swing, static.shapes(DT, SIG, N_ARW), swing.shapes(1000.0)


def rng(seed):
    return np.random.default_rng(seed)


def swing_runner(shapes):
    """Return ``run(name, p, seconds, ...)`` of a swing set's ``shapes`` (its tests' driver)."""
    def run(name, p, seconds, period=5.0, amp=AMP, seed=10, noise=0.0, stand=None):
        """Return (t, angle, rate, gyro in, fn's output) on a 1 kHz swing of ``seconds``."""
        stand = stand or stand_of(period, amp)
        t = np.arange(int(round(seconds * 1000))) * 1e-3
        angle, rate = stand(t)
        x = rate + noise * rng(seed + 1).standard_normal(t.size)
        out = shapes[name][0](t, x.copy(), t.copy(), angle.copy(), stand, rng(seed), **p)
        return t, angle, rate, x, out
    return run


def lines(err, per):
    """Return the complex Fourier series (rfft over n) of ``err`` folded over ``per`` samples."""
    fold = err[:err.size // per * per].reshape(-1, per).mean(axis=0)
    return np.fft.rfft(fold) / per


def white(n, seed):
    """White rate noise of the harness's level plus a small bias (a static record)."""
    return SIG * rng(seed).standard_normal(n) + 0.003


def noisy_run(seed=13):
    """Return (t, gyro): a 900 s, 1 kHz swing's true rate plus the preset gyro's white noise."""
    t = np.arange(900000) * 1e-3
    rate = AMP * W * np.cos(W * t)
    n_pre = S_LINE / np.sqrt(2 / 900.0)                                # the preset's N
    return t, rate + n_pre * np.sqrt(1000.0) * np.random.default_rng(seed).standard_normal(
        t.size)


def swing(fn, p, duration=60.0, stand=stand):
    t = np.arange(int(duration * 1000)) * 1e-3
    angle, rate = stand(t)
    return t, rate, fn(t, rate.copy(), t.copy(), angle.copy(), stand,
                       np.random.default_rng(10), **p)


def check_static_set(module, shapes, names=STATIC_NAMES, reproducible=False):
    """
    Names, edge z in [3.5, 4.5] below weak < strong, finite output that differs from x.

    ``reproducible``: also the same output from the same generator seed.
    """
    assert sorted(shapes) == sorted(names)
    for name, (fn, levels) in shapes.items():
        weak, strong, edge = [module.detectability(name, p, DT, SIG, N_ARW) for p in levels]
        assert 3.5 <= edge <= 4.5 and 2.5 * edge < weak < strong, (name, edge, weak, strong)
        for p in levels:
            rng = np.random.default_rng(1)
            x = SIG * rng.standard_normal(20000) + 0.003
            # Reproducible sets are run from a fresh generator (the same seed twice).
            y = fn(x.copy(), np.random.default_rng(1) if reproducible else rng, **p)
            assert y.shape == x.shape and np.all(np.isfinite(y)), name
            assert not np.allclose(y, x, rtol=0, atol=1e-12), name
            if reproducible:
                assert np.array_equal(fn(x.copy(), np.random.default_rng(1), **p), y), name


def check_swing_set(module, shapes):
    """Names, edge z in [3.5, 4.5] below weak < strong, finite increasing-stamp output."""
    assert sorted(shapes) == sorted(SWING_NAMES)
    for name, (fn, levels) in shapes.items():
        weak, strong, edge = [module.detectability(name, p) for p in levels]
        assert 3.5 <= edge <= 4.5 and 2.5 * edge < weak < strong, (name, edge, weak, strong)
        for p in levels:
            t, rate, out = swing(fn, p, 20.0)
            assert len(out) == 4 and all(a.shape == t.shape and np.all(np.isfinite(a))
                                         for a in out), name
            assert np.all(np.diff(out[2]) > 0) and np.all(np.diff(out[0]) > 0), name


def swing_set_tests(module, off):
    """
    Return the checks every swing set with edges at z ~ 4 shares, as pytest test functions.

    The set's names, levels and output (``check_swing_set``) and reproducible generators;
    each edge at z = 4 +- 0.15 (``module.detectability``); each shape at its ``off[name]``
    parameters returns the run unchanged.
    """
    shapes = module.shapes(1000.0)
    edge = {}

    def test_set_covers_the_catalogue_with_reproducible_generators():
        check_swing_set(module, shapes)
        for name, (fn, levels) in shapes.items():
            a, b = (swing(fn, levels[0], 10.0)[2] for _ in range(2))
            assert all(np.array_equal(u, v) for u, v in zip(a, b)), name

    @pytest.mark.parametrize('name', SWING_NAMES)
    def test_edge_is_at_z4(name):
        if name not in edge:
            edge[name] = module.detectability(name, shapes[name][1][2])
        assert edge[name] == pytest.approx(4.0, abs=0.15), name

    @pytest.mark.parametrize('name', SWING_NAMES)
    def test_off_levels_leave_the_run_unchanged(name):
        t, rate, out = swing(shapes[name][0], off[name], 10.0)
        want = (t, rate, t, AMP * np.sin(W * t))
        assert all(np.allclose(a, b, rtol=0, atol=1e-12) for a, b in zip(out, want)), name

    return (test_set_covers_the_catalogue_with_reproducible_generators, test_edge_is_at_z4,
            test_off_levels_leave_the_run_unchanged)


def solved_levels_test(module, names=None):
    """
    Return a test that the set's literal levels are those ``module.levels`` solves.

    ``names`` the shapes to check (all of ``module.KEY`` by default; the slow solves left out).
    """
    shapes = module.shapes(1000.0)

    @pytest.mark.parametrize('name', sorted(module.KEY) if names is None else names)
    def test_levels_are_the_solved_ones(name):
        assert module.levels([name])[name] == shapes[name][1], name

    return test_levels_are_the_solved_ones


def period_z_ratio(module, name, level=2):
    """Return the z of a shape's level at the 2.5 s period over that at 5 s."""
    p = module.shapes(1000.0)[name][1][level]
    return module.detectability(name, p, period_s=2.5) / module.detectability(name, p)


def unit_stamp_errors(fn, sigma, seed0, runs=4):
    """
    Return a stamp-error shape's encoder stamp errors over ``sigma`` (runs x 2^17 samples).

    Each run at 1 kHz, from seeds ``seed0``.., is checked to leave the IMU stamps and the
    encoder angle alone and to keep the encoder stamps increasing.
    """
    t = np.arange(2 ** 17) * 1e-3
    outs = [fn(t, t * 0, t.copy(), np.sin(W * t), None, rng(seed0 + i), sigma=sigma)
            for i in range(runs)]
    for out in outs:
        assert np.array_equal(out[0], t) and np.array_equal(out[3], np.sin(W * t))
        assert np.all(np.diff(out[2]) > 0)
    return np.array([(out[2] - t) / sigma for out in outs])


def check_harnesses(letter, shapes, swing_shapes, monkeypatch):
    """Both validation harnesses load the set by ``--held-out LETTER`` (no case is run)."""
    static = bench_script.load('validate_diagnosis')
    seen = []
    monkeypatch.setattr(static, 'cases', lambda *a, **k: seen.append(a[3]) or [])
    static.main(['--held-out', letter])
    assert sorted(seen[0]) == sorted(shapes)
    assert seen[0]['quantization'][1] == shapes['quantization'][1]
    harness = bench_script.load('validate_diagnosis_swing')
    assert sorted(harness.held_out_shapes(1000.0, letter)) == sorted(swing_shapes)
    assert (harness.held_out_shapes(1000.0, letter)['time_delay'][1]
            == swing_shapes['time_delay'][1])
