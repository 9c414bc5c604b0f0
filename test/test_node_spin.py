# gyro_char.nodes.common.spin: a callback that raises is logged and the node keeps running
# (a live node must not die of one bad message or one bug), real rclpy, in-process context.
import threading
import time

from gyro_char.nodes.common import spin
from node_harness import DOMAINS, ros_context
import rclpy
from rclpy.executors import SingleThreadedExecutor


def test_a_failing_callback_is_logged_and_the_node_keeps_running(capfd):
    calls, errors = [], []
    with ros_context(DOMAINS['shutdown']) as context:
        node = rclpy.create_node('spin_probe', context=context)

        def tick():
            calls.append(time.monotonic())
            if len(calls) == 2:
                raise IndexError('boom in a timer')
        node.create_timer(0.02, tick)

        def run():
            try:
                spin(node, SingleThreadedExecutor(context=context))
            except Exception as exc:  # noqa: B902 - reported below
                errors.append(exc)
        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        deadline = time.monotonic() + 20.0
        while len(calls) < 6 and time.monotonic() < deadline:
            time.sleep(0.02)
        rclpy.try_shutdown(context=context)
        thread.join(timeout=10.0)
        node.destroy_node()
    assert len(calls) >= 6, 'the timer stopped after its callback raised'
    assert not thread.is_alive()
    assert all(type(e).__name__ == 'ExternalShutdownException' for e in errors), errors
    err = capfd.readouterr().err
    assert 'a callback failed (1 so far; the node keeps running)' in err
    assert 'boom in a timer' in err
