"""
Vibration effects: a tone or a comb of lines (deterministic), a structural mode (random).

``vibration_lines`` defines a vibration's lines once, for the simulator and for the closed-form
spectra of the diagnosis. Axis-selecting parameters as in ``sensor`` (``base.axis_rows``).
"""
from gyro_char.errors import InputError
from gyro_char.sim.effects.base import axis_param, axis_rows, describe_without, Effect, register
from gyro_char.units import DEG
import numpy as np
from scipy import signal


# Comb lines kept: down to this share of the centre line's power, at most this many a side.
COMB_FLOOR = 1e-3
COMB_SIDE = 200
# Correlation time (s) of a tone's frequency wander where none is given.
WANDER_S = 10.0
# Tones in all: freq_hz and the unrelated freq2_hz ... freq<TONES>_hz (other machines, a
# belt's second shaft, the sum and difference lines a nonlinear mount makes of two shafts, a
# forest of fans at fixed speeds). Tones beyond the first SHOWN are left out of describe()
# where absent (earlier truth.json files).
TONES = 32
SHOWN = 6


def vibration_lines(params: dict, f_max: float = np.inf) -> list:
    """
    Return a vibration's lines as (frequency, amplitude) pairs (simulator and closed form).

    ``params`` as ``Vibration.PARAMS``. ``spacing_hz`` 0: the tone at freq_hz. Otherwise a
    comb: lines at freq_hz + k spacing_hz (0 < f < ``f_max``) whose power falls off as a
    Lorentzian of half width ``width_hz`` about the centre line: what a periodic,
    non-sinusoidal disturbance makes (a knock or kick every 1 / spacing_hz seconds, a gear mesh
    with shaft run-out sidebands, a frequency-modulated drive), the envelope being the response
    that shapes each event. Plus the unrelated tones ``freq2_hz`` ... (``TONES`` in all: other
    machines, intermodulation lines), where their amplitudes are not 0.
    """
    freq, amplitude = params['freq_hz'], params['amplitude']
    spacing, width = params.get('spacing_hz', 0.0), params.get('width_hz', 1.0)
    if spacing <= 0.0 or width <= 0.0:
        lines = [(freq, amplitude)]
    else:
        side = int(min(COMB_SIDE, np.ceil(width / spacing / np.sqrt(COMB_FLOOR))))
        k = np.arange(-side, side + 1)
        f = freq + k * spacing
        a = amplitude / np.sqrt(1.0 + (k * spacing / width) ** 2)
        keep = (f > 0.0) & (f < f_max)
        lines = list(zip(f[keep].tolist(), a[keep].tolist()))
    for j in range(2, TONES + 1):
        f, a = params.get(f'freq{j}_hz', 0.0), params.get(f'amplitude{j}', 0.0)
        if f > 0.0 and a != 0.0 and f < f_max:
            lines.append((f, a))
    return lines


