"""
Allan results in message form, duck-typed: the curve as a labelled array, a fit as KeyValues.

The unit of each noise term lives in its key (``N_rad_sqrt_s``), as in ``noise.json``; the 68 %
interval and whether the term is resolved ride along, so a dashboard reads one status per channel.
"""
import math
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

CURVE_QUANTITIES = ('tau_s', 'adev', 'adev_lo', 'adev_hi')
# Key suffixes of the SI units of noise.json, gyro then accel.
UNIT_KEYS = {
    'gyro': {'N': 'rad_sqrt_s', 'B': 'rad_s', 'K': 'rad_s_sqrt_s', 'Q': 'rad', 'R': 'rad_s2'},
    'accel': {'N': 'm_s_sqrt_s', 'B': 'm_s2', 'K': 'm_s2_sqrt_s', 'Q': 'm_s', 'R': 'm_s3'},
}


def curve_array(res: Any) -> Tuple[np.ndarray, List[Tuple[str, Optional[List[str]]]]]:
    """Return the curve as (channel, quantity, tau) data and its dimension labels."""
    data = np.stack([np.stack([res.tau, res.adev[:, c], res.adev_lo[:, c],
                               res.adev_hi[:, c]]) for c in range(len(res.channels))])
    return data, [('channel', list(res.channels)), ('quantity', list(CURVE_QUANTITIES)),
                  ('tau_index', None)]


def record_values(res: Any) -> Dict[str, Any]:
    """Return what every channel's status says about the record: samples, duration, tau_max."""
    return {'samples': res.n_samples, 'duration_s': res.n_samples * res.dt,
            'tau_max_s': float(res.tau[-1])}


def fit_values(fit: Any) -> Dict[str, Any]:
    """Return N, B, K, Q, R of one channel's fit with their 68 % intervals, units in the keys."""
    units = UNIT_KEYS[fit.kind]
    values: Dict[str, Any] = {}
    for term in ('N', 'B', 'K', 'Q', 'R'):
        est = fit.terms[term]
        lo, hi = est.ci68 if est.ci68 is not None else (math.nan, math.nan)
        values[f'{term}_{units[term]}'] = est.value
        values[f'{term}_lo_{units[term]}'] = lo
        values[f'{term}_hi_{units[term]}'] = hi
        values[f'{term}_resolved'] = bool(est.resolved)
    return values
