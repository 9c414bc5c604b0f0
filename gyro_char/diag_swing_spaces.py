"""
Search spaces of the swing diagnosis's candidate effects, scaled to the fitted record.

Bounds come from the record's own noise (what an effect must reach to be seen); signed
parameters get the sign that moves the twins towards the record (``signs``).
"""
from typing import Callable, List, Sequence, TYPE_CHECKING

from gyro_char.diag_fit import EffectSpace, Param
import numpy as np

if TYPE_CHECKING:  # diag_swing imports this module
    from gyro_char.diag_swing import SwingBaseline

G0 = 9.80665


def swing_spaces(base: 'SwingBaseline') -> List[EffectSpace]:
    """Search spaces scaled to the record (sign of signed parameters set by ``_signs``)."""
    w = 2.0 * np.pi / base.period_s
    rate = base.amplitude * w                       # peak swing rate, rad/s
    sig = base.N / np.sqrt(base.duration)           # rate noise averaged over the record
    # Quadrature noise of the angle residual at the swing frequency (random-walk angle of PSD
    # N^2 / w^2 projected over the record): a delay and a g-sensitivity are searched over
    # the same span of quadrature amplitudes, so neither is favoured by its grid.
    q = base.N / w * np.sqrt(2.0 / base.duration)
    return [
        EffectSpace('time_delay', [Param('delay_s', 0.5 * q / rate, 200.0 * q / rate)]),
        EffectSpace('g_sensitivity', [Param('gy', 0.5 * q * w / (G0 * base.amplitude),
                                            200.0 * q * w / (G0 * base.amplitude))]),
        EffectSpace('scale_factor_nonlinearity', [
            Param('k2', 0.03 * sig / rate ** 2, 300.0 * sig / rate ** 2),
            Param('k3', 0.03 * sig / rate ** 3, 300.0 * sig / rate ** 3)]),
        EffectSpace('scale_factor_asymmetry', [Param('a', 0.03 * sig / rate,
                                                     300.0 * sig / rate)]),
        EffectSpace('encoder_cyclic_error', [Param('a1', 0.1 * base.encoder_sigma + 1e-9,
                                                   30.0 * base.encoder_sigma + 1e-7)],
                    fixed={'a2': 0.0}),
        # Both streams: an IMU stamp error alone leaves no first-order trace here (the gyro
        # angle and the encoder read at the same wrong stamp move together); an encoder
        # stamp error shows as residual angle noise rate x error.
        EffectSpace('timestamp_jitter', [Param('sigma_s', 0.01 * base.encoder_dt,
                                               0.4 * base.encoder_dt)],
                    fixed={'stream': 2.0}),
    ]


SIGNED = {'time_delay': ['delay_s'], 'g_sensitivity': ['gy'],
          'scale_factor_nonlinearity': ['k2', 'k3'], 'scale_factor_asymmetry': ['a']}


def signs(spaces: List[EffectSpace], reals: Sequence[dict],
          simulate: Callable[[int, list, int], dict]) -> List[EffectSpace]:
    """
    Give each signed parameter the sign that moves the twins towards the record.

    A probe twin with the parameter at its range's geometric middle, against a baseline twin
    of the same seed (common random numbers: the difference is the effect alone), gives the
    effect's response on the harmonic blocks; its projection on the record's departure from
    the baseline twin gives the sign. With several records (``simulate(record, effects, seed)``
    as in ``diagnose.Problem``) the departures of all of them are projected together.
    """
    blocks = ('in_phase', 'quadrature', 'harmonic_2f', 'harmonic_3f')
    idx = range(len(reals))
    base = [simulate(i, [], 4242) for i in idx]
    dev = np.concatenate([reals[i][b] - base[i][b] for i in idx for b in blocks])
    out = []
    for sp in spaces:
        params = []
        for p in sp.params:
            if p.name in SIGNED.get(sp.name, []):
                fx = [(sp.name, {**sp.fixed, p.name: float(np.sqrt(p.lo * p.hi))})]
                probe = [simulate(i, fx, 4242) for i in idx]
                resp = np.concatenate([probe[i][b] - base[i][b] for i in idx for b in blocks])
                sign = 1.0 if float(np.einsum('i,i->', resp, dev)) >= 0 else -1.0
                p = Param(p.name, p.lo, p.hi, p.log, p.integer, sign)
            params.append(p)
        out.append(EffectSpace(sp.name, params, dict(sp.fixed), dict(sp.start)))
    return out
