"""
Data-driven starting values for the searches of correlated noise processes.

A Gauss-Markov process trades its strength against its correlation time along a curved valley
of the gap, which a coordinate search from the middle of both ranges (five decades each) can
leave at a corner: a second-order process of a third the correlation time instead of the
first-order one that is there. The record's own Allan variance in excess of the white noise
shows where the valley's bottom is: the first-order curve that best follows that excess, in
log, is where the search starts (it is still searched: the start only places the grid).
"""
from gyro_char.allan.expected import markov_avar
from gyro_char.diagnosis import observables as obs
import numpy as np

GRID = 64  # correlation times and strengths tried, log-spaced


def markov_start(y: np.ndarray, dt: float, n_white: float, tau_lo: float, tau_hi: float,
                 sigma_lo: float, sigma_hi: float):
    """
    Start (sigma, tau_s) of a Gauss-Markov search, or None where the record shows no excess.

    The first-order process that best explains the record's Allan variance above the white
    noise ``n_white`` (rad/sqrt(s)); None where no octave stands 4 sds above it.

    The misfit is the log Allan variance's, each octave weighted by its estimate's relative
    spread (~ sqrt(m / n) for white noise).
    """
    m = obs.octave_m(y.size)
    tau = m * dt
    real = obs.overlapping_adev(y, m, dt) ** 2
    white = n_white ** 2 / tau
    # Overlapping Allan variance of white noise: relative sd ~ sqrt(4 m / (3 n)).
    if not np.any(real / white - 1.0 > 4.0 * np.sqrt(4.0 * m / (3.0 * y.size))):
        return None
    w = 1.0 / np.sqrt(m)
    tcs = np.geomspace(tau_lo, tau_hi, GRID)
    sig2 = np.geomspace(sigma_lo, sigma_hi, GRID) ** 2
    # shape[tc, tau]: Allan variance of a unit-variance process (q^2 = 2 sigma^2 / tc).
    shape = np.array([markov_avar(tau, tc) * 2.0 / tc for tc in tcs])
    model = white[None, None, :] + sig2[None, :, None] * shape[:, None, :]
    cost = np.sum((w * np.log(model / real)) ** 2, axis=2)
    i, j = np.unravel_index(int(np.argmin(cost)), cost.shape)
    return float(np.sqrt(sig2[j])), float(tcs[i])
