"""
rclpy glue shared by the nodes: parameters, QoS, executor, status names, the process's run.

Parameters are listed once as ``Param`` specs; the default's type is the parameter's type.
``declare`` reads each start-up value, brings it to that type (an integer is accepted where a
float is declared: ``-p period_s:=30``) and checks it against its spec (range, choices,
finiteness); every refusal is collected into one ``InvalidParameter``, which ``run_node``
prints as one line on stderr with exit code 2. At run time the same coercion runs as a pre-set
callback and ``validate`` (the nodes' on-set callback) refuses a value with the same reason.

``run_node`` stops the process in order on SIGINT / SIGTERM (``gyro_char.nodes.shutdown``).
"""
from dataclasses import dataclass
import math
import sys
import traceback
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Type

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from gyro_char.nodes.shutdown import Interrupted, STOP
from msg_adapters.diagnostics import diagnostic_array, diagnostic_status
from rcl_interfaces.msg import (
    FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult)
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.parameter import Parameter
from rclpy.qos import (
    DurabilityPolicy, HistoryPolicy, qos_profile_sensor_data, QoSProfile, ReliabilityPolicy)
from rclpy.signals import SignalHandlerOptions

try:  # Jazzy: much cheaper per message than SingleThreadedExecutor (measured in bench/).
    from rclpy.experimental import EventsExecutor
except ImportError:  # pragma: no cover - older rclpy
    EventsExecutor = None


class InvalidParameter(ValueError):
    """A parameter value that the node refuses (the message says why)."""


def _kind(default: Any) -> str:
    """Name the type of a parameter from its default (for messages)."""
    if isinstance(default, bool):
        return 'true or false'
    if isinstance(default, int):
        return 'an integer'
    if isinstance(default, float):
        return 'a number'
    if isinstance(default, str):
        return 'a string'
    return 'a list of strings'


@dataclass
class Param:
    """One parameter: default (its type is the parameter's type), description, constraints."""

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

    def coerce(self, value: Any) -> Tuple[Any, Optional[str]]:
        """
        Return (``value`` in the declared type, None) or (None, why it is refused).

        An integer is accepted for a float parameter; no value (an empty YAML list) is the
        empty list for a list parameter. The value then has to pass ``check``.
        """
        d = self.default
        if isinstance(d, float) and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if isinstance(d, list):
            value = [] if value is None else value
            ok = isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value)
            value = list(value) if ok else value
        elif isinstance(d, bool) or isinstance(value, bool):
            ok = isinstance(d, bool) and isinstance(value, bool)
        else:
            ok = isinstance(value, type(d))
        if not ok:
            return None, f'{self.name} must be {_kind(d)}, got {value!r}'
        reason = self.check(value)
        return (None, reason) if reason else (value, None)

    def check(self, value: Any) -> Optional[str]:
        """Return why ``value`` (of the declared type) is refused, or None when acceptable."""
        if isinstance(value, float) and not math.isfinite(value):
            return f'{self.name} must be finite, got {value}'
        if self.low is not None and value < self.low:
            return f'{self.name} must be >= {self.low:g}, got {value}'
        if self.high is not None and value > self.high:
            return f'{self.name} must be <= {self.high:g}, got {value}'
        if self.choices is not None and isinstance(value, list):
            if not value or len(set(value)) < len(value) \
                    or any(v not in self.choices for v in value):
                return (f'{self.name} must be distinct names out of {list(self.choices)}, '
                        f'got {value!r}')
        elif self.choices is not None and value not in self.choices:
            return f'{self.name} must be one of {list(self.choices)}, got {value!r}'
        return None


def declare(node: Any, specs: Iterable[Param]) -> Dict[str, Any]:
    """
    Declare every spec on ``node``; return the values in force (overrides applied, coerced).

    Each start-up value (``-p``, parameter file, ``parameter_overrides``) is read through an
    untyped declaration first, so that a value of another type reaches ``Param.coerce``
    instead of raising inside rclpy; the parameter is then declared with its descriptor and
    the coerced value. All refusals are raised together as one ``InvalidParameter``.
    """
    specs = list(specs)
    values, problems = {}, []
    for spec in specs:
        given = node.declare_parameter(spec.name, spec.default,
                                       ParameterDescriptor(dynamic_typing=True)).value
        node.undeclare_parameter(spec.name)
        value, reason = spec.coerce(given)
        if reason:
            problems.append(reason)
            value = spec.default
        if isinstance(value, list) and not value:  # no element type: declared without a value
            node.declare_parameter(spec.name, Parameter.Type.STRING_ARRAY, spec.descriptor(),
                                   ignore_override=True)
        else:
            node.declare_parameter(spec.name, value, spec.descriptor(), ignore_override=True)
        values[spec.name] = value
    if problems:
        raise InvalidParameter('; '.join(problems))
    by_name = {s.name: s for s in specs}
    node.add_pre_set_parameters_callback(lambda params: coerce_numbers(by_name, params))
    return values


