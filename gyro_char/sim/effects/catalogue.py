"""Build effects from the CLI syntax or dicts, and describe the catalogue (``EFFECTS``)."""
from typing import Dict, List, Sequence

from gyro_char.errors import InputError
from gyro_char.sim.effects.base import Effect, EFFECTS


def parse_effect(text: str, index: int = 0) -> Effect:
    """Build an effect from ``NAME[:k=v,...]`` (the CLI syntax)."""
    name, _, rest = text.strip().partition(':')
    if name not in EFFECTS:
        raise InputError(f'unknown effect {name!r}; catalogue: {", ".join(sorted(EFFECTS))}')
    params: Dict[str, float] = {}
    for item in filter(None, (p.strip() for p in rest.split(','))):
        key, sep, value = item.partition('=')
        if not sep:
            raise InputError(f'effect {name}: expected k=v, got {item!r}')
        params[key.strip()] = value.strip()
    return EFFECTS[name](index=index, **params)


def build_effects(specs: Sequence) -> List[Effect]:
    """Effects from strings, ``{'name':.., 'params':{..}}`` dicts or ready instances."""
    out: List[Effect] = []
    for i, spec in enumerate(specs or ()):
        if isinstance(spec, Effect):
            out.append(spec)
        elif isinstance(spec, str):
            out.append(parse_effect(spec, index=i))
        elif isinstance(spec, dict) and spec.get('name') in EFFECTS:
            out.append(EFFECTS[spec['name']](index=i, **spec.get('params', {})))
        else:
            raise InputError(f'cannot build an effect from {spec!r}')
    return out


def catalogue() -> List[dict]:
    """Name, summary, physics and parameters of every effect (for docs and --help)."""
    return [{'name': n, 'summary': c.summary, 'physics': c.physics,
             'params': {k: {'default': d, 'unit': u, 'doc': doc}
                        for k, (d, u, doc) in c.PARAMS.items()}}
            for n, c in sorted(EFFECTS.items())]
