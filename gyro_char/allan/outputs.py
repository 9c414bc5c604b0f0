"""
The text outputs of an Allan analysis: ``allan.json`` and Kalibr's ``imu.yaml``.

Both the ``gyro-char allan`` command and ``allan_node`` write them (through
``gyro_char.report.allan_outputs.write_outputs``), so the two front doors give the same files.
"""
from gyro_char.units import RATE_UNITS, sensor_kind, SI_UNITS
import numpy as np


def allan_json(res, fits=None) -> dict:
    """
    Return allan.json (docs/design.md) of an ``AllanResult`` with intervals.

    ``fits`` ({channel: NoiseFit}) adds ``adev_fit``: the fitted model (every selected term,
    sensor filter and Markov terms included) at every tau; null for a channel without a fit.
    """
    out = {}
    for c, name in enumerate(res.channels):
        out[name] = {'tau_s': res.tau.tolist(), 'adev': res.adev[:, c].tolist(),
                     'adev_lo': res.adev_lo[:, c].tolist(),
                     'adev_hi': res.adev_hi[:, c].tolist(),
                     'unit': RATE_UNITS[sensor_kind(name)]}
        if fits is not None:
            fit = fits.get(name)
            out[name]['adev_fit'] = (None if fit is None
                                     else np.sqrt(fit.model_avar(res.tau)).tolist())
    return {'channels': out}


def noise_json(fits, spikes=None) -> dict:
    """
    Return noise.json (docs/design.md): N, B, K, Q, R per channel, plus extra fields.

    Extra fields of a channel: ``sensor_filter`` (the filter the fit used), ``markov`` (the
    selected Markov terms) and, when ``spikes`` ({channel: SpikeReport}) is given, ``spikes``.
    """
    out = {}
    for name, fit in fits.items():
        out[name] = {**fit.to_json(), **fit.extra_json()}
        rep = (spikes or {}).get(name)
        if rep is not None:
            out[name]['spikes'] = rep.to_json(RATE_UNITS[fit.kind], SI_UNITS[fit.kind]['N'])
    return {'channels': out}


def kalibr_yaml(fits, rate_hz: float, topic: str) -> str:
    """Return Kalibr's imu.yaml text (worst axis in the standard keys, per-axis extras)."""
    lines = ['# IMU noise model from gyro-char allan (IEEE 952 fit of the Allan variance).',
             '# Continuous time: *_noise_density = N (white noise), *_random_walk = K (bias',
             '# random walk). Standard keys hold the worst axis; the *_xyz lists are per axis.',
             f'rostopic: {topic}', f'update_rate: {rate_hz:.6g}']
    for kind, prefix, units in (('accel', 'accelerometer', ('m/s^2/sqrt(Hz)', 'm/s^3/sqrt(Hz)')),
                                ('gyro', 'gyroscope', ('rad/s/sqrt(Hz)', 'rad/s^2/sqrt(Hz)'))):
        names = [n for n in fits if fits[n].kind == kind]
        if not names:
            continue
        for term, key, unit in (('N', 'noise_density', units[0]), ('K', 'random_walk', units[1])):
            values = [fits[n].terms[term].value for n in names]
            bound = [n for n in names if not fits[n].terms[term].resolved]
            note = f'  # [{unit}]' + (f'; upper bound for {",".join(bound)}' if bound else '')
            lines.append(f'{prefix}_{key}: {max(values):.6e}{note}')
            lines.append(f'{prefix}_{key}_xyz: [' + ', '.join(f'{v:.6e}' for v in values)
                         + f']  # {",".join(names)}')
    return '\n'.join(lines) + '\n'
