"""
Search spaces of the static narrow-band effects: ``vibration`` and ``resonance``.

Both start from what the record's Welch PSD shows: the strongest narrow peak, the narrow lines
(a comb, further tones) and the highest broad bump (a structural mode with no narrow peak:
a mode folded from above the output Nyquist frequency, or one sensed in rate).
"""
from typing import Optional, Sequence

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.fit import EffectSpace, Param
import numpy as np


def resonance_space(sig_sample: float, f_tone: float, dt: float,
                    bump: Optional[float]) -> EffectSpace:
    """
    ``resonance``'s search: band-limited noise of width f0 / q about the strongest peak.

    The centre is searched within +-15 % (a mode's largest Welch bin need not be its centre).
    Where the PSD shows a broad bump elsewhere (``observables.broad_peak``), a mode about the
    bump is the alternative start: a wide mode has no narrow peak to start from.
    """
    def space(f0: float) -> EffectSpace:
        return EffectSpace('resonance', [
            Param('sigma', 0.01 * sig_sample, 2.0 * sig_sample),
            Param('freq_hz', 0.85 * f0, min(1.15 * f0, 0.45 / dt), log=False),
            Param('q', 1.0, 300.0)])
    main = space(f_tone)
    if bump is not None and abs(bump - f_tone) > 0.15 * f_tone and bump < 0.45 / dt:
        main.alternatives = (space(bump),)
    return main


def vibration_space(sig_sample: float, f_tone: Optional[float], df: float, dt: float,
                    lines: Sequence[float], levels: Sequence[float]) -> EffectSpace:
    """
    ``vibration``'s search: the tone at the strongest narrow peak; combs and tones if shown.

    ``lines``, ``levels``: the record's narrow lines, strongest first, and their amplitudes
    (``observables.narrow_lines``).
    Where three or more sit on one lattice (``observables.comb_of``), a comb about the
    strongest is an alternative start: lines at centre + k spacing under a Lorentzian
    envelope whose width is fitted (a tone is its narrow limit). Where two or more lines
    show, the three strongest as unrelated tones are another, each amplitude fitted within a
    factor 2 of its line's measured amplitude (``levels``; a search from one tone at a time
    crawls along the valley where their total power is right). Line frequencies and the
    spacing, measured on the lines' peaks, are kept (``estimated``): the observables hardly
    see a change within a bin, so a search would only trade them for noise.
    """
    amplitude = Param('amplitude', 0.01 * sig_sample, 2.0 * sig_sample)
    freq = (Param('freq_hz', max(f_tone - 2.0 * df, df), f_tone + 2.0 * df, log=False)
            if f_tone is not None else Param('freq_hz', 0.125 / dt, 0.375 / dt, log=False))
    lines = np.asarray(lines, dtype=float)
    others = []
    comb = obs.comb_of(lines, df)
    if comb is not None:
        centre, spacing = comb
        others.append(EffectSpace('vibration', [
            amplitude, Param('freq_hz', max(centre - 0.5 * df, 0.5 * df), centre + 0.5 * df,
                             log=False, init=centre),
            Param('width_hz', 0.25 * spacing, 1.0 / dt)], fixed={'spacing_hz': spacing},
            estimated=('spacing_hz',), passes=2))
    if lines.size >= 2:
        tones = lines[:3]
        names = [('freq_hz', 'amplitude'), ('freq2_hz', 'amplitude2'), ('freq3_hz', 'amplitude3')]
        lo, hi = 0.01 * sig_sample, 2.0 * sig_sample
        start = np.clip(levels[:tones.size], lo, hi)
        others.append(EffectSpace('vibration', [
            Param(a, max(0.5 * v, lo), min(2.0 * v, hi), init=v)
            for (_, a), v in zip(names, start.tolist())],
            fixed={f: float(v) for (f, _), v in zip(names, tones)},
            estimated=tuple(f for f, _ in names[:tones.size]), passes=2))
    return EffectSpace('vibration', [amplitude, freq], alternatives=tuple(others))
