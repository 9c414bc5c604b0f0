"""Write the files of an Allan analysis: allan.json, noise.json, imu.yaml and allan.png."""
import json
import os

from gyro_char.allan.outputs import allan_json, kalibr_yaml, noise_json
from gyro_char.report.allan_plot import plot_allan


def write_outputs(out: str, res, fits, topic: str, title: str = '') -> None:
    """Write allan.json, noise.json, imu.yaml and allan.png in ``out`` (the CLI and allan_node)."""
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, 'allan.json'), 'w') as fh:
        json.dump(allan_json(res, fits), fh)
    with open(os.path.join(out, 'noise.json'), 'w') as fh:
        json.dump(noise_json(fits, res.spikes), fh, indent=2)
    with open(os.path.join(out, 'imu.yaml'), 'w') as fh:
        fh.write(kalibr_yaml(fits, 1.0 / res.dt, topic))
    plot_allan(res, fits, os.path.join(out, 'allan.png'), title=title)
