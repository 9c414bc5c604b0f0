"""
Search spaces of the static narrow-band effects: ``vibration``, ``resonance``, a notch.

Each starts from what the record's Welch PSD shows: the strongest narrow peak, the narrow
lines (a comb, further tones) and the highest broad bump (a structural mode with no narrow
peak: a mode folded from above the output Nyquist frequency, or one sensed in rate); the
gap's own highest band (a weak mode) and deepest dip (an output-rate notch of
``internal_lowpass``).
"""
from dataclasses import replace
from typing import Callable, List, Optional, Sequence

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.narrow_lines import line_groups, line_scan, vibration_for
from gyro_char.sim.effects.vibration import TONES
import numpy as np


# The widest gap band taken for a mode's (hi / lo): a mode of q 1 raises about two octaves.
BAND_MAX_RATIO = 4.0
# A forest of steady lines (``forest_start``): at least FOREST_MIN lines at fine resolution,
# each within FOREST_GAP Hz of the next, about the strongest.
FOREST_MIN = 8
FOREST_GAP = 1.0
# Unrelated tones searched one amplitude each (the tones start): the six strongest lines.
SEARCHED_TONES = 6


def _mode_space(sig_sample: float, lo: float, hi: float, dt: float,
                q: Optional[float] = None) -> EffectSpace:
    """Return a ``resonance`` search with its centre in [lo, hi] Hz (q started at ``q``)."""
    hi = min(hi, 0.45 / dt)
    return EffectSpace('resonance', [
        Param('sigma', 0.01 * sig_sample, 2.0 * sig_sample),
        Param('freq_hz', min(lo, 0.9 * hi), hi, log=False,
              init=None if q is None else float(np.sqrt(lo * hi))),
        Param('q', 1.0, 300.0, init=q)])


def resonance_space(sig_sample: float, f_tone: float, dt: float,
                    bump: Optional[float]) -> EffectSpace:
    """
    ``resonance``'s search: band-limited noise of width f0 / q about the strongest peak.

    The centre is searched within +-15 % (a mode's largest Welch bin need not be its centre).
    Where the PSD shows a broad bump elsewhere (``observables.broad_peak``), a mode about the
    bump is the alternative start: a wide mode has no narrow peak to start from.
    """
    main = _mode_space(sig_sample, 0.85 * f_tone, 1.15 * f_tone, dt)
    if bump is not None and abs(bump - f_tone) > 0.15 * f_tone and bump < 0.45 / dt:
        main.alternatives = (_mode_space(sig_sample, 0.85 * bump, 1.15 * bump, dt),)
    return main


def _with_room(lo: float, hi: float, dt: float, psd_span: Sequence[float]) -> bool:
    """Whether the gap's band [lo, hi] Hz has room on both sides, is narrow and not at Nyquist."""
    return (psd_span[0] < lo and hi < psd_span[1] and hi <= BAND_MAX_RATIO * lo
            and np.sqrt(lo * hi) < 0.45 / dt)


def with_gap_band(spaces: Sequence[EffectSpace], where: Sequence[dict], sig_sample: float,
                  dt: float, psd_span: Sequence[float]) -> List[EffectSpace]:
    """
    Return ``spaces`` with a ``resonance`` start at the band where the PSD's gap is highest.

    A weak mode raises a band of the Welch PSD a little: too little for a bump in the raw
    PSD (``observables.broad_peak``), while the strongest narrow peak is then wherever the
    noise put it. The gap's own location (``where``: a run of Welch bins standing above the
    baseline's scatter) says where the mode is; its width gives q's start. Only a band with
    room on both sides within ``psd_span`` (the PSD block's lowest and highest frequency)
    and at most ``BAND_MAX_RATIO`` wide is a mode's: a rise towards either end of the
    spectrum is a slow process's, or a filter's.
    """
    bands = [w for w in where if w['observable'] == 'psd' and w['excess'] > 0.0]
    if not bands:
        return list(spaces)
    lo, hi = max(bands, key=lambda w: w['excess'])['range']
    centre = float(np.sqrt(lo * hi))
    if not _with_room(lo, hi, dt, psd_span):
        return list(spaces)
    q = float(np.clip(centre / max(hi - lo, 1e-9), 1.0, 300.0))
    band = _mode_space(sig_sample, min(lo, 0.85 * centre), max(hi, 1.15 * centre), dt, q)
    return [replace(space, alternatives=tuple(space.alternatives) + (band,))
            if space.name == 'resonance' and not any(
                _centre_in(s, centre) for s in (space,) + tuple(space.alternatives))
            else space for space in spaces]


