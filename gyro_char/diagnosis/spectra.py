"""
Power spectral densities of the static twin, in closed form: baseline plus catalogue effects.

A static twin (``gyro_char.diagnosis.static``) is a linear, Gaussian chain except for the
output rounding: white rate noise and the noise effects are generated at the internal rate
``dt / D``, pass the sensor's smoothing filter ``h`` (``internal_lowpass``), are decimated by
``D``, then get the angle quantization (``quantization``) and the output step ``lsb``. Each
stage has an exact discrete-time PSD, so the twin's output PSD is

    S_out(f) = |G(f)|^2 sum_r |H(f + r fs)|^2 S_int(f + r fs) + S_q(f) + S_lsb(f),   r = 0..D-1

(decimation folds the D images of the internal band; two-sided, per Hz; G is the sensor's
output-rate filters, if any: low-pass, notch, mode-split response, interleaved memory, their
delay of a slow warm-up neglected). Tones are lines, folded the same way, but a tone whose
frequency wanders is a noise part (``wander``); a warm-up is a deterministic mean term.
Stale samples (an output sample repeating the previous one) act last, on the whole output
(``holds.Holds``; those a glitch gate selects: ``gate``). ``ModelSpectrum`` holds the result
for one model; every observable's expectation is a linear functional of it
(``gyro_char.diagnosis.expected``). The output step is taken as white
rounding noise (lsb^2 / 12 per sample, exact while the per-sample noise exceeds about half a
step; below, given the rate's mean, the exact excess of rounding the white noise: ``rounding``).
"""
from collections import OrderedDict
from dataclasses import dataclass, field
from functools import partial
import threading
from typing import Callable, List, Optional, Sequence, Tuple

from gyro_char.allan.expected import moving_average_kernel
from gyro_char.diagnosis import rounding, wander
from gyro_char.diagnosis.gate import hold_model
from gyro_char.diagnosis.holds import GRID
from gyro_char.sim.effects.base import cycle_terms, transient_terms
from gyro_char.sim.effects.readout import framed_error_psd
from gyro_char.sim.effects.responses import (interleaved_memory_gain2, output_lowpass_gain2,
                                             output_notch_gain2, sense_gain2)
from gyro_char.sim.effects.sensor import DEFAULT_PIVOT_HZ, pivot_scale
from gyro_char.sim.effects.vibration import resonance_coefficients, vibration_lines, WANDER_S
import numpy as np

# Effects whose static output has a closed form here.
CLOSED_FORM = ('internal_lowpass', 'bias_instability', 'rate_random_walk', 'gauss_markov',
               'quantization', 'temperature_drift', 'vibration', 'resonance', 'stale_samples')


# Every internal PSD is a function of s2 = sin^2(pi f dt_i) (cos 2 pi f dt_i = 1 - 2 s2), so
# ``ModelSpectrum.one_sided`` takes one sine per frequency image for all of them; the forms
# below keep the small-f factors in s2 (no 1 - cos cancellation).
def _ar1(sigma: float, tau_s: float, dt: float, order: int) -> Callable:
    a = np.exp(-dt / tau_s)

    def psd(s2):
        den = (1.0 - a) ** 2 + 4.0 * a * s2
        if order == 2:
            return sigma ** 2 * (1.0 - a * a) ** 3 / (1.0 + a * a) * dt / den ** 2
        return sigma ** 2 * (1.0 - a * a) * dt / den
    return psd


def _resonance(sigma: float, freq_hz: float, q: float, dt: float) -> Callable:
    _, _, var_e = resonance_coefficients(freq_hz, q, dt)
    half = np.pi * freq_hz * dt                  # theta0 / 2
    r = np.exp(-half / q)
    one_minus_r2 = (-np.expm1(-half / q)) ** 2
    ch, sh = np.cos(half), np.sin(half)

    def psd(s2):
        # |1 - a1 z - a2 z^2|^2 = |1 - r e^(i th0) z|^2 |1 - r e^(-i th0) z|^2, z = e^(-i w),
        # each (1 - r)^2 + 4 r sin^2((w -+ th0) / 2): no cancellation for poles near the unit
        # circle. The PSD is even and 2 pi periodic, so cos(w / 2) >= 0 may be taken.
        s, c = np.sqrt(s2), np.sqrt(np.maximum(1.0 - s2, 0.0))
        minus, plus = s * ch - c * sh, s * ch + c * sh
        den = (one_minus_r2 + 4.0 * r * minus * minus) * (one_minus_r2 + 4.0 * r * plus * plus)
        return sigma ** 2 * var_e * dt / den
    return psd


