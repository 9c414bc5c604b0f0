"""
Sensor effects: smoothing, thermal transient, extra noise processes.

Axis-selecting parameters: ``axis`` -1 means all three gyro axes, 0/1/2 one of x/y/z
(``base.axis_rows``). Tones, combs and structural modes are in ``vibration``.
Effects that map exactly onto an IEEE 952 term (B, K, Q) add it, in quadrature, to the truth of
the channels they touch; ``internal_lowpass`` rescales truth N by its exact long-tau gain.
"""
# The kernel is the one the noise fit models (one definition): ``taps``-point averages cascaded.
from gyro_char.allan.expected import moving_average_kernel as bartlett_kernel
from gyro_char.errors import InputError
from gyro_char.records import GYRO_CHANNELS, IMU_CHANNELS
from gyro_char.sim import noise_gen
from gyro_char.sim.effects.base import (add_truth_term, axis_param, axis_rows, cycle_envelope,
                                        cycle_terms, describe_without, Effect, markov,
                                        register, second_order_gm, transient_terms)
from gyro_char.sim.effects.responses import (interleaved_memory, output_lowpass, output_notch,
                                             sense_response)
from gyro_char.units import DEG
import numpy as np
from scipy import signal


@register
class InternalLowpass(Effect):
    """The sensor's own digital smoothing: averaging at the internal rate, an output low-pass."""

    name = 'internal_lowpass'
    summary = 'sensor-internal FIR smoothing and decimation (correlated output samples)'
    physics = ('The ADIS16405 samples at 819.2 Hz internally and applies a Bartlett-window FIR '
               '(two cascaded N-point moving averages, N = 2^M taps set by SENS_AVG, datasheet '
               'Rev. B) before the output register is read at a lower rate. Simulated: the '
               'chain runs at decimation x the output rate, the kernel is applied causally '
               '(delay (N-1) internal samples), every decimation-th sample is output. White '
               'noise at the output then has lag-k autocorrelation sum_j h_j h_(j+kD) / '
               'sum h^2, a short-tau Allan curve below the N line, and the long-tau N kept '
               'at N sqrt(D sum_r H_r^2) (H_r: polyphase sums of h). corner_hz > 0 adds '
               'the digital low-pass most MEMS IMUs apply at the output data rate (a '
               'programmable DLPF): a Butterworth of the given order, mapped bilinearly, so '
               'its response falls to zero at the output Nyquist frequency; its DC gain is '
               '1, so N is unchanged. notch_hz > 0 adds a notch at the output rate (the '
               'band-stop flight controllers and robot IMU drivers put on a motor or '
               'propeller frequency): a second-order IIR of -3 dB width notch_hz / '
               'notch_q, unity gain elsewhere. split_hz > 0 is the rate response of an '
               'open-loop vibratory gyro operated mode-split (its sense mode split_hz above '
               'the drive, of half bandwidth sense_hz = f_sense / 2 q_sense): after '
               'demodulation H(s) = (g s + g^2 + w^2) / ((s + g)^2 + w^2), g = 2 pi '
               'sense_hz, w = 2 pi split_hz, unity at DC, a peak of about w / 2g near the '
               'split and a fall as 1 / f beyond, applied in band as it is (one transform of '
               'the record). memory > 0 is the memory of an interleaved front end: '
               'interleave converters (or the two capacitors of a double-sampled one) take '
               'the samples in turn and each keeps a share memory of its last charge, y_k = '
               '(1 - r) x_k + r y_(k-L): DC gain 1, dips at odd multiples of the rate / 2L, '
               'white noise correlated at lags L, 2L, .. only. All act on the decimated '
               'output before any output-stage error '
               '(angle quantization, stale samples).')
    PARAMS = {'taps': (4.0, 'samples', 'moving-average length N at the internal rate'),
              'stages': (2.0, '-', 'cascaded averages (2: Bartlett triangle, 1: boxcar)'),
              'decimation': (1.0, '-', 'internal samples per output sample'),
              'accel': (1.0, '-', '1: accelerometers are filtered too'),
              'corner_hz': (0.0, 'Hz', 'output-rate low-pass corner (0: none)'),
              'order': (2.0, '-', 'its Butterworth order (1 or 2)'),
              'notch_hz': (0.0, 'Hz', 'output-rate notch centre (0: none)'),
              'notch_q': (5.0, '-', 'its quality: centre / -3 dB width'),
              'split_hz': (0.0, 'Hz', 'mode-split sense response: sense-drive split (0: none)'),
              'sense_hz': (5.0, 'Hz', 'its sense mode half bandwidth f_sense / 2 q_sense'),
              'memory': (0.0, '-', 'interleaved front end: share of charge kept (0: none)'),
              'interleave': (2.0, '-', 'its converters taking the samples in turn (>= 1)')}
    output_stage = 0

    def check(self):
        for key in ('taps', 'stages', 'decimation'):
            if self.params[key] < 1 or self.params[key] != int(self.params[key]):
                raise InputError(f'internal_lowpass: {key} must be a whole number >= 1')
        if self.corner_hz < 0.0 or self.order not in (1.0, 2.0):
            raise InputError('internal_lowpass: corner_hz must be >= 0 and order 1 or 2')
        if self.notch_hz < 0.0 or self.notch_q <= 0.0:
            raise InputError('internal_lowpass: notch_hz must be >= 0 and notch_q > 0')
        if self.split_hz < 0.0 or self.sense_hz <= 0.0:
            raise InputError('internal_lowpass: split_hz must be >= 0 and sense_hz > 0')
        if not 0.0 <= self.memory < 1.0 or self.interleave < 1 \
                or self.interleave != int(self.interleave):
            raise InputError('internal_lowpass: memory in [0, 1), interleave a whole number '
                             '>= 1')

    def describe(self):
        out = describe_without(self, 'corner_hz', 'notch_hz', 'split_hz', 'memory')
        for key, companion in (('corner_hz', 'order'), ('notch_hz', 'notch_q'),
                               ('split_hz', 'sense_hz'), ('memory', 'interleave')):
            if key not in out['params']:
                del out['params'][companion]
        return out

    def kernel(self) -> np.ndarray:
        return bartlett_kernel(int(self.taps), int(self.stages))

    def oversample(self, ctx):
        return int(self.decimation)

    def internal(self, ctx, gyro, accel):
        h = self.kernel()
        return self._filter(h, [1.0], gyro), (self._filter(h, [1.0], accel) if self.accel
                                              else accel)

    def output(self, ctx, gyro, accel):
        for key in ('corner_hz', 'notch_hz'):
            if self.params[key] >= 0.5 / ctx.dt:
                raise InputError(f'internal_lowpass: {key} {self.params[key]:g} must be below '
                                 f'the output Nyquist frequency {0.5 / ctx.dt:g} Hz')
        filters = []
        if self.corner_hz:
            filters.append(output_lowpass(self.corner_hz, int(self.order), ctx.dt))
        if self.notch_hz:
            filters.append(output_notch(self.notch_hz, self.notch_q, ctx.dt))
        if self.memory:
            filters.append(interleaved_memory(self.memory, int(self.interleave)))
        for b, a in filters:
            gyro = self._filter(b, a, gyro)
            accel = self._filter(b, a, accel) if self.accel else accel
        if self.split_hz:     # the gyro's own sense mode: the accelerometers have none
            f = np.fft.rfftfreq(gyro.shape[1], ctx.dt)
            h = sense_response(f, self.split_hz, self.sense_hz)
            gyro = np.fft.irfft(np.fft.rfft(gyro, axis=1) * h, gyro.shape[1], axis=1)
        return gyro, accel

    @staticmethod
    def _filter(b, a, x):
        """Filter the rows of ``x`` by (b, a), started in steady state on the first sample."""
        if np.size(b) == 1 and np.size(a) == 1:   # the identity (a 1-tap kernel: no lfilter_zi)
            return x * (b[0] / a[0])
        # Steady state on the first sample: no start-up transient.
        zi = signal.lfilter_zi(b, a)[None, :] * x[:, :1]
        y, _ = signal.lfilter(b, a, x, axis=1, zi=zi)
        return y

    def noise_gain(self, decimation: int) -> float:
        """Long-tau ARW gain of filter + decimation: sqrt(D sum_r H_r^2)."""
        h = self.kernel()
        d = int(decimation)
        polyphase = np.array([h[r::d].sum() for r in range(d)])
        return float(np.sqrt(d * np.sum(polyphase ** 2)))

    def update_truth(self, ctx, truth):
        gain = self.noise_gain(ctx.oversample)
        names = IMU_CHANNELS if self.accel else GYRO_CHANNELS
        for name in names:
            if name in truth['channels']:
                truth['channels'][name]['N'] *= gain


