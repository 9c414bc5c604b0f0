"""
Impulsive outliers (spikes) in a rate record: detection on a robust scale, their bias, removal.

A spike is a sample far off both neighbours: its deviation from their mean,
e_i = y_i - (y_(i-1) + y_(i+1)) / 2, exceeds ``THRESHOLD`` robust standard deviations of e
(1.4826 x its median absolute deviation: the scale of the noise itself, which a few spikes do
not move) and is the largest |e| of its neighbourhood (a spike also moves its neighbours' e by
half its size). Gaussian noise of any colour passes 8 sd about once in 1e15 samples, so a clean
record reports none; e of an isolated spike of size A on smooth noise is A.

Bias: a spike of size A (rate) is a step A dt of the angle; each adds 2m (A dt)^2 to the
overlapping sum of tau = m dt, i.e. dt sum A^2 / (L tau) to sigma^2(tau) over L samples: white
noise of density N_spike^2 = dt sum A^2 / L added at every tau. N is biased up by
sqrt(N^2 + N_spike^2) / N and the other terms are masked where that white noise dominates.

Treatment (``despike``, opt in, counted in a note): each spike sample is replaced by the mean of
its two neighbours.
"""
from dataclasses import dataclass

from gyro_char.robust import robust_sd
import numpy as np

THRESHOLD = 8.0


@dataclass
class SpikeReport:
    """The spikes of one channel: where, how many, how large, what they add to sigma^2."""

    count: int
    share: float         # spikes per sample
    largest: float       # |A| of the largest, rate unit
    largest_sd: float    # the same in robust sd of e
    n_spike: float       # density of the white noise they add (N's unit)
    n_white: float       # the record's white density from the same robust scale
    index: np.ndarray
    removed: bool = False

    def to_json(self, unit: str, n_unit: str) -> dict:
        return {'count': self.count, 'share': self.share,
                'largest': {'value': self.largest, 'unit': unit},
                'white_noise_added': {'value': self.n_spike, 'unit': n_unit},
                'removed': self.removed}


def detect(y, dt: float, threshold: float = THRESHOLD) -> SpikeReport:
    """Return the spikes of rate samples ``y`` at interval ``dt`` (see the module docstring)."""
    y = np.asarray(y, dtype=np.float64)
    e = np.zeros_like(y)
    if y.size >= 3:
        e[1:-1] = y[1:-1] - 0.5 * (y[:-2] + y[2:])
    inner = e[1:-1]
    scale = float(robust_sd(inner)) if inner.size else 0.0
    if not scale > 0:  # coarsely quantized records: most e are 0; the sd is the scale left
        scale = float(np.std(inner)) if inner.size else 0.0
    if not scale > 0:
        return SpikeReport(0, 0.0, 0.0, 0.0, 0.0, 0.0, np.zeros(0, dtype=np.int64))
    mag = np.abs(e)
    left = np.concatenate(([0.0], mag[:-1]))
    right = np.concatenate((mag[1:], [0.0]))
    index = np.flatnonzero((mag > threshold * scale) & (mag >= left) & (mag > right))
    amp = e[index]
    count = int(index.size)
    largest = float(np.max(np.abs(amp))) if count else 0.0
    return SpikeReport(count=count, share=count / y.size, largest=largest,
                       largest_sd=largest / scale,
                       n_spike=float(np.sqrt(dt * np.sum(amp ** 2) / y.size)),
                       n_white=scale * float(np.sqrt(dt / 1.5)), index=index)


def remove(y, index) -> np.ndarray:
    """Return a copy of ``y`` with each sample of ``index`` replaced by its neighbours' mean."""
    y = np.array(y, dtype=np.float64)
    index = np.asarray(index, dtype=np.int64)
    lo = np.maximum(index - 1, 0)
    hi = np.minimum(index + 1, y.size - 1)
    y[index] = 0.5 * (y[lo] + y[hi])
    return y


def note(channel: str, rep: SpikeReport, unit: str) -> str:
    """Return the one-line note of a channel with spikes: count, share, size, bias, action."""
    bias = 100.0 * rep.n_spike ** 2 / rep.n_white ** 2 if rep.n_white > 0 else float('inf')
    action = ('replaced by the mean of their neighbours (--despike)' if rep.removed
              else 'kept (use --despike to replace them)')
    return (f'allan: {channel}: {rep.count} spike(s) ({100.0 * rep.share:.3g} % of the samples, '
            f'largest {rep.largest:.4g} {unit} = {rep.largest_sd:.3g} robust sd): they add '
            f'white noise of density {rep.n_spike:.3g} to every tau, sigma^2 up by about '
            f'{bias:.3g} % where white noise dominates; {action}')
