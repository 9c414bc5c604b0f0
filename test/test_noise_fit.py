"""IEEE 952 fit: exact on model curves, the L1 optimum, term selection, recovery on synthetics."""
from gyro_char.allan.compute import compute
from gyro_char.allan.edf import chi2_interval
from gyro_char.allan.fit import fit_noise, fit_result
from gyro_char.allan.model import design_matrix, model_avar, TERMS
from gyro_char.allan.solvers import fit_l1, L1Step, objective
from gyro_char.records import Recording
from gyro_char.sim.noise_gen import generate
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
        warm = L1Step(a_mat, avar)
        cold = L1Step(a_mat, avar)
        cold.highs = None
        z_w, z_c = fit_l1(a_mat, avar, step=warm), fit_l1(a_mat, avar, step=cold)
        assert objective(z_w, a_mat, np.log(avar)) == pytest.approx(
            objective(z_c, a_mat, np.log(avar)), rel=1e-9)


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


@pytest.mark.parametrize('truth', [{'N': 1e-3}, {'N': 1e-3, 'B': 2e-4}],
                         ids=['white', 'white+flicker'])
def test_selection_drops_absent_terms(truth):
    # 1 h at 50 Hz: terms the record does not hold are eliminated (coefficient 0) and never
    # reported resolved; the present ones are kept and resolved. Elimination is a one-sided
    # 5 % test per term, so a rare chance keep is allowed: at most 1 of the 27-36 cases.
    dt, n = 0.02, 180_000
    kept = []
    for seed in range(3):
        rate = generate(n, dt, rng=np.random.default_rng(10 + seed), **truth)
        res = compute(Recording(np.arange(n) * dt, {'gyro_x': rate}))
        for method in ('l1', 'l1w', 'weighted'):
            fit = fit_result(res, method=method, n_boot=20, seed=seed)['gyro_x']
            for t in TERMS:
                if t in truth:
                    assert fit.terms[t].resolved, (seed, method, t)
                    assert fit.fitted[t] == pytest.approx(truth[t], rel=0.3), (seed, method, t)
                else:
                    assert not fit.terms[t].resolved, (seed, method, t)
                    if fit.fitted[t] != 0.0:
                        kept.append((seed, method, t))
    assert len(kept) <= 1, kept


@pytest.fixture(scope='module')
def adis_session1(adis_records):
    from gyro_char.io import read_imu
    rec = read_imu(str(adis_records[0]), quiet=True)
    return compute(rec, ['gyro_x', 'gyro_y', 'gyro_z'])


@pytest.mark.parametrize('method', ['l1', 'l1w'])
def test_selected_model_follows_the_real_adis16405_curve(method, adis_session1):
    # Regression: formula (4) misfits the ADIS16405 below ~1 s (internal averaging filter, a
    # 20 Hz tone on Z), and selection by the correlated chi-square then kept only N on Z,
    # its curve 600x under the measured Allan variance at 2600 s. B (the flat floor, plainly
    # visible) must be resolved on every axis, and the selected model of the paper's
    # objective must follow the curve within a factor 2 (or the 95 % interval where that is
    # looser) for tau >= 1 s. 'l1w' is held to that on X and Z only: on Y it judges K a
    # 1.9 sigma term (below GAIN_MIN) and drops it, 4-8x under the last 8 points (EDF 2-4).
    res = adis_session1
    for c, (name, fit) in enumerate(fit_result(res, method=method, n_boot=20).items()):
        assert fit.terms['B'].resolved, (name, fit.to_json())
        if method == 'l1w' and name == 'gyro_y':
            continue
        sel = fit.tau >= 1.0
        model = model_avar(fit.tau, fit.coeffs())[sel]
        avar, edf = fit.avar[sel], res.edf[:, c][res.avar[:, c] > 0][fit.tau >= 1.0]
        lo, hi = chi2_interval(np.sqrt(avar), edf, 0.95)
        ok = ((model >= np.minimum(avar / 2.0, lo ** 2))
              & (model <= np.maximum(avar * 2.0, hi ** 2)))
        assert np.all(ok), (name, fit.tau[sel][~ok], (avar / model)[~ok])


def test_a_constant_channel_is_refused_not_fitted_on_rounding():
    # A fixed 9.81 m/s^2 through the streaming sums leaves Allan variances of ~1e-55: noise of
    # the arithmetic. It must fail with a reason, while a tiny but real noise still fits.
    from dataclasses import replace
    from gyro_char.live.allan_live import AllanLive
    rng = np.random.default_rng(3)
    n = 6000
    t = np.arange(n) * 0.003
    x = np.c_[np.full(n, 9.81), 9.81 + 1e-9 * rng.standard_normal(n)]
    live = AllanLive(('accel_z', 'accel_y'), m_max=4096)
    for k in range(0, n, 200):
        live.add(t[k:k + 200], x[k:k + 200])
    res = live.result()
    assert 0 < res.avar[:, 0].max() < 1e-45   # the rounding residue this guards against
    const = replace(res, avar=res.avar[:, [0]], edf=res.edf[:, [0]], alpha=res.alpha[:, [0]],
                    channels=('accel_z',))
    with pytest.raises(ValueError, match='constant'):
        fit_result(const, n_boot=4)
    tiny = replace(res, avar=res.avar[:, [1]], edf=res.edf[:, [1]], alpha=res.alpha[:, [1]],
                   channels=('accel_y',))
    fit = fit_result(tiny, n_boot=4)['accel_y']
    assert fit.coeffs()['N'] == pytest.approx(1e-9 * np.sqrt(0.003), rel=0.1)
