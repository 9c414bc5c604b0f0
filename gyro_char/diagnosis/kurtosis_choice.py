"""
The static choice criterion with the band kurtosis: a steady envelope tells a line from a mode.

A machine's tone whose frequency wanders or whose phase jitters spreads its power over a band
as a structural mode does, and on the Welch observables a mode fits that band better than a
line. But the tone keeps a constant envelope (excess kurtosis -3/2 where it fills the band),
while a mode driven by broadband noise is Gaussian (0): ``band_kurtosis``. Among candidates
the gap has found significant (``choice``), the deviance of each band's sample excess
kurtosis under the candidate's own expectation and spread is added to the criterion. It only
ranks: the gap itself does not score it (as a block of the gap it named no shape better and
left non-Gaussian shapes unexplainable). Candidates with no line in a band all expect 0
there, so the term cancels between them and decides only line against noise.
"""
from typing import Callable, Sequence

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.band_kurtosis import band_ranges, expected_kurtosis, record_kurtosis
from gyro_char.diagnosis.choice import Criterion, element_count
from gyro_char.diagnosis.fit import EffectSpace, Evaluation
import numpy as np

# The kurtosis spread is never taken below this: rounding and the model's approximations
# leave a few hundredths on clean records (a 2 h record's Gaussian spread is ~0.015).
SD_FLOOR = 0.02


class KurtosisCriterion(Criterion):
    """``Criterion`` plus the Gaussian deviance of the records' band excess kurtosis."""

    def __init__(self, reals: Sequence[dict], spaces: Sequence[EffectSpace],
                 records: Sequence[np.ndarray], dt: float, spectrum: Callable):
        super().__init__(reals, spaces)
        self.dt = float(dt)
        self.spectrum = spectrum      # effects -> the model's ModelSpectrum
        self.bands = []
        for x in records:
            x = obs.detrend(np.asarray(x, dtype=np.float64))
            ranges = band_ranges(x.size, dt)
            self.bands.append((x.size, ranges, record_kurtosis(x, dt, ranges)))
        count = element_count(reals) + sum(len(r) for _, r, _ in self.bands)
        self.log_n = float(np.log(max(count, 2)))

    def kurtosis_deviance(self, effects) -> float:
        """Return the bands' deviance under the model ``effects`` (nuisance included)."""
        spec = self.spectrum(list(effects))
        total = 0.0
        for n, ranges, got in self.bands:
            mean, sd = expected_kurtosis(spec, n, self.dt, ranges, spread=True)
            s = np.maximum(sd, SD_FLOOR)
            z = (got - mean) / s
            total += float(np.sum(z * z + 2.0 * np.log(s)))
        return total

    def __call__(self, ev: Evaluation) -> float:
        return super().__call__(ev) + self.kurtosis_deviance(ev.effects)