@register
class TemperatureDrift(Effect):
    """Exponential bias transient: a warm-up after power-on, or a thermal step mid-record."""

    name = 'temperature_drift'
    summary = 'bias transient settling exponentially while the sensor warms up'
    physics = ('The die warms with a first-order thermal time constant and the bias follows '
               'temperature linearly: bias(t) = bias + amplitude exp(-t / tau_s), settling to '
               'the nominal bias. In a static record: a deterministic decay seen as a slope '
               'at tau ~ tau_s in the Allan curve and a trend in the mean; in a swing run: a '
               'drift the linear-drift state only partly absorbs. t0_s > 0: the transient '
               'starts mid-record (a draught, a door, a heater or fan switching): the bias '
               'holds amplitude until t0_s, then settles through the same lag, '
               'amplitude exp(-(t - t0_s) / tau_s). rise_s > 0: a pulse instead, of peak '
               'amplitude, rising with rise_s and decaying with tau_s, zero before t0_s and '
               'long after (a bias sensing dT/dt under a passing temperature change). '
               'cycle_s > 0: a periodic cycle instead (an HVAC or thermostat cycle of the '
               'room reaching the die through its lag; a bias linear in temperature gives '
               'the fundamental, a curved one (near its turnover) the harmonics): '
               'amplitude sin(2 pi t / cycle_s + phase) + amplitude2 sin(4 pi t / cycle_s + '
               'phase2) + amplitude3 sin(6 pi t / cycle_s + phase3), times an envelope: 0 '
               'before t0_s, rising linearly to 1 over rise_s after it (an HVAC switched on '
               'mid-record; a control loop gone unstable, its cycle growing to a limit); '
               'both 0: the cycle runs throughout. tau_s is then not used.')
    PARAMS = {'amplitude': (0.05 * DEG, 'rad/s', 'bias offset at t = 0 (before t0_s); '
                            "a cycle's fundamental amplitude"),
              'tau_s': (600.0, 's', 'thermal time constant'),
              't0_s': (0.0, 's', 'when the transient (or the cycle) starts (0: at power-on)'),
              'rise_s': (0.0, 's', "rise time of a pulse (0: a step, no pulse); a cycle's "
                         'amplitude ramp from t0_s'),
              'cycle_s': (0.0, 's', 'period of a periodic cycle (0: a transient, no cycle)'),
              'phase': (0.0, 'rad', "the cycle's fundamental phase at t = 0"),
              'amplitude2': (0.0, 'rad/s', "the cycle's second harmonic amplitude"),
              'phase2': (0.0, 'rad', "the second harmonic's phase at t = 0"),
              'amplitude3': (0.0, 'rad/s', "the cycle's third harmonic amplitude"),
              'phase3': (0.0, 'rad', "the third harmonic's phase at t = 0"),
              'axis': axis_param()}

    def check(self):
        axis_rows(self)
        if self.tau_s <= 0 or self.t0_s < 0 or self.rise_s < 0 or self.cycle_s < 0:
            raise InputError('temperature_drift: tau_s must be > 0, t0_s, rise_s and cycle_s '
                             '>= 0')

    def describe(self):
        return describe_without(self, 't0_s', 'rise_s', 'cycle_s', 'phase', 'amplitude2',
                                'phase2', 'amplitude3', 'phase3')

    def sensor(self, ctx, gyro, accel):
        if self.cycle_s > 0.0:
            shape = sum(a * np.sin(2.0 * np.pi * ctx.t / period + phase)
                        for a, period, phase in cycle_terms(self.params))
            shape = shape * cycle_envelope(ctx.t, self.t0_s, self.rise_s)
        else:
            since = np.maximum(ctx.t - self.t0_s, 0.0)
            shape = sum(c * np.exp(-since / lag)
                        for c, lag in transient_terms(self.amplitude, self.tau_s, self.rise_s))
        gyro = gyro.copy()
        for r in axis_rows(self):
            gyro[r] += shape
        return gyro, accel


