"""
Unmodelled effects as composable additions to the bench simulator (docs/design.md).

The paper's model (``gyro_char.sim.simulator``) is the baseline. An effect is a subclass of
``Effect`` registered under its catalogue name in ``EFFECTS``; the simulator calls its hooks at
fixed stages of the chain, in the order the user listed the effects. Every hook has a no-op
default, so an effect overrides only the stages it acts on.

The chain, per run (``ctx`` is a ``SimContext``; gyro/accel arrays are 3 x n, rows x, y, z, SI):

1. ``oversample(ctx) -> int``: internal samples per output sample this effect needs (the
   simulator runs the sensor chain at ``output rate x max(oversample)``; default 1).
2. Stand motion and the sensor's true inputs at the internal sample instants: ``ctx.t``,
   ``ctx.angle`` (stand angle), ``ctx.true_rate`` and ``ctx.specific_force`` (3 x n, sensor
   frame). The baseline response is formed: gyro = (1 + scale error) cos(misalignment) rate +
   bias + drift t + IEEE noise terms; accel = specific force + bias + noise.
3. ``sensor(ctx, gyro, accel) -> (gyro, accel)``: physical errors at the internal rate (tones,
   g-sensitivity, nonlinearity, extra noise processes, thermal transients...).
4. ``internal(ctx, gyro, accel) -> (gyro, accel)``: the sensor's own digital processing at the
   internal rate (e.g. ``internal_lowpass``); same length in and out. The simulator then
   decimates to the output rate by keeping every D-th sample.
5. ``output(ctx, gyro, accel) -> (gyro, accel)``: at the output rate, before the baseline output
   quantization dH (``ctx.t_out`` holds the true output sample instants). Effects run here in
   the order of their ``output_stage`` (the sensor's own output filter, 0, before the
   output-stage errors, 1), the user's order within a stage.
6. ``stamps(ctx, t) -> t``: IMU header stamps from the true output sample instants.
7. ``encoder_angle(ctx, t, angle) -> angle``: the encoder's reading of the true stand angle at
   its sample instants, before its level/word quantization (swing runs only).
8. ``encoder_stamps(ctx, t) -> t``: encoder header stamps (swing runs only).
9. ``update_truth(ctx, truth)``: edit the ``truth.json`` dict where the effect maps exactly onto
   a reported quantity (e.g. ``bias_instability`` adds to B in quadrature).

Random numbers: ``ctx.rng(key)`` gives a generator seeded from (run seed, key); an effect uses
``self.rng(ctx)`` (key = its name and position), so adding an effect never changes the baseline
noise of the same seed - the clean/effect pair of records differs only by the effect.

Parameters: each effect lists ``PARAMS = {name: (default, unit, description)}`` (floats, SI);
``parse_effect('time_delay:delay_s=0.002')`` builds one from the CLI syntax ``NAME[:k=v,...]``.
Axis-selecting parameters take 0, 1, 2 for x, y, z (floats in the CLI, cast to int).
"""
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Optional, Tuple
import zlib

from gyro_char.errors import InputError
from gyro_char.records import GYRO_CHANNELS
import numpy as np
from numpy.polynomial import chebyshev
from scipy import signal


Array = np.ndarray


@dataclass
class SimContext:
    """What the hooks may read: the config, the run kind, the time bases and true inputs."""

    config: Any                     # gyro_char.sim.config.BenchConfig
    kind: str                       # 'static' or 'swing'
    seed: int
    dt: float                       # output sample interval, s
    oversample: int = 1             # internal samples per output sample
    axis: int = 0                   # row of the gyro axis on the swing axis
    t: Optional[Array] = None       # true internal sample instants, s
    t_out: Optional[Array] = None   # true output sample instants, s
    angle: Optional[Array] = None   # stand angle at ctx.t, rad (zeros for static)
    true_rate: Optional[Array] = None       # 3 x n true angular rate, sensor frame, rad/s
    specific_force: Optional[Array] = None  # 3 x n true specific force, m/s^2
    # Stand motion as functions of time (swing runs), for effects that need it elsewhere.
    stand_angle: Optional[Callable[[Array], Array]] = None
    stand_rate: Optional[Callable[[Array], Array]] = None
    extras: Dict[str, Any] = field(default_factory=dict)

    @property
    def dt_internal(self) -> float:
        return self.dt / self.oversample

    def rng(self, key: str) -> np.random.Generator:
        """Independent, reproducible stream for ``key`` under this run's seed."""
        return np.random.default_rng([self.seed, zlib.crc32(key.encode('utf-8'))])


