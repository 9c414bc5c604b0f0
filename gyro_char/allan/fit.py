"""
Fit formula (4) (R, K, B, N, Q >= 0) to an Allan variance curve, with intervals and selection.

Estimators over z = [R^2, K^2, B^2, N^2, Q^2] >= 0 with p^2(tau) = A z: ``'l1'`` (the paper's
log-domain L1), ``'l1w'`` (the same on EDF-standardised, median-unbiased logs) and
``'weighted'`` (EDF-weighted log least squares); solvers in ``gyro_char.allan.solvers``.
68 % intervals come from a parametric bootstrap with the inter-tau correlation; terms are chosen
by backward elimination judged by the estimator's own objective against a local dispersion, and
a term the record does not support is reported as an upper bound (``resolved: false``).
The reasoning is in docs/method.md, the measured accuracy in docs/validation.md.
"""
import contextlib
from dataclasses import dataclass, field
from typing import Callable, Dict, Optional, Tuple

from gyro_char.allan.edf import chi2_interval, chi2_ppf
from gyro_char.allan.model import design_matrix, TERMS
from gyro_char.allan.solvers import allan_cov, fit_l1, fit_weighted, L1Step
from gyro_char.units import sensor_kind, SI_UNITS
import numpy as np
from scipy import special

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
            self.steps[key] = L1Step(a_act, self.avar)
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
              n_boot: int = N_BOOT, rng: Optional[np.random.Generator] = None,
              interrupt: Optional[Callable[[], None]] = None) -> NoiseFit:
    """
    Fit formula (4) to one channel's curve; return values, 68 % intervals and ``resolved``.

    ``edf`` (K,) and ``alpha`` (K,) come from ``gyro_char.allan.edf``. The upper bound of an
    unresolved term is the largest coefficient whose term alone stays under the 95 % upper
    bound of the Allan variance at every fitted tau. ``interrupt()``, when given, runs before
    each bootstrap refit: a caller that must stop (a node shutting down) raises from it.
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
    if method not in ('l1', 'l1w', 'weighted'):
        raise ValueError(f'unknown fit method {method!r}')
    fitter = _Fitter(a_mat, avar_f, edf_f, cov, method)
    active, z = fitter.select(fitter.fit(np.ones(len(TERMS), dtype=bool)))
    rng = rng or np.random.default_rng(0)
    boot = []
    for curve in _draw_curves(a_mat @ z, edf_f, cov, n_boot, rng):
        if interrupt is not None:
            interrupt()
        boot.append(fitter.fit(active, curve, z0=z))
    boot = np.sqrt(np.maximum(np.array(boot), 0.0))
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
               n_boot: int = N_BOOT, seed: int = 0,
               interrupt: Optional[Callable[[], None]] = None) -> Dict[str, NoiseFit]:
    """Fit every channel of an ``AllanResult`` (with EDF); return {channel: NoiseFit}."""
    out = {}
    with threadpool_limits(1) if threadpool_limits is not None else contextlib.nullcontext():
        for c, name in enumerate(res.channels):
            out[name] = fit_noise(res.tau, res.avar[:, c], res.edf[:, c], res.alpha[:, c],
                                  channel=name, method=method, tau_min=tau_min,
                                  n_boot=n_boot, rng=np.random.default_rng(seed + c),
                                  interrupt=interrupt)
    return out
