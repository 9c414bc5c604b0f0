"""
IEEE Std 952 / 1554 noise terms: closed-form Allan variance per term, units, Kalibr mapping.

Formula (4) of docs/method.md:
    sigma^2(tau) = R^2 tau^2 / 2 + K^2 tau / 3 + B^2 (2/pi) ln2 + N^2 / tau + 3 Q^2 / tau^2
All coefficients are the IEEE ones in SI (B's flat floor on the sigma plot is 0.664 B).
"""
from typing import Dict

import numpy as np

TERMS = ('R', 'K', 'B', 'N', 'Q')

# Allan-variance coefficient of each term's squared IEEE coefficient, and the power of tau:
# sigma^2 = sum_t COEF[t] * X_t^2 * tau^POWER[t].
AVAR_COEF = {'R': 0.5, 'K': 1.0 / 3.0, 'B': 2.0 * np.log(2.0) / np.pi, 'N': 1.0, 'Q': 3.0}
AVAR_POWER = {'R': 2, 'K': 1, 'B': 0, 'N': -1, 'Q': -2}
# Slope of sigma(tau) on the log-log plot.
ADEV_SLOPE = {t: AVAR_POWER[t] / 2.0 for t in TERMS}
# Power-law noise exponent alpha of the rate (S_y(f) ~ f^alpha) dominated by each term; used to
# pick the Greenhall EDF. The ramp is deterministic; its estimator behaves like random walk.
ALPHA = {'R': -2, 'K': -2, 'B': -1, 'N': 0, 'Q': 2}
FLOOR_FACTOR = float(np.sqrt(AVAR_COEF['B']))  # 0.664


def term_avar(term: str, tau, value: float) -> np.ndarray:
    """Allan variance of one term with IEEE coefficient ``value`` at ``tau`` (s)."""
    tau = np.asarray(tau, dtype=np.float64)
    return AVAR_COEF[term] * value ** 2 * tau ** AVAR_POWER[term]


def model_avar(tau, coeffs: Dict[str, float]) -> np.ndarray:
    """Return formula (4): total Allan variance of ``coeffs`` (missing terms are 0)."""
    tau = np.asarray(tau, dtype=np.float64)
    total = np.zeros_like(tau)
    for term in TERMS:
        total = total + term_avar(term, tau, coeffs.get(term, 0.0))
    return total


def design_matrix(tau) -> np.ndarray:
    """Return A with sigma^2 = A @ [R^2, K^2, B^2, N^2, Q^2] (columns in TERMS order)."""
    tau = np.asarray(tau, dtype=np.float64)
    return np.stack([AVAR_COEF[t] * tau ** AVAR_POWER[t] for t in TERMS], axis=-1)


def kalibr_values(coeffs_by_channel: Dict[str, Dict[str, float]]) -> Dict[str, float]:
    """
    Kalibr / OpenVINS imu.yaml noise entries from per-channel IEEE coefficients.

    Kalibr's continuous-time ``*_noise_density`` is the white-noise density = N (rad/s/sqrt(Hz)
    = rad/sqrt(s)), and ``*_random_walk`` is the bias random-walk density = K (rad/s^2/sqrt(Hz)).
    Per sensor the worst (largest) axis is used, as Kalibr takes one value per sensor.
    """
    out = {}
    for kind, prefix in (('gyro', 'gyroscope'), ('accel', 'accelerometer')):
        chans = [c for c in coeffs_by_channel if c.startswith(kind + '_')]
        if not chans:
            continue
        out[f'{prefix}_noise_density'] = max(coeffs_by_channel[c]['N'] for c in chans)
        out[f'{prefix}_random_walk'] = max(coeffs_by_channel[c]['K'] for c in chans)
    return out
