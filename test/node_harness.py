"""Helpers for the node tests: isolated contexts, spinning, child processes on loopback DDS."""
import contextlib
import json
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import threading
import time
from typing import Callable, Dict, List, Optional

from diagnostic_msgs.msg import DiagnosticArray
from gyro_char.nodes import common as node_common
from msg_adapters import fill_imu, to_stamp
from msg_adapters.diagnostics import level_of, parse_key_values
import rclpy
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from sensor_msgs.msg import Imu, JointState

ROOT = Path(__file__).resolve().parents[1]
EPOCH = 1000.0  # stamp offset (s) of the simulated runs fed to the nodes


def _domain_ids() -> List[int]:
    """
    Return the ROS_DOMAIN_IDs the node tests may use, one per test file and mode.

    ``GYRO_CHAR_TEST_DOMAINS`` (e.g. ``63,163-169``) gives them when several sessions run node
    tests on one machine at once; the default is 80-93. Fewer ids than needed are reused in turn.
    """
    ids: List[int] = []
    for part in os.environ.get('GYRO_CHAR_TEST_DOMAINS', '80-93').split(','):
        low, _, high = part.strip().partition('-')
        ids += list(range(int(low), int(high or low) + 1))
    return ids


_IDS = _domain_ids()
_KEYS = [('swing', 2), ('allan', 2), ('bench_sim', 2), ('dds_smoke', 1), ('colcon', 1),
         ('shutdown', 1), ('instances', 1), ('params', 1), ('allan_filter', 1),
         ('demo', 1)]
DOMAINS: Dict[str, object] = {}
_next = 0
for _key, _n in _KEYS:
    _got = tuple(_IDS[(_next + k) % len(_IDS)] for k in range(_n))
    DOMAINS[_key] = _got if _n > 1 else _got[0]
    _next += _n


def ros_env(domain_id: int) -> Dict[str, str]:
    """Environment for a child process: loopback-only DDS on ``domain_id``."""
    env = dict(os.environ)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env['ROS_DOMAIN_ID'] = str(domain_id)
    env['PYTHONPATH'] = str(ROOT) + os.pathsep + env.get('PYTHONPATH', '')
    env.setdefault('MPLBACKEND', 'Agg')
    return env


def node_command(executable: str) -> List[str]:
    """Return the installed node executable, or the module run by this Python if not installed."""
    path = shutil.which(executable, path=str(Path(sys.executable).parent) + os.pathsep
                        + os.environ.get('PATH', ''))
    if path:
        return [path]
    return [sys.executable, '-m', f'gyro_char.nodes.{executable}']


@contextlib.contextmanager
def ros_context(domain_id: int):
    """Yield an isolated rclpy context on ``domain_id`` (loopback only); shut it down after."""
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain_id)
    try:
        yield context
    finally:
        rclpy.try_shutdown(context=context)


