"""Small simulated fleets for the fleet tests: the bench simulator's records, written to disk."""
import gzip
import shutil

from gyro_char.io import write_bag
from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_static
from gyro_char.units import DEG
import numpy as np

CHANNELS = ('gyro_x', 'gyro_y', 'gyro_z')


def static_recording(n_deg_rt_h: float, b_deg_h: float, seed: int, duration: float,
                     rate_hz: float = 50.0):
    """Simulate a static record whose three gyros have white noise N and bias instability B."""
    noise = {c: {'N': n_deg_rt_h * DEG / 60.0, 'B': b_deg_h * DEG / 3600.0, 'K': 0.0,
                 'Q': 0.0, 'R': 0.0} for c in CHANNELS}
    cfg = load(overrides={'gyro': {'static_rate_hz': rate_hz, 'output_step': 0.0},
                          'noise': noise})
    return simulate_static(cfg, duration=duration, seed=seed, channels=CHANNELS).imu


def write_csv(path, rec, compress: bool = False) -> str:
    """Write the CSV contract of docs/design.md section 3 (optionally gzipped)."""
    cols = ['t_s'] + [f'{c}_rads' for c in rec.channels]
    data = np.column_stack([rec.t] + [rec.channels[c] for c in rec.channels])
    lines = [','.join(cols)] + [','.join(repr(float(v)) for v in row) for row in data]
    text = '\n'.join(lines) + '\n'
    if compress:
        with gzip.open(path, 'wt') as fh:
            fh.write(text)
    else:
        path.write_text(text)
    return str(path)


def write_mcap_file(path, rec, scratch) -> str:
    """Write a lone ``.mcap`` file (the one file of a ROS 2 bag directory)."""
    write_bag(str(scratch), rec)
    shutil.copy(next(scratch.glob('*.mcap')), path)
    return str(path)
