"""
Solvers of the noise fit.

The log-domain L1 fit (sequential linear programs), weighted log least squares, and the
covariance of ln sigma^2 between taus used by the intervals and by the term selection.
"""
from typing import Optional, Tuple

import numpy as np
from scipy import optimize, special

try:  # scipy's own HiGHS binding: warm-started LPs (see L1Step); linprog otherwise.
    from scipy.optimize._highspy import _core as _highs_core
except ImportError:  # pragma: no cover - other scipy layouts
    _highs_core = None

# Correlation length (octaves) of ln sigma^2 between taus, by noise type alpha.
CORR_OCTAVES = {2: 1.5, 1: 1.5, 0: 1.5, -1: 2.2, -2: 6.0}


def objective(z, a_mat, log_a, wts=1.0):
    p = a_mat @ z
    if np.any(p <= 0):
        return np.inf
    return float(np.sum(wts * np.abs(log_a - np.log(p))))


class L1Step:
    """
    The linearised L1 step min_z>=0 sum |w (t - A z)| of one design matrix, warm-started.

    Solved through its small dual LP (5 rows): max (w t)^T y s.t. (diag(w) A S)^T y <= 0,
    -1 <= y <= 1, S = diag(scale); z is the dual value (marginal) of the rows, z = S * marginal.
    Substituting u = (w / w0) y with a fixed reference weight w0 = 1 / ``ref`` makes the
    constraint matrix diag(w0) A S the same for every step and every bootstrap curve: only the
    costs (w0 t) and the bounds (+-w / w0) change, so one HiGHS model per term set is kept and
    each step restarts the dual simplex from the previous basis (~0.3 ms instead of ~8 ms
    through ``linprog``). ``linprog`` is the fallback when scipy's HiGHS binding is missing
    or a warm solve does not report optimal.
    """

    def __init__(self, a_mat, ref):
        self.a_mat = a_mat
        with np.errstate(divide='ignore'):
            self.scale = 1.0 / np.max(a_mat / ref[:, None], axis=0)
        self.w0 = 1.0 / ref
        self.g0 = a_mat * self.scale * self.w0[:, None]
        self.highs = _highs_model(self.g0) if _highs_core is not None else None
        self.idx = np.arange(ref.size, dtype=np.int32)

    def __call__(self, target, weight) -> Optional[np.ndarray]:
        if self.highs is not None:
            h = self.highs
            h.changeColsCost(self.idx.size, self.idx, -(target * self.w0))
            bound = weight / self.w0
            h.changeColsBounds(self.idx.size, self.idx, -bound, bound)
            h.run()
            if h.getModelStatus() == _highs_core.HighsModelStatus.kOptimal:
                return np.maximum(-np.asarray(h.getSolution().row_dual), 0.0) * self.scale
            h.clearSolver()  # a stale basis: fall through to a cold, independent solve
        g = self.g0 * (weight / self.w0)[:, None]
        sol = optimize.linprog(-(target * weight), A_ub=g.T, b_ub=np.zeros(g.shape[1]),
                               bounds=(-1, 1), method='highs')
        if sol.status != 0:
            return None
        return np.maximum(-sol.ineqlin.marginals, 0.0) * self.scale


def _highs_model(g0):
    k, n = g0.shape
    h = _highs_core._Highs()
    h.setOptionValue('output_flag', False)
    lp = _highs_core.HighsLp()
    lp.num_col_, lp.num_row_ = k, n
    lp.col_cost_, lp.col_lower_, lp.col_upper_ = np.zeros(k), -np.ones(k), np.ones(k)
    lp.row_lower_, lp.row_upper_ = np.full(n, -np.inf), np.zeros(n)
    mat = lp.a_matrix_
    mat.format_ = _highs_core.MatrixFormat.kColwise
    mat.num_col_, mat.num_row_ = k, n
    mat.start_ = np.arange(0, k * n + 1, n, dtype=np.int32)
    mat.index_ = np.tile(np.arange(n, dtype=np.int32), k)
    mat.value_ = np.ascontiguousarray(g0).ravel()
    h.passModel(lp)
    return h


def fit_l1(a_mat: np.ndarray, avar: np.ndarray, z0: Optional[np.ndarray] = None,
           max_iter: int = 30, step: Optional[L1Step] = None, wts=1.0) -> np.ndarray:
    """
    Return z >= 0 minimising sum |ln avar - ln (A z)| (sequential LP, see module doc).

    ``step``: an ``L1Step`` of ``a_mat`` to reuse (warm starts across curves).
    """
    log_a = np.log(avar)
    step = step or L1Step(a_mat, avar)
    if z0 is None:
        z0 = step(avar, wts / avar)
    best = objective(z0, a_mat, log_a, wts)
    z = z0
    for _ in range(max_iter):
        p = a_mat @ z
        cand = step(p * (1.0 + log_a - np.log(p)), wts / p)
        if cand is None:
            break
        moved = _halve_towards(z, cand, best, lambda trial: objective(trial, a_mat, log_a, wts))
        if moved is None:
            break
        z, best = moved
    return z


def _halve_towards(z: np.ndarray, cand: np.ndarray, best: float, cost
                   ) -> Optional[Tuple[np.ndarray, float]]:
    """
    Step from ``z`` towards ``cand``, halving the step until ``cost`` drops below ``best``.

    Return ``(trial, cost(trial))`` of the first step that descends, or None when no step down
    to 1e-4 of the way does.
    """
    frac = 1.0
    while frac > 1e-4:
        trial = z + frac * (cand - z)
        f = cost(trial)
        if f < best - 1e-12 * max(1.0, best):
            return trial, f
        frac *= 0.5
    return None


def allan_cov(tau: np.ndarray, edf: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """Return the covariance of ln sigma^2 between taus (module docstring), made PSD."""
    var = special.polygamma(1, edf / 2.0)
    ell = np.array([CORR_OCTAVES[int(a)] for a in alpha])
    octaves = np.abs(np.log2(tau)[:, None] - np.log2(tau)[None, :])
    rho = np.exp(-octaves / np.sqrt(ell[:, None] * ell[None, :]))
    cov = rho * np.sqrt(var[:, None] * var[None, :])
    w, v = np.linalg.eigh(cov)
    return (v * np.maximum(w, 1e-9 * w.max())) @ v.T


def fit_weighted(a_mat, avar, edf, z0, max_iter: int = 30) -> np.ndarray:
    """
    Return z >= 0 from weighted least squares on ln sigma^2 (bias-corrected), from ``z0``.

    Gauss-Newton: ln(A z) is linearised around the current fit, the weighted linear problem
    with z >= 0 is solved by NNLS, and a step halving on the objective ensures descent.
    """
    bias = special.digamma(edf / 2.0) - np.log(edf / 2.0)
    white = np.diag(1.0 / np.sqrt(special.polygamma(1, edf / 2.0)))
    target = np.log(avar) - bias
    with np.errstate(divide='ignore'):
        scale = 1.0 / np.max(a_mat / avar[:, None], axis=0)

    def cost(z):
        p = a_mat @ z
        if np.any(p <= 0):
            return np.inf
        r = white @ (target - np.log(p))
        return float(r @ r)

    z, best = z0, cost(z0)
    for _ in range(max_iter):
        p = a_mat @ z
        jac = white @ (a_mat * scale / p[:, None])
        rhs = white @ (target - np.log(p) + 1.0)
        cand = optimize.nnls(jac, rhs)[0] * scale
        moved = _halve_towards(z, cand, best, cost)
        if moved is None:
            break
        z, best = moved
    return z