class Effect:
    """Base class: documented parameters and no-op hooks (see the module docstring)."""

    name = ''
    summary = ''
    physics = ''
    PARAMS: Dict[str, Tuple[float, str, str]] = {}
    output_stage = 1                # order of the ``output`` hooks (0: the sensor's own filter)

    def __init__(self, index: int = 0, **params: float) -> None:
        unknown = set(params) - set(self.PARAMS)
        if unknown:
            raise InputError(f'effect {self.name}: unknown parameter(s) '
                             f'{", ".join(sorted(unknown))}; known: '
                             f'{", ".join(self.PARAMS) or "none"}')
        self.index = index
        self.params: Dict[str, float] = {}
        for key, (default, _unit, _doc) in self.PARAMS.items():
            value = params.get(key, default)
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise InputError(f'effect {self.name}: {key} must be a number, '
                                 f'got {value!r}') from None
            if not np.isfinite(value):
                raise InputError(f'effect {self.name}: {key} must be finite')
            self.params[key] = value
        self.check()

    def __getattr__(self, key: str) -> float:
        params = self.__dict__.get('params', {})
        if key in params:
            return params[key]
        raise AttributeError(key)

    def check(self) -> None:
        """Refuse impossible parameter values with ``InputError`` (override as needed)."""

    def describe(self) -> dict:
        """Return the entry of truth.json's ``effects`` list."""
        return {'name': self.name, 'params': dict(self.params)}

    def rng(self, ctx: SimContext) -> np.random.Generator:
        return ctx.rng(f'effect:{self.name}:{self.index}')

    # ---- hooks (no-op defaults) -------------------------------------------------------
    def oversample(self, ctx: SimContext) -> int:
        return 1

    def sensor(self, ctx: SimContext, gyro: Array, accel: Array) -> Tuple[Array, Array]:
        return gyro, accel

    def internal(self, ctx: SimContext, gyro: Array, accel: Array) -> Tuple[Array, Array]:
        return gyro, accel

    def output(self, ctx: SimContext, gyro: Array, accel: Array) -> Tuple[Array, Array]:
        return gyro, accel

    def stamps(self, ctx: SimContext, t: Array) -> Array:
        return t

    def encoder_angle(self, ctx: SimContext, t: Array, angle: Array) -> Array:
        return angle

    def encoder_stamps(self, ctx: SimContext, t: Array) -> Array:
        return t

    def update_truth(self, ctx: SimContext, truth: dict) -> None:
        return None


EFFECTS: Dict[str, type] = {}


def markov(w: np.ndarray, a: float) -> np.ndarray:
    """
    Return a unit-variance first-order Gauss-Markov series (pole ``a``) from white ``w``.

    x_k = a x_(k-1) + sqrt(1 - a^2) w_k, started from the stationary law (x_0 = w_0).
    """
    e = np.array(w, dtype=np.float64)
    e[1:] *= np.sqrt(1.0 - a * a)
    return signal.lfilter([1.0], [1.0, -a], e)