def _power_law(coef2: float, alpha: float, plain: float, pivot_hz: float, dt: float) -> Callable:
    # Kasdin-Walter 1/f^alpha of innovation variance coef2, scaled as the simulator scales it
    # (sensor.pivot_scale) to meet the plain term at the pivot: coef2 scale^2 dt (2 sin)^-alpha.
    if alpha == plain == 1.0:
        return lambda s2: coef2 * dt / (2.0 * np.sqrt(s2))
    if alpha == plain == 2.0:
        return lambda s2: coef2 * dt / (4.0 * s2)
    c = coef2 * pivot_scale(alpha, plain, pivot_hz, dt) ** 2 * dt
    return lambda s2: c * (4.0 * s2) ** (-0.5 * alpha)


def _flicker(b: float, corner_hz: float, dt: float, alpha: float = 1.0,
             pivot_hz: float = DEFAULT_PIVOT_HZ) -> Callable:
    # Kasdin-Walter 1/f^alpha; with an upper corner times the lowpass of noise_gen.flicker,
    # ((1 - c) / |1 - c e^(-i w)|)^alpha, c = exp(-2 pi corner dt): 1/f^(2 alpha) above the
    # corner (1/f^2 for the plain flicker).
    one_over_f = _power_law(b * b, alpha, 1.0, pivot_hz, dt)
    if not corner_hz:
        return one_over_f
    c = float(np.exp(-2.0 * np.pi * corner_hz * dt))

    def psd(s2):
        den = np.sqrt((1.0 - c) ** 2 + 4.0 * c * s2)
        return one_over_f(s2) * ((1.0 - c) / den) ** alpha
    return psd


def internal_psd(name: str, p: dict, dt_i: float) -> Optional[Callable]:
    """
    Two-sided PSD per Hz at the internal rate of one noise effect (None: not a noise).

    The callable takes s2 = sin^2(pi f dt_i) (floored at 1e-300), not f.
    """
    if name == 'bias_instability':
        return _flicker(p['B'], p.get('corner_hz', 0.0), dt_i, p.get('alpha', 1.0),
                        p.get('pivot_hz', DEFAULT_PIVOT_HZ))
    if name == 'rate_random_walk':
        return _power_law(p['K'] * p['K'] * dt_i, p.get('alpha', 2.0), 2.0,
                          p.get('pivot_hz', DEFAULT_PIVOT_HZ), dt_i)
    if name == 'gauss_markov':
        return _ar1(p['sigma'], p['tau_s'], dt_i, int(p.get('order', 1.0)))
    if name == 'resonance':
        return _resonance(p['sigma'], p['freq_hz'], p['q'], dt_i)
    return None


def fold(f, rate: float):
    """Frequency ``f`` folded into [0, rate / 2] by sampling at ``rate``."""
    g = np.mod(f, rate)
    return np.minimum(g, rate - g)


_IMAGES: 'OrderedDict[tuple, tuple]' = OrderedDict()
_IMAGES_LOCK = threading.Lock()
IMAGE_CACHE = 8         # grids whose images are kept (~10 MB each for the Allan grids)


