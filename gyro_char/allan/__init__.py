"""
Allan variance and the IEEE 952 noise model.

``kernel`` (overlapping Allan variance on log-spaced taus), ``edf`` (equivalent degrees of
freedom and intervals), ``compute`` (a ``Recording`` to an ``AllanResult``), ``stream`` (the
bounded-memory accumulator), ``model`` (formula (4) per term), ``expected`` (exact Allan
variances from an autocovariance: FIR + decimation, Markov), ``sensor_filter`` (the sensor's
output filter: specs and ``auto``), ``spikes`` (impulsive outliers), ``design``, ``solvers``,
``selection``, ``markov`` and ``fit`` (the non-negative log-domain fit with term selection),
``outputs`` (allan.json, noise.json, Kalibr imu.yaml).
"""
from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result, NoiseFit
from gyro_char.allan.kernel import AllanResult

__all__ = ['AllanResult', 'compute', 'fit_result', 'NoiseFit']
