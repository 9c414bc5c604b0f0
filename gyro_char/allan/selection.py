"""
One channel's fitting problem and its term selection (backward elimination).

``TermFitter`` runs the estimator ('l1', 'l1w' or 'weighted', ``gyro_char.allan.solvers``) on
any subset of the columns of a design matrix and selects the terms: repeatedly drop the term
whose removal (the others refitted) costs the least of the estimator's own objective in units
of its null scale (chi-bar-square, with the correlation between taus and a local dispersion for
misfit), while that is below the term's threshold or the term never reaches ``SHARE_MIN`` of the
curve, unless the backstop keeps a visibly needed term. The reasoning is in docs/method.md.
"""
from typing import Optional, Sequence

from gyro_char.allan.edf import chi2_ppf
from gyro_char.allan.model import TERMS
from gyro_char.allan.solvers import fit_l1, fit_weighted, L1Step
import numpy as np
from scipy import special

SHARE_MIN = 0.3
GAIN_MIN = 4.0
REL_MAX = 0.5
R_INDEX = TERMS.index('R')
K_INDEX = TERMS.index('K')


class TermFitter:
    """One channel's fitting problem: the estimator on any subset of the design's columns."""

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
        """Return z >= 0 over all columns, fitted on the ``active`` ones (others 0)."""
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
        Return each point's dispersion phi_k at the full fit z (>= 1, see docs/method.md).

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
        weights of the score of x (see docs/method.md). 0 when j is redundant.
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

    def select(self, z, gain_min: Optional[Sequence[float]] = None, first: Sequence[int] = ()):
        """
        Backward elimination by the estimator's objective: return (active mask, z refitted).

        Repeatedly drop the term whose removal (the others refitted) costs the least objective
        in units of its null scale phi c_j, while that is below its threshold (``gain_min``,
        per column, default ``GAIN_MIN``; -inf keeps a column) or the term never reaches
        ``SHARE_MIN`` of the curve, unless the backstop keeps it. Collinear pairs lose one
        member, not both. Weak columns listed in ``first`` go before any other (the Markov
        terms: extras are dropped before a term of formula (4)); then, among the weak terms,
        R: a ramp is reported only when K cannot explain the bend.
        """
        n_col = self.a_mat.shape[1]
        gain_min = np.full(n_col, GAIN_MIN) if gain_min is None else np.asarray(gain_min)
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
                if gain_min[j] == -np.inf:
                    continue
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
                        and gain > gain_min[j] * self.null_scale(z, j, others, ones)):
                    gains[j] = np.inf
            weak = [j for j in gains if gains[j] < gain_min[j]]
            if not weak:
                break
            extra = [j for j in weak if j in first]
            # A ramp is claimed only if the random walk cannot explain the bend: R goes first,
            # also when K is the weak one (K and R are near-collinear at long tau; K dropped
            # and R kept would claim a ramp on the strength of a random walk).
            r_out = R_INDEX in gains and (R_INDEX in weak or K_INDEX in weak)
            if extra:
                drop = min(extra, key=gains.get)
            else:
                drop = R_INDEX if r_out else min(weak, key=gains.get)
            allowed[drop] = False
            z = fits[drop]
        active = allowed & (z > 0)
        return active, z
