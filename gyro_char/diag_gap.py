"""
The sim-to-real gap, in units of the simulation's own scatter.

Repeated simulations of a model give, for every observable element j, a mean m_j and a scatter
s_j. The real record's element r_j is scored z_j = (r_j - m_j) / s_j. A block's score is the mean
of z² over its elements; the gap (``GAP_METRIC``) is the square root of the mean block score, so
every block weighs the same whatever its length. A record drawn from the model itself scores
about 1; the exact null distribution is measured by scoring each repeat against the others
(leave-one-out), which is what "beyond the sim's own scatter" is judged against.
"""
from dataclasses import dataclass
from typing import Dict, List, Sequence

import numpy as np

GAP_METRIC = 'rms_z_blockwise'
# Scatter floors per block (in the block's own units): a sim that is deterministic in some
# element must not turn a rounding difference into an infinite z.
SCATTER_FLOOR = {'adev': 0.002, 'psd': 0.002, 'tone': 0.01, 'acf': 0.001, 'drift': 1e-9}
Obs = Dict[str, np.ndarray]


@dataclass
class SimStats:
    """Mean and scatter of each block over repeated simulations (and the repeats themselves)."""

    mean: Obs
    std: Obs
    repeats: List[Obs]


def sim_stats(repeats: Sequence[Obs]) -> SimStats:
    if len(repeats) < 3:
        raise ValueError('need at least 3 repeated simulations to know their scatter')
    blocks = repeats[0].keys()
    stack = {b: np.array([r[b] for r in repeats]) for b in blocks}
    mean = {b: v.mean(axis=0) for b, v in stack.items()}
    std = {b: np.maximum(v.std(axis=0, ddof=1), SCATTER_FLOOR.get(b, 0.0))
           for b, v in stack.items()}
    return SimStats(mean=mean, std=std, repeats=list(repeats))


def zscores(real: Obs, stats: SimStats) -> Obs:
    return {b: (real[b] - stats.mean[b]) / stats.std[b] for b in stats.mean}


def gap_of_z(z: Obs) -> float:
    return float(np.sqrt(np.mean([np.mean(v * v) for v in z.values()])))


def gap(real: Obs, stats: SimStats) -> float:
    return gap_of_z(zscores(real, stats))


def multi_gap(reals: Sequence[Obs], stats: Sequence[SimStats]) -> float:
    """Gap over several records (each with its own simulated repeats), blocks pooled."""
    scores = []
    for r, s in zip(reals, stats):
        scores.extend(np.mean(v * v) for v in zscores(r, s).values())
    return float(np.sqrt(np.mean(scores)))


def locate(z: Obs, ranges: Dict[str, np.ndarray], units: Dict[str, str], *,
           threshold: float = 3.0) -> List[dict]:
    """
    Contiguous runs of elements with |z| > threshold, per block, largest first.

    ``excess`` is the mean z over the run (signed: positive = real above the simulation), in
    units of the simulation's scatter.
    """
    found = []
    for b, v in z.items():
        hot = np.abs(v) > threshold
        i = 0
        while i < v.size:
            if not hot[i]:
                i += 1
                continue
            j = i
            while j + 1 < v.size and hot[j + 1] and np.sign(v[j + 1]) == np.sign(v[i]):
                j += 1
            found.append({'observable': b,
                          'range': [float(ranges[b][i][0]), float(ranges[b][j][1])],
                          'range_unit': units[b],
                          'excess': float(np.mean(v[i:j + 1]))})
            i = j + 1
    found.sort(key=lambda w: -abs(w['excess']))
    return found


def null_gaps(stats: Sequence[SimStats]) -> np.ndarray:
    """
    Gap of each repeat against the other repeats: the gap's distribution under the model.

    With several records, repeat k of every record plays the real records together.
    """
    k_max = min(len(s.repeats) for s in stats)
    out = []
    for k in range(k_max):
        reals = [s.repeats[k] for s in stats]
        others = [sim_stats(s.repeats[:k] + s.repeats[k + 1:]) for s in stats]
        out.append(multi_gap(reals, others))
    return np.asarray(out)
