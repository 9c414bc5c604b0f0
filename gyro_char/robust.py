"""Robust statistics shared by the core: the standard deviation read from the median deviation."""
import numpy as np

# sd / MAD of a Gaussian: 1 / Phi^-1(3/4).
MAD_TO_SD = 1.4826


def robust_sd(x, axis=None):
    """
    Return 1.4826 x the median absolute deviation of ``x`` (along ``axis``).

    The Gaussian standard deviation, unmoved by a few outliers (spikes, moved devices, motion).
    """
    x = np.asarray(x, dtype=np.float64)
    med = np.median(x, axis=axis, keepdims=axis is not None)
    return MAD_TO_SD * np.median(np.abs(x - med), axis=axis)
