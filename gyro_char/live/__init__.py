"""
Streaming front ends of the nodes, free of rclpy: what the nodes wire to topics and services.

``allan_live`` (static accumulation with motion detection), ``swing_online`` (the live swing
filter), ``convergence`` (when its estimates count as converged), ``stream_health``
(per-stream counters), ``status`` (the /diagnostics input-health report), ``checkpoint``
(periodic state on disk), ``motion_detect``.
"""
