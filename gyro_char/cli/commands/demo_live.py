"""
The live part of ``gyro-char demo --live``: the simulated bench through the live nodes.

Swing: ``bench_sim_node -> swing_kf_node``; static: ``bench_sim_node -> allan_node`` then its
``~/compute`` service. The nodes run as separate processes (``python -m``, the code of the
installed executables), DDS kept on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``,
``ROS_DOMAIN_ID`` from the environment, 0 if unset). Streams are best effort, so on a loaded
machine a replay faster than real time can lose samples; the counts are reported.
"""
import os
import subprocess
import sys
import time
from typing import Callable, Dict, List, Optional


def _env() -> dict:
    env = dict(os.environ)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env.setdefault('ROS_DOMAIN_ID', '0')
    return env


def _sim_cmd(cfg, kind: str, seed: int, duration: float, rate_factor: float, effects,
             config_file: Optional[str]) -> List[str]:
    # The consumer node must see the first sample: hold the run until it has subscribed.
    cmd = [sys.executable, '-m', 'gyro_char.nodes.bench_sim_node', '--ros-args',
           '-p', 'wait_for_subscribers:=1',
           '-p', f'preset:={cfg.preset}', '-p', f'seed:={seed}', '-p', f'kind:={kind}',
           '-p', f'duration_s:={float(duration)}', '-p', f'rate_factor:={float(rate_factor)}',
           '-p', f'period_s:={float(cfg.stand.period_s)}']
    if config_file:
        cmd += ['-p', f'config_file:={config_file}']
    if effects:
        cmd += ['-p', 'effects:=[' + ','.join(f"'{e}'" for e in effects) + ']']
    return cmd


class _Graph:
    """A listener node in its own Context plus child node processes, torn down together."""

    def __init__(self, log) -> None:
        import rclpy
        self.rclpy, self.log, self.env, self.procs = rclpy, log, _env(), []
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=int(self.env['ROS_DOMAIN_ID']))
        self.node = rclpy.create_node('gyro_char_demo_listener', context=self.context)
        self.executor = rclpy.executors.SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def start(self, cmd: List[str]) -> None:
        self.procs.append(subprocess.Popen(cmd, env=self.env, stdout=subprocess.PIPE,
                                           stderr=subprocess.STDOUT))

    def alive(self) -> bool:
        return all(p.poll() is None for p in self.procs)

    def spin_until(self, done: Callable[[], bool], timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.alive() and not done():
            self.executor.spin_once(timeout_sec=0.1)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)
        for p in self.procs:
            p.terminate()
        for p in self.procs:
            try:
                out, _ = p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                out, _ = p.communicate()
            self.log.write(f'$ {" ".join(p.args)}\n{out.decode(errors="replace")}\n')


def _imports(node_module: str) -> Optional[str]:
    try:
        import importlib
        import rclpy  # noqa: F401
        importlib.import_module(node_module)
    except ImportError as exc:
        return f'live nodes unavailable ({exc})'
    return None


def run_live(cfg, seed: int, duration: float, effects, log, rate_factor: float = 3.0,
             config_file: Optional[str] = None) -> Dict:
    """Replay ``duration`` s of the swing bench through swing_kf_node; return estimates (SI)."""
    problem = _imports('gyro_char.nodes.swing_kf_node')
    if problem:
        return {'missing': problem}
    from diagnostic_msgs.msg import DiagnosticArray
    from msg_adapters.diagnostics import parse_key_values
    latest: Dict = {}
    graph = _Graph(log)
    try:
        def on_estimates(msg):
            for status in msg.status:
                latest.update(parse_key_values(status))
        graph.node.create_subscription(DiagnosticArray, '/swing_kf_node/estimates',
                                       on_estimates, 10)
        graph.start([sys.executable, '-m', 'gyro_char.nodes.swing_kf_node', '--ros-args',
                     '-p', f'period_s:={float(cfg.stand.period_s)}',
                     '-p', f'axis:={cfg.gyro.axis}', '-p', 'publish_rate_hz:=2.0'])
        time.sleep(1.0)    # the filter node subscribes before the simulator starts
        graph.start(_sim_cmd(cfg, 'swing', seed, duration, rate_factor, effects, config_file))
        # Generation (~1 s) + replay + two estimate periods; on a loaded machine the replay
        # falls behind, so keep listening while the filter still receives samples (up to
        # twice the nominal time).
        nominal = 3.0 + duration / rate_factor + 1.5
        graph.spin_until(lambda: False, nominal)
        seen = [-1, time.monotonic()]

        def stalled() -> bool:
            count = latest.get('samples_gyro', -1)
            if count != seen[0]:
                seen[:] = [count, time.monotonic()]
            return time.monotonic() - seen[1] > 1.5
        graph.spin_until(stalled, nominal)
    finally:
        graph.close()
    if not latest:
        return {'missing': 'no estimates arrived from swing_kf_node (see demo.log)'}
    return {'scale_factor_error': latest.get('scale_factor_error'),
            'bias': latest.get('bias_rad_s'), 'bias_drift': latest.get('bias_drift_rad_s2'),
            'samples_gyro': latest.get('samples_gyro'),
            'samples_encoder': latest.get('samples_encoder'),
            'converged': latest.get('converged')}


def run_live_static(cfg, seed: int, duration: float, effects, log, rate_factor: float = 5.0,
                    config_file: Optional[str] = None) -> Dict:
    """Replay a static record through allan_node, call ~/compute, return its noise terms."""
    problem = _imports('gyro_char.nodes.allan_node')
    if problem:
        return {'missing': problem}
    from diagnostic_msgs.msg import DiagnosticArray
    from msg_adapters.diagnostics import parse_key_values
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from std_srvs.srv import Trigger
    noise: Dict[str, Dict] = {}
    graph = _Graph(log)
    result: Dict = {}
    try:
        def on_noise(msg):
            for status in msg.status:
                noise[status.name.rsplit(' ', 1)[-1]] = parse_key_values(status)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        graph.node.create_subscription(DiagnosticArray, '/allan_node/noise', on_noise, latched)
        client = graph.node.create_client(Trigger, '/allan_node/compute')
        graph.start([sys.executable, '-m', 'gyro_char.nodes.allan_node', '--ros-args',
                     '-p', 'fit_bootstrap:=20'])
        graph.spin_until(lambda: client.service_is_ready(), 30.0)
        graph.start(_sim_cmd(cfg, 'static', seed, duration, rate_factor, effects, config_file))
        graph.spin_until(lambda: False, 3.0 + duration / rate_factor + 2.0)
        future = client.call_async(Trigger.Request())
        graph.spin_until(future.done, 30.0)
        if future.done() and future.result() is not None:
            result['message'] = future.result().message
            graph.spin_until(lambda: 'gyro_x' in noise, 120.0)
    finally:
        graph.close()
    if not noise:
        return {'missing': 'no noise terms arrived from allan_node '
                + (f'({result.get("message")})' if result else '(see demo.log)')}
    return {'channels': noise, 'message': result.get('message', '')}