def second_order_gm(a: float, w: np.ndarray, start) -> np.ndarray:
    """
    Return unit-variance s2 of s1_k = a s1_(k-1) + w_k, s2_k = a s2_(k-1) + s1_k, stationary.

    The pole twice: a process that wanders without steps (PSD ~ f^-4 above its corner). The
    initial state (s1_0, s2_0) is drawn from the cascade's stationary covariance (discrete
    Lyapunov equation of A = [[a, 0], [a, a]], Q = [[1, 1], [1, 1]]: P11 = 1 / q, P12 = 1 / q^2,
    P22 = (1 + a^2) / q^3, q = 1 - a^2) through its Cholesky factor, written out so that it
    stays exact for correlation times far longer than the record; ``start`` holds the two unit
    normal draws, ``w[1:]`` drives the cascade (``w[0]`` is not used).
    """
    q = 1.0 - a * a
    z0, z1 = float(start[0]), float(start[1])
    s1_0 = z0 / np.sqrt(q)
    s2_0 = (z0 + a * z1) / q ** 1.5
    s1 = signal.lfilter([1.0], [1.0, -a], w[1:], zi=[a * s1_0])[0]
    s2 = signal.lfilter([1.0], [1.0, -a], s1, zi=[a * s2_0])[0]
    return np.r_[s2_0, s2] / np.sqrt((1.0 + a * a) / q ** 3)


def one_pole(x: np.ndarray, lag_s: float, dt: float, start: str = 'first') -> np.ndarray:
    """
    First-order lag of time constant ``lag_s`` along the last axis, started in steady state.

    Backward-Euler form y[n] = a y[n-1] + (1 - a) x[n], a = lag / (lag + dt): its group delay
    at low frequency is exactly ``lag_s`` (the exponential form's is lag - dt / 2 + ...).
    ``start``: 'first', settled on the first sample (a signal that was there before the run);
    'periodic', in the state the run ends in (a stand that swung before the record: exact
    for whole periods of a periodic input, no warm-up it never had). ``lag_s`` 0: ``x``.
    """
    if lag_s <= 0.0:
        return x
    a = lag_s / (lag_s + dt)
    b, den = np.array([1.0 - a]), np.array([1.0, -a])
    zi = signal.lfilter_zi(b, den) * x[..., :1]
    if start == 'periodic':
        zi = signal.lfilter(b, den, x, axis=-1, zi=zi)[1]
    return signal.lfilter(b, den, x, axis=-1, zi=zi)[0]


def axis_param(default: float = -1.0) -> tuple:
    """Return the PARAMS entry of the ``axis`` parameter that ``axis_rows`` reads."""
    return (default, '-', '-1: all gyro axes, 0/1/2: x/y/z')


def axis_rows(effect) -> list:
    """Return the gyro rows an effect's ``axis`` parameter selects (-1: all three)."""
    axis = int(effect.params.get('axis', -1))
    if axis not in (-1, 0, 1, 2):
        raise InputError(f'{effect.name}: axis must be -1 (all), 0, 1 or 2')
    return [0, 1, 2] if axis == -1 else [axis]


# Suffixes of a cycle's fundamental's and harmonics' parameters (``cycle_terms``).
CYCLE_HARMONICS = ('', '2', '3')


def cycle_terms(params: dict) -> list:
    """
    Return a periodic bias as (amplitude, period, phase) sinusoids: the fundamental and harmonics.

    ``cycle_s`` is the fundamental's period; ``amplitude``/``phase`` its sinusoid, ``amplitudeK``
    /``phaseK`` the K-th harmonic's (K = 2, 3), left out where their amplitude is 0. Empty
    where ``cycle_s`` is 0 (the bias is a transient then).
    """
    period = params.get('cycle_s', 0.0)
    if not period > 0.0:
        return []
    out = []
    for k, suffix in enumerate(CYCLE_HARMONICS, start=1):
        a = params.get('amplitude' + suffix, 0.0)
        if a:
            out.append((a, period / k, params.get('phase' + suffix, 0.0)))
    return out


