"""
Fit formula (4) (R, K, B, N, Q >= 0) to an Allan variance curve, with intervals and selection.

Three estimators over z = [R^2, K^2, B^2, N^2, Q^2] >= 0, p^2(tau) = A z:

- ``'l1'`` (the paper's): min sum_k |ln sigma^2_k - ln p^2_k|. Solved exactly as a sequence
  of linear programs: the log is linearised around the current fit (the first pass uses
  relative residuals, (sigma^2 - p^2) / sigma^2), each LP is solved by HiGHS, and a step
  halving on the true objective guarantees descent.
- ``'l1w'``: the same L1 objective on standardised, median-unbiased log estimates:
  sum_k |ln(sigma^2_k / med_k) - ln p^2_k| / sd_k, with med_k the median of chi2(edf)/edf
  (ln sigma^2 is left-skewed at low EDF: its median lies below ln sigma^2 by ~2/(3 edf), and
  an L1 fit is a median fit) and sd_k = sqrt(trigamma(edf/2)) the sd of ln sigma^2. Plain
  ``'l1'`` gives the ~60 long-tau points of 1-10 degrees of freedom (sd of ln sigma^2 0.4-1.8)
  the same say as points known to 1 %, which costs K accuracy (bench/fit_recovery.py, 24
  seeds: median |K error| 14 % for 'l1', 9 % for 'l1w'; the bias correction alone, without
  the weights, does not help: 15 % with the median, 19 % with the mean correction).
- ``'weighted'``: least squares on ln sigma^2 weighted by the inverse variance of the log Allan
  variance, trigamma(edf/2) (exact for a chi-square), with the chi-square log bias
  psi(edf/2) - ln(edf/2) removed. Diagonal on purpose: a full GLS with the (approximate)
  correlation between neighbouring taus below was tried and is fragile (adjacent taus are
  0.9+ correlated, so GLS ends up fitting the curve's local slope and scattered N by 2-3 %).

68 % intervals: parametric bootstrap. Curves are redrawn around the fit with the covariance of
ln sigma^2 (``allan_cov``: EDF variances, correlation between taus exp(-octaves / l) with l from
the noise type, 1.5 octaves for white, 2.2 for flicker, 6 for random walk, measured on simulated
records; Gaussian copula with exact log-chi-square marginals) and refitted with the same
estimator; the interval is the 16..84 % percentile range.

Term selection (``_Fitter.select``): backward elimination judged by the estimator's own
objective S (the L1 sum for 'l1'/'l1w', the weighted sum of squares for 'weighted'), so the
selection is consistent with the fit. Dropping term j (refitting the rest) raises S by dS_j.
Under the null "j is absent" and a correct model, local asymptotics give dS_j ~ c_j chi2_1
(a chi-bar-square: z_j >= 0 sits on the boundary), with c_j from the linearised fit:
x = d ln p / d z_j residualised on the other kept terms, and for L1 (Koenker-Bassett)
c_j = Var(sum w x sign e) / (4 sum w f x^2), f = 1 / (sqrt(2 pi) sd) the density of a log
residual at its median; for least squares c_j = Var(sum w x e) / sum w x^2. The variances use
the correlation between taus of ``allan_cov`` (for signs, (2/pi) arcsin rho), which matters:
neighbouring taus are 0.9+ correlated, so a chance improvement is ~10-30x larger than with
independent points (on simulated records without R and Q, dS / c of those terms came out
0.1-3.3, as a chi2_1 should).

Misfit. Real curves need not follow formula (4): the ADIS16405's internal averaging filter
and a 20 Hz tone bend the short-tau end, where the points have 1e4-1e5 degrees of freedom, so
the objective there is 10-100x what noise explains. As in quasi-likelihood / an F test, the
drop is judged against the dispersion phi = S_full / E S of the full model (E S the objective
expected from estimation noise alone: sd sqrt(2/pi) (n-p)/n per point for L1, (n-p)/n for
least squares), but locally: phi_k per point (its term of S over the expected one, pooled over
the correlated neighbours with weights rho, floored at 1), entering c_j where the misfit acts
(L1: the residual density f_k -> f_k / phi_k; least squares: var e_k -> phi_k var e_k). A
single global phi is dominated by the filtered short taus and made B and K on the Z gyro look
insignificant against it; the local one judges a long-tau term by the long-tau scatter.
A term stays when dS_j >= ``GAIN_MIN`` c_j (chi-bar-square ~2.3 % tail) and it makes up at
least ``SHARE_MIN`` of p^2 at some fitted tau. Backstop: a drop that is significant against
pure noise (phi = 1) and raises S by more than ``REL_MAX`` x max(S, E S) over the taus where
the term holds ``SHARE_MIN`` of the curve, or doubles S overall, is never accepted (a term
whose removal visibly breaks the fit is present, whatever phi says). (The earlier rule,
elimination on the correlated chi-square of the log residuals, measured a criterion the L1
fit does not minimise: on the ADIS16405 Z gyro, chi2/dof ~ 1000 from the short-tau misfit,
dropping B and K *lowered* it while the L1 objective rose 20x, and the reported curve missed
the data by 600x at 2600 s.)

K and R are near-collinear at long tau, and a random walk's chance trend looks like a ramp,
so a ramp is claimed only when the random walk cannot explain the bend: R is dropped first
when R or K is weak, R never gets the backstop (a ramp beyond K lives in the last octave's
few degrees of freedom, where a 50 % local rise is within chance), and a term at zero in the
full fit does not re-enter when another is dropped, except K taking over from R.

The kept terms are refitted and bootstrapped; a kept term is ``resolved`` when its interval
also excludes zero by a margin (lower bound > ``LO_MIN`` x value). Otherwise the record does
not support it and the reported value is an upper bound: the largest coefficient for which the
term alone stays under the one-sided 95 % upper Allan bound at every tau (every term is
non-negative, so none can exceed the curve).
"""
import contextlib
from dataclasses import dataclass, field
from typing import Dict, Optional, Tuple

