"""
Bench-simulator configuration: dataclasses built from a preset, optionally overridden by YAML.

A YAML override file uses the preset's own nested names (see ``gyro_char.sim.presets``), SI units::

    preset: adis16405          # optional, default adis16405
    stand: {amplitude: 0.2, period_s: 4.0}
    gyro: {bias: {x: 0.001}, output_step: 0.0}
    noise: {gyro_x: {N: 1.0e-4}}

Unknown keys and non-finite or negative sizes are refused with ``InputError`` (never silently
ignored, so that a typo cannot leave a default in place).
"""
from dataclasses import asdict, dataclass, field, fields
import math
from typing import Dict, Optional

from gyro_char.errors import InputError
from gyro_char.sim.presets import DEFAULT_PRESET, preset

AXES = ('x', 'y', 'z')
TERMS = ('N', 'B', 'K', 'Q', 'R')
_TEXT = {'axis', 'quantizer'}
# Fields that may be negative (signed errors and angles); every other number must be >= 0.
_SIGNED = {'phase', 'offset', 'drift_rate', 'drift_accel', 'scale_factor_error', 'bias',
           'bias_drift', 'misalignment'}


@dataclass
class StandConfig:
    """Swing stand: phi = (A + dA) sin(2 pi t / T + psi0) + phi0 + (w0 + dw0) t + wdot0 t^2/2."""

    amplitude: float            # A, rad
    period_s: float             # T, s
    phase: float                # psi0, rad
    offset: float               # phi0, rad
    drift_rate: float           # w0 of the swing axis, rad/s
    drift_accel: float          # wdot0 of the swing axis, rad/s^2
    amplitude_noise: float      # sigma of dA (white, per sample instant), rad
    drift_rate_noise: float     # sigma of dw0 (white, per sample instant), rad/s


@dataclass
class EncoderConfig:
    """Sine-cosine angle encoder: [([phi/d1] d1 + dd1) / d2] d2 sampled with jitter."""

    rate_hz: float
    level_step: float           # d1, rad (0: no level quantization)
    adc_noise: float            # sigma of dd1, rad
    word_step: float            # d2, rad (0: no word quantization)
    jitter_s: float             # sigma of the sampling-instant jitter, s


@dataclass
class GyroConfig:
    """Gyro chain; per-axis errors are dicts {'x': .., 'y': .., 'z': ..}."""

    rate_hz: float              # output rate of swing runs
    static_rate_hz: float       # output rate of static records
    axis: str                   # sensitive axis mounted along the swing axis
    jitter_s: float             # sigma of the sampling-instant jitter, s
    output_step: float          # dH, rad/s (0: no quantization)
    quantizer: str              # 'round' or 'floor' (the paper's integer part)
    scale_factor_error: Dict[str, float]    # fraction
    bias: Dict[str, float]                  # w0H, rad/s
    bias_drift: Dict[str, float]            # wdot0H, rad/s^2
    misalignment: float         # dtheta between sensitive and swing axis, rad
    misalignment_noise: float   # sigma of delta dtheta (white, per sample), rad
    # First sample instant of a swing run's gyro, s (the encoder's is 0): where the gyro
    # samples fall between encoder samples, which the diagnosis's twins copy from a record.
    start_s: float = 0.0


@dataclass
class AccelConfig:
    """Accelerometer output quantization and constant biases (m/s^2)."""

    output_step: float
    bias: Dict[str, float]