def cycle_envelope(t: np.ndarray, t0_s: float = 0.0, rise_s: float = 0.0) -> np.ndarray:
    """
    Return a cycle's amplitude envelope at times ``t``: 0 before ``t0_s``, 1 after the rise.

    ``rise_s`` 0: switched on at ``t0_s`` (an HVAC or a fan turned on); > 0: a linear ramp
    over it (a control loop gone unstable, its cycle growing to a limit). 1 everywhere with
    both 0 (a cycle running before the record).
    """
    t = np.asarray(t, dtype=np.float64)
    if rise_s > 0.0:
        return np.clip((t - t0_s) / rise_s, 0.0, 1.0)
    return (t >= t0_s).astype(np.float64) if t0_s > 0.0 else np.ones_like(t)


def transient_terms(amplitude: float, tau_s: float, rise_s: float = 0.0) -> list:
    """
    Return a bias transient as (coefficient, lag) terms c exp(-(t - t0) / lag), held before t0.

    ``rise_s`` 0: one term, the step or warm-up of ``amplitude``. ``rise_s`` > 0: a pulse of
    peak ``amplitude``, zero before t0 and long after, a (e^(-s / tau) - e^(-s / rise)) / peak:
    the response of a bias that senses the temperature's rate of change (a gradient across the
    die) to a temperature step passing through two lags.
    """
    if rise_s <= 0.0:
        return [(amplitude, tau_s)]
    if abs(tau_s - rise_s) < 1e-6 * tau_s:
        rise_s = tau_s * (1.0 - 1e-6)          # the equal-lag limit, s/tau e^(-s/tau)
    s_peak = tau_s * rise_s * np.log(tau_s / rise_s) / (tau_s - rise_s)
    peak = np.exp(-s_peak / tau_s) - np.exp(-s_peak / rise_s)
    return [(amplitude / peak, tau_s), (-amplitude / peak, rise_s)]


def add_truth_term(truth: dict, rows, term: str, value: float) -> None:
    """Add ``value`` in quadrature to IEEE term ``term`` of the truth of gyro rows ``rows``."""
    for r in rows:
        ch = truth['channels'].get(GYRO_CHANNELS[r])
        if ch is not None:
            ch[term] = float(np.hypot(ch[term], value))


def table_params(prefix: str, orders, unit: str, what: str) -> dict:
    """``PARAMS`` entries of a tabulated form's coefficients (all 0 by default)."""
    return {f'{prefix}{n}': (0.0, unit, f'Chebyshev coefficient of order {n} of the {what}')
            for n in orders}


def table(effect: Effect, prefix: str, orders, x: np.ndarray, span: float,
          even: bool = False, sensed: Optional[np.ndarray] = None) -> np.ndarray:
    """
    Return sum c_n T_n(x / span) over ``orders`` (x clipped to the span), 0 without a span.

    ``even``: each term less its value at 0, so that the table adds nothing at x = 0.
    ``sensed``: the table bends the sensed value rather than ``x`` (the true input): to first
    order in the difference, table(x) + table'(x) (sensed - x), so that the noise comes out
    scaled by the slope where the input is, however far the noise reaches past the span.
    """
    c = np.zeros(max(orders) + 1)
    for n in orders:
        c[n] = effect.params[f'{prefix}{n}']
    if span <= 0.0 or not c.any():
        return np.zeros_like(x)
    u = np.clip(x / span, -1.0, 1.0)
    out = chebyshev.chebval(u, c)
    if even:
        out = out - chebyshev.chebval(0.0, c)
    if sensed is not None:
        out = out + chebyshev.chebval(u, chebyshev.chebder(c)) / span * (sensed - x)
    return out


def describe_without(effect: Effect, *optional: str) -> dict:
    """``describe()`` leaving out optional parameters at their default 0 (earlier truth.json)."""
    out = Effect.describe(effect)
    for name in optional:
        if not out['params'][name]:
            del out['params'][name]
    return out


def register(cls: type) -> type:
    """Class decorator adding an effect to the catalogue under ``cls.name``."""
    if not cls.name or cls.name in EFFECTS:
        raise ValueError(f'effect name {cls.name!r} empty or registered twice')
    EFFECTS[cls.name] = cls
    return cls
