"""
Narrow lines at fine frequency resolution: a check beside the gap.

The gap's ``tone`` block reads Welch segments of at most 2048 samples (0.05 Hz at 100 Hz):
wide enough bins for wandering tones and modes, with hundreds of segments behind each bin.
A steady line's excess over the noise in its bin grows as the segment length while the
bin's scatter falls only as the square root of the number of segments, so a line the tone
block cannot see stands far out at a finer resolution (a 2 h record: segments of 2^15
samples, 0.003 Hz, 42 of them).

Test, per bin: the Welch PSD over its running median (``FLOOR_SHARE`` of the bins wide,
~0.5 Hz: a mode wider than that lifts its own floor and is not a line here). Under Gaussian
noise a bin is its mean times chi-square / dof with 2 K_eff degrees of freedom (K_eff: the
overlapping Hann segments' equivalent count) and the running median is that mean times the
law's median, so the bin's excess r has the tail P(chi2_(2K) > 2 K r med). K is divided by
the segments' own dispersion about their mean (``dispersion``: 1 for stationary noise, more
where the level changes along the record, whose bins then have fewer degrees of freedom),
and the tail is averaged over the floor's own error (the median of the window's bins:
log-normal, relative sd 1.2533 / sqrt(K n_eff), n_eff the window's bins over the Hann
neighbours' variance inflation 1 + 2 (4/9 + 1/36); 9-point Gauss-Hermite). The family-wise
p of a bin is 1 - (1 - tail)^M over the M bins tested (neighbouring Hann bins correlate,
which makes it conservative). Bins within half a floor window of either end are not tested.

Whether the selected model makes a line is read off the model's own spectrum on the same
bins: its continuous part at the bin frequencies plus its lines' Hann leakage, over its own
running median (``model_excess``); a line whose model excess reaches ``MODEL_SHARE`` of the
record's is the model's. The others are what the gap cannot see.
"""
from typing import Callable, Optional, Tuple

from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis.expected import line_bins
import numpy as np
from scipy import ndimage, signal, special

MIN_SEGMENTS = 32       # Welch segments at least (50 % overlap)
MAX_SEGMENT = 2 ** 16   # samples per segment at most
FLOOR_SHARE = 100       # the floor's running median spans 1/FLOOR_SHARE of the bins
REPORT_P = 1e-3         # family-wise p below which a bin is reported
HANN_INFLATION = 1.0 + 2.0 * (4.0 / 9.0 + 1.0 / 36.0)   # neighbouring bins' correlation
MAX_REPORTED = 10       # lines reported at most, smallest p first
LINE_BINS = 2           # Hann leakage bins either side summed into a line's power
MODEL_SHARE = 0.5       # a model excess this share of the record's makes the line the model's
NAMED_TONES = 6         # lines a model lacks named as one vibration after the search, at most