class _NoiseTerm(Effect):
    """An extra IEEE noise process from ``noise_gen`` on the selected gyro axes."""

    term = ''

    def check(self):
        axis_rows(self)
        if self.params[self.term] < 0:
            raise InputError(f'{self.name}: {self.term} must be >= 0')

    def series(self, n: int, ctx, rng) -> np.ndarray:
        """Return one axis's ``n`` internal samples of the process."""
        return noise_gen.generate(n, ctx.dt_internal, rng=rng,
                                  **{self.term: self.params[self.term]})

    def sensor(self, ctx, gyro, accel):
        gyro = gyro.copy()
        rng = self.rng(ctx)
        for r in axis_rows(self):
            gyro[r] += self.series(gyro.shape[1], ctx, rng)
        return gyro, accel

    def update_truth(self, ctx, truth):
        add_truth_term(truth, axis_rows(self), self.term, self.params[self.term])


def pivot_scale(alpha: float, plain: float, pivot_hz: float, dt: float) -> float:
    """
    Innovation scale of a 1/f^alpha process that equals the plain 1/f^plain one at ``pivot_hz``.

    The Kasdin-Walter filter (1 - z^-1)^(-alpha/2) of unit innovations has the two-sided PSD
    dt (2 sin(pi f dt))^(-alpha); scaling it by (2 sin(pi f_p dt))^((alpha - plain) / 2) makes
    it cross the plain process's PSD at f_p, so the coefficient keeps its meaning there.
    """
    return float((2.0 * np.sin(np.pi * pivot_hz * dt)) ** (0.5 * (alpha - plain)))


