"""
Frequency responses of the sensor's internal smoothing (``internal_lowpass``).

The filters the simulator applies and their squared gains, which the closed-form spectra use:
one definition of each, so the simulated and the expected output cannot drift apart.
"""
import numpy as np
from scipy import signal


def output_lowpass(corner_hz: float, order: int, dt: float) -> tuple:
    """(b, a) of the output-rate Butterworth low-pass (bilinear, corner ``corner_hz``)."""
    return signal.butter(int(order), corner_hz, fs=1.0 / dt)


def output_lowpass_gain2(f, corner_hz: float, order: int, dt: float) -> np.ndarray:
    """|G(f)|^2 of ``output_lowpass``: 1 / (1 + (tan(pi f dt) / tan(pi fc dt))^(2 order))."""
    f = np.abs(np.asarray(f, dtype=np.float64))
    ratio = np.tan(np.pi * np.minimum(f * dt, 0.5 - 1e-12)) / np.tan(np.pi * corner_hz * dt)
    return 1.0 / (1.0 + ratio ** (2 * int(order)))


def output_notch(notch_hz: float, q: float, dt: float) -> tuple:
    """(b, a) of the output-rate notch (second-order IIR band-stop, -3 dB width notch_hz / q)."""
    return signal.iirnotch(notch_hz, q, fs=1.0 / dt)


def output_notch_gain2(f, notch_hz: float, q: float, dt: float) -> np.ndarray:
    """|N(f)|^2 of ``output_notch`` at output frequencies ``f``."""
    b, a = output_notch(notch_hz, q, dt)
    z = np.exp(-2j * np.pi * np.asarray(f, dtype=np.float64) * dt)
    h = (b[0] + b[1] * z + b[2] * z * z) / (a[0] + a[1] * z + a[2] * z * z)
    return np.abs(h) ** 2


def interleaved_memory(memory: float, interleave: int) -> tuple:
    """
    (b, a) of an interleaved front end's memory: y_k = (1 - r) x_k + r y_(k-L).

    L converters (or sampling capacitors) take the samples in turn, and each keeps a share r
    of what it held at its last turn (incomplete reset): L interleaved one-poles, DC gain 1.
    """
    a = np.zeros(int(interleave) + 1)
    a[0], a[-1] = 1.0, -memory
    return np.array([1.0 - memory]), a


def interleaved_memory_gain2(f, memory: float, interleave: int, dt: float) -> np.ndarray:
    """|M(f)|^2 of ``interleaved_memory``: (1 - r)^2 / (1 - 2 r cos(2 pi f L dt) + r^2)."""
    r = float(memory)
    s = np.sin(np.pi * np.asarray(f, dtype=np.float64) * int(interleave) * dt)
    return (1.0 - r) ** 2 / ((1.0 - r) ** 2 + 4.0 * r * s * s)


def sense_response(f, split_hz: float, sense_hz: float) -> np.ndarray:
    """
    Complex rate response of a mode-split sense channel at frequencies ``f`` (Hz).

    H(s) = (g s + g^2 + w^2) / ((s + g)^2 + w^2), s = 2 pi i f, g = 2 pi sense_hz (the sense
    mode's half bandwidth), w = 2 pi split_hz (its offset from the drive): the demodulated
    response of an open-loop vibratory gyro operated mode-split, unity at DC. Applied in band
    as it is (the analog mode acts before the output is sampled).
    """
    s = 2j * np.pi * np.asarray(f, dtype=np.float64)
    g, w = 2.0 * np.pi * sense_hz, 2.0 * np.pi * split_hz
    k = g * g + w * w
    return (g * s + k) / ((s + g) ** 2 + w * w)


def sense_gain2(f, split_hz: float, sense_hz: float) -> np.ndarray:
    """|H(f)|^2 of ``sense_response``."""
    return np.abs(sense_response(f, split_hz, sense_hz)) ** 2
