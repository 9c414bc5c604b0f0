"""
Units: degree and g constants, SI unit strings of the noise terms, human units of tables.

Inside the package everything is SI (rad, rad/s, m/s^2, s); tables for people use the field's
units (deg/sqrt(h), deg/h, ug). ``HUMAN_UNITS[kind][term] = (factor, unit)`` with
human value = SI value / factor.
"""
import numpy as np

# SI unit strings (noise.json) and the human units of the table.
SI_UNITS = {
    'gyro': {'N': 'rad/s^0.5', 'B': 'rad/s', 'K': 'rad/s^1.5', 'Q': 'rad', 'R': 'rad/s^2'},
    'accel': {'N': 'm/s^1.5', 'B': 'm/s^2', 'K': 'm/s^2.5', 'Q': 'm/s', 'R': 'm/s^3'},
}
RATE_UNITS = {'gyro': 'rad/s', 'accel': 'm/s^2'}
DEG = np.pi / 180.0
G0 = 9.80665
# (factor, unit): human value = SI value / factor.
HUMAN_UNITS = {
    'gyro': {'N': (DEG / 60.0, 'deg/h^0.5'), 'B': (DEG / 3600.0, 'deg/h'),
             'K': (DEG / 3600.0 / 60.0, 'deg/h^1.5'), 'Q': (DEG / 3600.0, 'arcsec'),
             'R': (DEG / 3600.0 ** 2, 'deg/h^2')},
    'accel': {'N': (1.0 / 60.0, 'm/s/h^0.5'), 'B': (G0 * 1e-6, 'ug'),
              'K': (G0 * 1e-6 / 60.0, 'ug/h^0.5'), 'Q': (1.0, 'm/s'),
              'R': (G0 * 1e-6, 'ug/s')},
}


def sensor_kind(channel: str) -> str:
    """Return ``'gyro'`` or ``'accel'`` from a channel name like ``gyro_x``."""
    kind = channel.split('_', 1)[0]
    if kind not in SI_UNITS:
        raise ValueError(f'channel {channel!r} is neither gyro_* nor accel_*')
    return kind


def to_human(term: str, kind: str, value: float) -> float:
    """Convert an SI coefficient to the human unit of ``HUMAN_UNITS``."""
    return value / HUMAN_UNITS[kind][term][0]


# Unit expressions of the field (a datasheet's 'deg/sqrt(h)', 'ug/sqrt(Hz)', 'ppm'), parsed into
# an SI factor and a dimension (angle, length, time) so that a limit given in any of them can be
# compared with the SI values of the outputs, and a unit of the wrong kind is refused.
_BASE_UNITS = {
    '1': (1.0, (0, 0, 0)), 'rad': (1.0, (1, 0, 0)), 'mrad': (1e-3, (1, 0, 0)),
    'urad': (1e-6, (1, 0, 0)), 'deg': (DEG, (1, 0, 0)), 'arcmin': (DEG / 60.0, (1, 0, 0)),
    'arcsec': (DEG / 3600.0, (1, 0, 0)), 'm': (1.0, (0, 1, 0)), 'mm': (1e-3, (0, 1, 0)),
    's': (1.0, (0, 0, 1)), 'ms': (1e-3, (0, 0, 1)), 'min': (60.0, (0, 0, 1)),
    'h': (3600.0, (0, 0, 1)), 'hr': (3600.0, (0, 0, 1)), 'Hz': (1.0, (0, 0, -1)),
    'g': (G0, (0, 1, -2)), 'mg': (G0 * 1e-3, (0, 1, -2)), 'ug': (G0 * 1e-6, (0, 1, -2)),
    '%': (1e-2, (0, 0, 0)), 'ppm': (1e-6, (0, 0, 0)),
}
_UNIT_ALIASES = {'°': 'deg', 'µg': 'ug', 'μg': 'ug', 'sec': 's', 'hz': 'Hz'}


def parse_unit(unit: str):
    """
    Return ``(factor, dims)`` of a unit expression: SI value = value x factor.

    Grammar: factors joined by ``*`` and ``/`` (left to right), each ``NAME``, ``NAME^P`` or
    ``sqrt(EXPR)`` (also ``√EXPR``); names as in ``_BASE_UNITS`` (rad, deg, arcsec, m, s, min, h,
    Hz, g, mg, ug, %, ppm, 1). ``dims`` are the powers of (angle, length, time).

    Raises
    ------
    ValueError
        On an unknown name or a malformed expression.

    """
    text = str(unit).strip().replace(' ', '').replace('**', '^').replace('√', 'sqrt')
    factor, dims, pos = _unit_product(text, 0)
    if pos != len(text):
        raise ValueError(f'cannot read unit {unit!r} (at {text[pos:]!r})')
    return factor, dims


def _unit_product(text: str, pos: int):
    factor, dims, pos = _unit_factor(text, pos)
    while pos < len(text) and text[pos] in '*/':
        sign = 1.0 if text[pos] == '*' else -1.0
        f, d, pos = _unit_factor(text, pos + 1)
        factor *= f ** sign
        dims = tuple(a + sign * b for a, b in zip(dims, d))
    return factor, dims, pos


def _unit_factor(text: str, pos: int):
    if text.startswith('sqrt(', pos):
        factor, dims, pos = _unit_product(text, pos + 5)
        if pos >= len(text) or text[pos] != ')':
            raise ValueError(f'unbalanced parenthesis in unit {text!r}')
        factor, dims, pos = factor ** 0.5, tuple(0.5 * d for d in dims), pos + 1
    elif text.startswith('(', pos):
        factor, dims, pos = _unit_product(text, pos + 1)
        if pos >= len(text) or text[pos] != ')':
            raise ValueError(f'unbalanced parenthesis in unit {text!r}')
        pos += 1
    else:
        end = pos
        while end < len(text) and text[end] not in '*/^()':
            end += 1
        name = _UNIT_ALIASES.get(text[pos:end], text[pos:end])
        if name not in _BASE_UNITS:
            known = ', '.join(sorted(_BASE_UNITS))
            raise ValueError(f'unknown unit {text[pos:end]!r} (known: {known}, sqrt(...))')
        (factor, dims), pos = _BASE_UNITS[name], end
    if pos < len(text) and text[pos] == '^':
        end = pos + 1
        while end < len(text) and (text[end].isdigit() or text[end] in '.-+'):
            end += 1
        try:
            power = float(text[pos + 1:end])
        except ValueError:
            raise ValueError(f'bad power in unit {text!r}') from None
        factor, dims, pos = factor ** power, tuple(power * d for d in dims), end
    return float(factor), tuple(float(d) for d in dims), pos


def to_si(value: float, unit: str, si_unit: str) -> float:
    """
    Convert ``value`` given in ``unit`` to the SI unit ``si_unit`` (e.g. of noise.json).

    Raises
    ------
    ValueError
        When ``unit`` cannot be read or is not a unit of the same kind as ``si_unit``.

    """
    factor, dims = parse_unit(unit)
    si_factor, si_dims = parse_unit(si_unit)
    if any(abs(a - b) > 1e-9 for a, b in zip(dims, si_dims)):
        raise ValueError(f'{unit!r} is not a unit of the same kind as {si_unit!r}')
    return float(value) * factor / si_factor