@dataclass
class ModelSpectrum:
    """Output PSD of a static twin: continuous part, lines, deterministic mean term."""

    dt: float
    decimation: int
    taps: int                            # internal moving average: taps, cascaded stages
    stages: int
    white_int: float                     # two-sided white PSD at the internal rate
    internal: List[Callable] = field(default_factory=list)   # two-sided, internal rate
    output_white: float = 0.0            # two-sided white PSD added at the output
    angle_var: float = 0.0               # white angle error variance (rad^2), at the output
    # Angle errors read once a frame and held: their rate errors' two-sided PSDs at the output.
    framed: List[Callable] = field(default_factory=list)
    lines: List[Tuple[float, float]] = field(default_factory=list)  # (f_out, mean square)
    # (amplitude, tau_s, t0_s): a transient from power-on (t0 0) or from mid-record.
    warmups: List[Tuple[float, float, float]] = field(default_factory=list)
    # (amplitude, period, phase): a periodic cycle's sinusoids (``cycle_terms``), and their
    # envelope's (t0_s, rise_s) (``cycle_envelope``).
    cycles: List[Tuple[float, float, float]] = field(default_factory=list)
    cycle_onset: Tuple[float, float] = (0.0, 0.0)
    peaks: List[Tuple[float, float]] = field(default_factory=list)  # (f_out, width) to resolve
    holds: Optional[object] = None       # ``Holds`` or ``GateHolds``; ``lines`` then held
    unheld_lines: List[Tuple[float, float]] = field(default_factory=list)
    # Noise parts with a constant envelope (a wandering tone: a line's fourth moment, a
    # noise's spectrum; ``band_kurtosis``): (f_out, mean square, wander_hz, wander_s, index
    # in ``internal``).
    envelopes: List[tuple] = field(default_factory=list)
    # The output-rate filters (``internal_lowpass`` corner_hz, order; notch_hz, notch_q;
    # the mode-split sense response split_hz, sense_hz; memory, interleave): 0 for none.
    corner_hz: float = 0.0
    order: int = 0
    notch_hz: float = 0.0
    notch_q: float = 0.0
    split_hz: float = 0.0
    sense_hz: float = 0.0
    memory: float = 0.0                  # an interleaved front end's memory, and its L
    interleave: int = 2
    _hold_terms: dict = field(default_factory=dict, repr=False)

    def refine(self, nu: np.ndarray, points: int = 400) -> np.ndarray:
        """``nu`` (cycles per output sample, sorted) with dense points across every peak."""
        if not self.peaks:
            return nu
        extra = [nu]
        for f0, width in self.peaks:
            c, w = f0 * self.dt, width * self.dt
            d = np.linspace(max(c - 12 * w, nu[0]), min(c + 12 * w, nu[-1]), points)
            extra.append(d)
        return np.unique(np.concatenate(extra))

    @property
    def dt_i(self) -> float:
        return self.dt / self.decimation

    def h2(self, f: np.ndarray) -> np.ndarray:
        """|H(f)|^2 of the internal filter at internal-rate frequencies ``f``."""
        if self.taps <= 1:
            return np.ones(np.shape(f))
        x = np.pi * np.asarray(f, dtype=np.float64) * self.dt_i
        return self._h2(np.sin(x), np.sin(self.taps * x))

    def _h2(self, sin_x: np.ndarray, sin_tx: np.ndarray) -> np.ndarray:
        small = np.abs(sin_x) < 1e-12
        ratio = np.where(small, 1.0, sin_tx / (self.taps * np.where(small, 1.0, sin_x)))
        ratio = ratio * ratio
        out = ratio
        for _ in range(self.stages - 1):
            out = out * ratio
        return out

    @property
    def filtered(self) -> bool:
        """Whether an output-rate filter is set (``g2`` is not 1)."""
        return bool(self.corner_hz or self.notch_hz or self.split_hz or self.memory)

    def g2(self, f) -> np.ndarray:
        """|G(f)|^2 of the output-rate filters at output frequencies ``f``."""
        out = np.ones(np.shape(f))
        if self.corner_hz:
            out = out * output_lowpass_gain2(f, self.corner_hz, self.order, self.dt)
        if self.notch_hz:
            out = out * output_notch_gain2(f, self.notch_hz, self.notch_q, self.dt)
        if self.split_hz:
            out = out * sense_gain2(f, self.split_hz, self.sense_hz)
        if self.memory:
            out = out * interleaved_memory_gain2(f, self.memory, self.interleave, self.dt)
        return out

    def images(self, f: np.ndarray) -> tuple:
        """
        Per image r of the decimation: (sin^2(pi dt_i (f + r fs)), floored; |H|^2 there).

        Also 4 sin^2(pi f dt) / dt, the output-rate white angle error's shape. They depend on
        the grid and the filter only, not on the effects, so the last few grids' are kept
        (keyed by the grid's bytes); the sines of all the images come from one sine and
        cosine of the grid (x + pi r / D, by angle addition).
        """
        key = (self.taps, self.stages, self.decimation, self.dt, f.tobytes())
        with _IMAGES_LOCK:        # a Dask worker may run several diagnoses in threads
            hit = _IMAGES.get(key)
            if hit is not None:
                _IMAGES.move_to_end(key)
                return hit
        x = np.pi * self.dt_i * f
        sx, cx = np.sin(x), np.cos(x)
        if self.taps > 1:
            stx, ctx = np.sin(self.taps * x), np.cos(self.taps * x)
        out = []
        for r in range(self.decimation):
            b = np.pi * r / self.decimation
            s = sx * np.cos(b) + cx * np.sin(b) if r else sx
            if self.taps > 1:
                bt = self.taps * b
                h2 = self._h2(s, stx * np.cos(bt) + ctx * np.sin(bt) if r else stx)
            else:
                h2 = np.ones_like(f)
            out.append((np.maximum(s * s, 1e-300), h2))
        s_out = np.sin(np.pi * f * self.dt)
        hit = (out, 4.0 * s_out * s_out / self.dt)
        with _IMAGES_LOCK:
            _IMAGES[key] = hit
            while len(_IMAGES) > IMAGE_CACHE:
                _IMAGES.popitem(last=False)
        return hit

    def one_sided(self, f, parts: Optional[Sequence[int]] = None) -> np.ndarray:
        """
        One-sided output PSD (unit^2/Hz) at output frequencies ``f`` in (0, fs / 2].

        ``parts``: indices of ``internal`` to include (default all), plus the white parts;
        ``parts=()`` gives the white parts only. With holds, each part is held on its own (the
        map is linear); the lines' lost power joins the total (``parts`` None) only.
        """
        f = np.ascontiguousarray(f, dtype=np.float64)
        if self.holds is None:
            return self._unheld(f, parts)
        key = None if parts is None else tuple(parts)
        if key not in self._hold_terms:
            grid = self.refine(np.linspace(0.5 / GRID, 0.5, GRID)) / self.dt
            self._hold_terms[key] = self.holds.terms(
                grid, self._unheld(grid, parts), self.unheld_lines if parts is None else (),
                self.dt)
        return self.holds.apply(f, self._unheld(f, parts), self._hold_terms[key], self.dt)

    def _unheld(self, f: np.ndarray, parts) -> np.ndarray:
        total = np.zeros_like(f)
        sel = range(len(self.internal)) if parts is None else parts
        images, angle_shape = self.images(f)
        for s2, h2 in images:
            s = np.full_like(f, self.white_int)
            for i in sel:
                s += self.internal[i](s2)
            total += h2 * s
        if self.filtered:
            total *= self.g2(f)
        total += self.output_white
        if self.angle_var:
            total += self.angle_var * angle_shape
        for part in self.framed:
            total += part(f)
        return 2.0 * total

    @property
    def time_shift(self) -> float:
        """Where an output sample's mean term is taken: decimation phase less filter delay."""
        return (self.decimation - 1) * self.dt_i - 0.5 * (self.taps - 1) * self.stages * self.dt_i


