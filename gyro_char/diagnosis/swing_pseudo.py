"""
A swing pseudo-twin's observables: its baseline twin's noise parts plus the effect parts.

The parts come from ``swing_expect.EffectParts``; this is how they add up (``combine``) and
what a pseudo-twin then shows (``pseudo_twin``).
"""
from typing import Sequence

from gyro_char.diagnosis.swing_expect import LINEAR, QUADRATIC
from gyro_char.diagnosis.swing_obs import finish
import numpy as np


def combine(noise: dict, parts: Sequence[dict]) -> dict:
    """
    Return a pseudo-twin's raw parts: its noise twin's plus the effect parts (module doc).

    Line peaks: a deterministic part is a line, its squared peak adds; a noise part raises
    the band's noise, whose largest peak scales with the band's mean power. A colouring
    (``floor``: its power ratio on the gyro noise alone) removes at most that share of
    this twin's power, however large its one-realisation estimate.
    """
    out = dict(noise)
    for p in parts:
        new = {k: out[k] + p[k] for k in LINEAR + QUADRATIC}
        for k, ratio in p.get('floor', {}).items():
            new[k] = np.maximum(new[k], out[k] * ratio)
        if p.get('noise'):
            new['line2'] = out['line2'] * new['mean2'] / np.maximum(out['mean2'], 1e-300)
        out.update(new)
    return out


def pseudo_twin(noise: dict, parts: Sequence[dict]) -> dict:
    """Observables of a pseudo-twin (``finish`` of ``combine``) and its scale."""
    raw = combine(noise, parts)
    return finish(raw), float(raw['scale'])
