"""
rclpy glue shared by the nodes: parameter declaration with descriptors, QoS, executor.

Parameters are listed once as ``Param`` specs; ``declare`` turns them into descriptors (type,
description, range, ``read_only``) and ``check`` validates a value against its spec (range,
choices, finiteness) so that the node's on-set callback can refuse a value with a reason.
"""
from dataclasses import dataclass
import math
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Type

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from msg_adapters.diagnostics import diagnostic_array, diagnostic_status
from rcl_interfaces.msg import (
    FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult)
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.qos import (
    DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data, QoSProfile, ReliabilityPolicy)

try:  # Jazzy: much cheaper per message than SingleThreadedExecutor (measured in bench/).
    from rclpy.experimental import EventsExecutor
except ImportError:  # pragma: no cover - older rclpy
    EventsExecutor = None


class InvalidParameter(ValueError):
    """A parameter value that the node refuses (the message says why)."""


@dataclass
class Param:
    """One parameter: default, description and constraints."""

    name: str
    default: Any
    description: str
    read_only: bool = False
    low: Optional[float] = None
    high: Optional[float] = None
    choices: Optional[Sequence[str]] = None

    def descriptor(self) -> ParameterDescriptor:
        desc = ParameterDescriptor(name=self.name, description=self.description,
                                   read_only=self.read_only)
        if self.choices:
            desc.additional_constraints = 'one of: ' + ', '.join(self.choices)
        if self.low is not None and self.high is not None:
            if isinstance(self.default, float):
                desc.floating_point_range = [FloatingPointRange(
                    from_value=float(self.low), to_value=float(self.high), step=0.0)]
            elif isinstance(self.default, int) and not isinstance(self.default, bool):
                desc.integer_range = [IntegerRange(
                    from_value=int(self.low), to_value=int(self.high), step=1)]
        return desc

    def check(self, value: Any) -> Optional[str]:
        """Return why ``value`` is refused, or None when it is acceptable."""
        if isinstance(value, float) and not math.isfinite(value):
            return f'{self.name} must be finite, got {value}'
        if self.low is not None and value < self.low:
            return f'{self.name} must be >= {self.low:g}, got {value}'
        if self.high is not None and value > self.high:
            return f'{self.name} must be <= {self.high:g}, got {value}'
        if self.choices is not None and value not in self.choices:
            return f'{self.name} must be one of {list(self.choices)}, got {value!r}'
        return None


def declare(node: Any, specs: Iterable[Param]) -> Dict[str, Any]:
    """Declare every spec on ``node``; return the values in force (overrides applied)."""
    specs = list(specs)
    for spec in specs:
        node.declare_parameter(spec.name, spec.default, spec.descriptor())
    values = {s.name: node.get_parameter(s.name).value for s in specs}
    problems = [r for r in (s.check(values[s.name]) for s in specs) if r]
    if problems:
        raise InvalidParameter('; '.join(problems))
    return values


def validate(specs: Dict[str, Param], params: List[Any],
             cross_check=None, current: Optional[Dict[str, Any]] = None) -> SetParametersResult:
    """
    On-set callback body: check each changed parameter, then the combination.

    ``cross_check(values) -> reason or None`` sees the current values updated with the
    proposed ones, for constraints between parameters.
    """
    proposed = dict(current or {})
    for p in params:
        spec = specs.get(p.name)
        if spec is None:
            continue
        reason = spec.check(p.value)
        if reason:
            return SetParametersResult(successful=False, reason=reason)
        proposed[p.name] = p.value
    if cross_check is not None:
        reason = cross_check(proposed)
        if reason:
            return SetParametersResult(successful=False, reason=reason)
    return SetParametersResult(successful=True)


def sensor_qos(depth: int) -> QoSProfile:
    """
    Return ``qos_profile_sensor_data`` with a deeper history.

    Best effort and volatile like the stock profile, but depth 5 would overwrite samples of a
    1 kHz stream whenever the node spends more than 5 ms in a chunk, so the depth is a
    (read-only) parameter.
    """
    base = qos_profile_sensor_data
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=int(depth),
                      reliability=base.reliability, durability=base.durability)


RELIABLE_10 = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.VOLATILE)
LATCHED_1 = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                       reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)


def make_executor(context: Any = None) -> Any:
    """Return an EventsExecutor when rclpy has it, else the single-threaded one."""
    if EventsExecutor is not None:
        return EventsExecutor(context=context)
    return SingleThreadedExecutor(context=context)


def spin(node: Any, executor: Any = None) -> None:
    """
    Spin ``node`` until its context shuts down (the body of the Jazzy ``rclpy.spin`` idiom).

    ``rclpy.spin`` calls ``spin_once()`` without a timeout, and Jazzy's EventsExecutor turns
    that (and its own ``spin()``) into a busy loop that also ignores Ctrl-C (measured: ~40 % of
    a core while idle). ``spin_once`` with a timeout sleeps properly and lets SIGINT through.
    """
    executor = executor or make_executor(node.context)
    executor.add_node(node)
    try:
        while node.context.ok():
            executor.spin_once(timeout_sec=0.2)
    finally:
        executor.remove_node(node)


def publish_status(node: Any, publisher: Any, name: str, level: int, message: str,
                   hardware_id: str, values: Dict[str, Any]) -> None:
    """Publish one DiagnosticStatus (numeric/string ``values``) as a DiagnosticArray now."""
    status = diagnostic_status(DiagnosticStatus, KeyValue, name, level, message, hardware_id,
                               values)
    publisher.publish(diagnostic_array(DiagnosticArray, node.get_clock().now().to_msg(),
                                       [status]))


def publish_input_health(node: Any, name: str) -> None:
    """Publish ``node.health_status()`` as the ``<name>: inputs`` status on ``node.diag_pub``."""
    level, message, values = node.health_status()
    publish_status(node, node.diag_pub, f'{name}: inputs', level, message,
                   node.p['hardware_id'], values)


def run_node(factory: Callable[[], Any], name: str,
             errors: Tuple[Type[BaseException], ...] = (InvalidParameter,),
             error_prefix: str = 'invalid parameter: ', spin_fn: Callable[[Any], None] = spin,
             on_exit: Optional[Callable[[Any], None]] = None, args=None) -> int:
    """
    Run one node the Jazzy way: init, spin until Ctrl-C or shutdown, tear down; the exit code.

    ``errors`` raised while building or spinning the node (a refused parameter, a bad config)
    print one line ``<name>: <error_prefix><error>`` and give exit code 2. ``on_exit(node)``
    runs before the node is destroyed (e.g. a last checkpoint).
    """
    rclpy.init(args=args)
    node = None
    try:
        node = factory()
        spin_fn(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except errors as exc:
        print(f'{name}: {error_prefix}{exc}', flush=True)
        return 2
    finally:
        if node is not None:
            if on_exit is not None:
                on_exit(node)
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


def split_at_markers(items: Sequence[Tuple]) -> List[List[Tuple]]:
    """Split drained queue items at ``None`` markers (segment restarts) into runs."""
    runs, current = [], []
    for item in items:
        if item is None:
            runs.append(current)
            current = []
        else:
            current.append(item)
    runs.append(current)
    return runs
