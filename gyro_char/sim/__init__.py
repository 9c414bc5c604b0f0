"""
The bench simulator: the paper's swing stand and sensor model, plus the effect catalogue.

``presets`` and ``config`` (the sensor classes and their overrides), ``chain`` (stand motion,
encoder, quantizers), ``noise_gen`` (IEEE 952 noise with a known Allan variance), ``effects``
(unmodelled effects added at fixed stages), ``simulator`` (static and swing runs with their
truth), ``monte_carlo`` (the paper's study of the method's own error).
"""
from gyro_char.sim.config import BenchConfig, load
from gyro_char.sim.simulator import simulate_static, simulate_swing

__all__ = ['BenchConfig', 'load', 'simulate_static', 'simulate_swing']
