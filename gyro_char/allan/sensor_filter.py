"""
The sensor's own output filter in the noise fit: ``--sensor-filter`` specs and ``auto``.

Many MEMS sensors average internally (the ADIS16405: a Bartlett window at 819.2 Hz, read at a
lower rate), so neighbouring output samples are correlated and the short-tau Allan curve sits
below formula (4)'s N^2 / tau. With a filter given, the fit replaces that term by the exact
Allan variance of white noise through the filter and the decimation
(``gyro_char.allan.expected.white_avar_unit``); N stays the long-tau angle random walk.

Specs: ``none``; ``boxcar:TAPS[@RATE]`` (one TAPS-point moving average); ``bartlett:TAPS[@RATE]``
(two cascaded TAPS-point moving averages, a 2 TAPS - 1 point triangle); RATE the internal rate
as a multiple of the output rate (``8x``) or in Hz (``819.2``, rounded to a whole multiple of
the output rate), default the output rate; ``auto[@RATE]`` estimates the filter from the record.

``auto``: the record's spectrum (Welch, 256-point segments, bins below 2 % of the sample rate
left out: that is where flicker and random walks live) is the Fourier transform of its
autocorrelation at small lags, which white noise dominates. Every candidate (boxcar and
Bartlett, internal rates 1, 2, 4, 8, 16 x, taps up to 4 x the rate, one per distinct output
autocorrelation) is fitted as scale x its exact aliased spectrum + a white angle (quantization)
term, and scored by the mean |log residual| over the best 80 % of the bins (a tone or a
resonance band does not decide). Candidates within ``TIE`` x the score's estimation noise of
the best are equivalent for the record; among them the one needing the least white angle
term wins (a lag-1-only filter of too high a correlation can be pulled down by that term), then
the lowest rate and the fewest taps. The lag-1 correlation of the
record and of the chosen filter are both noted. When the best candidate does not beat no
filter by ``SCORE_GAIN`` (relative), or its lag-1 correlation is below ``RHO_MIN``, the record
shows no smoothing and ``none`` is used, with a note.

The Allan variance depends on the filter only through the output autocorrelation, so filters
with the same autocorrelation (a 12-point boxcar at 8 x and a 3-point one at 2 x both give a
lag-1 correlation of 1/3) are the same to the fit: ``auto`` names the simplest; pin the rate
(``auto@8x``) to get the taps at a known internal rate.
"""
from dataclasses import dataclass
import re
from typing import Dict, List, Optional, Tuple

from gyro_char.allan.expected import (autocorrelation, decimated_autocov,
                                      moving_average_kernel, white_avar_unit)
from gyro_char.errors import InputError
import numpy as np
from scipy import optimize, signal

STAGES = {'boxcar': 1, 'bartlett': 2}
RATES = (1, 2, 4, 8, 16)
SEGMENT = 256
F_LOW = 0.02  # cycles per sample: bins below are left to flicker / random walk
TRIM = 0.2
TIE = 0.1
SCORE_GAIN = 0.25
MAX_RATE = 64  # largest internal rate multiple accepted
RHO_MIN = 0.02
MIN_SAMPLES = 16 * SEGMENT


@dataclass(frozen=True)
class SensorFilter:
    """A moving-average filter at ``decimation`` x the output rate, then decimation."""

    kind: str         # 'boxcar' or 'bartlett'
    taps: int
    decimation: int = 1

    @property
    def label(self) -> str:
        return f'{self.kind}:{self.taps}@{self.decimation}x'

    def kernel(self) -> np.ndarray:
        """Return the impulse response at the internal rate (unit DC gain)."""
        return moving_average_kernel(self.taps, STAGES[self.kind])

    def rho(self, lags: int = 1) -> np.ndarray:
        """Return the output's autocorrelation at lags 0..``lags`` for white input."""
        return autocorrelation(self.kernel(), self.decimation, lags)

    def white_avar(self, tau, dt: float) -> np.ndarray:
        """Return sigma^2(tau) / N^2 of white noise N through the filter (exact, aliased)."""
        tau = np.asarray(tau, dtype=np.float64)
        m = np.maximum(np.round(tau / dt), 1.0)
        return white_avar_unit(self.kernel(), self.decimation, m) / tau

    def to_json(self) -> dict:
        return {'kind': self.kind, 'taps': self.taps, 'internal_rate_x': self.decimation,
                'lag1_correlation': float(self.rho(1)[1])}


