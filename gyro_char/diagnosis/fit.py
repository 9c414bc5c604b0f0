"""
Fitting an effect's parameters to a real record by minimising the sim-to-real gap.

The model is a callable ``simulate(effects, seed) -> observables``; ``effects`` is the
catalogue's composable list ``[(name, params), ...]``. Every evaluation runs the same seeds
(common random numbers), so the gap is a smooth function of the parameters and a 1-D search
converges in a handful of evaluations. Parameters are searched coordinate-wise: a coarse grid
(log-spaced where the parameter is a scale) to find the basin, then a bounded Brent refinement
around the best grid point. Effects here have one to three parameters, so this is cheap and,
unlike a gradient method, does not get stuck on the flat region where an effect is too small
to matter.
"""
from dataclasses import dataclass, field, replace
from typing import Callable, Dict, List, Optional, Sequence, Tuple

from gyro_char.diagnosis import gap as diag_gap
import numpy as np
from scipy import optimize

Effects = List[Tuple[str, dict]]
Obs = Dict[str, np.ndarray]


@dataclass(frozen=True)
class Param:
    """
    One searched parameter: bounds of its magnitude, scale, sign, and whether it is whole.

    A whole-number parameter is searched over every value in [lo, hi] on the grid (no Brent
    refinement); ``sign`` = -1 searches the magnitude of a negative parameter. A ``choice`` is
    a whole-number structural parameter (a filter's number of stages, a process's order) that
    changes what the other parameters mean: they are fitted anew for each of its values.
    ``off_at``: 'hi' or 'lo', that bound means "absent" and is stored as ``off_value`` (a
    corner frequency at or above where it could show, stored as 0; a gyro lag at its
    shortest, which a long record would still see as a correlation of lag / dt; a power law's
    plain slope, stored as itself); the search starts there, so the effect is first fitted
    without this part, and a criterion counts the parameter as free only when it is not off.
    """

    name: str
    lo: float
    hi: float
    log: bool = True
    integer: bool = False
    sign: float = 1.0
    choice: bool = False
    off_at: str = ''
    off_value: float = 0.0
    # Where the search starts (default: the middle of the range); unlike ``EffectSpace.start``
    # still searched. An optional refinement whose bound is as good as absent (a stamp
    # error's correlation time at 0.05 interval: white) starts there, so the main parameter
    # is fitted as without it; one whose bound is not (a gyro lag) uses ``off_at``.
    init: Optional[float] = None
    # A digital filter's corner below this Nyquist frequency (Hz): searched on the prewarped
    # tangent, log tan(pi v / (2 nyquist)), where its response changes evenly (near Nyquist a
    # tenth of a hertz matters as much as an octave lower down).
    nyquist: float = 0.0
    # Values of the coarse grid, given (default: ``grid`` points evenly over the range): a
    # parameter whose gap is sharp near a data-driven start (a full-scale limit near the
    # record's crest: 1 % of the limit moves the clipped depth by a quarter) is gridded
    # densely there, and Brent refines between the best point's neighbours as usual.
    points: tuple = ()

    def is_off(self, value: float) -> bool:
        """Return True if ``value`` is this parameter's "absent" value (``off_at``)."""
        return bool(self.off_at) and value == self.off_value

    def to_u(self, v: float) -> float:
        """Return the search variable of value ``v`` (log, linear or prewarped tangent)."""
        if self.is_off(v):
            v = self.hi if self.off_at == 'hi' else self.lo
        v = abs(v)
        if self.nyquist:
            return float(np.log(np.tan(0.5 * np.pi * v / self.nyquist)))
        return float(np.log(v)) if self.log else float(v)

    def from_u(self, u: float) -> float:
        """Return the value at search variable ``u`` (``off_value`` at an ``off_at`` bound)."""
        if (self.off_at == 'hi' and u >= self.to_u(self.hi) - 1e-12
                or self.off_at == 'lo' and u <= self.to_u(self.lo) + 1e-12):
            return self.off_value
        if self.nyquist:
            v = float(2.0 * self.nyquist / np.pi * np.arctan(np.exp(u)))
        else:
            v = float(np.exp(u)) if self.log else float(u)
        return self.sign * (float(np.round(v)) if self.integer else v)


@dataclass(frozen=True)
class LinearTerms:
    """
    Coefficients of an effect that are solved, not searched: its blocks are linear in them.

    ``basis[i][block]`` is, on record i, the change of that block per unit of each of
    ``names`` (rows), measured once; ``fit_effect`` solves the coefficients by least squares
    on what the model without the effect leaves in ``blocks``, weighted as the gap weighs
    them (each element by the baseline's scatter, each block by its length), so one evaluation
    replaces a search over a dozen coefficients (a tabulated rate response).
    """

    names: tuple
    blocks: tuple
    basis: tuple