def with_notch_band(spaces: Sequence[EffectSpace], where: Sequence[dict], dt: float,
                    psd_span: Sequence[float]) -> List[EffectSpace]:
    """
    Return ``spaces`` with an ``internal_lowpass`` notch started at the PSD's deepest dip.

    A notch (``notch_hz``, ``notch_q``) takes a band out of the spectrum and keeps the rest:
    the gap's location (``where``: a run of Welch bins standing below the baseline's scatter)
    says where, its width gives q's start: the deepest dip with room on both sides within
    ``psd_span``, at most ``BAND_MAX_RATIO`` wide (a fall towards the top of the spectrum is
    a low-pass's). No such dip, no notch searched: a notch can fit no noise where none shows.
    """
    dips = [w for w in where if w['observable'] == 'psd' and w['excess'] < 0.0
            and _with_room(*w['range'], dt, psd_span)]
    if not dips:
        return list(spaces)
    lo, hi = min(dips, key=lambda w: w['excess'])['range']
    centre = float(np.sqrt(lo * hi))
    q = float(np.clip(centre / max(hi - lo, 1e-9), 0.5, 100.0))
    notch = EffectSpace('internal_lowpass', [
        Param('notch_hz', 0.85 * lo, min(1.15 * hi, 0.45 / dt), log=False, init=centre),
        Param('notch_q', 0.5, 100.0, init=q)],
        fixed={'taps': 1.0, 'stages': 1.0, 'decimation': 1.0})
    return [replace(space, alternatives=tuple(space.alternatives) + (notch,))
            if space.name == 'internal_lowpass' else space for space in spaces]


def _centre_in(space: EffectSpace, f: float) -> bool:
    p = next(p for p in space.params if p.name == 'freq_hz')
    return p.lo <= f <= p.hi


def forest_start(x: np.ndarray, dt: float) -> Optional[list]:
    """
    Return the lines of a forest of steady lines in ``x`` (``narrow_lines.line_groups``), or None.

    Many machines at fixed speeds (a rack of fans, pumps at one duty) put many steady lines
    in one band: at the gap's resolution a band like a mode's, at the line scan's
    (``narrow_lines.line_scan``) lines, where a mode's band shows none. The forest is the run
    of lines about the strongest whose neighbours are within FOREST_GAP Hz, if it holds
    FOREST_MIN or more (the TONES strongest of them).
    """
    try:
        lines = sorted(line_groups(line_scan(x, dt)), key=lambda d: d['frequency_hz'])
    except ValueError:
        return None
    if len(lines) < FOREST_MIN:
        return None
    f = np.array([d['frequency_hz'] for d in lines])
    top = int(np.argmax([d['mean_square'] for d in lines]))
    cuts = np.flatnonzero(np.diff(f) > FOREST_GAP) + 1
    run = next(r for r in np.split(np.arange(f.size), cuts) if top in r)
    if run.size < FOREST_MIN:
        return None
    return sorted((lines[i] for i in run), key=lambda d: -d['mean_square'])[:TONES]


def forest_space(forest: list, spectrum: Callable) -> EffectSpace:
    """
    ``vibration``'s forest: every line at its measured frequency and mean square, none searched.

    Each amplitude carries its line's mean square through the baseline's filters
    (``narrow_lines.vibration_for``); frequencies and amplitudes are estimated from the
    record (two parameters a line to the criterion).
    """
    _, params = vibration_for(forest, spectrum, [])
    return EffectSpace('vibration', [], fixed=params, estimated=tuple(params))


