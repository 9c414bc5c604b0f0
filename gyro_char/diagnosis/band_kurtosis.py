"""
Excess kurtosis of a record in frequency bands: a narrow-band excess random, or a line.

Every noise of the static catalogue is Gaussian once band-passed away from 0 Hz (the band's
samples sum many input samples), a structural mode excited by broadband noise
(``resonance``) included: excess kurtosis 0. A machine's vibration is a line of constant
amplitude: a sinusoid of random phase has excess kurtosis -3/2, and a band of total power
P holding Gaussian noise and independent lines of powers P_i has
    kappa = -1.5 * sum(P_i^2) / P^2,
whatever the lines' frequencies. A wandering or beating tone spreads its power in the
spectrum like a mode, but keeps a steady envelope; the fourth moment tells the two apart
(``vibration``'s ``wander_hz``: a share q of its power in a band adds (1.5 q - 3 q^2) P^2 to
the band's fourth cumulant, exact for slow wander).
Not modelled: ``stale_samples``' holds, a random map whose output is a Gaussian scale
mixture with a positive excess kurtosis (+0.3 near Nyquist at p = 0.3, isolated holds), and
an angle read once a frame (``quantization:frame``), whose error falls on one sample in M at
a fixed phase (a coarse 10-sample frame: +2.6 to +3.2 in 5 Hz bands at 100 Hz, -0.6 to +0.6
at 333 Hz); the expectation stays the Gaussian one there, and a departing band says so.

It is a check beside the gap, not a block of it (``non_gaussian_bands``): scored as a block
it named no blind shape better and made the gaps of non-Gaussian shapes unexplainable
(docs/validation.md, session 16). Where a band departs from the selected model's
expectation, ``diagnosis.json`` says so.

Per band (the ``tone`` block's equal-width bands above the first, which holds the slow
terms), the band's FFT bins of the detrended record are moved to [1/4, 1/2) cycles/sample
of a signal four samples long per bin - the band signal at four times its width, the same
signal up to its carrier - and its sample excess kurtosis m4 / m2^2 - 3 is taken there.

Spread: the delta method on (m2, m4) with the Gaussian part expanded in Hermite
polynomials; the cross terms with a line follow its harmonics (one line of the band's whole
line power at the strongest line's frequency stands for all of them). Gaussian alone this is
24 sum_k rho(k)^4 / n'.
"""
from math import factorial
from typing import Sequence, Tuple

from gyro_char.diagnosis import observables as obs, wander
import numpy as np

LAGS = 4096        # lag grid of the band's autocorrelation (periodic; rho falls as 1 / k)
THETA = 16         # phase samples of a line's harmonics (exact up to the 8th)
POINTS = 512       # PSD samples across a band
# A band is reported when it departs from the model by this many standard deviations and by
# this much excess kurtosis (a 2 h record's sd is ~0.015: rounding leaves a few hundredths).
REPORT_Z = 6.0
REPORT_EXCESS = 0.1
# Relative spread taken for a wandering tone's kurtosis term (its share of a band varies with
# the time the frequency spends there): where it stays, where it only visits.
ENVELOPE_REL = 0.03
VISIT_REL = 0.5


def band_ranges(n: int, dt: float) -> np.ndarray:
    """Return the kurtosis bands (Hz): the tone block's bands without the lowest one."""
    return np.asarray(obs.static_layout(n, dt).ranges['tone'], dtype=float)[1:]


