"""
The static diagnosis on closed forms: expected observables of a twin from its spectrum.

``closed_form_problem`` builds the same ``Problem`` as the twin-based static kind, with
``expect`` set: every candidate is scored on ``expected`` / ``spread`` of the model's
spectrum (``spectra``). A few simulated twins of the fitted baseline per record (``twins``,
cheap: white noise and rounding) give the residuals the pseudo-twins and the null level are
built from, and check the closed forms on this very record.
"""
from dataclasses import replace
from typing import Sequence

from gyro_char.diagnosis import expected, expected_tone, spread
from gyro_char.diagnosis import gap as diag_gap
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis import rounding
from gyro_char.diagnosis import static as ds
from gyro_char.diagnosis.closed_form import ExpectedStats, residual_check, standardize
from gyro_char.diagnosis.deterministic import has_mean_term
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.line_choice import LineCriterion
from gyro_char.diagnosis.narrow_lines import LineCheck
from gyro_char.diagnosis.spectra import model_spectrum
import numpy as np

# Twins of the baseline behind the null level (its 95th percentile and spread): with 8, the
# 95th percentile of a skewed distribution is read off nearly its largest sample, and 5 of 30
# clean 2 h records scored above it. They are cheap (white noise and rounding).
NULL_TWINS = 32


def _split(base, effects):
    b, fx = base, []
    for name, params in effects:
        if name == ds.NUISANCE:
            b = replace(base, N=base.N * params['n_scale'])
        else:
            fx.append((name, params))
    return b, fx


class StaticExpect:
    """``expect(i, effects)`` for static records: closed-form statistics per record."""

    def __init__(self, base, layouts):
        self.base = base
        self.layouts = list(layouts)
        self.residuals = [[] for _ in self.layouts]
        self._det = {}
        self.log_bias = []
        for lay in self.layouts:
            g = expected.grids(lay.n, lay.dt)
            spec = model_spectrum(base.N, base.lsb, base.dt, [], bias=base.bias)
            self.log_bias.append(spread.log_adev_moments(spread.adev_edf(spec, g))[0])

    def _deterministic(self, i, spec):
        if not has_mean_term(spec):
            return None
        key = (i, tuple(spec.warmups), tuple(spec.cycles), spec.cycle_onset, spec.decimation,
               spec.taps, spec.stages)
        if key not in self._det:
            if len(self._det) > 64:
                self._det.clear()
            lay = self.layouts[i]
            self._det[key] = expected.deterministic(spec, expected.grids(lay.n, lay.dt),
                                                    obs.ACF_LAGS)
        return self._det[key]

    def spectrum(self, effects: list):
        """Return the model spectrum of the baseline plus ``effects`` (nuisance included)."""
        b, fx = _split(self.base, effects)
        return model_spectrum(b.N, b.lsb, b.dt, fx, bias=b.bias)

    def __call__(self, i: int, effects: list) -> ExpectedStats:
        spec = self.spectrum(effects)
        lay = self.layouts[i]
        det = self._deterministic(i, spec)
        mean = expected.expected_blocks(spec, lay, det, log_bias=self.log_bias[i])
        return ExpectedStats(mean, lambda: spread.spreads(spec, lay, det),
                             self.residuals[i], floors=diag_gap.SCATTER_FLOOR)

    def calibrate(self, twins_per_record: Sequence[Sequence[dict]]) -> dict:
        """Set the residuals from simulated baseline twins; return the check per record."""
        checks = []
        for i, twins in enumerate(twins_per_record):
            self.residuals[i] = standardize(twins, self(i, []))
            checks.append(residual_check(self.residuals[i]))
        return {'records': checks}


def calibrate_n(base, x: np.ndarray):
    """
    Rescale N so that the expected white-band Welch level matches the record's.

    The closed-form counterpart of ``diag_static.calibrate_n``: the expected median of the
    Welch bins in 1-5 % of the sample rate (white rate noise plus the output step's rounding
    noise, the bins' chi-square median included) against the record's. Where the step is
    coarser than ``rounding.EXACT_BELOW`` per-sample sd, the white noise whose exactly
    rounded variance is the record's white level (``rounding.sigma_for``).
    """
    real = ds.white_level(x, base.dt)
    lay = obs.static_layout(x.size, base.dt)
    g = expected.grids(lay.n, lay.dt)
    noise, _ = expected.welch_expected(model_spectrum(base.N, base.lsb, base.dt, []), g)
    f = np.arange(noise.size) / (g.nps * g.dt)
    band = obs.white_band(f, base.dt)
    med = float(expected_tone.tone_draws(noise.size, round(g.k_eff, 1))[2])
    white_out = base.lsb ** 2 / 12.0 * base.dt * 2.0
    model_white = float(np.median(noise[band])) - white_out
    real_white = real / med - white_out
    ratio = max(real_white, 1e-300) / max(model_white, 1e-300)
    n_white = base.N * float(np.sqrt(ratio))
    if base.lsb > 0.0 and (real_white <= 0.0 or model_white <= 0.0
                           or n_white < rounding.EXACT_BELOW * base.lsb * np.sqrt(base.dt)):
        sigma = rounding.sigma_for(real / med / (2.0 * base.dt), base.bias, base.lsb)
        n_white = sigma * np.sqrt(base.dt)
    return replace(base, N=n_white)


def white_band_spread(n: int, dt: float) -> float:
    """Relative standard error of N from the median Welch level in 1-5 % of the rate."""
    g = expected.grids(n, dt)
    f = np.arange(g.nps // 2 + 1) / (g.nps * dt)
    bins = int(np.count_nonzero(obs.white_band(f, dt)))
    # Median of ~bins/2 independent chi-square(2 k_eff) bins (Hann neighbours correlate):
    # relative spread 1.25 sqrt(1 / (k_eff bins / 2)); N goes as its square root.
    return 0.5 * 1.25 / np.sqrt(max(g.k_eff * bins / 2.0, 1.0))


def closed_form_problem(records, dt, *, channel='gyro_x', max_samples=None,
                        names=ds.STATIC_EFFECTS, base=None, twins=NULL_TWINS, seed=1):
    """Build the static ``Problem`` with closed-form ``expect`` (see the module docstring)."""
    recs, layouts = ds.checked_records(records, dt, max_samples)
    if base is None:
        base = calibrate_n(ds.fit_baseline(recs[0], dt), recs[0])
    problem = ds.static_problem(recs, dt, channel=channel, names=names, base=base)
    # N is re-tuned with every candidate within what the white-band level pins it to: +-5 %
    # on long records, wider on short ones (a median over few Welch bins of few segments).
    spread_n = white_band_spread(recs[0].size, dt)
    width = max(0.05, 3.0 * spread_n)
    problem.nuisance = EffectSpace(ds.NUISANCE, [Param('n_scale', 1.0 - width, 1.0 + width)])
    exp = StaticExpect(base, layouts)
    sims = [[problem.simulate(i, [], seed * 1000 + 700 + k) for k in range(twins)]
            for i in range(len(recs))]
    problem.check = exp.calibrate(sims)
    problem.expect = exp
    # Steady lines too narrow for the tone bands, checked once the search is done.
    problem.lines = LineCheck(recs[0], dt, exp.spectrum)
    # Among significant candidates: the own-spread deviance plus the bands' kurtosis (a
    # steady envelope is a line's or a wandering tone's, not a mode's: ``kurtosis_choice``)
    # and the fine scan's lines (steady lines are a machine's: ``line_choice``).
    problem.choose = LineCriterion(problem.reals, problem.spaces, recs, dt, exp.spectrum,
                                   problem.lines)
    return problem
