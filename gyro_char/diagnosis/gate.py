"""
Holds a glitch gate selects, in closed form (``stale_samples`` with ``gate`` > 0).

A driver guarding against bus glitches republishes its last output wherever the new sample
differs from it by more than the gate g: y_k = x_k if |x_k - y_(k-1)| <= g, else y_(k-1).
Unlike random holds the gate picks the largest steps, so one share of holds takes far more
power from the top of the band, and the variance drops. On white Gaussian input of sd s the
published value is a Markov chain; its stationary law and autocovariance come from the
transition matrix on cells of the normal law (each cell's mass and mean exact, the acceptance
window cut at the cells' edges, so the result is smooth in g). The grid's own error is
removed by subtracting the same computation without a gate, which must give white noise: the
output's autocovariance is s^2 (delta_k + c_k).

Slower parts (drifts, walks, lines, the colour of a filtered noise) pass as through
independent holds of the gate's share (``holds.Holds``): the gate sees the white noise, their
per-sample steps being far smaller. A smoothing filter ahead of the gate changes its share;
that case is left to the twins.
"""
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Tuple

from gyro_char.diagnosis.holds import cosine_series, Holds
import numpy as np
from scipy import special

CELLS = 320          # cells of the normal law on [-EDGE, EDGE] (the tails in the end cells)
EDGE = 8.0
LAGS = 1500          # at most this many lags of the correction; fewer once below TOL
TOL = 1e-10
# Gates modelled, in input sds: a share of holds from 16 % to ~1e-14. Below 2 sds the chain
# sticks for thousands of samples after an outlier (a gate no driver would use).
GATE_LO, GATE_HI = 2.0, 8.0


@lru_cache(maxsize=1)
def _cells() -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return the cells' lower and upper edges (infinite at the ends), masses and means."""
    b = np.linspace(-EDGE, EDGE, CELLS + 1)
    lo, hi = np.r_[-np.inf, b[1:-1]], np.r_[b[1:-1], np.inf]
    q = special.ndtr(hi) - special.ndtr(lo)
    return lo, hi, q, (_normal_pdf(lo) - _normal_pdf(hi)) / q


def _normal_pdf(v: np.ndarray) -> np.ndarray:
    return np.exp(-0.5 * v * v) / np.sqrt(2.0 * np.pi)


def _transition(g: float) -> Tuple[np.ndarray, np.ndarray]:
    """Return the chain's transition matrix at gate ``g`` (in sds) and each state's stay."""
    lo, hi, _, m = _cells()
    a = special.ndtr(np.minimum(hi[None, :], m[:, None] + g))
    b = special.ndtr(np.maximum(lo[None, :], m[:, None] - g))
    t = np.clip(a - b, 0.0, None)
    stay = np.clip(1.0 - t.sum(axis=1), 0.0, 1.0)
    t[np.diag_indices_from(t)] += stay
    return t, stay


def _stationary(t: np.ndarray) -> np.ndarray:
    a = t.T - np.eye(t.shape[0])
    a[-1, :] = 1.0
    rhs = np.zeros(t.shape[0])
    rhs[-1] = 1.0
    pi = np.clip(np.linalg.solve(a, rhs), 0.0, None)
    return pi / pi.sum()


@lru_cache(maxsize=512)
def share(g: float) -> float:
    """Return the stationary share of held samples at gate ``g`` (in input sds)."""
    t, stay = _transition(g)
    return float(_stationary(t) @ stay)


@lru_cache(maxsize=256)
def correction(g: float) -> np.ndarray:
    """Return c_k, k = 0, 1, ..: the gated white noise's autocovariance less delta_k (sd 1)."""
    t, _ = _transition(g)
    pi = _stationary(t)
    m = _cells()[3]
    mean = float(pi @ m)
    v, out = m.copy(), []
    for k in range(LAGS):
        out.append(float(pi @ (m * v)) - mean * mean)
        if k and abs(out[-1]) < TOL:
            break
        v = t @ v
    out = np.array(out)
    out[0] -= float(_cells()[2] @ (m * m))        # the grid's variance without a gate
    return out


