"""Synthetic noise generator: each IEEE term against its closed-form Allan variance."""
from gyro_char.allan.kernel import overlapping_avar
from gyro_char.allan.model import model_avar
from gyro_char.sim.noise_gen import expected_avar, generate
import numpy as np
import pytest

DT = 0.01
M = np.array([1, 2, 4, 16, 64, 256, 1024])


def test_expected_avar_tends_to_formula_4():
    coeffs = {'N': 1e-3, 'B': 2e-4, 'K': 1e-5, 'Q': 5e-4, 'R': 1e-7}
    exact = expected_avar(M, DT, **coeffs)
    closed = model_avar(M * DT, coeffs)
    rel = exact / closed - 1.0
    assert np.all(np.abs(rel[M >= 64]) < 1e-3)
    # Single flicker term: the documented discrete-time excess at m = 1 is 1/ln2.
    ratio = expected_avar([1], DT, B=1.0)[0] / model_avar([DT], {'B': 1.0})[0]
    assert ratio == pytest.approx(1.0 / np.log(2.0), rel=1e-6)


@pytest.mark.parametrize('term,value', [('N', 1e-3), ('B', 2e-4), ('K', 3e-5), ('Q', 1e-3),
                                        ('R', 1e-6)])
def test_each_term_matches_closed_form(term, value):
    n, seeds = 200_000, 4
    mean = np.zeros(M.size)
    for seed in range(seeds):
        rate = generate(n, DT, rng=np.random.default_rng(seed), **{term: value})
        _, avar, _ = overlapping_avar(rate, DT, m=M)
        mean += avar / seeds
    expected = expected_avar(M, DT, **{term: value})
    rel = mean / expected - 1.0
    if term == 'R':  # deterministic: exact up to rounding
        assert np.max(np.abs(rel)) < 1e-9
        return
    # Overlapping AVAR has about n/m equivalent degrees of freedom for these noises (fewer
    # for random walk), i.e. a relative s.d. of sqrt(2 m / n) per seed; allow 5 s.d.
    sd = np.sqrt(2.0 * M / (n * seeds)) * (2.0 if term == 'K' else 1.0)
    assert np.all(np.abs(rel) < 5.0 * sd + 1e-3), (term, rel, sd)


def test_flicker_is_one_over_f():
    rate = generate(2 ** 18, DT, B=1.0, rng=np.random.default_rng(7))
    f = np.fft.rfftfreq(rate.size, DT)[1:]
    psd = np.abs(np.fft.rfft(rate))[1:] ** 2 * 2.0 * DT / rate.size
    sel = (f > 0.01) & (f < 5.0)
    slope = np.polyfit(np.log(f[sel]), np.log(psd[sel]), 1)[0]
    assert slope == pytest.approx(-1.0, abs=0.05)  # Gauss-Markov would flatten to 0 at low f
    # Level: one-sided PSD ~ B^2 / (pi f).
    # Periodogram ordinates are exponential, whose median is ln2 times the mean.
    level = np.median(psd[sel] * f[sel] * np.pi) / np.log(2.0)
    assert level == pytest.approx(1.0, rel=0.1)


def test_sum_of_terms_and_validation():
    coeffs = {'N': 1e-3, 'B': 2e-4, 'K': 1e-5, 'Q': 5e-4, 'R': 1e-7}
    rate = generate(100_000, DT, rng=np.random.default_rng(3), **coeffs)
    assert rate.shape == (100_000,) and rate.dtype == np.float64
    with pytest.raises(ValueError):
        generate(10, DT, N=-1.0, rng=np.random.default_rng(0))
    with pytest.raises(ValueError):
        generate(0, DT, rng=np.random.default_rng(0))
    assert not np.any(generate(10, DT, rng=np.random.default_rng(0)))
