# The output step's exact rounding of a coarse-grid rate: the closed form against rounded
# samples, its inverse, and a diagnosis of records whose step exceeds their noise.
from gyro_char.diagnosis import rounding, static_expect
from gyro_char.diagnosis.engine import run
import numpy as np
import pytest

DT = 0.01


@pytest.mark.parametrize('ratio, frac', [(4.0, 0.0), (4.0, 0.3), (4.0, 0.5), (2.0, 0.2),
                                         (1.0, 0.45), (0.6, 0.1)])
def test_rounded_variance_equals_rounded_samples(ratio, frac):
    sigma, q = 1.0, ratio
    mu = (7 + frac) * q
    x = np.random.default_rng(3).normal(mu, sigma, 2_000_000)
    v = np.var(np.round(x / q) * q)
    assert rounding.rounded_variance(sigma, mu, q) == pytest.approx(v, rel=0.01)


def test_a_fine_step_adds_exactly_lsb2_over_12_and_a_coarse_one_depends_on_the_mean():
    q = 0.5
    assert rounding.excess(1.0, 0.123, q) == q * q / 12.0       # sd 2 steps: the white model
    on_level = rounding.excess(0.25 ** 2, 0.0, 1.0)               # sd a quarter step
    half_way = rounding.excess(0.25 ** 2, 0.5, 1.0)
    assert on_level < 0.0 < 1.0 / 12.0 < half_way                 # hides noise / a coin flip


@pytest.mark.parametrize('frac', [0.0, 0.3])
def test_sigma_for_inverts_the_rounded_variance(frac):
    q, sigma = 1.0, 0.3
    v = rounding.rounded_variance(sigma, frac * q, q)
    assert rounding.sigma_for(v, frac * q, q) == pytest.approx(sigma, rel=0.02)


def _coarse(n, seed, q_over_sigma, frac, extra=None):
    sigma = 5e-3
    q = q_over_sigma * sigma
    rng = np.random.default_rng(seed)
    x = (3 + frac) * q + sigma * rng.standard_normal(n)
    if extra is not None:
        x = x + extra
    return np.round(x / q) * q


@pytest.mark.parametrize('q_over_sigma, frac', [(4.0, 0.8), (2.5, 0.5)])
def test_a_clean_record_on_a_coarse_grid_is_consistent_with_its_baseline(q_over_sigma, frac):
    # Before the exact rounding the twins lay off the closed forms by ~60-100 rms and the
    # null level rose to ~50 (a strong effect on such a record went undetected).
    x = _coarse(2 ** 17, 4, q_over_sigma, frac)
    problem = static_expect.closed_form_problem([x], DT, seed=3)
    assert all(c['rms_residual'] < 2.0 for c in problem.check['records'][0].values())
    assert problem.baseline['N']['value'] == pytest.approx(5e-4, rel=0.2)
    d = run(problem, seed=3)
    assert d.null_gap['q95'] < 1.5 and d.selected_effects == []
    assert d.verdict['code'] == 'consistent'


def test_a_tone_on_a_coarse_grid_is_named():
    n = 2 ** 16
    tone = 4e-3 * np.sin(2 * np.pi * 17.3 * np.arange(n) * DT)
    x = _coarse(n, 5, 3.0, 0.3, extra=tone)
    d = run(static_expect.closed_form_problem([x], DT, seed=3), seed=3)
    assert d.null_gap['q95'] < 1.5
    assert d.selected_effects[:1] == ['vibration']
    assert d.final_gap < 0.2 * d.baseline_gap
