"""Helpers every kind of the diagnosis uses to build twins: output step, axis row, effect specs."""
from typing import Optional, Sequence

from gyro_char.records import GYRO_CHANNELS
from gyro_char.sim.effects import EFFECTS
import numpy as np


def output_step(x: np.ndarray) -> float:
    """
    Return the record's quantization step (0 when it is not quantized).

    A quantized output takes values on a grid: every difference between distinct values is a
    whole multiple of the smallest one.
    """
    u = np.unique(x)
    if u.size < 3 or u.size > x.size // 4:
        return 0.0
    d = np.diff(u)
    step = float(np.min(d))
    if step <= 0:
        return 0.0
    k = d / step
    return step if np.all(np.abs(k - np.round(k)) < 1e-3) else 0.0


def channel_row(channel: str) -> int:
    """Row (0, 1, 2 = x, y, z) of a gyro channel; 0 for any other channel."""
    return GYRO_CHANNELS.index(channel) if channel in GYRO_CHANNELS else 0


def twin_effects(effects: Sequence, channel: Optional[str] = None) -> list:
    """
    Catalogue effect specs for a twin: never on the accelerometers.

    With ``channel`` the effect acts on that gyro axis only; without, its ``axis`` is kept.
    """
    out = []
    for name, params in effects:
        params = dict(params)
        if channel is not None and 'axis' in EFFECTS[name].PARAMS:
            params['axis'] = float(channel_row(channel))
        if 'accel' in EFFECTS[name].PARAMS:
            params['accel'] = 0.0
        out.append({'name': name, 'params': params})
    return out