def gate_for_share(p: float) -> float:
    """Return the gate (in input sds) whose held share is ``p`` (bisection; share falls in g)."""
    lo, hi = GATE_LO, GATE_HI
    if p >= share(lo):
        return lo
    if p <= share(hi):
        return hi
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if share(round(mid, 9)) > p else (lo, mid)
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class GateHolds:
    """Holds a gate of ``gate`` (rad/s) selects on white input of per-sample sd ``sigma``."""

    gate: float
    sigma: float
    c: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, 'c', correction(self.g))

    @property
    def g(self) -> float:
        """Return the gate in input sds (rounded: the key of the cached chain results)."""
        return round(self.gate / self.sigma, 9)

    @property
    def p(self) -> float:
        """Return the held share."""
        return share(self.g)

    def ratio(self, nu) -> np.ndarray:
        """Return the gated white PSD over the input's at ``nu`` cycles a sample."""
        return 1.0 + cosine_series(self.c, nu, by_fft=self.c.size > 32)

    def gain(self) -> float:
        """Return the gain on white noise (in N) in the white band, 1-5 % of the rate."""
        return float(np.sqrt(np.mean(self.ratio(np.linspace(0.01, 0.05, 65)))))

    def g2(self, f, dt: float) -> np.ndarray:
        """Return |G|^2 of the slower parts: independent holds of the same share."""
        return Holds(self.p).g2(f, dt)

    def lags(self) -> int:
        """Return how many lags of the correction are kept."""
        return int(self.c.size)

    def terms(self, f, s, lines, dt: float) -> np.ndarray:
        """Return the correction (the gate's map of the white part does not depend on ``s``)."""
        return self.c

    def apply(self, f, s: np.ndarray, terms: np.ndarray, dt: float) -> np.ndarray:
        """Return the output's one-sided PSD at ``f`` from the ungated one ``s``."""
        f = np.asarray(f, dtype=np.float64)
        white = 2.0 * dt * self.sigma ** 2
        return self.g2(f, dt) * (s - white) + white * self.ratio(f * dt)


@lru_cache(maxsize=1)
def _gain_table() -> Tuple[np.ndarray, np.ndarray]:
    """Return log gates (in sds) and the log of their white-band gains, for interpolation."""
    g = np.geomspace(GATE_LO, GATE_HI, 49)
    return np.log(g), np.log([GateHolds(float(v), 1.0).gain() for v in g])


def input_sd(gate: float, out_sd: float) -> float:
    """
    Return the white input sd s whose gated output has the white-band sd ``out_sd``.

    Solves s gain(gate / s) = out_sd (the left side rises with s: a wider gate holds less) by
    bisection in log s on the tabulated gain, taken as its end values beyond the table (a
    gate above it holds nothing).
    """
    lg, lgain = _gain_table()

    def excess(log_s):              # np.interp holds the table's end values beyond it
        return log_s + float(np.interp(np.log(gate) - log_s, lg, lgain)) - np.log(out_sd)
    lo, hi = np.log(out_sd) - lgain.max() - 0.1, np.log(out_sd) + 0.1
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if excess(mid) > 0.0 else (mid, hi)
    return float(np.exp(0.5 * (lo + hi)))


def hold_model(params: dict, n_white: float, dt: float, other_gain: float = 1.0):
    """
    Return the holds of a ``stale_samples`` parameter dict: ``Holds`` or ``GateHolds``.

    A gate needs the sd of the white noise it sees: the input N that, times the other
    effects' gain ``other_gain`` and the gate's own, gives the output's ``n_white``.
    """
    gate = float(params.get('gate', 0.0))
    if gate <= 0.0:
        return Holds.from_params(params)
    sd = input_sd(gate, n_white / other_gain / np.sqrt(dt))
    return GateHolds(gate, sd)
