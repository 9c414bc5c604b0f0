"""
The static choice criterion with the fine line scan: steady lines are a machine's, not a mode's.

A forest of machines at fixed speeds (a rack of fans) fills a band of the gap's Welch
observables as a structural mode does, and a mode's three parameters fit that band as well as
the forest's two per line, which the criterion's penalty then charges. The line scan
(``narrow_lines``) sees what the gap cannot: each line standing out at fine resolution. Among
candidates the gap has found significant (``choice``), the chi-square deviance of each line's
bin under the candidate's own spectrum is added: K (rho - 1 - ln rho), rho the record's
excess over the floor against the model's (``narrow_lines.model_excess``, at least 1), K the
scan's equivalent segment count (the bin is chi-square of 2 K degrees of freedom), at most
2 ln(M / p) per line, the evidence on which the scan reported it (M bins tested, family-wise
p ``REPORT_P``). A model that makes a line pays nothing for it; lines no candidate makes cost
all of them alike. Uncapped, the deviance of 65 lines no candidate made (a swept fan's comb)
ran to 2e5 and the models' slightly different smooth spectra under them decided the name.
"""
from typing import Callable, Sequence

from gyro_char.diagnosis.fit import EffectSpace, Evaluation
from gyro_char.diagnosis.kurtosis_choice import KurtosisCriterion
from gyro_char.diagnosis.narrow_lines import line_groups, LineCheck, model_excess, REPORT_P
import numpy as np


class LineCriterion(KurtosisCriterion):
    """``KurtosisCriterion`` plus the deviance of the first record's fine-scan lines."""

    def __init__(self, reals: Sequence[dict], spaces: Sequence[EffectSpace],
                 records: Sequence[np.ndarray], dt: float, spectrum: Callable,
                 check: LineCheck):
        super().__init__(reals, spaces, records, dt, spectrum)
        self.scan = check.scan()
        self.lines = line_groups(self.scan) if self.scan is not None else []
        self.log_n = float(np.log(np.exp(self.log_n) + len(self.lines)))

    def line_deviance(self, effects) -> float:
        """Return the lines' deviance under the model ``effects`` (0 without lines)."""
        if not self.lines:
            return 0.0
        scan = self.scan
        f = np.fft.rfftfreq(scan['segment'], self.dt)
        made = model_excess(self.spectrum(list(effects)), f, self.dt, scan['segment'],
                            scan['size'])[scan['keep']]
        rho = np.array([d['excess'] / max(made[d['bin']], 1.0) for d in self.lines])
        cap = 2.0 * np.log(scan['bins'] / REPORT_P)
        return float(np.sum(np.minimum(scan['k_eff'] * (rho - 1.0 - np.log(rho)), cap)))

    def __call__(self, ev: Evaluation) -> float:
        return super().__call__(ev) + self.line_deviance(ev.effects)
