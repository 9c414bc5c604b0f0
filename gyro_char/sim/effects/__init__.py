"""
Unmodelled effects as composable additions to the bench simulator.

``base`` holds the hook contract (``Effect``, ``SimContext``) and the registry ``EFFECTS``;
``motion``, ``readout``, ``sensor``, ``timing`` and ``vibration`` hold the implementations,
which register themselves on import (``responses``: the smoothing filters' frequency
responses); ``catalogue`` builds effects from the CLI syntax ``NAME[:k=v,...]`` or dicts.
"""
# The implementations register themselves in EFFECTS on import.
from gyro_char.sim.effects import motion, readout, sensor, timing, vibration  # noqa: F401
from gyro_char.sim.effects.base import Effect, EFFECTS, register, SimContext
from gyro_char.sim.effects.catalogue import build_effects, catalogue, parse_effect

__all__ = ['build_effects', 'catalogue', 'Effect', 'EFFECTS', 'parse_effect', 'register',
           'SimContext']