@dataclass(frozen=True)
class FilterSpec:
    """A parsed ``--sensor-filter``: ``mode`` 'none', 'fixed' (``sensor_filter``) or 'auto'."""

    mode: str
    sensor_filter: Optional[SensorFilter] = None
    decimation: Optional[int] = None  # 'auto@RATE': the internal rate pinned
    rate_hz: Optional[float] = None   # RATE given in Hz: turned into a multiple per record


_SPEC = re.compile(r'^(none|auto|boxcar|bartlett)(?::(\d+))?(?:@([0-9.]+)(x|hz)?)?$')


def parse_spec(text) -> FilterSpec:
    """
    Parse ``none``, ``auto[@RATE]``, ``boxcar:TAPS[@RATE]`` or ``bartlett:TAPS[@RATE]``.

    A ``FilterSpec`` is returned as it is. Raises InputError with the accepted forms.
    """
    if isinstance(text, FilterSpec):
        return text
    spec = (text or 'none').strip().lower()
    match = _SPEC.match(spec)
    if not match:
        raise InputError(f'sensor filter {text!r}: expected none, auto[@RATE], '
                         'boxcar:TAPS[@RATE] or bartlett:TAPS[@RATE] (RATE: 8x or Hz)')
    kind, taps, rate, unit = match.groups()
    if kind == 'none':
        if taps or rate:
            raise InputError(f'sensor filter {text!r}: none takes no taps or rate')
        return FilterSpec('none')
    if (kind == 'auto') == (taps is not None):
        raise InputError(f'sensor filter {text!r}: ' + (
            'auto takes no taps' if kind == 'auto' else f'{kind} needs TAPS (e.g. {kind}:7)'))
    dec, hz = 1, None
    if rate is not None:
        try:
            value = float(rate)
        except ValueError:
            raise InputError(f'sensor filter {text!r}: bad rate {rate!r}') from None
        if unit == 'x' or unit is None and value == int(value) and value <= 64:
            if not 1 <= value <= MAX_RATE or value != int(value):
                raise InputError(f'sensor filter {text!r}: the rate multiple must be a whole '
                                 f'number from 1 to {MAX_RATE}')
            dec = int(value)
        else:
            if not value > 0:
                raise InputError(f'sensor filter {text!r}: the rate must be > 0 Hz')
            hz = value
    if kind == 'auto':
        return FilterSpec('auto', decimation=dec if rate is not None else None, rate_hz=hz)
    if int(taps) < 1:
        raise InputError(f'sensor filter {text!r}: TAPS must be >= 1')
    return FilterSpec('fixed', SensorFilter(kind, int(taps), dec), rate_hz=hz)


def candidates(decimations=RATES) -> List[SensorFilter]:
    """Return every filter of the ``auto`` search, one per distinct output autocorrelation."""
    seen, out = set(), []
    for d in decimations:
        for kind in STAGES:
            for taps in range(2, max(4 * d, 16) + 1):
                f = SensorFilter(kind, taps, d)
                r = decimated_autocov(f.kernel(), d)
                if r.size < 2:  # no longer than the decimation: output samples uncorrelated
                    continue
                key = tuple(np.round(r / r[0], 9))
                if key not in seen:
                    seen.add(key)
                    out.append(f)
    return out


def _spectrum(f: Optional[SensorFilter], freq: np.ndarray) -> np.ndarray:
    if f is None:
        return np.ones_like(freq)
    r = decimated_autocov(f.kernel(), f.decimation)
    r = r / r[0]
    k = np.arange(1, r.size)
    return r[0] + 2.0 * np.cos(2.0 * np.pi * np.outer(freq, k)) @ r[1:]


def _score(freq, psd, shape) -> Tuple[float, float]:
    """Return (trimmed mean |log residual|, share of the white angle term) of one shape."""
    cols = np.column_stack([shape, np.sin(np.pi * freq) ** 2])
    z = optimize.nnls(cols / psd[:, None], np.ones_like(freq))[0]
    model = np.maximum(cols @ z, 1e-300)
    err = np.sort(np.abs(np.log(psd / model)))
    return (float(np.mean(err[:max(int((1.0 - TRIM) * err.size), 1)])),
            float(np.sum(cols[:, 1] * z[1]) / np.sum(model)))


def lag1(x: np.ndarray) -> float:
    """Return the lag-1 autocorrelation of ``x`` (mean removed)."""
    y = np.asarray(x, dtype=np.float64) - np.mean(x)
    den = float(np.dot(y, y))
    return float(np.dot(y[:-1], y[1:]) / den) if den > 0 else 0.0