def _add_wandering_tone(spec: ModelSpectrum, power: float, f0: float, wander_hz: float,
                        wander_s: float) -> None:
    """Add a tone of wandering frequency (``wander``) as a noise part, its envelope noted."""
    fs = 1.0 / spec.dt_i
    f_i = float(fold(f0, fs))

    def psd(s2):
        f = np.arcsin(np.sqrt(np.minimum(s2, 1.0))) / (np.pi * spec.dt_i)
        return (wander.tone_psd(f, power, f_i, wander_hz, wander_s)
                + wander.tone_psd(fs - f, power, f_i, wander_hz, wander_s))
    spec.internal.append(psd)
    f_out = float(fold(f_i, 1.0 / spec.dt))
    spec.peaks.append((f_out, wander.spread_hz(wander_hz, wander_s)))
    spec.envelopes.append((f_out, power * float(spec.h2(np.array([f_i]))[0] * spec.g2(f_out)),
                           wander_hz, wander_s, len(spec.internal) - 1))


def _rounding(n_white: float, lsb: float, dt: float, bias: Optional[float]) -> float:
    """
    Variance the output step adds per sample.

    The output's variance is kept above a tenth of the white noise's and a thousandth of
    lsb^2 / 12: a baseline that rounds to a constant (forced; ``fit_baseline`` gives no step
    to a record varying less than lsb^2 / 12) must not make every spread zero.
    """
    if bias is None:
        return lsb * lsb / 12.0
    sigma2 = n_white * n_white / dt
    return max(rounding.excess(sigma2, bias, lsb), -0.9 * sigma2,
               1e-3 * lsb * lsb / 12.0 - sigma2)