@register
class Vibration(Effect):
    """A sinusoidal tone in the gyro output, or a comb of lines (a periodic disturbance)."""

    name = 'vibration'
    summary = ('sinusoidal tone on gyro axes (e.g. the ADIS16405 Z-gyro tone near 17-21 Hz), '
               'or a comb of lines spacing_hz apart around it')
    physics = ('rate += amplitude sin(2 pi freq_hz t + phase), phase uniform random: a PSD '
               'line of power amplitude^2 / 2 at freq_hz (aliased if above Nyquist of the '
               'internal rate); Allan deviation oscillating below ~1/freq_hz. With spacing_hz '
               '> 0, a periodic non-sinusoidal disturbance: lines at freq_hz + k spacing_hz, '
               'each of its own random phase, power amplitude^2 / 2 / (1 + (k spacing_hz / '
               'width_hz)^2) (knocks, kicks, gear-mesh sidebands, a frequency-modulated drive). '
               'freq2_hz ... freq32_hz: further tones of their own amplitudes (other machines, '
               'intermodulation lines, a forest of fans). '
               'wander_hz > 0 (one tone): a machine whose speed is not held, the frequency '
               'freq_hz + wander_hz u(t), u a unit Gauss-Markov process of correlation time '
               "wander_s: the power spreads over a band (the frequency's own law when slow, a "
               'Lorentzian line when fast), the envelope stays constant.')
    PARAMS = {'freq_hz': (19.0, 'Hz', "tone frequency (the comb's centre line)"),
              'amplitude': (0.05 * DEG, 'rad/s', "tone amplitude (the centre line's)"),
              'spacing_hz': (0.0, 'Hz', 'comb line spacing; 0 = one tone'),
              'width_hz': (1.0, 'Hz', "half width of the comb's Lorentzian power envelope"),
              'wander_hz': (0.0, 'Hz', "rms wander of the tone's frequency (0 = held)"),
              'wander_s': (WANDER_S, 's', "correlation time of the frequency's wander"),
              **{key: entry for j in range(2, TONES + 1) for key, entry in (
                  (f'freq{j}_hz', (0.0, 'Hz', f'unrelated tone {j} (0 = none)')),
                  (f'amplitude{j}', (0.0, 'rad/s', f'tone {j} amplitude')))},
              'axis': axis_param(2.0)}

    def check(self):
        axis_rows(self)
        if self.freq_hz <= 0:
            raise InputError('vibration: freq_hz must be > 0')
        if (self.spacing_hz < 0 or self.width_hz <= 0
                or any(self.params[f'freq{j}_hz'] < 0 for j in range(2, TONES + 1))):
            raise InputError('vibration: spacing_hz and the further tones freq2_hz ... >= 0, '
                             'width_hz > 0')
        if self.wander_hz < 0 or self.wander_s <= 0:
            raise InputError('vibration: wander_hz >= 0 and wander_s > 0')
        if self.wander_hz > 0 and self.spacing_hz > 0:
            raise InputError('vibration: wander_hz applies to one tone, not to a comb '
                             '(spacing_hz > 0)')

    def describe(self):
        return describe_without(self, *(key for j in range(SHOWN + 1, TONES + 1)
                                        for key in (f'freq{j}_hz', f'amplitude{j}')))

    def lines(self, f_max: float = np.inf) -> list:
        """Return this vibration's (frequency, amplitude) lines below ``f_max``."""
        return vibration_lines(self.params, f_max)

    def sensor(self, ctx, gyro, accel):
        lines = self.lines()
        phases = self.rng(ctx).uniform(0.0, 2.0 * np.pi, len(lines))
        tone = np.zeros(ctx.t.size)
        for k, ((f, a), phase) in enumerate(zip(lines, phases)):
            if k == 0 and self.wander_hz > 0:
                phase = phase + self._wander_phase(ctx)
            tone += a * np.sin(2.0 * np.pi * f * ctx.t + phase)
        gyro = gyro.copy()
        for r in axis_rows(self):
            gyro[r] += tone
        return gyro, accel

    def _wander_phase(self, ctx) -> np.ndarray:
        """Phase added by the frequency's Gauss-Markov wander (stationary from the start)."""
        dt = ctx.dt_internal
        a = np.exp(-dt / self.wander_s)
        rng = ctx.rng(f'effect:{self.name}:{self.index}:wander')
        e = np.sqrt(1.0 - a * a) * rng.standard_normal(ctx.t.size)
        u0 = rng.standard_normal()
        u, _ = signal.lfilter([1.0], [1.0, -a], e, zi=[a * u0])
        # The phase is the integral of the frequency (trapezoid between samples).
        f = self.wander_hz * u
        return 2.0 * np.pi * np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * dt)])


