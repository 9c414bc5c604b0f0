"""
Sim-to-real diagnosis: where a record departs from the paper's model, and which effect explains it.

``engine`` (the greedy search and its scoring), ``gap`` (the gap metric and its null),
``fit`` (fitting one effect's parameters), ``observables`` (static observables), ``static`` and
``swing`` (the two kinds: baselines, twins, search spaces), ``swing_residuals`` / ``swing_obs`` /
``swing_spaces`` / ``swing_speed_gate`` / ``swing_baseline`` (the swing kind's parts),
``twins`` (helpers shared by both kinds).
"""