def model_spectrum(n_white: float, lsb: float, dt: float, effects: Sequence,
                   bias: Optional[float] = None) -> ModelSpectrum:
    """
    Return the output spectrum of a static twin: white rate noise N, output step, ``effects``.

    ``n_white`` is the baseline's N at the output (the twin scales the internal white noise by
    the filter's and the holds' long-tau gains so that the output keeps N). The step adds
    lsb^2 / 12 of white noise, or, given the rate's mean ``bias``, what rounding the white
    noise N^2 / dt there exactly adds (``rounding.excess``: differs only for a step coarser
    than 1.2 per-sample sd). Raises ValueError for an effect without a closed form (a motion
    or encoder effect).
    """
    decim, taps, stages, hold_params, corner, order = 1, 1, 1, None, 0.0, 0
    notch, split, memory = (0.0, 0.0), (0.0, 0.0), (0.0, 2)
    for name, p in effects:
        if name == 'internal_lowpass':
            decim = max(decim, int(p.get('decimation', 1.0)))
            taps, stages = int(p['taps']), int(p.get('stages', 2.0))
            corner, order = p.get('corner_hz', 0.0), int(p.get('order', 2.0))
            if p.get('notch_hz', 0.0):
                notch = (p['notch_hz'], p.get('notch_q', 5.0))
            if p.get('split_hz', 0.0):
                split = (p['split_hz'], p.get('sense_hz', 5.0))
            if p.get('memory', 0.0):
                memory = (p['memory'], int(p.get('interleave', 2.0)))
        elif name == 'stale_samples':
            hold_params = p
    h = moving_average_kernel(taps, stages)
    gain = float(np.sqrt(decim * np.sum([h[r::decim].sum() ** 2 for r in range(decim)])))
    holds = None if hold_params is None else hold_model(hold_params, n_white, dt, gain)
    if holds is not None:
        gain *= holds.gain()
    dt_i = dt / decim
    spec = ModelSpectrum(dt=dt, decimation=decim, taps=taps, stages=stages,
                         white_int=(n_white / gain) ** 2,
                         output_white=_rounding(n_white, lsb, dt, bias) * dt, corner_hz=corner,
                         order=order if corner else 0, notch_hz=notch[0], notch_q=notch[1],
                         split_hz=split[0], sense_hz=split[1], memory=memory[0],
                         interleave=memory[1])
    for name, p in effects:
        if name not in CLOSED_FORM:
            raise ValueError(f'effect {name} has no closed-form static spectrum')
        psd = internal_psd(name, p, dt_i)
        if psd is not None:
            spec.internal.append(psd)
            if name == 'resonance':
                spec.peaks.append((float(fold(p['freq_hz'], 1.0 / dt)),
                                   p['freq_hz'] / max(p['q'], 0.5)))
        elif name == 'quantization':
            frame = int(round(p.get('frame', 1.0)))
            if frame > 1:
                spec.framed.append(partial(framed_error_psd, step=p['step_rad'], frame=frame,
                                           dither=p.get('dither', 0.0), n_white=n_white,
                                           bias=bias or 0.0, dt=dt))
            else:
                spec.angle_var += p['step_rad'] ** 2 / (6.0 if p.get('dither', 0.0) else 12.0)
        elif name == 'vibration':
            lines = vibration_lines(p)
            if p.get('wander_hz', 0.0) > 0.0 and not p.get('spacing_hz', 0.0) > 0.0:
                (f0, a), lines = lines[0], lines[1:]
                _add_wandering_tone(spec, 0.5 * a * a, f0, p['wander_hz'],
                                    p.get('wander_s', WANDER_S))
                if not lines:
                    continue
            fa = fold(np.array([f for f, _ in lines]), 1.0 / dt_i)
            f_out = fold(fa, 1.0 / dt)
            power = 0.5 * np.array([a for _, a in lines]) ** 2 * spec.h2(fa) * spec.g2(f_out)
            spec.lines.extend(zip(f_out.tolist(), power.tolist()))
        elif name == 'temperature_drift' and p.get('cycle_s', 0.0) > 0.0:
            spec.cycles.extend(cycle_terms(p))
            spec.cycle_onset = (float(p.get('t0_s', 0.0)), float(p.get('rise_s', 0.0)))
        elif name == 'temperature_drift':
            for c, lag in transient_terms(p['amplitude'], p['tau_s'], p.get('rise_s', 0.0)):
                spec.warmups.append((c, lag, p.get('t0_s', 0.0)))
    if holds is not None:
        # Mean terms pass unchanged (a hold shifts a slow mean by p dt / (1 - p) of its slope).
        spec.holds, spec.unheld_lines = holds, list(spec.lines)
        spec.lines = [(f0, a * float(holds.g2(f0, dt))) for f0, a in spec.lines]
    return spec
