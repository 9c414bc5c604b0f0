"""
When the live swing estimates count as converged, judged by their own 1-sigma.

Every estimate of the paper's (1)-(3) (scale-factor error, bias, bias drift) must be determined:
its sigma at most ``rel_sigma`` times its own magnitude, or at most its absolute tolerance when
one is set (a drift far below what the run can resolve is "determined" once its sigma is small
in absolute terms). The condition must hold without a break over ``periods`` swing periods of
data (stamp time), so that one lucky update does not flip the flag; once reached, the flag stays
set until the filter restarts (``reset``). With ``rel_sigma`` 0.25 converged means every
estimate is at least 4 sigma away from zero.
"""
import math
from typing import Dict, List, Optional

QUANTITIES = ('scale_factor_error', 'bias', 'bias_drift')


class Convergence:
    """Latched convergence flag of a ``SwingEstimates`` stream."""

    def __init__(self, period_s: float, rel_sigma: float = 0.25, periods: float = 3.0,
                 abs_sigma: Optional[Dict[str, float]] = None) -> None:
        self.period_s = float(period_s)
        self.rel_sigma = float(rel_sigma)
        self.periods = float(periods)
        self.abs_sigma = {q: float((abs_sigma or {}).get(q, 0.0)) for q in QUANTITIES}
        self.reset()

    def reset(self) -> None:
        """Start over (the filter restarted)."""
        self.converged = False
        self.since: Optional[float] = None
        self.unmet: List[str] = list(QUANTITIES)

    def tolerance(self, quantity: str, value: float) -> float:
        """Return the largest sigma accepted for ``quantity`` at ``value``."""
        return max(self.rel_sigma * abs(value), self.abs_sigma[quantity])

    def update(self, estimates, data_time: float) -> bool:
        """
        Judge ``estimates`` (a ``SwingEstimates``) at stamp ``data_time`` (s); return the flag.

        ``unmet`` lists the quantities whose sigma is still above its tolerance.
        """
        if self.converged:
            return True
        self.unmet = []
        for q in QUANTITIES:
            est = getattr(estimates, q)
            ok = math.isfinite(est.value) and math.isfinite(est.sigma) \
                and est.sigma <= self.tolerance(q, est.value)
            if not ok:
                self.unmet.append(q)
        if self.unmet or not math.isfinite(data_time):
            self.since = None
            return False
        if self.since is None:
            self.since = data_time
        self.converged = data_time - self.since >= self.periods * self.period_s
        return self.converged
