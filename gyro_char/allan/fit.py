"""
Fit formula (4) (R, K, B, N, Q >= 0) to an Allan variance curve, with intervals and selection.

Estimators over z = [R^2, K^2, B^2, N^2, Q^2] >= 0 with p^2(tau) = A z: ``'l1'`` (the paper's
log-domain L1), ``'l1w'`` (the same on EDF-standardised, median-unbiased logs) and
``'weighted'`` (EDF-weighted log least squares); solvers in ``gyro_char.allan.solvers``.
68 % intervals come from a parametric bootstrap with the inter-tau correlation; terms are chosen
by backward elimination judged by the estimator's own objective against a local dispersion
(``gyro_char.allan.selection``), and a term the record does not support is reported as an upper
bound (``resolved: false``). Two extensions of the model (``gyro_char.allan.design``): the
sensor's own filter in the white term (``gyro_char.allan.sensor_filter``), and IEEE 952 Annex C
Markov terms where the record needs them (``gyro_char.allan.markov``).
The reasoning is in docs/method.md, the measured accuracy in docs/validation.md.
"""
import contextlib
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Tuple

from gyro_char.allan.design import FitDesign
from gyro_char.allan.edf import chi2_interval, chi2_ppf
from gyro_char.allan.markov import GAIN_MARKOV, MARKOV_MAX, search_tc
from gyro_char.allan.model import TERMS
from gyro_char.allan.selection import GAIN_MIN, TermFitter
from gyro_char.allan.sensor_filter import filter_choices, FilterChoice
from gyro_char.allan.solvers import allan_cov
from gyro_char.units import sensor_kind, SI_UNITS
import numpy as np
from scipy import special

try:  # the 175 x 175 factorisations here are 20x slower with OpenBLAS threads on a busy host
    from threadpoolctl import threadpool_limits
except ImportError:  # pragma: no cover - optional
    threadpool_limits = None

LO_MIN = 0.2
BOUND_CI = 0.9
N_BOOT = 100
# Allan variances at or below this (SI units squared) are arithmetic, not noise: a constant
# channel (an accelerometer that reports a fixed 9.81) leaves ~1e-55 from the running sums,
# which a log-domain fit would turn into a confident, meaningless N. The best strategic-grade
# gyros sit near 1e-20.
AVAR_FLOOR = 1e-40


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
class MarkovEstimate:
    """One selected Markov term: driving density q, rate sd sigma = q sqrt(T_c / 2), T_c."""

    q: TermEstimate
    sigma: TermEstimate
    tau_c: float

    def to_json(self) -> dict:
        return {'q': self.q.to_json(), 'sigma': self.sigma.to_json(),
                'tau_c': {'value': float(self.tau_c), 'unit': 's'}}


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
    design: FitDesign = field(default_factory=FitDesign)
    z: Optional[np.ndarray] = None  # squared coefficients of every design column
    markov: List[MarkovEstimate] = field(default_factory=list)
    sensor_filter: Optional[FilterChoice] = None

    def coeffs(self) -> Dict[str, float]:
        """Return formula (4)'s point estimates used for the fitted curve (0 = absent)."""
        return dict(self.fitted)

    def model_avar(self, tau) -> np.ndarray:
        """Return the fitted model (every selected term, filter and Markov included) at tau."""
        return self.design.matrix(tau) @ self.z

    def term_avars(self, tau) -> Dict[str, np.ndarray]:
        """Return each selected term's Allan variance at tau, by column name (N, M1, ...)."""
        a_mat = self.design.matrix(tau)
        return {name: a_mat[:, j] * self.z[j] for j, name in enumerate(self.design.names)
                if self.z[j] > 0}

    def to_json(self) -> dict:
        return {t: self.terms[t].to_json() for t in ('N', 'B', 'K', 'Q', 'R')}

    def extra_json(self) -> dict:
        """Return noise.json's extra fields of the channel: the sensor filter, Markov terms."""
        choice = self.sensor_filter or FilterChoice(None, 'none', '')
        return {'sensor_filter': choice.to_json(),
                'markov': [m.to_json() for m in self.markov]}