def solve_linear(objective, selected: Effects, terms: LinearTerms) -> Tuple[dict, float]:
    """
    Return the coefficients ``terms.names`` that best close the gap left by ``selected``.

    And what fitting them to noise alone would take off the squared gap, on average: the
    hat matrix's diagonal over the rows' noise variances (each row weighted as the gap weighs
    it). Forms of one effect are compared with twice that added (``fit_effect``): a table of
    a dozen coefficients would otherwise beat the one-parameter form it contains by fitting
    the noise.
    """
    ev = objective.evaluate(list(selected))
    nblocks = sum(len(r) for r in objective.reals)
    rows, rhs = [], []
    for i, (real, st) in enumerate(zip(objective.reals, ev.stats)):
        ref = objective.reference[i] if objective.reference else st.std
        for b in terms.blocks:
            if b not in real or b not in terms.basis[i]:
                continue
            w = 1.0 / (np.asarray(ref[b]) * np.sqrt(real[b].size * nblocks))
            rows.append(np.asarray(terms.basis[i][b]).T * w[:, None])
            rhs.append((real[b] - st.mean[b]) * w)
    if not rows:
        return dict.fromkeys(terms.names, 0.0), 0.0
    a, y = np.vstack(rows), np.concatenate(rhs)
    coef = np.linalg.lstsq(a, y, rcond=None)[0]
    # Row j's noise variance in the gap's weighting is 1 / (block size x blocks).
    sizes = np.concatenate([np.full(len(r), float(len(r))) for r in rhs])
    q = np.linalg.qr(a)[0]
    optimism = float(np.sum(np.einsum('ij,ij->i', q, q) / (sizes * nblocks)))
    return {n: float(c) for n, c in zip(terms.names, coef)}, optimism


@dataclass
class EffectSpace:
    """What is searched for one catalogue effect on one record (bounds depend on the record)."""

    name: str
    params: List[Param]
    fixed: dict = field(default_factory=dict)
    # Data-driven starting values (e.g. the frequency of a detected tone), if any.
    start: dict = field(default_factory=dict)
    # Coordinate passes at least (2 where one parameter shifts another's best value).
    passes: int = 1
    # Other starts of the same search (another sign, another data-driven start): each is
    # fitted too and the best kept, as for a ``choice`` parameter.
    alternatives: tuple = ()
    # Entries of ``fixed`` estimated from the record rather than known (a comb's spacing, from
    # its lines): not searched, but free parameters to a criterion that counts them.
    estimated: tuple = ()
    # A refit near an earlier fit (a later greedy step, the joint refit) also fits the
    # alternatives that fit did not take, over their whole spaces: forms of one effect that
    # trade differently with the effects selected since (a filter's averages and its
    # output low-pass beside a mode). Otherwise a refit keeps to the earlier fit's start.
    refit_all: bool = False
    # Coefficients solved by least squares before the search (``LinearTerms``), if any.
    linear: Optional[LinearTerms] = None


@dataclass
class Evaluation:
    """The gap of one model, with the statistics of its repeated simulations."""

    effects: Effects
    gap: float
    stats: List[diag_gap.SimStats]
    # What solving the model's linear coefficients on noise alone takes off gap² on average
    # (``solve_linear``); 0 for searched parameters.
    optimism: float = 0.0


class GapObjective:
    """Gap between fixed real observables and a model, simulated with fixed seeds."""

    def __init__(self, reals: Sequence[Obs],
                 simulate: Callable[[int, Effects, int], Obs], seeds: Sequence[int]):
        # simulate(record_index, effects, seed) -> observables of a simulated twin of that record
        self.reals = list(reals)
        self.simulate = simulate
        self.seeds = list(seeds)
        self.calls = 0
        # Scatter of the baseline's twins per record (diag_gap's deviance reference); None
        # until the baseline is known, and the baseline's own gap is then the plain rms z.
        self.reference: Optional[List[Obs]] = None

    def evaluate(self, effects: Effects) -> Evaluation:
        self.calls += 1
        stats = [diag_gap.sim_stats([self.simulate(i, effects, s) for s in self.seeds])
                 for i in range(len(self.reals))]
        return Evaluation(effects=list(effects),
                          gap=diag_gap.multi_gap(self.reals, stats, self.reference),
                          stats=stats)

    def set_reference(self, baseline: Evaluation) -> None:
        self.reference = [s.std for s in baseline.stats]


def _start_value(p: Param) -> float:
    """Where the search of ``p`` starts: ``init``, absent if it can be, else mid-range."""
    if p.init is not None:
        return p.init
    if p.off_at:
        return p.off_value
    return p.from_u(0.5 * (p.to_u(p.lo) + p.to_u(p.hi)))