from gyro_char.allan_edf import chi2_interval, chi2_ppf
from gyro_char.noise_model import design_matrix, sensor_kind, SI_UNITS, TERMS
import numpy as np
from scipy import optimize, special

try:  # scipy's own HiGHS binding: warm-started LPs (see _L1Step); linprog otherwise.
    from scipy.optimize._highspy import _core as _highs_core
except ImportError:  # pragma: no cover - other scipy layouts
    _highs_core = None
try:  # the 175 x 175 factorisations here are 20x slower with OpenBLAS threads on a busy host
    from threadpoolctl import threadpool_limits
except ImportError:  # pragma: no cover - optional
    threadpool_limits = None

SHARE_MIN = 0.3
LO_MIN = 0.2
GAIN_MIN = 4.0
REL_MAX = 0.5
BOUND_CI = 0.9
R_INDEX = TERMS.index('R')
K_INDEX = TERMS.index('K')
CORR_OCTAVES = {2: 1.5, 1: 1.5, 0: 1.5, -1: 2.2, -2: 6.0}
N_BOOT = 100


@dataclass
class TermEstimate:
    value: float
    unit: str
    ci68: Optional[Tuple[float, float]]
    resolved: bool

    def to_json(self) -> dict:
        return {'value': float(self.value), 'unit': self.unit,
                'ci68': None if self.ci68 is None else [float(v) for v in self.ci68],
                'resolved': bool(self.resolved)}


@dataclass
class NoiseFit:
    """IEEE coefficients of one channel (SI), with the curve they were fitted to."""

    channel: str
    kind: str
    method: str
    terms: Dict[str, TermEstimate]
    tau: np.ndarray
    avar: np.ndarray
    fitted: Dict[str, float] = field(default_factory=dict)  # point estimates, all terms

    def coeffs(self) -> Dict[str, float]:
        """Return the point estimates actually used for the fitted curve (0 = absent)."""
        return dict(self.fitted)

    def to_json(self) -> dict:
        return {t: self.terms[t].to_json() for t in ('N', 'B', 'K', 'Q', 'R')}


def _objective(z, a_mat, log_a, wts=1.0):
    p = a_mat @ z
    if np.any(p <= 0):
        return np.inf
    return float(np.sum(wts * np.abs(log_a - np.log(p))))