class _PowerLawTerm(_NoiseTerm):
    """A noise term whose PSD slope ``alpha`` may depart from its IEEE value ``plain``."""

    plain = 0.0

    def check(self):
        super().check()
        if not 0.0 < self.alpha < 3.0 or not self.pivot_hz > 0.0:
            raise InputError(f'{self.name}: alpha must lie in (0, 3) and pivot_hz be > 0')

    def fractional(self) -> bool:
        """Return True if the slope departs from the plain IEEE term's."""
        return self.alpha != self.plain

    def describe(self):
        out = Effect.describe(self)
        if not self.fractional():        # the plain term's description, as it always was
            del out['params']['alpha'], out['params']['pivot_hz']
        return out

    def update_truth(self, ctx, truth):
        # Only the plain slope is an IEEE term; a fractional one has no coefficient in the model.
        if not self.fractional():
            super().update_truth(ctx, truth)


# Where a fractional slope meets the plain term unless said (the closed forms use it too).
DEFAULT_PIVOT_HZ = 0.01
PIVOT_PARAMS = {
    'pivot_hz': (DEFAULT_PIVOT_HZ, 'Hz',
                 'where a fractional slope crosses the plain one (coefficient defined there)')}


@register
class BiasInstability(_PowerLawTerm):
    """Flicker (1/f) bias noise, optionally of a fractional slope 1/f^alpha."""

    name = 'bias_instability'
    term = 'B'
    plain = 1.0
    summary = 'flicker (1/f) bias noise: the flat Allan floor 0.664 B'
    physics = ('1/f rate noise (Kasdin-Walter fractional integration, noise_gen): PSD '
               'B^2 / (pi f), Allan variance 2 ln2 / pi B^2 (flat floor 0.664 B). '
               'corner_hz > 0: band-limited flicker, as a sum of Gauss-Markov processes '
               'with log-spaced correlation times is (real MEMS bias instability; the '
               'shortest time sets the corner): the same flicker through the half-order '
               'lowpass (1 - b)^(1/2) (1 - b z^-1)^(-1/2), b = exp(-2 pi corner_hz dt), at '
               'the internal rate: PSD B^2 / (pi f) / sqrt(1 + (f / corner_hz)^2) in the '
               'continuous limit, 1/f below the corner (floor 0.664 B at tau >> '
               '1 / corner_hz), 1/f^2 above it. alpha != 1: 1/f^alpha noise (an Allan slope '
               '(alpha - 1) / 2 instead of a floor, as a spread of trap energies that is '
               'not flat gives), equal to the 1/f one of coefficient B at pivot_hz (the '
               'corner then acts as (1 - b)^(alpha/2) (1 - b z^-1)^(-alpha/2)).')
    PARAMS = {'B': (10.0 * DEG / 3600.0, 'rad/s', 'IEEE bias-instability coefficient'),
              'axis': axis_param(),
              'corner_hz': (0.0, 'Hz', 'upper corner: 1/f below, 1/f^2 above (0: none)'),
              'alpha': (1.0, '', 'PSD slope: 1/f^alpha (1: flicker)'), **PIVOT_PARAMS}

    def check(self):
        super().check()
        if self.corner_hz < 0:
            raise InputError('bias_instability: corner_hz must be >= 0')

    def series(self, n: int, ctx, rng) -> np.ndarray:
        if not self.corner_hz and not self.fractional():
            return super().series(n, ctx, rng)   # 1/f up to Nyquist, as always
        dt = ctx.dt_internal
        return (self.B * pivot_scale(self.alpha, self.plain, self.pivot_hz, dt)
                * noise_gen.flicker(n, rng, alpha=self.alpha, corner=self.corner_hz * dt))


