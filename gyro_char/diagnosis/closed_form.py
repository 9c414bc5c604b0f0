"""
The gap objective on closed-form expectations: candidates are scored without simulation.

``ExpectedStats`` plays the part of the twins' statistics (``gap.SimStats``) for one model and
one record: its ``mean`` is the closed-form expectation of every observable
(``expected``), its ``std`` the closed-form sampling spread (``spread``, computed
only when a yardstick needs it), and its ``repeats`` are pseudo-twins: the expectation plus
the spread times the standardized residuals of a few simulated twins of the baseline
(``residuals``). Those keep what no closed form here gives - the correlation between
neighbouring elements and the estimators' tails - and they are how the simulator checks the
closed forms: a closed form that missed would show as residuals far from zero mean and unit
spread, and raise the null level accordingly.
"""
from typing import Callable, Dict, List, Optional, Sequence

from gyro_char.diagnosis import gap as diag_gap
from gyro_char.diagnosis.fit import Evaluation
import numpy as np

Obs = Dict[str, np.ndarray]


class ExpectedStats:
    """Closed-form mean and (lazily) spread of the observables of one model on one record."""

    exact = True

    def __init__(self, mean: Obs, spread: Callable[[], Obs], residuals: Sequence[Obs],
                 floors: Optional[Dict[str, float]] = None):
        self.mean = mean
        self._spread = spread
        self._std: Optional[Obs] = None
        self._residuals = list(residuals)
        self._floors = floors or {}

    @property
    def std(self) -> Obs:
        if self._std is None:
            raw = self._spread()
            self._std = {b: np.maximum(v, self._floors.get(b, 0.0)) for b, v in raw.items()}
        return self._std

    @property
    def repeats(self) -> List[Obs]:
        s = self.std
        return [{b: self.mean[b] + s[b] * u[b] for b in self.mean} for u in self._residuals]


def standardize(twins: Sequence[Obs], stats: ExpectedStats) -> List[Obs]:
    """Residuals of simulated twins in units of the closed form's spread, about its mean."""
    return [{b: (t[b] - stats.mean[b]) / stats.std[b] for b in stats.mean} for t in twins]


def residual_check(residuals: Sequence[Obs]) -> dict:
    """How well the closed form matches the twins: mean and rms of the residuals per block."""
    out = {}
    for b in residuals[0]:
        u = np.array([r[b] for r in residuals])
        k = u.shape[0]
        z_mean = u.mean(axis=0) * np.sqrt(k)
        out[b] = {'mean_z_of_twin_mean': float(np.sqrt(np.mean(z_mean ** 2))),
                  'rms_residual': float(np.sqrt(np.mean(u * u)))}
    return out


class ExpectedObjective:
    """``GapObjective``'s interface on closed-form statistics (no simulation per call)."""

    def __init__(self, reals: Sequence[Obs], expect: Callable[[int, list], ExpectedStats]):
        self.reals = list(reals)
        self.expect = expect
        self.calls = 0
        self.reference: Optional[List[Obs]] = None

    def evaluate(self, effects) -> Evaluation:
        self.calls += 1
        stats = [self.expect(i, list(effects)) for i in range(len(self.reals))]
        return Evaluation(effects=list(effects),
                          gap=diag_gap.multi_gap(self.reals, stats, self.reference),
                          stats=stats)

    def set_reference(self, baseline) -> None:
        self.reference = [s.std for s in baseline.stats]
