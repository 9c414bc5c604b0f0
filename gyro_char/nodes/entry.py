"""
The node executables: stop-signal handlers first, then the node module's imports and ``main``.

Importing a node module (numpy, scipy, rclpy) takes seconds on a loaded machine; a SIGINT or
SIGTERM in that window would otherwise end the process with a traceback or by the signal.
The console scripts of ``setup.py`` point here so that ``STOP`` handles it from the start.
"""
from gyro_char.nodes.shutdown import STOP


def allan_node() -> int:
    """Run ``allan_node``."""
    STOP.install()
    from gyro_char.nodes.allan_node import main
    return main()


def swing_kf_node() -> int:
    """Run ``swing_kf_node``."""
    STOP.install()
    from gyro_char.nodes.swing_kf_node import main
    return main()


def bench_sim_node() -> int:
    """Run ``bench_sim_node``."""
    STOP.install()
    from gyro_char.nodes.bench_sim_node import main
    return main()
