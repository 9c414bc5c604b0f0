"""
Datasheet limits (spec YAML) and the pass / fail verdict of each device.

A spec names limits in the field's units, converted to SI with ``gyro_char.units.to_si``::

    gyro:                       # every gyro channel of an allan run
      N: {max: 3.5, unit: deg/sqrt(h)}
      B: {max: 60, unit: deg/h}
    accel:
      N: {max: 60, unit: ug/sqrt(Hz)}
    gyro_z:                     # one channel; overrides the sensor's limit for that quantity
      B: {max: 80, unit: deg/h}
    swing:
      scale_factor_error: {max_abs: 500, unit: ppm}
    diagnose:
      final_gap: {max: 3}

A limit has ``min``, ``max`` and / or ``max_abs`` and an optional ``unit`` (default: the SI
unit of the quantity). Sections ``gyro``, ``accel`` and channel names apply to allan runs,
``swing`` to swing runs and ``diagnose`` to diagnoses.
"""
from dataclasses import dataclass
import math
from typing import Dict, List, Optional, Tuple

from gyro_char.errors import InputError
from gyro_char.jobs import job_module
from gyro_char.jobs.base import is_upper_bound
from gyro_char.units import SI_UNITS, to_si
import yaml

_BOUNDS = ('min', 'max', 'max_abs')


@dataclass
class Limit:
    """One quantity's limits, kept in the spec's unit (and converted for comparison)."""

    section: str
    quantity: str
    unit: str
    si_unit: str
    bounds: Dict[str, float]

    def check(self, value: float) -> List[str]:
        """Reasons ``value`` (SI) breaks this limit; empty when it passes."""
        if not math.isfinite(value):
            return [f'{self.quantity} is not finite']
        shown = value * to_si(1.0, self.si_unit, self.unit)
        out = []
        for name, bound in self.bounds.items():
            bad = {'min': shown < bound, 'max': shown > bound,
                   'max_abs': abs(shown) > bound}[name]
            if bad:
                rel = {'min': '<', 'max': '>', 'max_abs': '> (abs)'}[name]
                out.append(f'{shown:.4g} {rel} {name} {bound:g} {self.unit}')
        return out


def _sections() -> Dict[str, Tuple[str, Dict[str, str]]]:
    """Section name -> (device kind, quantity -> SI unit)."""
    out = {}
    for sensor, units in SI_UNITS.items():
        out[sensor] = ('allan', units)
        out.update({f'{sensor}_{axis}': ('allan', units) for axis in 'xyz'})
    for kind in ('swing', 'diagnose'):
        out[kind] = (kind, job_module(kind).QUANTITIES)
    return out


def load_spec(path: str) -> Dict[str, Dict[str, Limit]]:
    """
    Read a spec YAML into ``{section: {quantity: Limit}}``.

    Raises
    ------
    InputError
        On a missing file, bad YAML, an unknown section, quantity or bound, or a unit that is
        not one of the quantity's kind.

    """
    try:
        with open(path) as fh:
            raw = yaml.safe_load(fh)
    except OSError as exc:
        raise InputError(f'--spec {path}: {exc.strerror}') from None
    except yaml.YAMLError as exc:
        raise InputError(f'--spec {path}: not YAML ({str(exc).splitlines()[0]})') from None
    if not isinstance(raw, dict) or not raw:
        raise InputError(f'--spec {path}: expected a mapping of sections (gyro, accel, '
                         'swing, ...)')
    known = _sections()
    spec = {}
    for section, items in raw.items():
        if section not in known:
            raise InputError(f'--spec {path}: unknown section {section!r}; known: '
                             f'{", ".join(known)}')
        units = known[section][1]
        if not isinstance(items, dict):
            raise InputError(f'--spec {path}: {section} must map quantities to limits')
        spec[section] = {}
        for quantity, lim in items.items():
            where = f'--spec {path}: {section}.{quantity}'
            if quantity not in units:
                raise InputError(f'{where}: unknown quantity; known: {", ".join(units)}')
            if not isinstance(lim, dict) or not set(lim) & set(_BOUNDS) \
                    or set(lim) - set(_BOUNDS) - {'unit'}:
                raise InputError(f'{where}: give min, max and/or max_abs (and unit)')
            unit = str(lim.get('unit', units[quantity]))
            try:
                to_si(1.0, unit, units[quantity])
                bounds = {k: float(lim[k]) for k in _BOUNDS if k in lim}
            except (TypeError, ValueError) as exc:
                raise InputError(f'{where}: {exc}') from None
            spec[section][quantity] = Limit(section, quantity, unit, units[quantity], bounds)
    return spec


def limit_for(spec, kind: str, channel: str, quantity: str) -> Optional[Limit]:
    """Return the limit that applies to one row (a channel's own section first), or None."""
    if kind == 'allan':
        order = [channel, channel.split('_', 1)[0]]
    else:
        order = [kind]
    for section in order:
        if quantity in spec.get(section, {}):
            return spec[section][quantity]
    return None


def _governed(section: str, kind: str, channels: List[str]) -> List[str]:
    """Return the record's channels that a section speaks for."""
    if kind != 'allan':
        return channels
    if section in SI_UNITS:
        return [c for c in channels if c.startswith(section + '_')]
    return [section] if section in channels else []


def judge(spec, kind: str, status: str, message: str, rows: List[dict]):
    """
    Return ``(verdict, reasons, passes)`` of one device.

    ``passes[i]`` is True / False for rows with a limit, None otherwise (empty for a device in
    error). A limit the record cannot be checked against (e.g. accel limits on a gyro-only
    record) fails the device: a datasheet promise that was not measured is not met.
    """
    if status != 'ok':
        return 'error', message, []
    reasons, passes = [], []
    for row in rows:
        lim = limit_for(spec, kind, row['channel'], row['quantity'])
        if lim is None:
            passes.append(None)
            continue
        why = lim.check(row['value'])
        bound = ' (upper bound)' if is_upper_bound(row) else ''
        reasons.extend(f'{row["channel"]} {row["quantity"]}{bound}: {w}' for w in why)
        passes.append(not why)
    have = {(r['channel'], r['quantity']) for r in rows}
    channels = sorted({r['channel'] for r in rows})
    sections = _sections()
    for section, limits in spec.items():
        if sections[section][0] != kind:
            continue
        governed = _governed(section, kind, channels)
        if not governed:
            reasons.append(f'{section}: not in the record')
        for quantity, lim in limits.items():
            reasons.extend(f'{c} {quantity}: not measured' for c in governed
                           if limit_for(spec, kind, c, quantity) is lim
                           and (c, quantity) not in have)
    return ('fail' if reasons else 'pass'), '; '.join(reasons), passes
