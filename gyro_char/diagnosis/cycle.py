"""
A slow periodic cycle in a static record: its period, harmonics and phases, read from it.

An HVAC or thermostat cycle of the room reaches the die through its thermal lag, and the bias
follows: a line at the cycle's frequency, and at its harmonics where the bias curves with
temperature, in the record's low-frequency periodogram, far below the Welch PSD's first bin.
``cycle_start`` takes the strongest line that stands CYCLE_RATIO times above the local median
of the differenced record's periodogram (at least MIN_CYCLES cycles in the record) as the
fundamental or one of its first harmonics, refines the period by least squares on the
record's block means and reads each harmonic's amplitude and phase there. A harmonic is kept
where its own bin stands HARMONIC_RATIO above its surroundings. ``static_spaces`` searches
the amplitudes from there.
"""
from dataclasses import dataclass
from typing import Optional, Tuple

from gyro_char.sim.effects.base import CYCLE_HARMONICS
import numpy as np
from scipy import optimize

BLOCKS = 8192          # block means the periodogram and the least squares are taken on
MIN_CYCLES = 4         # fewer cycles in the record are a wander, not a cycle
# A Hann periodogram bin of Gaussian noise is exponential: it exceeds R times the local
# median (ln 2 of its mean) with probability 2^-R, 1e-9 at 30 (a record tests ~200 bins).
CYCLE_RATIO = 30.0
HARMONIC_RATIO = 8.0   # a harmonic of a found cycle: 2^-8 per harmonic tested


@dataclass(frozen=True)
class CycleStart:
    """A cycle read from a record: period (s), and per harmonic the amplitude and phase."""

    period: float
    amplitudes: Tuple[float, ...]     # rad/s, 0 where the harmonic is not kept
    phases: Tuple[float, ...]         # rad, of sin(2 pi k t / period + phase)


def block_means(y: np.ndarray, dt: float, blocks: int = BLOCKS):
    """Return the record's means over ~``blocks`` blocks, their centre times and the block size."""
    size = max(1, y.size // blocks)
    nb = y.size // size
    means = y[:nb * size].reshape(nb, size).mean(axis=1)
    return means, (np.arange(nb) * size + 0.5 * (size - 1)) * dt, size


def standing(p: np.ndarray, k: int) -> float:
    """Return bin ``k`` over the median of bins k/2 to 2k + 3 but its own main lobe (±2)."""
    j = np.arange(max(k // 2, 1), min(2 * k + 4, p.size))
    near = j[np.abs(j - k) > 2]
    if near.size < 3:
        return 0.0
    floor = float(np.median(p[near]))
    return float(p[k] / floor) if floor > 0.0 else np.inf


def sines_fit(b: np.ndarray, t: np.ndarray, periods) -> Tuple[np.ndarray, np.ndarray]:
    """Return the least-squares (sine, cosine) coefficients at each period (with a line), fit."""
    cols = [np.ones_like(t), t - t.mean()]
    for period in periods:
        cols += [np.sin(2.0 * np.pi * t / period), np.cos(2.0 * np.pi * t / period)]
    a = np.column_stack(cols)
    coef = np.linalg.lstsq(a, b, rcond=None)[0]
    return coef[2:].reshape(-1, 2), a @ coef


def cycle_start(y: np.ndarray, dt: float, shortest: float) -> Optional[CycleStart]:
    """
    Return the record's slow cycle (``CycleStart``), or None where no line stands out.

    ``y`` is the detrended record; periods from ``shortest`` (s) to a MIN_CYCLES-th of it.
    Amplitudes are corrected for the block averaging (sinc of the block over the period).
    """
    b, t, size = block_means(y, dt)
    big_t = b.size * size * dt
    # The differenced block means' periodogram: a random walk's and flicker's red continuum
    # turns flat or nearly so, which a median of the neighbours then reads at the line's bin
    # (undifferenced, a walk's steep fall put bin 4 30 times over the bins above it).
    p = np.abs(np.fft.rfft(np.hanning(b.size - 1) * np.diff(b))) ** 2
    k_hi = min(int(big_t / shortest), p.size - 2)
    found = [k for k in range(MIN_CYCLES, k_hi + 1)
             if p[k] >= max(p[k - 1], p[k + 1]) and standing(p, k) > CYCLE_RATIO]
    if not found:
        return None
    # The strongest line is the fundamental or a harmonic: the fundamental is the lowest of
    # its subharmonics whose own bin stands out too (a curved bias can put more power in the
    # second harmonic than in the fundamental).
    # (power compared undifferenced: the difference raises a line k bins up by sin^2(pi k / nb))
    top = max(found, key=lambda k: p[k] / np.sin(np.pi * k / b.size) ** 2)
    h_top = next(h for h in range(len(CYCLE_HARMONICS), 0, -1)
                 if h == 1 or top / h >= MIN_CYCLES
                 and standing(p, int(round(top / h))) > HARMONIC_RATIO)
    harmonics = np.arange(1, len(CYCLE_HARMONICS) + 1)

    def refine(k_top, held=None):
        # The strongest line's frequency (in bins) by least squares, the other harmonics
        # held where ``held`` (the fundamental, in bins) puts them: a morphing fundamental's
        # sidebands pull a fit of every harmonic off the line, an unmodelled harmonic biases
        # the line's alone.
        rest = [big_t / (h * held) for h in harmonics if h != h_top] if held else []

        def misfit(k):
            return float(np.sum((b - sines_fit(b, t, [big_t / k] + rest)[1]) ** 2))
        grid = np.linspace(k_top - 1.0, k_top + 1.0, 41)
        best = grid[int(np.argmin([misfit(k) for k in grid]))]
        step = grid[1] - grid[0]
        return optimize.minimize_scalar(misfit, bounds=(best - step, best + step),
                                        method='bounded', options={'xatol': 1e-4}).x
    k = refine(top) / h_top
    k = refine(k * h_top, k) / h_top
    period = big_t / k
    sc = sines_fit(b, t, big_t / (k * harmonics))[0]
    amps, phases = [], []
    for h, (s, c) in zip(harmonics, sc):
        kept = h == 1 or standing(p, int(round(h * k))) > HARMONIC_RATIO
        gain = np.sinc(size * dt * h / period)
        amps.append(float(np.hypot(s, c) / gain) if kept else 0.0)
        phases.append(float(np.arctan2(c, s)) if kept else 0.0)
    return CycleStart(float(period), tuple(amps), tuple(phases))