def fit_effect(objective: GapObjective, selected: Effects, space: EffectSpace, *,
               grid: int = 5, refine: int = 4, passes: int = 1,
               near: Optional[dict] = None, at: Optional[int] = None) -> Tuple[dict, Evaluation]:
    """
    Best parameters of ``space`` added on top of ``selected``, and the evaluation there.

    ``near``: parameters of an earlier fit of the same effect; the search then covers only
    one coarse grid cell either side of them (3 points), which is what a later greedy step
    needs when the effects already selected change the picture only a little. ``at``: the
    position in ``selected`` where the effect goes (default: last); an effect's random numbers
    follow its position, so a refit in place keeps the common random numbers.
    Cost: about ``passes * len(params) * (grid + refine)`` evaluations of the objective, times
    the number of values of a ``choice`` parameter (with ``near``, the choice is kept) and
    the number of ``alternatives`` plus one.
    """
    if space.alternatives:
        options = (replace(space, alternatives=()),) + tuple(space.alternatives)
        starts = [near] * len(options)
        if near:   # a refit keeps to the start whose parameters the earlier fit has
            own = [{p.name for p in sp.params} | set(sp.fixed) == set(near) for sp in options]
            if space.refit_all and any(own):
                starts = [near if o else None for o in own]
            elif any(own):
                options = tuple(sp for sp, o in zip(options, own) if o)
        fits = [fit_effect(objective, selected, sp, grid=grid, refine=refine, passes=passes,
                           near=start, at=at) for sp, start in zip(options, starts)]
        return min(fits, key=lambda f: f[1].gap ** 2 + 2.0 * f[1].optimism)
    choices = [p for p in space.params if p.choice]
    if choices:
        p = choices[0]
        rest = [q for q in space.params if q is not p]
        values = ([near[p.name]] if near and p.name in near
                  else np.arange(int(p.lo), int(p.hi) + 1, dtype=float))
        fits = [fit_effect(objective, selected,
                           EffectSpace(space.name, rest, {**space.fixed, p.name: float(v)},
                                       space.start, space.passes),
                           grid=grid, refine=refine, passes=passes, near=near, at=at)
                for v in values]
        return min(fits, key=lambda f: f[1].gap)
    optimism = 0.0
    if space.linear is not None:
        pos = len(selected) if at is None else at
        solved, optimism = solve_linear(objective, list(selected[:pos]) + list(selected[pos:]),
                                        space.linear)
        space = replace(space, fixed={**space.fixed, **solved})
        near = {k: v for k, v in (near or {}).items() if k not in solved} or None
    values = {p.name: space.start.get(p.name, _start_value(p)) for p in space.params}
    if not near:   # a refit near an earlier fit keeps to the caller's passes
        passes = max(passes, space.passes)
    if near:
        values.update({k: v for k, v in near.items() if k in values})
    best = None

    pos = len(selected) if at is None else at

    def run(vals: dict) -> Evaluation:
        return objective.evaluate(list(selected[:pos]) + [(space.name, {**space.fixed, **vals})]
                                  + list(selected[pos:]))

    for _ in range(passes):
        for p in space.params:
            if p.name in space.start and len(space.params) > 1 and passes == 1:
                continue  # trusted data-driven value (e.g. tone frequency): spend on the rest
            lo_u, hi_u = p.to_u(p.lo), p.to_u(p.hi)
            if near and p.name in near:
                cell = (hi_u - lo_u) / (grid - 1)
                u0 = p.to_u(values[p.name])
                us = np.clip(np.array([u0 - cell, u0, u0 + cell]), lo_u, hi_u)
            elif p.integer:
                whole = np.unique(np.round(np.geomspace(p.lo, p.hi, grid + 2)))
                us = np.array([p.to_u(v) for v in whole])
            elif p.points:
                us = np.unique(np.clip([p.to_u(v) for v in p.points], lo_u, hi_u))
            else:
                us = np.linspace(lo_u, hi_u, grid)
            # The current value is a candidate too: a step never ends worse than where it
            # started (a data-driven start between grid points, a good first coordinate).
            u_now = p.to_u(values[p.name])
            if np.min(np.abs(us - u_now)) > 1e-9:
                us = np.sort(np.r_[us, u_now])
            evals = []
            for u in us:
                e = run({**values, p.name: p.from_u(u)})
                evals.append(e)
            k = int(np.argmin([e.gap for e in evals]))
            cache = {}

            def f(u, p=p):
                e = run({**values, p.name: p.from_u(u)})
                cache[u] = e
                return e.gap

            a, b = us[max(k - 1, 0)], us[min(k + 1, us.size - 1)]
            if p.integer:
                # Every whole value between the best grid point's neighbours.
                near_k = [v for v in range(int(round(abs(p.from_u(a)))) + 1,
                                           int(round(abs(p.from_u(b)))))
                          if v != int(round(abs(p.from_u(us[k]))))]
                u_best, e_best = us[k], evals[k]
                for v in near_k:
                    e = run({**values, p.name: p.sign * float(v)})
                    if e.gap < e_best.gap:
                        u_best, e_best = p.to_u(float(v)), e
            elif refine > 0 and b > a:
                res = optimize.minimize_scalar(f, bounds=(a, b), method='bounded',
                                               options={'maxiter': refine, 'xatol': 1e-3})
                cand = cache.get(res.x) or run({**values, p.name: p.from_u(res.x)})
                u_best, e_best = (res.x, cand) if cand.gap < evals[k].gap else (us[k], evals[k])
            else:
                u_best, e_best = us[k], evals[k]
            values[p.name] = p.from_u(u_best)
            best = e_best
    if best is None:  # every parameter was fixed by the data
        best = run(values)
    if optimism:
        best = replace(best, optimism=optimism)
    return {**space.fixed, **values}, best