def spin_until(executor, predicate: Callable[[], bool], timeout: float) -> bool:
    """Spin until ``predicate()`` is true or ``timeout`` seconds passed; return the predicate."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        executor.spin_once(timeout_sec=0.02)
    return predicate()


def collect(domain_id: int, msg_type, topic: str, qos, count: int, timeout: float,
            alive: Callable[[], bool] = lambda: True, convert: Callable = lambda m: m,
            node_name: str = 'collector', poll: float = 0.1) -> list:
    """
    Receive ``count`` messages of ``topic`` in a fresh context on ``domain_id`` (loopback).

    Spins a single-threaded executor until ``count`` messages arrived, ``timeout`` seconds
    passed or ``alive()`` turned false (e.g. the publishing child exited), then tears the node
    and context down. Returns the messages received (through ``convert``), however many.
    """
    received: list = []
    with ros_context(domain_id) as context:
        node = rclpy.create_node(node_name, context=context)
        node.create_subscription(msg_type, topic, lambda m: received.append(convert(m)), qos)
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        deadline = time.monotonic() + timeout
        while len(received) < count and time.monotonic() < deadline and alive():
            executor.spin_once(timeout_sec=poll)
        executor.shutdown()
        node.destroy_node()
    return received


class Listener:
    """Collects DiagnosticArray statuses by name from several topics (last one wins)."""

    def __init__(self, node, topics: List[str], qos=10) -> None:
        self.last: Dict[str, tuple] = {}
        self.count: Dict[str, int] = {}
        for topic in topics:
            node.create_subscription(DiagnosticArray, topic, self._on, qos)

    def _on(self, msg) -> None:
        for st in msg.status:
            self.last[st.name] = (level_of(st), st.message, parse_key_values(st))
            self.count[st.name] = self.count.get(st.name, 0) + 1

    def values(self, name: str) -> Optional[dict]:
        got = self.last.get(name)
        return None if got is None else got[2]


class Feeder:
    """In-process publisher of Imu / JointState messages on the sensor-data QoS."""

    def __init__(self, node, encoder: bool = True, qos: QoSProfile = qos_profile_sensor_data):
        self.imu = node.create_publisher(Imu, 'imu/data_raw', qos)
        self.enc = node.create_publisher(JointState, 'stand/joint_states', qos) if encoder \
            else None
        self.msg_imu = Imu()
        self.msg_enc = JointState()

    def imu_sample(self, t: float, gyro, accel=(0.0, 0.0, 9.81), frame_id='imu_link',
                   raw_stamp=None) -> None:
        msg = fill_imu(self.msg_imu, t if raw_stamp is None else 1.0, gyro, accel, frame_id)
        if raw_stamp is not None:
            msg.header.stamp.sec, msg.header.stamp.nanosec = raw_stamp
        self.imu.publish(msg)

    def encoder_sample(self, t: float, angle: float, name: str = 'swing') -> None:
        to_stamp(self.msg_enc.header.stamp, t)
        self.msg_enc.name = [name]
        self.msg_enc.position = [float(angle)]
        self.enc.publish(self.msg_enc)


def make_executor(context):
    """Return the executor the nodes use in production (EventsExecutor where rclpy has it)."""
    return node_common.make_executor(context)


def stop(proc: subprocess.Popen, timeout: float = 10.0) -> str:
    """Stop a child we started (SIGINT, then SIGKILL); return its combined output."""
    if proc.poll() is None:
        proc.send_signal(2)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    out = proc.stdout.read() if proc.stdout else b''
    return out.decode(errors='replace') if isinstance(out, bytes) else out


class NodeProcess:
    """
    A node executable we started, its output collected line by line in the background.

    ``wait_for(text)`` blocks until a line containing ``text`` was printed (e.g. a log line
    that marks the instant to send a signal); ``stop(sig)`` sends one signal and waits.
    """

    def __init__(self, executable: str, ros_args: List[str], domain_id: int) -> None:
        self.lines: List[str] = []
        self._cond = threading.Condition()
        self.proc = subprocess.Popen(node_command(executable) + ['--ros-args', *ros_args],
                                     env=ros_env(domain_id), stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            with self._cond:
                self.lines.append(line)
                self._cond.notify_all()

    @property
    def output(self) -> str:
        """Return everything printed so far."""
        with self._cond:
            return ''.join(self.lines)

    def wait_for(self, text: str, timeout: float) -> bool:
        """Wait until a printed line contains ``text``; False on timeout or process exit."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while not any(text in line for line in self.lines):
                left = deadline - time.monotonic()
                if left <= 0 or self.proc.poll() is not None:
                    return any(text in line for line in self.lines)
                self._cond.wait(min(left, 0.1))
        return True

    def stop(self, sig: int = signal.SIGINT, timeout: float = 15.0) -> Optional[float]:
        """Send ``sig`` and wait; return the seconds until exit (None: killed after timeout)."""
        start = time.monotonic()
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            self._reader.join(5.0)
            return None
        self._reader.join(5.0)
        return time.monotonic() - start


def clean_exit_problems(proc: 'NodeProcess') -> List[str]:
    """List what is wrong with a node's exit: a code other than 0, a traceback, an abort."""
    out = proc.output
    problems = [] if proc.proc.returncode == 0 else [f'exit code {proc.proc.returncode}']
    for bad in ('Traceback', 'terminate called', 'Fatal Python error', 'RCLError',
                'Exception in'):
        if bad in out:
            problems.append(f'{bad!r} in the output')
    return problems


def read_json(path: Path) -> dict:
    with open(path) as f:
        return json.load(f)
