"""
A gyro noise whose size follows the rate: its search forms and what it does to a twin's N.

Three forms (``sim.effects.motion.rate_noise_level``): a white scale-factor noise, extra
noise of density sf_noise |w| (a noisy reference or drive gain); the same on negative rates
only (``scale_factor_asymmetry``: one driver half noisier); and a noisier range switched in
above a rate (``gate_noise`` above ``noise_gate_rads``: an auto-ranging front end, a
crossfade to a high-range channel). A stamp error also turns rate into noise (rate x error,
in the angle), but its angle error is white where this one's is a random walk, and its
size follows the rate's magnitude only, not a gate or a sign.

The swing baseline's N is pinned on the record's residual PSD (``swing_calibrate``), which
such a noise raises by its mean power over the swing: a twin that adds it must start from N²
less that mean (``rate_noise_gain``), or it counts the noise twice.
"""
from dataclasses import replace
from typing import List, Optional, Sequence

from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.swing_baseline import SwingBaseline
from gyro_char.sim.effects.motion import rate_noise_level
import numpy as np

NOISE_PARAMS = ('sf_noise', 'gate_noise')
NOISE_KEYS = {'scale_factor_nonlinearity': ('sf_noise', 'gate_noise', 'noise_gate_rads'),
              'scale_factor_asymmetry': ('sf_noise',)}
NAMES = tuple(NOISE_KEYS)
# The plain forms' parameters at 0 beside a noise alone (their catalogue defaults are not).
PLAIN_OFF = {'scale_factor_nonlinearity': {'k2': 0.0}, 'scale_factor_asymmetry': {'a': 0.0}}
LEVEL = (0.05, 50.0)     # extra density at the peak rate searched, in units of the gyro's N
GATE = (0.05, 0.95)      # gate searched, fractions of the smallest / largest peak rate
GAIN_FLOOR = 0.05        # a twin keeps at least this share of the baseline's white power
GAIN = (1e-4, 0.1)       # a switched range's own scale-factor change searched (magnitude)
PHASES = 4096            # points of the swing phase the mean power is taken over


def is_rate_noise(fx: dict) -> bool:
    """Return True if a simulator spec carries a rate-dependent noise."""
    return fx['name'] in NAMES and any(float(fx['params'].get(k, 0.0)) for k in NOISE_PARAMS)


def split(fx: dict) -> tuple:
    """
    Return (deterministic part, noise part) of a spec, either None where absent.

    The noise part keeps only the noise's parameters, the plain form's off: a pseudo-twin
    takes its quadratic parts from unit runs (``swing_expect.EffectParts._rate_noise``), the
    deterministic part from the noise-free difference as any other.
    """
    if not is_rate_noise(fx):
        return fx, None
    keys = NOISE_KEYS[fx['name']]
    noise = {**PLAIN_OFF[fx['name']], **{k: float(fx['params'].get(k, 0.0)) for k in keys}}
    # The gate serves the noise and the deterministic gain above it alike.
    rest = {k: v for k, v in fx['params'].items() if k not in keys or k == 'noise_gate_rads'}
    if not float(rest.get('gate_gain', 0.0)):
        rest.pop('noise_gate_rads', None)
    det = {'name': fx['name'], 'params': rest} if _acts(fx['name'], rest) else None
    return det, {'name': fx['name'], 'params': noise}


def _acts(name: str, params: dict) -> bool:
    # Whether the spec without its noise still does something: a parameter other than the
    # plain one non-zero, or the plain one, counted at its catalogue default when not given.
    plain = next(iter(PLAIN_OFF[name]))
    return bool(float(params.get(plain, 1.0))) or any(
        float(v) for k, v in params.items() if k != plain)


def mean_power(fx: dict, base: SwingBaseline) -> float:
    """Return the noise's density squared averaged over the swing (rad²/s² per Hz)."""
    theta = (np.arange(PHASES) + 0.5) * 2.0 * np.pi / PHASES
    w = base.peak_rate * np.cos(theta)
    level = rate_noise_level(fx['params'], w, one_sided=fx['name'] == 'scale_factor_asymmetry')
    return 0.0 if level is None else float(np.mean(level ** 2))


def rate_noise_gain(effects: Sequence[dict], base: SwingBaseline) -> float:
    """
    Return the share of the baseline's gyro white power a twin with ``effects`` keeps.

    1 - (the noises' mean power) / N², at least ``GAIN_FLOOR`` (module docstring).
    """
    extra = sum(mean_power(fx, base) for fx in effects if is_rate_noise(fx))
    if not extra:
        return 1.0
    return float(max(1.0 - extra / max(base.N, 1e-300) ** 2, GAIN_FLOOR))


def with_rate_noise(spaces: List[EffectSpace],
                    bases: Sequence[SwingBaseline]) -> List[EffectSpace]:
    """
    Give the two scale-factor effects their rate-dependent noise as further forms.

    The level from a twentieth to fifty times the gyro's N at the peak rate (below, the
    noise raises no rate bin by a sample's spread on 15 minutes; above, it is no longer a
    share of the white noise the baseline pinned); the gate from a twentieth of the
    smallest peak rate to 95 % of the largest; a switched range's own gain change from
    none up to 10 %, either sign (a range switch: its own noise and gain).
    """
    n = min(b.N for b in bases)
    peaks = [b.peak_rate for b in bases]
    w = max(peaks)
    sf = Param('sf_noise', LEVEL[0] * n / w, LEVEL[1] * n / w)
    gate = [Param('gate_noise', LEVEL[0] * n, LEVEL[1] * n),
            Param('noise_gate_rads', GATE[0] * min(peaks), GATE[1] * w, log=False)]
    # The switched range's gain, either sign, searched from none (the gated noise alone).
    switch = tuple(EffectSpace('scale_factor_nonlinearity', gate + [
        Param('gate_gain', GAIN[0], GAIN[1], sign=sign, off_at='lo')],
        fixed={'k2': 0.0}, passes=2) for sign in (1.0, -1.0))
    forms = {
        'scale_factor_nonlinearity': (
            EffectSpace('scale_factor_nonlinearity', [sf], fixed={'k2': 0.0}),) + switch,
        'scale_factor_asymmetry': (
            EffectSpace('scale_factor_asymmetry', [sf], fixed={'a': 0.0}),),
    }
    return [replace(sp, alternatives=tuple(sp.alternatives) + forms[sp.name])
            if sp.name in forms else sp for sp in spaces]


def unit_level(name: str, base: SwingBaseline, gated: bool) -> dict:
    """Return a unit run's noise parameters: 1e-3 rad/s/sqrt(Hz) at the peak rate."""
    if gated:
        return {'gate_noise': 1e-3}
    return {'sf_noise': 1e-3 / base.peak_rate}


def gate_grid(base: SwingBaseline, points: int = 17) -> np.ndarray:
    """Return the gates a gated noise's unit runs are made at: 0 to the peak rate."""
    return np.linspace(0.0, base.peak_rate, points)


def gate_weights(gate: float, grid: np.ndarray) -> Optional[tuple]:
    """Return (k, f): ``gate`` between grid points k and k + 1, f of the way; None beyond."""
    if gate >= grid[-1]:
        return None
    k = int(np.clip(np.searchsorted(grid, gate) - 1, 0, grid.size - 2))
    return k, float((gate - grid[k]) / (grid[k + 1] - grid[k]))