def fine_segment(n: int) -> int:
    """Longest power-of-two segment with ``MIN_SEGMENTS`` half-overlapping segments in ``n``."""
    seg = 2 ** int(np.floor(np.log2(max(2 * n // (MIN_SEGMENTS + 1), 2))))
    return int(min(seg, MAX_SEGMENT))


def equivalent_segments(n: int, nps: int) -> float:
    """K_eff of Welch's half-overlapping Hann segments (their overlap correlates them)."""
    segs = (n - nps) // (nps // 2) + 1
    w = signal.get_window('hann', nps)
    rho = float(np.dot(w[:nps // 2], w[nps // 2:]) / np.dot(w, w))
    return segs / (1.0 + 2.0 * rho * rho * (segs - 1) / segs)


def line_scan(x: np.ndarray, dt: float) -> dict:
    """
    Every tested bin's frequency, excess over the floor and family-wise p (module docstring).

    ``x``: rate samples, detrended here. A record too short for ``MIN_SEGMENTS`` segments
    longer than the tone block's cannot be resolved finer than it: a ValueError says so.
    """
    x = obs.detrend(np.asarray(x, dtype=np.float64))
    nps = fine_segment(x.size)
    if nps <= obs.welch_segment(x.size):
        raise ValueError(f'record too short for a finer line scan than the tone block: '
                         f'{x.size} samples (need >= {(MIN_SEGMENTS + 1) * 2048})')
    f, _, seg = signal.spectrogram(x, fs=1.0 / dt, window='hann', nperseg=nps,
                                   noverlap=nps // 2, detrend='constant', scaling='density')
    p = seg.mean(axis=1)                # Welch's PSD (the mean of the segments')
    size = max(31, (p.size // FLOOR_SHARE) | 1)
    k = equivalent_segments(x.size, nps) / dispersion(seg, p, size)
    floor = ndimage.median_filter(p, size=size, mode='nearest')
    half = size // 2
    keep = slice(half, p.size - half)
    k = k[keep]
    med = special.gammaincinv(k, 0.5) / k
    excess = p[keep] / np.maximum(floor[keep], 1e-300) * med
    tail = floor_averaged_tail(excess, k, size)
    m = excess.size
    family = -np.expm1(m * np.log1p(-np.minimum(tail, 1.0 - 1e-16)))
    return {'segment': nps, 'resolution_hz': float(f[1]), 'k_eff': float(np.median(k)),
            'tested_hz': [float(f[keep][0]), float(f[keep][-1])], 'bins': int(m),
            'f': f[keep], 'excess': excess, 'p': family, 'keep': keep, 'size': size,
            'psd': p[keep], 'noise': floor[keep] / med}


def dispersion(seg: np.ndarray, p: np.ndarray, size: int) -> np.ndarray:
    """
    Per bin, how much more the segments' periodograms scatter than stationary noise's (>= 1).

    A Gaussian stationary record's segment periodograms are exponential about their mean
    (variance / mean^2 = 1); a record whose level changes along it (a filter switched on, a
    burst) scatters more, and its Welch bins have fewer degrees of freedom than the segment
    count says. The ratio is averaged over the floor's window (one bin's, over ~40 segments,
    is too noisy), and never taken below 1.
    """
    ratio = seg.var(axis=1, ddof=1) / np.maximum(p * p, 1e-300)
    local = ndimage.uniform_filter1d(ratio, size=size, mode='nearest')
    return np.maximum(local, 1.0)


def floor_averaged_tail(excess: np.ndarray, k, size: int) -> np.ndarray:
    """P(bin > excess x floor) for chi-square/dof bins (2k dof), the floor's error averaged."""
    sd = 1.2533 / np.sqrt(k * size / HANN_INFLATION)
    x, w = np.polynomial.hermite_e.hermegauss(9)
    w = w / w.sum()
    out = np.zeros_like(excess)
    for xi, wi in zip(x, w):
        out += wi * special.gammaincc(k, k * excess * np.exp(sd * xi))
    return out


def model_excess(spec, f: np.ndarray, dt: float, nps: int, size: int) -> np.ndarray:
    """Return the expected Welch PSD of ``spec`` on all bins ``f`` over its running median."""
    w = signal.get_window('hann', nps)
    cont = np.zeros(f.size)
    cont[1:] = spec.one_sided(f[1:])
    psd = cont + line_bins(list(spec.lines), dt, nps) * 2.0 * dt / np.dot(w, w)
    floor = ndimage.median_filter(psd, size=size, mode='nearest')
    return psd / np.maximum(floor, 1e-300)


def narrow_lines(x: np.ndarray, dt: float, spec=None, *, report_p: float = REPORT_P,
                 scan: Optional[dict] = None) -> Optional[dict]:
    """
    Lines standing out at fine resolution, and whether the model ``spec`` makes each.

    Returns None for a record too short to look finer than the tone block. Contiguous
    reported bins (one line leaks into its Hann neighbours) are one line, at its largest bin.
    ``scan``: the record's ``line_scan``, if the caller has it already.
    """
    if scan is None:
        try:
            scan = line_scan(x, dt)
        except ValueError:
            return None
    found = line_groups(scan, report_p)
    if spec is not None and found:
        f_all = np.fft.rfftfreq(scan['segment'], dt)
        made = model_excess(spec, f_all, dt, scan['segment'], scan['size'])[scan['keep']]
        for entry in found:
            entry['model_excess'] = float(made[entry['bin']])
            entry['in_model'] = bool(entry['model_excess'] >= MODEL_SHARE * entry['excess'])
    for entry in found:
        del entry['bin']
    found.sort(key=lambda d: d['p_value'])
    summary = {k: scan[k] for k in ('segment', 'resolution_hz', 'k_eff', 'tested_hz', 'bins')}
    return {**summary, 'report_p': report_p, 'lines': found[:MAX_REPORTED],
            'more': max(len(found) - MAX_REPORTED, 0)}


def line_groups(scan: dict, report_p: float = REPORT_P) -> list:
    """
    Every line of ``scan`` (``line_scan``) with a family-wise p below ``report_p``.

    Contiguous bins are one line, at its largest: its frequency, excess, p, bins, mean
    square (its bins and LINE_BINS either side above the floor) and ``bin`` (tested bin).
    """
    hot = np.flatnonzero(scan['p'] < report_p)
    groups = np.split(hot, np.flatnonzero(np.diff(hot) > 1) + 1) if hot.size else []
    found = []
    for g in groups:
        i = g[np.argmax(scan['excess'][g])]
        lo, hi = max(g[0] - LINE_BINS, 0), min(g[-1] + LINE_BINS + 1, scan['f'].size)
        power = float(np.sum(scan['psd'][lo:hi] - scan['noise'][lo:hi])
                      * scan['resolution_hz'])
        found.append({'frequency_hz': peak_frequency(scan, i),
                      'excess': float(scan['excess'][i]), 'p_value': float(scan['p'][i]),
                      'bins': int(g.size), 'mean_square': max(power, 0.0), 'bin': int(i)})
    return found


def peak_frequency(scan: dict, i: int) -> float:
    """Frequency of the line peaking at tested bin ``i`` (``observables.peak_shift``)."""
    f = scan['f']
    if i == 0 or i == f.size - 1:
        return float(f[i])
    shift = obs.peak_shift(scan['psd'], np.array([i]))[0]
    return float(f[i] + shift * scan['resolution_hz'])


def missing(found: dict) -> list:
    """Return the reported lines the model does not make, smallest p first."""
    return [d for d in found['lines'] if not d.get('in_model', False)]


def vibration_for(new: list, spectrum: Callable[[list], object],
                  model: list) -> Tuple[str, dict]:
    """
    Return the ``vibration`` effect that makes the lines ``new`` (at most its ``TONES``).

    Each line at its peak frequency, with the amplitude whose output line (through the
    model's own filters: ``spectrum`` of the model plus a unit tone) carries the line's
    measured mean square.
    """
    params = {}
    for j, d in enumerate(sorted(new, key=lambda d: -d['mean_square'])):
        f0 = d['frequency_hz']
        unit = spectrum(list(model) + [('vibration', {'freq_hz': f0, 'amplitude': 1.0})])
        gain = unit.lines[-1][1] if unit.lines else 0.0
        amp = float(np.sqrt(d['mean_square'] / gain)) if gain > 0 else 0.0
        key = '' if j == 0 else str(j + 1)
        params[f'freq{key}_hz'] = f0
        params[f'amplitude{key}'] = amp
    return 'vibration', params


class LineCheck:
    """
    ``Problem.lines`` of a static record: the vibration that makes the lines a model lacks.

    ``spectrum(effects)``: the model spectrum of the baseline plus ``effects``
    (``static_expect.StaticExpect.spectrum``). The record is scanned once (``line_scan``
    does not depend on the model); ``report`` compares it with a model, a call names what
    that model lacks, with the evidence: the lines, their resolution and the smallest p.
    """

    def __init__(self, x: np.ndarray, dt: float, spectrum: Callable[[list], object]):
        self.x = np.asarray(x, dtype=np.float64)
        self.dt = dt
        self.spectrum = spectrum
        self._scan = None

    def scan(self) -> Optional[dict]:
        """Return the record's ``line_scan``, once (None: too short to look finer)."""
        if self._scan is None:
            try:
                self._scan = line_scan(self.x, self.dt)
            except ValueError:
                return None
        return self._scan

    def report(self, model: list) -> Optional[dict]:
        """Return ``narrow_lines`` of the record against ``model`` (None: too short)."""
        if self.scan() is None:
            return None
        return narrow_lines(self.x, self.dt, self.spectrum(list(model)), scan=self._scan)

    def __call__(self, model: list) -> Optional[tuple]:
        found = self.report(model)
        new = [] if found is None else missing(found)[:NAMED_TONES]
        if not new:
            return None
        where = ', '.join(f'{d["frequency_hz"]:.3f}' for d in new)
        what = 'a narrow line at {} Hz stands' if len(new) == 1 else 'narrow lines at {} Hz stand'
        text = (f'{what.format(where)} out at {found["resolution_hz"]:.2g} Hz '
                f"resolution, finer than the gap's tone bands (family-wise p "
                f'{min(d["p_value"] for d in new):.1e})')
        return (vibration_for(new, self.spectrum, model),
                {'check': 'narrow_lines', 'text': text, 'lines': new})