def vibration_space(sig_sample: float, f_tone: Optional[float], df: float, dt: float,
                    lines: Sequence[float], levels: Sequence[float],
                    wander: bool = False, forest=None,
                    spectrum: Optional[Callable] = None) -> EffectSpace:
    """
    ``vibration``'s search: the tone at the strongest narrow peak; combs and tones if shown.

    ``lines``, ``levels``: the record's narrow lines, strongest first, and their amplitudes
    (``observables.narrow_lines``).
    With ``wander`` (the peak's band has a steady envelope: ``band_kurtosis``), a tone
    whose frequency wanders (``wander_hz``, ``wander_s``) about the peak is one alternative
    start. Where three or more sit on one lattice (``observables.comb_of``), a comb about the
    strongest is an alternative start: lines at centre + k spacing under a Lorentzian
    envelope whose width is fitted (a tone is its narrow limit). Where two or more lines
    show, the SEARCHED_TONES strongest as unrelated tones are another, each amplitude fitted
    within a factor 2 of its line's measured amplitude (``levels``; a search from one tone at
    a time crawls along the valley where their total power is right). ``forest``
    (``forest_start``): a forest of steady lines, each where the fine scan measures it
    (``forest_space``, ``spectrum`` the baseline's model spectrum of effects). Line
    frequencies and the spacing, measured on the lines' peaks, are kept (``estimated``): the
    observables hardly see a change within a bin, so a search would only trade them for
    noise.
    """
    amplitude = Param('amplitude', 0.01 * sig_sample, 2.0 * sig_sample)
    freq = (Param('freq_hz', max(f_tone - 2.0 * df, df), f_tone + 2.0 * df, log=False)
            if f_tone is not None else Param('freq_hz', 0.125 / dt, 0.375 / dt, log=False))
    lines = np.asarray(lines, dtype=float)
    others = []
    if f_tone is not None and wander:
        # A machine whose speed wanders: the tone spread over a band (``wander``) like a
        # mode's, with a steady envelope; its centre searched as a mode's (+-15 %).
        others.append(EffectSpace('vibration', [
            amplitude, Param('freq_hz', 0.85 * f_tone, min(1.15 * f_tone, 0.45 / dt),
                             log=False, init=f_tone),
            Param('wander_hz', max(0.25 * df, 1e-3), 0.15 * f_tone),
            Param('wander_s', 0.05, 300.0)], passes=2))
    comb = obs.comb_of(lines, df)
    if comb is not None:
        centre, spacing = comb
        others.append(EffectSpace('vibration', [
            amplitude, Param('freq_hz', max(centre - 0.5 * df, 0.5 * df), centre + 0.5 * df,
                             log=False, init=centre),
            Param('width_hz', 0.25 * spacing, 1.0 / dt)], fixed={'spacing_hz': spacing},
            estimated=('spacing_hz',), passes=2))
    if lines.size >= 2:
        tones = lines[:SEARCHED_TONES]
        names = [('freq_hz', 'amplitude')] + [(f'freq{j}_hz', f'amplitude{j}')
                                              for j in range(2, SEARCHED_TONES + 1)]
        lo, hi = 0.01 * sig_sample, 2.0 * sig_sample
        start = np.clip(levels[:tones.size], lo, hi)
        others.append(EffectSpace('vibration', [
            Param(a, max(0.5 * v, lo), min(2.0 * v, hi), init=v)
            for (_, a), v in zip(names, start.tolist())],
            fixed={f: float(v) for (f, _), v in zip(names, tones)},
            estimated=tuple(f for f, _ in names[:tones.size]), passes=2))
    if forest is not None:
        others.append(forest_space(forest, spectrum))
    return EffectSpace('vibration', [amplitude, freq], alternatives=tuple(others))
