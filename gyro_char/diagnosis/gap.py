"""
The sim-to-real gap, in units of the simulation's own scatter.

Repeated simulations of the baseline model give, for every observable element j, a scatter s0_j;
repeated simulations of any candidate model give a mean m_j. The real record's element r_j is
scored z_j = (r_j - m_j) / s0_j. A block's score is the mean of z² over its elements; the gap
(``GAP_METRIC``) is the square root of the mean block score, so every block weighs the same
whatever its length.

The yardstick s0 is the baseline's scatter for every model on purpose: were each model judged
by its own scatter, an effect could "explain" a gap by making the twins noisier rather than by
bringing their mean to the real record. A model that genuinely adds variance (flicker, a random
walk) then leaves a residual gap even when right; that is why the null distribution - each
repeat of the model scored against the other repeats with the same yardstick (leave-one-out) -
is recomputed for every model, and "within the sim's own scatter" is judged against it.
"""
from dataclasses import dataclass
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

GAP_METRIC = 'rms_z_in_baseline_scatter'
# Scatter floors per block (in the block's own units): a sim that is deterministic in some
# element must not turn a rounding difference into an infinite z.
SCATTER_FLOOR = {'adev': 0.002, 'psd': 0.002, 'tone': 0.01, 'acf': 0.001, 'drift': 1e-9,
                 'encoder_lines': 0.02, 'rate_locked': 0.002, 'rate_sign': 1e-4,
                 'rate_acf': 1e-4, 'increment_acf': 0.001}
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


def leave_out(stats, k: int):
    """
    Return the statistics without repeat k: what a left-out repeat is scored against.

    Closed-form statistics (``exact``: their mean and spread do not come from the repeats) are
    returned as they are.
    """
    if getattr(stats, 'exact', False):
        return stats
    return sim_stats(stats.repeats[:k] + stats.repeats[k + 1:])


def zscores(real: Obs, stats: SimStats, ref: Optional[Obs] = None) -> Obs:
    """Scores of ``real`` against the twins' mean, in ``ref`` scatter (default: their own)."""
    scale = stats.std if ref is None else ref
    return {b: (real[b] - stats.mean[b]) / scale[b] for b in stats.mean}


def gap(real: Obs, stats: SimStats, ref: Optional[Obs] = None) -> float:
    return multi_gap([real], [stats], None if ref is None else [ref])


def multi_gap(reals: Sequence[Obs], stats: Sequence[SimStats],
              refs: Optional[Sequence[Obs]] = None) -> float:
    """Gap over several records (each with its own simulated repeats), blocks pooled."""
    scores = []
    for i, (r, s) in enumerate(zip(reals, stats)):
        z = zscores(r, s, None if refs is None else refs[i])
        scores.extend(float(np.mean(v * v)) for v in z.values())
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


def null_gaps(stats: Sequence[SimStats],
              ref_stats: Optional[Sequence[SimStats]] = None,
              yardstick: Optional[Callable[[int], List[Obs]]] = None) -> np.ndarray:
    """
    Gap of each repeat against the other repeats: the gap's distribution under the model.

    With several records, repeat k of every record plays the real records together. The
    yardstick is the scatter of ``ref_stats`` (the baseline's twins) without repeat k, or of
    the model's other repeats: in both cases a scatter the left-out repeat took no part in, as
    the real record took no part in the scatter it is scored in. ``yardstick(k)``, if given,
    supplies that scatter per record instead (it too must leave repeat k out).
    """
    k_max = min(len(s.repeats) for s in stats)
    out = []
    for k in range(k_max):
        reals = [s.repeats[k] for s in stats]
        others = [leave_out(s, k) for s in stats]
        if yardstick is not None:
            refs = yardstick(k)
        elif ref_stats is None:
            refs = [o.std for o in others]
        else:
            refs = [leave_out(r, k).std for r in ref_stats]
        out.append(multi_gap(reals, others, refs))
    return np.asarray(out)