@dataclass
class BenchConfig:
    """Everything the simulator needs; build with ``from_preset`` or ``load``."""

    preset: str
    stand: StandConfig
    encoder: EncoderConfig
    gyro: GyroConfig
    accel: AccelConfig
    # IEEE 952 static terms per channel: {'gyro_x': {'N':.., 'B':.., 'K':.., 'Q':.., 'R':..}}
    noise: Dict[str, Dict[str, float]] = field(default_factory=dict)

    @classmethod
    def from_preset(cls, name: str = DEFAULT_PRESET,
                    overrides: Optional[dict] = None) -> 'BenchConfig':
        try:
            values = preset(name)
        except KeyError as exc:
            raise InputError(str(exc.args[0])) from None
        if overrides:
            _merge(values, overrides, 'config')
        cfg = cls(preset=name,
                  stand=StandConfig(**values['stand']),
                  encoder=EncoderConfig(**values['encoder']),
                  gyro=GyroConfig(**values['gyro']),
                  accel=AccelConfig(**values['accel']),
                  noise=values['noise'])
        cfg.validate()
        return cfg

    def to_dict(self) -> dict:
        return asdict(self)

    def validate(self) -> None:
        for section in (self.stand, self.encoder, self.gyro, self.accel):
            for f in fields(section):
                _check_number(type(section).__name__, f.name, getattr(section, f.name))
        for channel, terms in self.noise.items():
            for term, value in terms.items():
                _check_number(channel, term, value)
        if self.gyro.axis not in AXES:
            raise InputError(f'gyro.axis must be one of x, y, z, got {self.gyro.axis!r}')
        if self.gyro.quantizer not in ('round', 'floor'):
            raise InputError(f'gyro.quantizer must be round or floor, got '
                             f'{self.gyro.quantizer!r}')
        for name in ('rate_hz', 'static_rate_hz'):
            if not getattr(self.gyro, name) > 0:
                raise InputError(f'gyro.{name} must be > 0')
        if not self.encoder.rate_hz > 0 or not self.stand.period_s > 0:
            raise InputError('encoder.rate_hz and stand.period_s must be > 0')

    def channel_terms(self, channel: str) -> Dict[str, float]:
        """IEEE terms of one channel, zeros for missing ones."""
        terms = self.noise.get(channel, {})
        return {t: float(terms.get(t, 0.0)) for t in TERMS}


def load(path: Optional[str] = None, preset_name: Optional[str] = None,
         overrides: Optional[dict] = None) -> BenchConfig:
    """Config from a preset name, an optional YAML file on top, then ``overrides`` on top."""
    data: dict = {}
    if path:
        import yaml
        try:
            with open(path, encoding='utf-8') as stream:
                data = yaml.safe_load(stream) or {}
        except (OSError, yaml.YAMLError) as exc:
            raise InputError(f'cannot read config {path}: {exc}') from None
        if not isinstance(data, dict):
            raise InputError(f'config {path}: top level must be a mapping')
    name = preset_name or data.pop('preset', None) or DEFAULT_PRESET
    data.pop('preset', None)
    if overrides:
        _merge(data, overrides, 'overrides', strict=False)
    return BenchConfig.from_preset(name, data)


def _merge(base: dict, extra: dict, where: str, strict: bool = True) -> None:
    for key, value in extra.items():
        if strict and key not in base:
            known = ', '.join(sorted(base))
            raise InputError(f'{where}: unknown key {key!r} (known: {known})')
        if isinstance(value, dict):
            if key in base and not isinstance(base[key], dict):
                raise InputError(f'{where}.{key}: expected a number, got a mapping')
            base.setdefault(key, {})
            _merge(base[key], value, f'{where}.{key}', strict)
        else:
            if isinstance(base.get(key), dict):
                raise InputError(f'{where}.{key}: expected a mapping')
            base[key] = value


def _check_number(section: str, name: str, value) -> None:
    if isinstance(value, dict):
        for key, item in value.items():
            _check_number(section, f'{name}.{key}', item)
        return
    if isinstance(value, str) and name in _TEXT:
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f'{section}.{name} must be a number, got {value!r}')
    if not math.isfinite(value):
        raise InputError(f'{section}.{name} must be finite, got {value!r}')
    if value < 0 and name.split('.')[0] not in _SIGNED:
        raise InputError(f'{section}.{name} must be >= 0, got {value!r}')


def noiseless(cfg: BenchConfig, keep_errors: bool = True) -> BenchConfig:
    """
    Return a copy with every random element and quantizer off (for closed-form checks).

    Kept when ``keep_errors``: the deterministic stand motion and drift, the gyro's scale
    factor, bias, drift and misalignment angle. Off: stand and encoder noises, jitter, all
    IEEE terms, misalignment instability, and the quantizers d1, d2, dH and the accel step.
    """
    import copy
    out = copy.deepcopy(cfg)
    s, e, g = out.stand, out.encoder, out.gyro
    s.amplitude_noise = s.drift_rate_noise = 0.0
    e.level_step = e.word_step = e.adc_noise = e.jitter_s = 0.0
    g.jitter_s = g.output_step = g.misalignment_noise = 0.0
    out.accel.output_step = 0.0
    out.noise = {ch: dict.fromkeys(TERMS, 0.0) for ch in out.noise}
    if not keep_errors:
        s.offset = s.drift_rate = s.drift_accel = 0.0
        g.misalignment = 0.0
        for key in ('scale_factor_error', 'bias', 'bias_drift'):
            setattr(g, key, dict.fromkeys(AXES, 0.0))
        out.accel.bias = dict.fromkeys(AXES, 0.0)
    return out
