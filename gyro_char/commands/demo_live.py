"""
The live part of ``gyro-char demo --live``: bench_sim_node -> swing_kf_node on loopback.

Both nodes run as separate processes (their installed executables' code, ``python -m``), DDS
kept on this machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``, ``ROS_DOMAIN_ID`` from the
environment, 0 if unset). The demo listens to ``/swing_kf_node/estimates`` and returns the last
estimates after the simulated run has been replayed.
"""
import os
import subprocess
import sys
import time
from typing import Dict, Optional


def _env() -> dict:
    env = dict(os.environ)
    env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    env.setdefault('ROS_DOMAIN_ID', '0')
    return env


def run_live(cfg, seed: int, duration: float, effects, log, rate_factor: float = 3.0,
             config_file: Optional[str] = None) -> Dict:
    """Replay ``duration`` s of the swing bench through the live nodes; return estimates (SI)."""
    try:
        import rclpy
        from diagnostic_msgs.msg import DiagnosticArray
        from msg_adapters.diagnostics import parse_key_values
        import gyro_char.nodes.swing_kf_node  # noqa: F401
    except ImportError as exc:
        return {'missing': f'live nodes unavailable ({exc})'}
    env = _env()
    sim = [sys.executable, '-m', 'gyro_char.nodes.bench_sim_node', '--ros-args',
           '-p', f'preset:={cfg.preset}', '-p', f'seed:={seed}', '-p', 'kind:=swing',
           '-p', f'duration_s:={float(duration)}', '-p', f'rate_factor:={float(rate_factor)}',
           '-p', f'period_s:={float(cfg.stand.period_s)}']
    if config_file:
        sim += ['-p', f'config_file:={config_file}']
    if effects:
        sim += ['-p', 'effects:=[' + ','.join(f"'{e}'" for e in effects) + ']']
    kf = [sys.executable, '-m', 'gyro_char.nodes.swing_kf_node', '--ros-args',
          '-p', f'period_s:={float(cfg.stand.period_s)}', '-p', f'axis:={cfg.gyro.axis}',
          '-p', 'publish_rate_hz:=2.0']
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(env['ROS_DOMAIN_ID']))
    latest: Dict = {}
    procs = []
    try:
        node = rclpy.create_node('gyro_char_demo_listener', context=context)

        def on_estimates(msg):
            for status in msg.status:
                latest.update(parse_key_values(status))
        node.create_subscription(DiagnosticArray, '/swing_kf_node/estimates', on_estimates, 10)
        executor = rclpy.executors.SingleThreadedExecutor(context=context)
        executor.add_node(node)
        procs.append(subprocess.Popen(kf, env=env, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT))
        time.sleep(1.0)    # the filter node subscribes before the simulator starts
        procs.append(subprocess.Popen(sim, env=env, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT))
        # Generation (~1 s) + replay + two estimate periods; on a loaded machine the replay
        # falls behind, so keep listening while the filter still receives samples (up to
        # twice the nominal time).
        start = time.monotonic()
        nominal = start + 3.0 + duration / rate_factor + 1.5
        hard = start + 2.0 * (nominal - start)
        seen, last_growth = -1, start
        while time.monotonic() < hard and all(p.poll() is None for p in procs):
            executor.spin_once(timeout_sec=0.1)
            count = latest.get('samples_gyro', -1)
            if count != seen:
                seen, last_growth = count, time.monotonic()
            if time.monotonic() > nominal and time.monotonic() - last_growth > 1.5:
                break
        executor.shutdown()
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
        for p in procs:
            p.terminate()
        for p in procs:
            try:
                out, _ = p.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                out, _ = p.communicate()
            log.write(f'$ {" ".join(p.args)}\n{out.decode(errors="replace")}\n')
    if not latest:
        return {'missing': 'no estimates arrived from swing_kf_node (see demo.log)'}
    return {'scale_factor_error': latest.get('scale_factor_error'),
            'bias': latest.get('bias_rad_s'), 'bias_drift': latest.get('bias_drift_rad_s2'),
            'samples_gyro': latest.get('samples_gyro'),
            'samples_encoder': latest.get('samples_encoder'),
            'converged': latest.get('converged')}