class _L1Step:
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
           max_iter: int = 30, step: Optional[_L1Step] = None, wts=1.0) -> np.ndarray:
    """
    Return z >= 0 minimising sum |ln avar - ln (A z)| (sequential LP, see module doc).

    ``step``: an ``_L1Step`` of ``a_mat`` to reuse (warm starts across curves).
    """
    log_a = np.log(avar)
    step = step or _L1Step(a_mat, avar)
    if z0 is None:
        z0 = step(avar, wts / avar)
    best = _objective(z0, a_mat, log_a, wts)
    z = z0
    for _ in range(max_iter):
        p = a_mat @ z
        cand = step(p * (1.0 + log_a - np.log(p)), wts / p)
        if cand is None:
            break
        moved = _halve_towards(z, cand, best, lambda trial: _objective(trial, a_mat, log_a, wts))
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


class _Fitter:
    """One channel's fitting problem: the estimator on any subset of the terms."""

    def __init__(self, a_mat, avar, edf, cov, method):
        self.a_mat, self.avar, self.edf, self.method = a_mat, avar, edf, method
        self.sd = np.sqrt(special.polygamma(1, edf / 2.0))  # sd of ln sigma^2
        corr = cov / np.outer(np.sqrt(np.diag(cov)), np.sqrt(np.diag(cov)))
        self.corr = corr
        if method == 'weighted':
            self.noise_cov = cov  # of the log residuals
        else:  # of their signs (Gaussian copula)
            self.noise_cov = (2.0 / np.pi) * np.arcsin(np.clip(corr, -1.0, 1.0))
        self.bias = special.digamma(edf / 2.0) - np.log(edf / 2.0)  # E ln(chi2_v / v)
        self.steps = {}
        # 'l1w': sigma^2 divided by the median of chi2(edf)/edf (an L1 fit is a median fit),
        # residuals in units of the sd of ln sigma^2, sqrt(trigamma(edf / 2)).
        self.l1_shift, self.l1_wts = 1.0, np.ones_like(avar)
        if method == 'l1w':
            self.l1_shift = edf / chi2_ppf(0.5, edf)
            self.l1_wts = 1.0 / self.sd
        self.log_l1 = np.log(avar * self.l1_shift)
        self.log_ls = np.log(avar) - self.bias

    def fit(self, active, curve=None, z0=None) -> np.ndarray:
        curve = self.avar if curve is None else curve
        a_act = self.a_mat[:, active]
        key = tuple(active)
        if key not in self.steps:
            self.steps[key] = _L1Step(a_act, self.avar)
        z = np.zeros(self.a_mat.shape[1])
        za = fit_l1(a_act, curve * self.l1_shift, None if z0 is None else z0[active],
                    step=self.steps[key], wts=self.l1_wts)
        if self.method == 'weighted':
            za = fit_weighted(a_act, curve, self.edf, za)
        z[active] = za
        return z

    def pointwise(self, z) -> np.ndarray:
        """Return each point's term of the estimator's own objective (L1 or squares) at z."""
        p = np.maximum(self.a_mat @ z, 1e-300)
        if self.method == 'weighted':
            return ((self.log_ls - np.log(p)) / self.sd) ** 2
        return self.l1_wts * np.abs(self.log_l1 - np.log(p))

    def objective(self, z) -> float:
        """Return the estimator's own objective at z (L1 sum or weighted sum of squares)."""
        return float(np.sum(self.pointwise(z))) if np.all(self.a_mat @ z > 0) else np.inf

    def expected(self, n_par: int) -> np.ndarray:
        """Return each point's expected objective term from estimation noise alone."""
        n = self.avar.size
        dof = max(n - n_par, 1) / n  # the fit absorbs n_par of the n residuals
        if self.method == 'weighted':
            return np.full(n, dof)
        return self.l1_wts * self.sd * np.sqrt(2.0 / np.pi) * dof

    def dispersion(self, z) -> np.ndarray:
        """
        Return each point's dispersion phi_k at the full fit z (>= 1, see the module doc).

        Its objective term over the expected one, pooled over correlated neighbours (one
        point alone is too noisy), never below 1.
        """
        d = self.pointwise(z) / self.expected(np.count_nonzero(z > 0))
        return np.maximum(1.0, (self.corr @ d) / self.corr.sum(axis=1))

    def null_scale(self, z, j, others, disp) -> float:
        """
        Return phi_j c_j: under "term j is absent" keeping it gains ~ phi_j c_j chi2_1.

        Linearised at z: x = d ln p / d z_j residualised on the ``others`` columns in the
        curvature metric; ``disp`` the per-point dispersion of the full fit, averaged with the
        weights of the score of x (see the module docstring). 0 when j is redundant.
        """
        jac = self.a_mat / (self.a_mat @ z)[:, None]
        if self.method == 'weighted':
            wts = 1.0 / self.sd ** 2
            curv = wts
        else:
            wts = self.l1_wts
            curv = wts / (np.sqrt(2.0 * np.pi) * self.sd)
        x = jac[:, j]
        if np.any(others):
            jo = jac[:, others]
            coef = np.linalg.lstsq(jo * np.sqrt(curv)[:, None], x * np.sqrt(curv), rcond=None)[0]
            x_res = x - jo @ coef
        else:
            x_res = x
        quad = float(np.sum(curv * x_res ** 2))
        if quad <= 1e-10 * float(np.sum(curv * x ** 2)):
            return 0.0
        wx = wts * x_res
        if self.method == 'weighted':  # misfit scales each residual's sd by sqrt(phi_k)
            wx = wx * np.sqrt(disp)
            return float(wx @ self.noise_cov @ wx) / quad
        # L1: signs are scale-free; misfit flattens the residual density, f_k -> f_k / phi_k
        return float(wx @ self.noise_cov @ wx) / (4.0 * float(np.sum(curv * x_res ** 2 / disp)))

    def select(self, z):
        """
        Backward elimination by the estimator's objective: return (active mask, z refitted).

        Repeatedly drop the term whose removal (the others refitted) costs the least objective
        in units of its null scale phi c_j, while that is below ``GAIN_MIN`` or the term never
        reaches ``SHARE_MIN`` of the curve, unless the backstop of the module docstring keeps
        it. Collinear pairs lose one member, not both. A random walk's chance trend looks like
        a ramp at long tau, so among the weak terms R is dropped first: a ramp is reported only
        when K cannot explain the bend.
        """
        # A term at zero in the estimator's optimum is absent: it may not re-enter when another
        # is dropped (K dropped and a ramp R taking over would be a swap, not a simplification),
        # except K when R is in: the random walk may take over the bend from a ramp.
        allowed = z > 0
        allowed[K_INDEX] |= allowed[R_INDEX]
        obj_full = self.pointwise(z)
        floor = np.maximum(obj_full, self.expected(np.count_nonzero(z > 0)))
        disp = self.dispersion(z)
        ones = np.ones_like(disp)
        while np.count_nonzero(z > 0) > 1:
            share = (self.a_mat * z) / (self.a_mat @ z)[:, None]
            base = self.objective(z)
            gains, fits = {}, {}
            for j in np.flatnonzero(allowed & (z > 0)):
                trial = allowed.copy()
                trial[j] = False
                fits[j] = self.fit(trial, z0=z)
                obj_trial = self.pointwise(fits[j])
                if share[:, j].max() < SHARE_MIN:
                    gains[j] = -np.inf
                    continue
                others = trial & (z > 0)
                gain = float(np.sum(obj_trial)) - base
                scale = self.null_scale(z, j, others, disp)
                gains[j] = gain / scale if scale > 0 else -np.inf  # redundant given the rest
                # The backstop: a drop significant against pure noise (phi = 1) that raises
                # the objective by half where the term matters, or doubles it overall, is a
                # visible term, however large the misfit elsewhere makes phi. Not for R: a
                # ramp beyond K lives in the last octave's few degrees of freedom, where a
                # 50 % local rise is within chance; R is judged by the statistic alone.
                rise = obj_trial - obj_full
                where = share[:, j] >= SHARE_MIN
                visible = (np.sum(rise) > np.sum(obj_full)
                           or np.sum(rise[where]) > REL_MAX * np.sum(floor[where]))
                if (j != R_INDEX and visible
                        and gain > GAIN_MIN * self.null_scale(z, j, others, ones)):
                    gains[j] = np.inf
            weak = [j for j in gains if gains[j] < GAIN_MIN]
            if not weak:
                break
            # A ramp is claimed only if the random walk cannot explain the bend: R goes first,
            # also when K is the weak one (K and R are near-collinear at long tau; K dropped
            # and R kept would claim a ramp on the strength of a random walk).
            r_out = R_INDEX in gains and (R_INDEX in weak or K_INDEX in weak)
            drop = R_INDEX if r_out else min(weak, key=gains.get)
            allowed[drop] = False
            z = fits[drop]
        active = allowed & (z > 0)
        return active, z