def _draw_curves(p2, edf, cov, n, rng):
    # Gaussian copula with exact log-chi-square marginals around the fitted curve.
    chol = np.linalg.cholesky(cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov))))
    g = rng.standard_normal((n, p2.size)) @ chol.T
    u = np.clip(special.ndtr(g), 1e-12, 1 - 1e-12)
    return p2 * chi2_ppf(u, edf) / edf


def _select(design, tau, avar, edf, cov, method, markov):
    """Return (design, fitter, active, z): formula (4), then with Markov terms if they stay."""
    fitter = TermFitter(design.matrix(tau), avar, edf, cov, method)
    active, z = fitter.select(fitter.fit(np.ones(len(TERMS), dtype=bool)))
    if not markov:
        return design, fitter, active, z

    def extended(tcs):
        ext = FitDesign(design.dt, design.sensor_filter, tuple(tcs))
        f = TermFitter(ext.matrix(tau), avar, edf, cov, method)
        return ext, f, f.fit(np.ones(len(ext.names), dtype=bool))

    def score(tcs):
        _, f, z_full = extended(tcs)
        return f.objective(z_full)

    tcs = search_tc(score, tau, markov)
    if not tcs:
        return design, fitter, active, z
    ext, f_ext, z_full = extended(tcs)
    gain_min = np.array([GAIN_MIN] * len(TERMS) + [GAIN_MARKOV] * len(tcs))
    act_ext, z_ext = f_ext.select(z_full, gain_min, first=ext.markov_columns)
    kept = [i for i, j in enumerate(ext.markov_columns) if act_ext[j]]
    if kept:
        # Against formula (4)'s own selection (not nested when the Markov terms displaced a
        # term): the Markov terms must gain GAIN_MARKOV x their null scales over it.
        disp = f_ext.dispersion(z_ext)
        cols = [ext.markov_columns[i] for i in kept]
        scale = sum(f_ext.null_scale(z_ext, j, act_ext & (np.arange(act_ext.size) != j), disp)
                    for j in cols)
        if fitter.objective(z) - f_ext.objective(z_ext) < GAIN_MARKOV * scale:
            kept = []
    if not kept:  # formula (4) explains the record: its own selection stands, unchanged
        return design, fitter, active, z
    final = FitDesign(design.dt, design.sensor_filter, tuple(tcs[i] for i in kept))
    cols = list(range(len(TERMS))) + [ext.markov_columns[i] for i in kept]
    fitter = TermFitter(final.matrix(tau), avar, edf, cov, method)
    return final, fitter, act_ext[cols], z_ext[cols]