def _band_bins(n: int, dt: float, lo: float, hi: float) -> Tuple[int, int]:
    df = 1.0 / (n * dt)
    return int(np.ceil(lo / df)), min(int(np.ceil(hi / df)), n // 2)


def record_kurtosis(x: np.ndarray, dt: float, ranges: np.ndarray) -> np.ndarray:
    """Excess kurtosis of the detrended record ``x`` in each band of ``ranges`` (Hz)."""
    n = x.size
    spec = np.fft.rfft(x)
    out = np.zeros(len(ranges))
    for i, (lo, hi) in enumerate(ranges):
        a, b = _band_bins(n, dt, lo, hi)
        m = b - a
        if m < 8:
            continue
        moved = np.zeros(2 * m + 1, dtype=complex)
        moved[m:2 * m] = spec[a:b]
        y = np.fft.irfft(moved, 4 * m)
        y2 = y * y
        m2 = float(np.mean(y2))
        if m2 > 0.0:
            out[i] = float(np.mean(y2 * y2)) / (m2 * m2) - 3.0
    return out


def _band_models(spec, ranges) -> list:
    """
    Per band: the Gaussian part (PSD, power), the lines, the wandering tones.

    The wandering tones (``spec.envelopes``): their power in the band, their fourth cumulant
    there and its spread.
    """
    ranges = np.asarray(ranges, dtype=float)
    u = (np.arange(POINTS) + 0.5) / POINTS
    f = ranges[:, :1] + u * (ranges[:, 1:] - ranges[:, :1])
    envelopes = spec.envelopes
    parts = None
    if envelopes:
        skip = {e[4] for e in envelopes}
        parts = [i for i in range(len(spec.internal)) if i not in skip]
    s = np.maximum(spec.one_sided(f.ravel(), parts), 0.0).reshape(f.shape)
    out = []
    for (lo, hi), row in zip(ranges, s):
        inside = [(f0, p) for f0, p in spec.lines if lo <= f0 < hi and p > 0.0]
        # A wandering tone has a share q of its power in the band. Slow wander (beta > 1):
        # there a share q of the time, its band signal the tone or nothing, fourth cumulant
        # (1.5 q - 3 q^2) P^2 (negative where it stays, positive where it visits). Fast
        # wander: a Lorentzian line whose tails are noise-like, -1.5 q^2 P^2. The spread
        # taken is ENVELOPE_REL of the term where it stays, VISIT_REL where it visits (the
        # band edge's transition makes the visit term approximate; neither derived).
        env_power, env_c4, env_sd = 0.0, 0.0, 0.0
        for f0, power, w, tau, _ in envelopes:
            q = min(max(wander.band_share(lo, hi, f0, w, tau), 0.0), 1.0)
            slow = (2.0 * np.pi * w * tau) ** 2 > 1.0
            c4 = ((1.5 * q - 3.0 * q * q) if slow else -1.5 * q * q) * power * power
            env_power += q * power
            env_c4 += c4
            env_sd += (ENVELOPE_REL if q >= 0.5 else VISIT_REL) * abs(c4)
        out.append((row, float(row.mean()) * (hi - lo), np.array([p for _, p in inside]),
                    [f0 for f0, _ in inside], env_power, env_c4, env_sd))
    return out


def _moved_rho(shape: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Autocorrelation of the moved band signal, and its two-sided density on ``LAGS`` bins."""
    nu = np.arange(LAGS) / LAGS
    dens = np.zeros(LAGS)
    up = (nu >= 0.25) & (nu < 0.5)
    u = (nu[up] - 0.25) * 4.0 * shape.size
    dens[up] = np.interp(u, np.arange(shape.size) + 0.5, shape)
    dens = dens + np.roll(dens[::-1], 1)           # the mirror image at 1 - nu
    dens /= max(dens.sum(), 1e-300) / LAGS        # integrates to 1 over a cycle
    rho = np.real(np.fft.ifft(dens))
    return rho / max(rho[0], 1e-300), dens


def _hermite_coefficients(a: float, b: float) -> list:
    """Return the Fourier coefficients (line phase) of the linearised kappa's Hermite terms."""
    s = a + b
    c = 2.0 * (3.0 * s * s - 1.5 * b * b) / s ** 3
    t = np.sqrt(2.0 * b) * np.cos(2.0 * np.pi * np.arange(THETA) / THETA)
    ra = np.sqrt(a)
    h = [(4.0 * ra * t ** 3 + 12.0 * a * ra * t) / s ** 2 - 2.0 * c * t * ra,
         (6.0 * a * t * t + 6.0 * a * a) / s ** 2 - c * a,
         4.0 * t * a * ra / s ** 2,
         np.full(THETA, a * a / s ** 2)]
    return [np.fft.fft(hm) / THETA for hm in h]


def _band_sd(shape, p_g: float, powers: np.ndarray, where, lo: float, hi: float,
             m: int) -> float:
    """Return the standard deviation of one band's sample excess kurtosis (``m`` FFT bins)."""
    if p_g <= 0.0:
        return 0.0
    rho, dens = _moved_rho(shape / max(float(np.mean(shape)), 1e-300))
    b_pow = float(powers.sum())
    f0 = where[int(np.argmax(powers))] if powers.size else 0.5 * (lo + hi)
    nu0 = 0.25 + 0.25 * (f0 - lo) / (hi - lo)
    k = np.fft.fftfreq(LAGS, 1.0 / LAGS)
    var = 0.0
    for order, coef in enumerate(_hermite_coefficients(p_g, b_pow), start=1):
        for p in range(-THETA // 2 + 1, THETA // 2):
            w = abs(coef[p % THETA]) ** 2
            if w < 1e-30:
                continue
            if order == 1:      # sum_k rho(k) e^{i p w0 k}: the density at p nu0
                ssum = np.interp((p * nu0) % 1.0, np.arange(LAGS) / LAGS, dens, period=1.0)
            else:
                ssum = float(np.sum(rho ** order * np.cos(2.0 * np.pi * p * nu0 * k)))
            var += factorial(order) * w * ssum
    return float(np.sqrt(max(var, 0.0) / (4 * m)))


def expected_kurtosis(spec, n: int, dt: float, ranges: Sequence,
                      spread: bool = False):
    """
    Return the expected excess kurtosis per band of an ``n``-sample twin of ``spec``.

    With ``spread``, return (mean, standard deviation).
    """
    mean, sd = np.zeros(len(ranges)), np.zeros(len(ranges))
    for i, ((lo, hi), (shape, p_g, powers, where, env_power, env_c4, env_sd)) in enumerate(
            zip(ranges, _band_models(spec, ranges))):
        a, b = _band_bins(n, dt, lo, hi)
        total = p_g + float(powers.sum()) + env_power
        if b - a < 8 or total <= 0.0:
            continue
        env = env_c4 / (total * total)
        mean[i] = -1.5 * float(np.sum(powers ** 2)) / (total * total) + env
        if spread:
            sd[i] = float(np.hypot(_band_sd(shape, p_g, powers, where, lo, hi, b - a),
                                   env_sd / (total * total)))
    return (mean, sd) if spread else mean


def steady_envelope(y: np.ndarray, dt: float, f0: float, spec) -> bool:
    """
    Whether the record's band holding ``f0`` Hz has a steadier envelope than ``spec`` makes.

    ``y``: the detrended record (``observables.detrend``). Its excess kurtosis below the
    model's (the baseline's: Gaussian) by REPORT_Z standard deviations and REPORT_EXCESS: a
    line or a wandering tone, not noise.
    """
    ranges = band_ranges(y.size, dt)
    inside = np.flatnonzero((ranges[:, 0] <= f0) & (f0 < ranges[:, 1]))
    if not inside.size:
        return False
    band = ranges[inside[:1]]
    got = record_kurtosis(y, dt, band)[0]
    mean, sd = expected_kurtosis(spec, y.size, dt, band, spread=True)
    return bool(got - mean[0] < -max(REPORT_Z * sd[0], REPORT_EXCESS))


def non_gaussian_bands(x: np.ndarray, dt: float, spec) -> list:
    """
    Bands where the record's excess kurtosis departs from the model ``spec``'s expectation.

    ``x``: the record (rad/s, detrended here). Each entry: the band (Hz), the record's excess
    kurtosis, the model's and its standard deviation, and what a departure of that sign means.
    """
    x = obs.detrend(np.asarray(x, dtype=np.float64))
    ranges = band_ranges(x.size, dt)
    got = record_kurtosis(x, dt, ranges)
    mean, sd = expected_kurtosis(spec, x.size, dt, ranges, spread=True)
    out = []
    for (lo, hi), k, m, s in zip(ranges, got, mean, sd):
        if abs(k - m) < max(REPORT_Z * s, REPORT_EXCESS):
            continue
        meaning = ('heavier tails than the model: power that comes and goes (bursts, knocks, '
                   'a machine switching on and off), which no catalogue effect makes'
                   if k > m else
                   'a steadier envelope than the model: a line of constant amplitude (a '
                   'machine, a self-oscillation) where the model has noise')
        if spec.holds is not None or spec.framed:
            meaning += ('; or the holds or the read-out once a frame of the selected model, '
                        'which are not Gaussian either (their kurtosis is not modelled)')
        out.append({'range_hz': [float(lo), float(hi)], 'excess_kurtosis': float(k),
                    'model': float(m), 'model_sd': float(s), 'meaning': meaning})
    return out
