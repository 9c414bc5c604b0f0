"""
Data-driven starting values for the searches of correlated noise processes.

A Gauss-Markov process trades its strength against its correlation time along a curved valley
of the gap, which a coordinate search from the middle of both ranges (five decades each) can
leave at a corner: a second-order process of a third the correlation time instead of the
first-order one that is there. The record's own Allan variance in excess of the white noise
shows where the valley's bottom is: the first-order curve that best follows that excess, in
log, is where the search starts (it is still searched: the start only places the grid).
Likewise an angle read once a frame (``frame_start``): the frame from the PSD's comb of nulls.
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


# Frames tried for an angle read once a frame (at least two nulls inside the band), how far
# below its neighbours the PSD must sit at the frame's nulls, and their half width as a share
# of the frame rate.
FRAMES = np.arange(5, 65)
NULL_DEPTH = 0.6
NULL_WIDTH = 0.02


def frame_start(psd, dt: float):
    """
    Start (step_rad, frame, floor) of a quantization read once a frame, or None.

    An angle error held for M samples is differenced once a frame: its PSD vanishes at every
    multiple of the frame rate 1 / (M dt), a comb of nulls (wide when the error is white from
    frame to frame, narrow when a coarse step keeps it correlated). For each M the PSD's
    median near the nulls inside the band is compared, null by null, to the lower of the
    medians midway either side (a slope or a mode is not below both of its neighbours); the
    largest M whose nulls all lie ``NULL_DEPTH`` below is kept (M's divisors share its
    nulls). ``floor``: the PSD's median near those nulls, where the read-out adds nothing.
    The step from the level midway (an error white across frames: 8 var sin^2 / (M dt)).
    """
    f, p = psd
    df = f[1] - f[0] if f.size > 1 else 0.0
    found = None
    for m in FRAMES:
        rate = 1.0 / (m * dt)
        half = max(NULL_WIDTH * rate, 1.5 * df)

        def near(c):
            sel = np.abs(f - c) <= half
            return float(np.median(p[sel])) if sel.any() else np.nan
        k = np.arange(1, (m + 1) // 2)                 # nulls with a midpoint either side
        nulls = np.array([near(c) for c in k * rate])
        mids = np.array([near(c) for c in (np.r_[k, k[-1] + 1] - 0.5) * rate])
        if k.size < 2 or not np.all(np.isfinite(nulls)) or not np.all(np.isfinite(mids)):
            continue
        ratio = nulls / np.minimum(mids[:-1], mids[1:])
        if np.all(ratio < NULL_DEPTH):
            found = (int(m), float(np.median(nulls)), float(np.median(mids)))
    if found is None:
        return None
    m, floor, mid = found
    return float(np.sqrt(12.0 * max(mid - floor, 0.0) * m * dt / 8.0)), m, floor