def _draw_curves(p2, edf, cov, n, rng):
    # Gaussian copula with exact log-chi-square marginals around the fitted curve.
    chol = np.linalg.cholesky(cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov))))
    g = rng.standard_normal((n, p2.size)) @ chol.T
    u = np.clip(special.ndtr(g), 1e-12, 1 - 1e-12)
    return p2 * chi2_ppf(u, edf) / edf


def fit_noise(tau, avar, edf, alpha=None, *, channel: str = 'gyro_x', method: str = 'l1',
              tau_min: Optional[float] = None, tau_max: Optional[float] = None,
              n_boot: int = N_BOOT, rng: Optional[np.random.Generator] = None) -> NoiseFit:
    """
    Fit formula (4) to one channel's curve; return values, 68 % intervals and ``resolved``.

    ``edf`` (K,) and ``alpha`` (K,) come from ``gyro_char.allan_edf``. The upper bound of an
    unresolved term is the largest coefficient whose term alone stays under the 95 % upper
    bound of the Allan variance at every fitted tau.
    """
    kind = sensor_kind(channel)
    tau, avar, edf = (np.asarray(v, dtype=np.float64) for v in (tau, avar, edf))
    alpha = np.zeros(tau.size, dtype=int) if alpha is None else np.asarray(alpha, dtype=int)
    sel = (avar > 0) & np.isfinite(edf) & (edf > 0)
    if tau_min is not None:
        sel &= tau >= tau_min
    if tau_max is not None:
        sel &= tau <= tau_max
    if np.count_nonzero(sel) < 3:
        raise ValueError(f'{channel}: fewer than 3 usable tau points to fit')
    tau_f, avar_f, edf_f, alpha_f = tau[sel], avar[sel], edf[sel], alpha[sel]
    a_mat = design_matrix(tau_f)
    cov = allan_cov(tau_f, edf_f, alpha_f)
    if method == 'l1-raw':  # earlier name of the same (uncorrected) paper objective
        method = 'l1'
    if method not in ('l1', 'l1w', 'weighted'):
        raise ValueError(f'unknown fit method {method!r}')
    fitter = _Fitter(a_mat, avar_f, edf_f, cov, method)
    active, z = fitter.select(fitter.fit(np.ones(len(TERMS), dtype=bool)))
    rng = rng or np.random.default_rng(0)
    boot = np.array([fitter.fit(active, curve, z0=z)
                     for curve in _draw_curves(a_mat @ z, edf_f, cov, n_boot, rng)])
    boot = np.sqrt(np.maximum(boot, 0.0))
    coef = np.sqrt(np.maximum(z, 0.0))
    lo, hi = np.percentile(boot, [100 * 0.1587, 100 * 0.8413], axis=0)
    avar_hi = chi2_interval(np.sqrt(avar_f), edf_f, BOUND_CI)[1] ** 2
    terms = {}
    for j, t in enumerate(TERMS):
        if active[j] and lo[j] > LO_MIN * coef[j]:
            terms[t] = TermEstimate(float(coef[j]), SI_UNITS[kind][t],
                                    (float(lo[j]), float(hi[j])), True)
        else:
            bound = float(np.sqrt(np.min(avar_hi / a_mat[:, j])))
            terms[t] = TermEstimate(bound, SI_UNITS[kind][t], None, False)
    return NoiseFit(channel=channel, kind=kind, method=method, terms=terms, tau=tau_f,
                    avar=avar_f, fitted=dict(zip(TERMS, (float(c) for c in coef))))


def fit_result(res, *, method: str = 'l1', tau_min: Optional[float] = None,
               n_boot: int = N_BOOT, seed: int = 0) -> Dict[str, NoiseFit]:
    """Fit every channel of an ``AllanResult`` (with EDF) and return {channel: NoiseFit}."""
    out = {}
    with threadpool_limits(1) if threadpool_limits is not None else contextlib.nullcontext():
        for c, name in enumerate(res.channels):
            out[name] = fit_noise(res.tau, res.avar[:, c], res.edf[:, c], res.alpha[:, c],
                                  channel=name, method=method, tau_min=tau_min,
                                  n_boot=n_boot, rng=np.random.default_rng(seed + c))
    return out