def estimate(x: np.ndarray, decimation: Optional[int] = None
             ) -> Tuple[Optional[SensorFilter], str]:
    """
    Return (the filter ``auto`` finds in ``x``, or None for no smoothing; a one-line note).

    ``decimation`` pins the internal rate (``auto@RATE``); otherwise every rate is tried.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.size < MIN_SAMPLES:
        return None, (f'{x.size} samples are too few to estimate a filter (need '
                      f'{MIN_SAMPLES}); none used')
    freq, psd = signal.welch(x, fs=1.0, nperseg=SEGMENT, detrend='constant')
    keep = (freq >= F_LOW) & (psd > 0)
    freq, psd = freq[keep], psd[keep]
    rho1 = lag1(x)
    cands = candidates(RATES if decimation is None else (int(decimation),))
    scored = [_score(freq, psd, _spectrum(c, freq)) for c in cands]
    none_score = _score(freq, psd, _spectrum(None, freq))[0]
    best = min(s for s, _ in scored)
    # Estimation noise of the score: sd of a log Welch bin ~ 1 / sqrt(segments).
    tol = TIE * np.sqrt(2.0 / np.pi) / np.sqrt(2.0 * x.size / SEGMENT)
    tied = [(q, c) for c, (s, q) in zip(cands, scored) if s <= best + tol]
    choice = min(tied, key=lambda v: (round(v[0], 3), v[1].decimation, v[1].taps))[1]
    if (rho1 < RHO_MIN or best > (1.0 - SCORE_GAIN) * none_score
            or choice.rho(1)[1] < RHO_MIN):
        return None, (f'the record shows no smoothing (lag-1 correlation {rho1:.3f}); '
                      'none used')
    return choice, (f'{choice.label} (lag-1 correlation: record {rho1:.3f}, filter '
                    f'{choice.rho(1)[1]:.3f}; {len(tied)} equivalent candidate(s))')


@dataclass(frozen=True)
class FilterChoice:
    """The filter used for one channel (None: none), where it came from and a note."""

    sensor_filter: Optional[SensorFilter]
    source: str  # 'none' (not asked), 'user' (given), 'auto' (estimated; filter None: none)
    note: str = ''

    def to_json(self) -> dict:
        """Return noise.json's ``sensor_filter`` field of a channel."""
        if self.sensor_filter is None:
            return {'kind': 'none', 'source': self.source, 'note': self.note}
        out = self.sensor_filter.to_json()
        out.update(source=self.source, note=self.note)
        return out


def _multiple(rate_hz: float, dt: float) -> int:
    """Return the internal rate in Hz as a whole multiple of the output rate 1 / dt."""
    dec = max(int(round(rate_hz * dt)), 1)
    if dec > MAX_RATE:
        raise InputError(f'sensor filter: internal rate {rate_hz:g} Hz is {rate_hz * dt:.4g} x '
                         f'the output rate; at most {MAX_RATE} x is accepted')
    return dec


def _fixed(spec: FilterSpec, dt: float) -> FilterChoice:
    f = spec.sensor_filter
    if spec.rate_hz is not None:
        f = SensorFilter(f.kind, f.taps, _multiple(spec.rate_hz, dt))
    return FilterChoice(f, 'user', f'{f.label} (given)')


def resolve(spec, x: np.ndarray, dt: float) -> FilterChoice:
    """Return the filter of one channel's record ``x`` (sample interval ``dt``) for ``spec``."""
    spec = parse_spec(spec)
    if spec.mode == 'none':
        return FilterChoice(None, 'none')
    if spec.mode == 'fixed':
        return _fixed(spec, dt)
    dec = spec.decimation
    if spec.rate_hz is not None:
        dec = _multiple(spec.rate_hz, dt)
    found, note = estimate(x, dec)
    return FilterChoice(found, 'auto', f'auto: {note}')


def filter_choices(res, spec=None) -> Dict[str, FilterChoice]:
    """
    Return {channel: FilterChoice} for the fit of an ``AllanResult``.

    ``spec`` None: the choices ``compute`` resolved from the samples (``res.sensor_filters``),
    none when absent. A spec string applies to every channel; ``auto`` needs the samples and
    is refused here (ValueError).
    """
    if spec is None:
        return dict(getattr(res, 'sensor_filters', None) or {})
    spec = parse_spec(spec)
    if spec.mode == 'auto':
        raise ValueError('sensor filter auto needs the samples: resolve it with '
                         'gyro_char.allan.compute.compute(sensor_filter=...)')
    if spec.mode == 'none':
        return {}
    return {name: _fixed(spec, res.dt) for name in res.channels}
