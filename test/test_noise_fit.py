"""IEEE 952 fit: exact on model curves, the L1 optimum, term selection, recovery on synthetics."""
from gyro_char.allan_input import compute
from gyro_char.noise_fit import _L1Step, _objective, fit_l1, fit_noise, fit_result
from gyro_char.noise_gen import generate
from gyro_char.noise_model import design_matrix, model_avar, TERMS
from gyro_char.recordings import Recording
import numpy as np
import pytest
from scipy import optimize

TAU = np.logspace(-2, 3.5, 56)
TRUE = {'R': 2e-7, 'K': 1e-5, 'B': 1e-4, 'N': 1e-3, 'Q': 2e-5}


def test_exact_on_noise_free_curve():
    avar = model_avar(TAU, TRUE)
    z = fit_l1(design_matrix(TAU), avar)
    coef = dict(zip(TERMS, np.sqrt(z)))
    for t in TERMS:
        assert coef[t] == pytest.approx(TRUE[t], rel=1e-4), t


def test_l1_solution_is_the_optimum():
    # On a noisy curve no local search from the LP answer (or from the truth) does better.
    rng = np.random.default_rng(3)
    a_mat = design_matrix(TAU)
    avar = model_avar(TAU, TRUE) * np.exp(0.3 * rng.standard_normal(TAU.size))
    z = fit_l1(a_mat, avar)
    assert np.all(z >= 0)

    def obj(x):
        return np.sum(np.abs(np.log(avar) - np.log(a_mat @ (x ** 2))))

    best = obj(np.sqrt(z))
    for start in (np.sqrt(z), np.array([TRUE[t] for t in TERMS])):
        sol = optimize.minimize(obj, start * 1.05, method='Nelder-Mead',
                                options={'xatol': 1e-12, 'fatol': 1e-12, 'maxiter': 4000})
        assert sol.fun >= best - 1e-9


def test_unsupported_term_is_unresolved_with_upper_bound():
    truth = {'N': 1e-3, 'B': 1e-4}
    avar = model_avar(TAU, truth)
    edf = np.full(TAU.size, 50.0)
    fit = fit_noise(TAU, avar, edf, np.zeros(TAU.size, int), channel='gyro_x', n_boot=30)
    assert fit.terms['N'].resolved and fit.terms['B'].resolved
    for t in ('K', 'R', 'Q'):
        term = fit.terms[t]
        assert not term.resolved and term.ci68 is None and term.value > 0
        # the bound is where the term alone reaches the upper 68 % curve somewhere
        assert np.all(model_avar(TAU, {t: term.value}) <= avar * 1.5)
        assert np.any(model_avar(TAU, {t: term.value * 1.01}) > avar)
    assert fit.to_json()['N']['unit'] == 'rad/s^0.5'
    assert set(fit.to_json()) == {'N', 'B', 'K', 'Q', 'R'}


SYN_TRUTH = {'N': 1e-3, 'B': 2e-4, 'K': 2e-5, 'Q': 3e-4, 'R': 1e-8}


@pytest.fixture(scope='module')
def synthetic_results():
    dt, n = 0.02, 360_000
    out = []
    for seed in range(3):
        rate = generate(n, dt, rng=np.random.default_rng(seed), **SYN_TRUTH)
        out.append(compute(Recording(np.arange(n) * dt, {'gyro_x': rate})))
    return out


def test_warm_highs_step_matches_linprog():
    # The warm-started HiGHS model and the cold linprog fallback reach the same L1 optimum.
    rng = np.random.default_rng(5)
    a_mat = design_matrix(TAU)
    for _ in range(3):
        avar = model_avar(TAU, TRUE) * np.exp(0.3 * rng.standard_normal(TAU.size))
        warm = _L1Step(a_mat, avar)
        cold = _L1Step(a_mat, avar)
        cold.highs = None
        z_w, z_c = fit_l1(a_mat, avar, step=warm), fit_l1(a_mat, avar, step=cold)
        assert _objective(z_w, a_mat, np.log(avar)) == pytest.approx(
            _objective(z_c, a_mat, np.log(avar)), rel=1e-9)


@pytest.mark.parametrize('method', ['l1', 'l1w', 'weighted'])
def test_recovery_on_synthetic_records(method, synthetic_results):
    # Small version of bench/fit_recovery.py: 2 h at 50 Hz, 3 seeds, all five terms (K
    # dominates only the last 1.5 decades of tau, so its error is larger than in 8 h).
    truth = SYN_TRUTH
    errs = []
    for seed, res in enumerate(synthetic_results):
        fit = fit_result(res, method=method, n_boot=20, seed=seed)['gyro_x']
        errs.append({t: fit.terms[t].value / truth[t] - 1.0 for t in truth})
        assert fit.terms['N'].resolved and fit.terms['Q'].resolved
        assert not fit.terms['R'].resolved  # 1e-8 rad/s^2 is invisible in 2 h
    med = {t: np.median([abs(e[t]) for e in errs]) for t in truth}
    assert med['N'] <= 0.03 and med['Q'] <= 0.03 and med['K'] <= 0.2 and med['B'] <= 0.3, med