@register
class RateRandomWalk(_PowerLawTerm):
    """Random walk of the rate (integrated white noise), optionally of a fractional slope."""

    name = 'rate_random_walk'
    term = 'K'
    plain = 2.0
    summary = 'rate random walk: Allan slope +1/2, sigma^2 = K^2 tau / 3'
    physics = ('Integrated white rate-acceleration noise: PSD K^2 / (2 pi f)^2, Allan '
               'variance K^2 tau / 3. alpha != 2: a 1/f^alpha walk (fractional Brownian '
               'motion of Hurst exponent (alpha - 1) / 2 for 1 < alpha < 3: an '
               'anti-persistent creep below 2, a persistent one above), Allan slope '
               '(alpha - 1) / 2, equal to the plain walk of coefficient K at pivot_hz.')
    PARAMS = {'K': (1.0 * DEG / 3600.0, 'rad/s/sqrt(s)', 'IEEE rate-random-walk coefficient'),
              'axis': axis_param(),
              'alpha': (2.0, '', 'PSD slope: 1/f^alpha (2: random walk)'), **PIVOT_PARAMS}

    def series(self, n: int, ctx, rng) -> np.ndarray:
        if not self.fractional():
            return super().series(n, ctx, rng)
        dt = ctx.dt_internal
        return (self.K * np.sqrt(dt) * pivot_scale(self.alpha, self.plain, self.pivot_hz, dt)
                * noise_gen.flicker(n, rng, alpha=self.alpha))


@register
class GaussMarkov(Effect):
    """Gauss-Markov (exponentially correlated) rate noise, first or second order."""

    name = 'gauss_markov'
    summary = 'exponentially correlated rate noise (a bump in the Allan curve near 1.9 tau_c)'
    physics = ('x_k = a x_(k-1) + sigma sqrt(1 - a^2) w_k, a = exp(-dt / tau_s), stationary '
               'from the first sample: autocorrelation sigma^2 exp(-|lag| / tau_s); Allan '
               'variance (q tau_c^2 / tau) [1 - tau_c / (2 tau) (3 - 4 e^(-tau/tau_c) + '
               'e^(-2 tau/tau_c))] with q = 2 sigma^2 / tau_c. order = 2: two such stages in '
               'cascade (the critically damped second-order Gauss-Markov model, whose PSD '
               'falls as f^-4 above 1 / (2 pi tau_s): a process with inertia, e.g. a '
               'resonance-driven or twice-filtered disturbance), scaled to standard deviation '
               'sigma, autocorrelation (1 + |lag| / tau_s) exp(-|lag| / tau_s) in the '
               'continuous limit; also stationary from the first sample.')
    PARAMS = {'sigma': (0.01 * DEG, 'rad/s', 'stationary standard deviation'),
              'tau_s': (10.0, 's', 'correlation time'),
              'axis': axis_param(),
              'order': (1.0, '-', '1: first order, 2: two first-order stages in cascade')}

    def check(self):
        axis_rows(self)
        if self.sigma < 0 or self.tau_s <= 0:
            raise InputError('gauss_markov: sigma >= 0 and tau_s > 0')
        if self.order not in (1.0, 2.0):
            raise InputError('gauss_markov: order must be 1 or 2')

    def sensor(self, ctx, gyro, accel):
        a = np.exp(-ctx.dt_internal / self.tau_s)
        rng = self.rng(ctx)
        gyro = gyro.copy()
        n = gyro.shape[1]
        for r in axis_rows(self):
            w = rng.standard_normal(n)
            if int(self.order) == 2:
                gyro[r] += self.sigma * second_order_gm(a, w, rng.standard_normal(2))
                continue
            gyro[r] += self.sigma * markov(w, a)
        return gyro, accel
