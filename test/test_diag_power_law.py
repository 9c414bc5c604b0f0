"""Power laws off their IEEE slope: bias_instability and rate_random_walk with ``alpha``."""
import bench_script
from gyro_char.diagnosis import engine, expected, static, static_expect
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS
from gyro_char.sim.effects.sensor import pivot_scale
import numpy as np
import pytest
from scipy import signal

DT = 0.01
BASE = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=0.0, dt=DT)


def _exact_avar(c: np.ndarray, m: int) -> float:
    # Allan variance of unit innovations through the causal filter c: the estimator is the
    # filter (C_j - 2 C_(j-m) + C_(j-2m)) / (sqrt(2) m) on the innovations, C = cumsum(c).
    big = np.concatenate([np.zeros(2 * m + 1), np.cumsum(c)])
    g = big[2 * m:] - 2.0 * big[m:-m] + big[:-2 * m]
    return float(np.dot(g, g) / (2.0 * m * m))


@pytest.mark.parametrize('name,alpha,corner', [('bias_instability', 1.0, 0.05),
                                               ('bias_instability', 1.0, 2.0),
                                               ('bias_instability', 1.3, 0.0),
                                               ('bias_instability', 1.3, 0.5),
                                               ('rate_random_walk', 1.7, 0.0)])
def test_closed_form_allan_equals_the_generators_exact_avar(name, alpha, corner):
    # From the generator's own impulse response, (1 - z^-1)^(-alpha/2) (times the corner's
    # (1 - b)^(alpha/2) b^k h_k), scaled by pivot_scale: independent of the PSD form. The
    # plain flicker with a corner (alpha 1) too.
    n, pivot = 2 ** 16, 0.003
    plain, key, coef = (1.0, 'B', 5e-5) if name == 'bias_instability' else (2.0, 'K', 2e-5)
    params = {key: coef, 'alpha': alpha, 'pivot_hz': pivot}
    if corner:
        params['corner_hz'] = corner
    g = expected.grids(n, DT)
    got = expected.avar(model_spectrum(0.0, 0.0, DT, [(name, params)]), g)[:10]
    scale = coef * pivot_scale(alpha, plain, pivot, DT) * (np.sqrt(DT) if plain == 2.0 else 1.0)
    pole = np.exp(-2.0 * np.pi * corner * DT)
    want = []
    for m in g.m[:10]:
        length = 2000 * int(m)
        k = np.arange(1, length, dtype=np.float64)
        h = np.concatenate([[1.0], np.cumprod((k - 1.0 + alpha / 2.0) / k)])
        if corner:
            h = signal.fftconvolve(h, (1.0 - pole) ** (alpha / 2.0)
                                   * pole ** np.arange(length) * h)[:length]
        want.append(scale ** 2 * _exact_avar(h, int(m)))
    np.testing.assert_allclose(got, want, rtol=5e-3)


def test_the_pivot_is_where_the_fractional_psd_meets_the_plain_one():
    f = np.array([0.003, 0.03])
    for name, key, plain, other in (('bias_instability', 'B', 1.0, 1.4),
                                    ('rate_random_walk', 'K', 2.0, 1.6)):
        p = {key: 1e-4, 'pivot_hz': 0.003}
        a = model_spectrum(0.0, 0.0, DT, [(name, p)]).one_sided(f)
        b = model_spectrum(0.0, 0.0, DT, [(name, {**p, 'alpha': other})]).one_sided(f)
        assert b[0] == pytest.approx(a[0], rel=1e-9)
        # A decade above it the slopes part by (plain - alpha) decades of power.
        assert np.log10(b[1] / a[1]) == pytest.approx(plain - other, abs=1e-3)


def test_the_plain_slope_is_the_old_effect_bit_for_bit():
    n = 5000
    for name, p, plain in (('bias_instability', {'B': 3e-4}, 1.0),
                           ('rate_random_walk', {'K': 3e-5}, 2.0)):
        old = static.simulate_twin(BASE, n, [(name, p)], 4)
        new = static.simulate_twin(BASE, n, [(name, {**p, 'alpha': plain, 'pivot_hz': 0.2})], 4)
        assert np.array_equal(old, new)
        assert 'alpha' not in EFFECTS[name](**p).describe()['params']
        assert EFFECTS[name](**p, alpha=plain + 0.25).describe()['params']['alpha'] == plain + 0.25
        for bad in ({'alpha': 0.0}, {'alpha': 3.0}, {'pivot_hz': 0.0}):
            with pytest.raises(InputError):
                EFFECTS[name](**p, **bad).check()


def _fbm_rate(n: int, hurst: float, c: float, rng) -> np.ndarray:
    # Fractional Brownian motion from zero by circulant embedding of its increments' (fGn)
    # autocovariance (Davies-Harte), variogram c^2 (u / 1 s)^(2 H): not the simulator's
    # fractional filter.
    k = np.arange(n + 1, dtype=float)
    h2 = 2.0 * hurst
    cov = 0.5 * (np.abs(k + 1) ** h2 - 2 * k ** h2 + np.abs(k - 1) ** h2)
    lam = np.fft.fft(np.concatenate([cov, cov[-2:0:-1]])).real
    z = rng.standard_normal(2 * n) + 1j * rng.standard_normal(2 * n)
    w = np.fft.fft(np.sqrt(np.maximum(lam, 0.0) / (2 * n)) * z)[:n].real
    return np.cumsum(w) * c * DT ** hurst


def test_a_fractional_walk_is_named_a_walk_with_its_slope():
    # Two hours of fBm of H 0.3 (PSD 1/f^1.6): between flicker and a walk, nearer the walk.
    # Without a slope, a Gauss-Markov process of ~170 s followed it best and took the name.
    h = bench_script.load('validate_diagnosis')
    n = 720000
    rng = np.random.default_rng(17)
    x = h.make_record([], n, seed=17) + _fbm_rate(n, 0.3, 2e-4, rng)
    p = static_expect.closed_form_problem([x], h.DT, twins=5, seed=29)
    d = engine.run(p, repeats=5, seed=29)
    assert d.selected_effects[:1] == ['rate_random_walk']
    fit = dict(d.model)['rate_random_walk']
    assert 1.5 <= fit['alpha'] <= 1.75