def resonance_coefficients(freq_hz: float, q: float, dt: float):
    """
    AR(2) coefficients of a resonance and its innovation variance for unit output variance.

    x_k = a1 x_(k-1) + a2 x_(k-2) + e_k with poles r exp(+-i 2 pi f0 dt), r = exp(-pi f0 dt / Q):
    white noise through a second-order resonator of centre f0 and -3 dB bandwidth f0 / Q.
    Returns (a1, a2, var_e), var_e giving a stationary variance of 1.
    """
    theta = 2.0 * np.pi * freq_hz * dt
    r = np.exp(-np.pi * freq_hz * dt / q)
    a1, a2 = 2.0 * r * np.cos(theta), -r * r
    # gamma0 = (1 - a2) / ((1 + a2) ((1 - a2)^2 - a1^2)), in forms without cancellation for
    # poles near the unit circle: 1 + a2 = 1 - r^2, (1 + r^2)^2 - 4 r^2 cos^2 = (1 - r^2)^2 +
    # 4 r^2 sin^2.
    one_minus_r2 = -np.expm1(-2.0 * np.pi * freq_hz * dt / q)
    gamma0 = (1.0 + r * r) / (one_minus_r2 * (one_minus_r2 ** 2
                                              + 4.0 * r * r * np.sin(theta) ** 2))
    return float(a1), float(a2), float(1.0 / gamma0)


def resonant_noise(rng: np.random.Generator, n: int, freq_hz: float, q: float,
                   dt: float) -> np.ndarray:
    """Return n samples of the unit-variance AR(2) resonance, stationary from the first."""
    a1, a2, var_e = resonance_coefficients(freq_hz, q, dt)
    chol = np.linalg.cholesky(np.array([[1.0, a1 / (1.0 - a2)], [a1 / (1.0 - a2), 1.0]]))
    y1, y2 = chol @ rng.standard_normal(2)       # x_(-1), x_(-2), stationary
    e = np.sqrt(var_e) * rng.standard_normal(n)
    zi = signal.lfiltic([1.0], [1.0, -a1, -a2], y=[y1, y2])
    return signal.lfilter([1.0], [1.0, -a1, -a2], e, zi=zi)[0]


@register
class Resonance(Effect):
    """Band-limited rate noise around a frequency: a structural mode excited by broadband noise."""

    name = 'resonance'
    summary = 'band-limited noise around freq_hz with quality factor q (a structural mode)'
    physics = ('A lightly damped mode (mount, package, the sense element itself) driven by '
               'broadband disturbances: white noise through a second-order resonator, '
               'x_k = a1 x_(k-1) + a2 x_(k-2) + e_k with poles r exp(+-i 2 pi f0 dt), '
               'r = exp(-pi f0 dt / q), at the internal rate, scaled to standard deviation '
               'sigma and stationary from the first sample. PSD: a peak of -3 dB width '
               'f0 / q (a pure tone is the limit q -> infinity, a wide bump q ~ 1); its '
               'phase wanders, so unlike ``vibration`` its line broadens with record length '
               'no further than f0 / q.')
    PARAMS = {'sigma': (0.05 * DEG, 'rad/s', 'stationary standard deviation'),
              'freq_hz': (20.0, 'Hz', 'centre frequency f0'),
              'q': (20.0, '-', 'quality factor: f0 / (-3 dB bandwidth)'),
              'axis': axis_param(2.0)}

    def check(self):
        axis_rows(self)
        if self.sigma < 0 or self.freq_hz <= 0 or self.q < 0.5:
            raise InputError('resonance: sigma >= 0, freq_hz > 0 and q >= 0.5')

    def sensor(self, ctx, gyro, accel):
        if self.freq_hz >= 0.5 / ctx.dt_internal:
            raise InputError(f'resonance: freq_hz {self.freq_hz:g} is at or above the internal '
                             f'Nyquist frequency {0.5 / ctx.dt_internal:g} Hz')
        rng = self.rng(ctx)
        gyro = gyro.copy()
        for r in axis_rows(self):
            gyro[r] += self.sigma * resonant_noise(rng, gyro.shape[1], self.freq_hz, self.q,
                                                   ctx.dt_internal)
        return gyro, accel