def coerce_numbers(specs: Dict[str, Param], params: List[Any]) -> List[Any]:
    """Pre-set callback body: an integer set on a float parameter becomes that float."""
    out = []
    for p in params:
        spec = specs.get(p.name)
        if spec is not None and isinstance(spec.default, float) and isinstance(p.value, int) \
                and not isinstance(p.value, bool):
            p = Parameter(p.name, value=float(p.value))
        out.append(p)
    return out


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
    Spin ``node`` until a stop is requested or its context shuts down.

    ``rclpy.spin`` calls ``spin_once()`` without a timeout, and Jazzy's EventsExecutor turns
    that (and its own ``spin()``) into a busy loop (measured: ~40 % of a core while idle).
    ``spin_once`` with a timeout sleeps properly, and the loop sees ``STOP`` within 0.2 s.
    A callback that raises does not end the node: the error is logged (the first three and
    every hundredth, with the traceback) and the node keeps serving its other callbacks and
    the next messages. A parameter error and a shutdown still end it.
    """
    executor = executor or make_executor(node.context)
    executor.add_node(node)
    failures = 0
    try:
        while node.context.ok() and not STOP.is_set():
            try:
                executor.spin_once(timeout_sec=0.2)
            except (InvalidParameter, ExternalShutdownException):
                raise
            except Exception as exc:  # noqa: B902 - any bug in one callback
                failures += 1
                if node.context.ok() and (failures <= 3 or failures % 100 == 0):
                    node.get_logger().error(
                        f'a callback failed ({failures} so far; the node keeps running): '
                        f'{exc!r}\n{traceback.format_exc()}')
    finally:
        executor.remove_node(node)


def status_name(node: Any, what: str) -> str:
    """
    Return a DiagnosticStatus name ``<fully qualified node name>: <what>``.

    The ``diagnostic_updater`` convention (with ``use_fqn``): instances in different
    namespaces (``/imu0/allan_node: inputs``, ``/imu1/allan_node: inputs``) stay apart.
    """
    return f'{node.get_fully_qualified_name()}: {what}'


def publish_status(node: Any, publisher: Any, name: str, level: int, message: str,
                   hardware_id: str, values: Dict[str, Any]) -> None:
    """Publish one DiagnosticStatus (numeric/string ``values``) as a DiagnosticArray now."""
    status = diagnostic_status(DiagnosticStatus, KeyValue, name, level, message, hardware_id,
                               values)
    publisher.publish(diagnostic_array(DiagnosticArray, node.get_clock().now().to_msg(),
                                       [status]))


def publish_input_health(node: Any) -> None:
    """Publish ``node.health_status()`` as the ``<fqn>: inputs`` status on ``node.diag_pub``."""
    level, message, values = node.health_status()
    publish_status(node, node.diag_pub, status_name(node, 'inputs'), level, message,
                   node.hardware_id, values)


def run_node(factory: Callable[[], Any], name: str,
             errors: Tuple[Type[BaseException], ...] = (),
             on_exit: Optional[Callable[[Any], None]] = None, args=None,
             executor_type: Optional[Callable[..., Any]] = None) -> int:
    """
    Run one node process: init, spin until SIGINT / SIGTERM, stop in order; the exit code.

    rclpy is initialised without its signal handlers: ``STOP`` takes the signals, the spin
    loop ends, ``on_exit(node)`` runs while the context is still valid (cancel and join
    workers, write a last checkpoint), then the node and the context are torn down; exit 0.
    ``errors`` raised while building or spinning the node (a refused parameter, a bad config)
    and unusable ``--ros-args`` print one line ``<name>: <reason>`` on stderr; exit 2.
    ``InvalidParameter`` is always one of them. ``executor_type(context=...)`` replaces
    ``make_executor``'s choice.
    """
    STOP.install()
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RuntimeError as exc:  # rclpy's RCLError: --ros-args that rcl cannot parse
        print(f'{name}: invalid arguments: {str(exc).splitlines()[0]}', file=sys.stderr,
              flush=True)
        return 2
    node = None
    code = 0
    try:
        if not STOP.is_set():
            node = factory()
            spin(node, executor_type(context=node.context) if executor_type else None)
    except (Interrupted, KeyboardInterrupt, ExternalShutdownException):
        pass
    except (InvalidParameter, *errors) as exc:
        prefix = 'invalid parameter: ' if isinstance(exc, InvalidParameter) else ''
        print(f'{name}: {prefix}{exc}', file=sys.stderr, flush=True)
        code = 2
    finally:
        if node is not None:
            if on_exit is not None:
                on_exit(node)
            node.destroy_node()
        rclpy.try_shutdown()
        STOP.ignore_from_now()
    return code


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