def fit_noise(tau, avar, edf, alpha=None, *, channel: str = 'gyro_x', method: str = 'l1',
              tau_min: Optional[float] = None, tau_max: Optional[float] = None,
              n_boot: int = N_BOOT, rng: Optional[np.random.Generator] = None,
              dt: Optional[float] = None, sensor_filter: Optional[FilterChoice] = None,
              markov: int = 0, interrupt: Optional[Callable[[], None]] = None) -> NoiseFit:
    """
    Fit formula (4) to one channel's curve; return values, 68 % intervals and ``resolved``.

    ``edf`` (K,) and ``alpha`` (K,) come from ``gyro_char.allan.edf``. The upper bound of an
    unresolved term is the largest coefficient whose term alone stays under the 95 % upper
    bound of the Allan variance at every fitted tau. ``sensor_filter`` (with ``dt``, the
    sample interval) replaces the white term by the filter's exact one; ``markov`` is the
    largest number of Markov terms searched (0, the default: formula (4) only; at most
    ``MARKOV_MAX``). ``interrupt()``, when given, runs before each bootstrap refit: a caller
    that must stop (a node shutting down) raises from it.
    """
    kind = sensor_kind(channel)
    tau, avar, edf = (np.asarray(v, dtype=np.float64) for v in (tau, avar, edf))
    alpha = np.zeros(tau.size, dtype=int) if alpha is None else np.asarray(alpha, dtype=int)
    if not np.any(avar > AVAR_FLOOR):
        raise ValueError(f'{channel}: constant (Allan variance at most {AVAR_FLOOR:g} at every '
                         'tau: no noise to fit)')
    sel = (avar > AVAR_FLOOR) & np.isfinite(edf) & (edf > 0)
    if tau_min is not None:
        sel &= tau >= tau_min
    if tau_max is not None:
        sel &= tau <= tau_max
    if np.count_nonzero(sel) < 3:
        raise ValueError(f'{channel}: fewer than 3 usable tau points to fit')
    if method == 'l1-raw':  # earlier name of the same (uncorrected) paper objective
        method = 'l1'
    if method not in ('l1', 'l1w', 'weighted'):
        raise ValueError(f'unknown fit method {method!r}')
    tau_f, avar_f, edf_f, alpha_f = tau[sel], avar[sel], edf[sel], alpha[sel]
    cov = allan_cov(tau_f, edf_f, alpha_f)
    filt = sensor_filter.sensor_filter if sensor_filter is not None else None
    if not 0 <= int(markov) <= MARKOV_MAX:
        raise ValueError(f'markov must be 0..{MARKOV_MAX}, got {markov}')
    design, fitter, active, z = _select(FitDesign(dt, filt), tau_f, avar_f, edf_f, cov,
                                        method, int(markov))
    a_mat = fitter.a_mat
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

    def estimate(j, unit, factor=1.0):
        if active[j] and lo[j] > LO_MIN * coef[j]:
            return TermEstimate(float(coef[j] * factor), unit,
                                (float(lo[j] * factor), float(hi[j] * factor)), True)
        bound = float(np.sqrt(np.min(avar_hi / a_mat[:, j])))
        return TermEstimate(bound * factor, unit, None, False)

    terms = {t: estimate(j, SI_UNITS[kind][t]) for j, t in enumerate(TERMS)}
    rate = SI_UNITS[kind]['B']
    markov_terms = [MarkovEstimate(estimate(j, SI_UNITS[kind]['K']),
                                   estimate(j, rate, float(np.sqrt(tc / 2.0))), tc)
                    for j, tc in zip(design.markov_columns, design.markov_tc)]
    return NoiseFit(channel=channel, kind=kind, method=method, terms=terms, tau=tau_f,
                    avar=avar_f, fitted=dict(zip(TERMS, (float(c) for c in coef))),
                    design=design, z=np.maximum(z, 0.0), markov=markov_terms,
                    sensor_filter=sensor_filter)


def fit_result(res, *, method: str = 'l1', tau_min: Optional[float] = None,
               n_boot: int = N_BOOT, seed: int = 0, sensor_filter=None,
               markov: int = 0,
               interrupt: Optional[Callable[[], None]] = None) -> Dict[str, NoiseFit]:
    """
    Fit every channel of an ``AllanResult`` (with EDF) and return {channel: NoiseFit}.

    ``sensor_filter``: None uses the filters ``gyro_char.allan.compute.compute`` resolved
    (``res.sensor_filters``; none when absent), or a spec (``'bartlett:7@8x'``; ``'auto'``
    needs the samples, so it is resolved by ``compute``) for every channel.
    """
    choices = filter_choices(res, sensor_filter)
    out = {}
    with threadpool_limits(1) if threadpool_limits is not None else contextlib.nullcontext():
        for c, name in enumerate(res.channels):
            out[name] = fit_noise(res.tau, res.avar[:, c], res.edf[:, c], res.alpha[:, c],
                                  channel=name, method=method, tau_min=tau_min,
                                  n_boot=n_boot, rng=np.random.default_rng(seed + c),
                                  dt=res.dt, sensor_filter=choices.get(name),
                                  markov=markov, interrupt=interrupt)
    return out
