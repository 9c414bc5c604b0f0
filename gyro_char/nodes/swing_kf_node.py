"""
swing_kf_node: live swing-stand calibration of one gyro axis against the stand encoder.

Per message the callbacks only check the stamp (``StreamHealth.admit``) and append
``(stamp, receive time, value)`` to a deque; a timer drains the deques every
``processing_period_s`` and feeds the chunks to ``SwingOnline`` (the core aligns the streams by
their header stamps). Estimates go out on ``~/estimates`` at ``publish_rate_hz``, with the stamp
their bias refers to (``bias_epoch_s``) and the ``converged`` flag judged from their own sigmas
(``live.convergence``); input health and convergence on ``/diagnostics`` at 1 Hz.
"""
from collections import deque
import math
import time
from typing import Any, Dict, List

from diagnostic_msgs.msg import DiagnosticArray
from gyro_char.live.convergence import Convergence
from gyro_char.live.status import InputStatus
from gyro_char.live.stream_health import DROP, RESTART, stream_skew_s, StreamHealth
from gyro_char.live.swing_online import SwingOnline
from gyro_char.nodes.common import (declare, Param, publish_input_health, publish_status,
                                    RELIABLE_10, run_node, sensor_qos, split_at_markers,
                                    status_name, validate)
from gyro_char.swing.model import SwingNoise
from msg_adapters import joint_angle, stamp_seconds
from msg_adapters.diagnostics import OK, WARN
import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import Imu, JointState
from std_srvs.srv import Trigger

NAME = 'swing_kf_node'

PARAMS = [
    Param('imu_topic', 'imu/data_raw', 'sensor_msgs/Imu input topic', read_only=True),
    Param('encoder_topic', 'stand/joint_states',
          'sensor_msgs/JointState with the stand angle (rad)', read_only=True),
    Param('input_queue_depth', 2000,
          'subscription history depth (best effort); must cover the longest pause between '
          'chunk timer runs at the input rate', read_only=True, low=10, high=100000),
    Param('axis', 'x', 'gyro axis along the swing axis', choices=('x', 'y', 'z')),
    Param('joint_name', '', 'encoder joint name in JointState.name ("" = use joint_index)'),
    Param('joint_index', 0, 'encoder joint index in JointState.position when joint_name is ""',
          low=0, high=1000),
    Param('period_s', 5.0, 'stand swing period (s)', low=0.01, high=3600.0),
    Param('publish_rate_hz', 2.0, 'rate of ~/estimates (Hz)', low=0.01, high=50.0),
    Param('processing_period_s', 0.05, 'chunk timer period (s): buffered samples are fed to '
          'the filter this often', read_only=True, low=0.001, high=1.0),
    Param('encoder_noise_rad', 0.0,
          'encoder white angle noise 1-sigma (rad); 0 = estimate from the data', low=0.0,
          high=1.0),
    Param('gyro_noise_density_rad_sqrt_s', 0.0,
          'gyro white rate noise density (rad/sqrt(s)); 0 = estimate from the data', low=0.0,
          high=1.0),
    Param('frame_id', '', 'expected Imu header.frame_id ("" = accept any)'),
    Param('hardware_id', '', 'hardware_id reported in /diagnostics ("" = the resolved IMU '
          'topic name, which differs per instance)'),
    Param('converged_rel_sigma', 0.25, 'converged: the sigma of every estimate at most this '
          'fraction of its magnitude (or within its absolute tolerance below)', low=0.0,
          high=1e3),
    Param('converged_scale_factor_error_sigma', 0.0, 'converged: scale-factor error sigma '
          'accepted whatever its value (0 = relative rule only)', low=0.0, high=1.0),
    Param('converged_bias_sigma_rad_s', 0.0, 'converged: bias sigma (rad/s) accepted whatever '
          'its value (0 = relative rule only)', low=0.0, high=1e3),
    Param('converged_bias_drift_sigma_rad_s2', 0.0, 'converged: bias drift sigma (rad/s^2) '
          'accepted whatever its value (0 = relative rule only)', low=0.0, high=1e3),
    Param('converged_periods', 3.0, 'converged: the sigma rule must hold without a break over '
          'this many swing periods of data', low=0.0, high=1e5),
    Param('stall_timeout_s', 1.0, 'a stream silent this long is reported stalled (s)',
          low=0.01, high=3600.0),
    Param('max_skew_s', 0.05, 'largest tolerated difference between the stamp-to-arrival '
          'offsets of the two streams (s)', low=1e-4, high=3600.0),
    Param('max_rate_hz', 20000.0, 'messages per second per stream above which the excess is '
          'dropped as a flood (0 = no limit)', low=0.0, high=1e6),
]
SPECS = {p.name: p for p in PARAMS}
# Changing these restarts the filter (the accumulated information refers to the old setting).
RESTARTING = {'axis', 'joint_name', 'joint_index', 'period_s', 'encoder_noise_rad',
              'gyro_noise_density_rad_sqrt_s'}
# Changing these judges convergence afresh (the filter keeps its information).
CONVERGENCE = {'converged_rel_sigma', 'converged_scale_factor_error_sigma',
               'converged_bias_sigma_rad_s', 'converged_bias_drift_sigma_rad_s2',
               'converged_periods'}


class SwingKfNode(Node):
    """Thin rclpy front door to ``SwingOnline``."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NAME, **kwargs)
        self.p = declare(self, PARAMS)
        self._imu_q: deque = deque()
        self._enc_q: deque = deque()
        self.imu_health = StreamHealth('imu')
        self.enc_health = StreamHealth('encoder')
        self.missing_joint = 0
        self.core_restarts = 0
        self.processing_errors = 0
        self._converged = False
        self._fed_last: Dict[str, float] = {}
        self.status = InputStatus()
        self._configure()
        depth = self.p['input_queue_depth']
        sub = self.create_subscription(Imu, self.p['imu_topic'], self._on_imu,
                                       sensor_qos(depth))
        self.imu_topic = sub.topic_name  # resolved: namespace and remapping applied
        self.create_subscription(JointState, self.p['encoder_topic'], self._on_encoder,
                                 sensor_qos(depth))
        self.estimates_pub = self.create_publisher(DiagnosticArray, '~/estimates', RELIABLE_10)
        self.diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', RELIABLE_10)
        self.create_service(Trigger, '~/reset', self._on_reset)
        self.create_timer(self.p['processing_period_s'], self.process)
        self._publish_timer = self.create_timer(1.0 / self.p['publish_rate_hz'],
                                                self.publish_estimates)
        self.create_timer(1.0, self.publish_diagnostics)
        self.add_on_set_parameters_callback(self._validate)
        self.add_post_set_parameters_callback(self._apply)

    # -- configuration -----------------------------------------------------------------------

    def _configure(self) -> None:
        p = self.p
        self._axis = p['axis']
        self._joint = p['joint_name'] or p['joint_index']
        noise = SwingNoise(p['encoder_noise_rad'] or None,
                           p['gyro_noise_density_rad_sqrt_s'] or None)
        self.core = SwingOnline(p['period_s'], noise)
        self._configure_convergence()
        for h in (self.imu_health, self.enc_health):
            h.max_rate_hz = p['max_rate_hz']
        self.imu_health.frame_id = p['frame_id']

    def _configure_convergence(self) -> None:
        p = self.p
        self.convergence = Convergence(p['period_s'], rel_sigma=p['converged_rel_sigma'],
                                       periods=p['converged_periods'], abs_sigma={
            'scale_factor_error': p['converged_scale_factor_error_sigma'],
            'bias': p['converged_bias_sigma_rad_s'],
            'bias_drift': p['converged_bias_drift_sigma_rad_s2']})

    @property
    def hardware_id(self) -> str:
        """Return the hardware_id of this node's statuses (default: the IMU topic)."""
        return self.p['hardware_id'] or self.imu_topic

    def _validate(self, params: List[Any]):
        return validate(SPECS, params, current=self.p)

    def _apply(self, params: List[Any]) -> None:
        names = {q.name for q in params}
        self.p.update({q.name: q.value for q in params if q.name in SPECS})
        if names & RESTARTING:
            self._restart_core('parameters changed: ' + ', '.join(sorted(names & RESTARTING)))
        else:
            for h in (self.imu_health, self.enc_health):
                h.max_rate_hz = self.p['max_rate_hz']
            self.imu_health.frame_id = self.p['frame_id']
            if names & CONVERGENCE:
                self._configure_convergence()
        if 'publish_rate_hz' in names:
            self.destroy_timer(self._publish_timer)
            self._publish_timer = self.create_timer(1.0 / self.p['publish_rate_hz'],
                                                    self.publish_estimates)

    def _restart_core(self, why: str, drain: bool = True) -> None:
        if drain:  # feed what arrived under the old setting first
            self.process()
        self._configure()
        self.core_restarts += 1
        self.get_logger().info(f'filter restarted ({why})')

    # -- per message: O(1) ---------------------------------------------------------------------

    def _on_imu(self, msg: Imu) -> None:
        t = stamp_seconds(msg.header.stamp)
        now = time.time()
        code = self.imu_health.admit(t, now, msg.header.frame_id)
        if code == DROP:
            return
        if code == RESTART:
            self._imu_q.append(None)
        self._imu_q.append((t, now, getattr(msg.angular_velocity, self._axis)))

    def _on_encoder(self, msg: JointState) -> None:
        sample = joint_angle(msg, self._joint)
        if sample is None:
            self.missing_joint += 1
            return
        t, angle = sample
        now = time.time()
        code = self.enc_health.admit(t, now)
        if code == DROP:
            return
        if code == RESTART:
            self._enc_q.append(None)
        self._enc_q.append((t, now, angle))

    # -- per chunk -----------------------------------------------------------------------------

    def process(self) -> None:
        """Drain both queues into the filter; a failing chunk is counted, never fatal."""
        try:
            self._process()
        except (ValueError, ArithmeticError, IndexError) as exc:
            self.processing_errors += 1
            self.get_logger().error(f'chunk dropped: {exc!r}', throttle_duration_sec=10.0)

    def _process(self) -> None:
        for q, health, feed in ((self._imu_q, self.imu_health, 'add_imu'),
                                (self._enc_q, self.enc_health, 'add_encoder')):
            n = len(q)
            if not n:
                continue
            items = [q.popleft() for _ in range(n)]
            runs = split_at_markers(items)
            for i, run in enumerate(runs):
                if not run:
                    continue
                t_ref = self.core.t_ref
                # A restarted source: restart the filter unless it already restarted on the
                # new clock (the other stream's restart came first).
                if i > 0 and (t_ref is None or run[0][0] < t_ref - 1.0):
                    self._restart_core(f'{health.name} stamps restarted', drain=False)
                arr = np.array(run, dtype=np.float64)
                finite = np.isfinite(arr[:, 2])
                health.count_non_finite(arr.shape[0] - int(finite.sum()))
                arr = arr[finite]
                health.observe_chunk(arr[:, 0], arr[:, 1], self._fed_last.get(health.name))
                if arr.shape[0]:
                    self._fed_last[health.name] = float(arr[-1, 0])
                    getattr(self.core, feed)(arr[:, 0], arr[:, 2])

    # -- outputs -------------------------------------------------------------------------------

    def estimate_values(self) -> Dict[str, Any]:
        """
        Return the current estimates as diagnostics key/values (SI units in the keys).

        ``bias_epoch_s`` is the stamp (s) the bias refers to: the first sample since the
        filter (re)started; the bias at stamp t is bias + bias_drift (t - bias_epoch_s).
        Judges convergence (``Convergence.update``) at the newest gyro stamp.
        """
        e = self.core.estimates()
        converged = self.convergence.update(e, self._fed_last.get('imu', math.nan))
        t_ref = self.core.t_ref
        return {
            'scale_factor_error': e.scale_factor_error.value,
            'scale_factor_error_sigma': e.scale_factor_error.sigma,
            'bias_rad_s': e.bias.value,
            'bias_sigma_rad_s': e.bias.sigma,
            'bias_epoch_s': math.nan if t_ref is None else float(t_ref),
            'bias_drift_rad_s2': e.bias_drift.value,
            'bias_drift_sigma_rad_s2': e.bias_drift.sigma,
            'amplitude_encoder_rad': e.amplitude_encoder.value,
            'amplitude_encoder_sigma_rad': e.amplitude_encoder.sigma,
            'amplitude_gyro_rad': e.amplitude_gyro.value,
            'amplitude_gyro_sigma_rad': e.amplitude_gyro.sigma,
            'period_s': e.period_s,
            'samples_gyro': e.samples_gyro,
            'samples_encoder': e.samples_encoder,
            'converged': converged,
            'noise_encoder_rad': e.noise_encoder_rad,
            'noise_gyro_rad_sqrt_s': e.noise_gyro_arw,
        }

    def publish_estimates(self) -> None:
        """Publish ``~/estimates`` (one status: OK when converged, WARN before)."""
        values = self.estimate_values()
        if values['converged']:
            level, msg = OK, 'converged'
        else:
            level = WARN
            msg = 'not converged yet'
            if self.convergence.unmet:
                msg += ': sigma above tolerance for ' + ', '.join(self.convergence.unmet)
        publish_status(self, self.estimates_pub, status_name(self, 'estimates'), level, msg,
                       self.hardware_id, values)
        self._converged = values['converged']

    def health_status(self) -> tuple:
        """Return (level, message, values) of the input health."""
        st = self.status.begin()
        st.streams([self.imu_health, self.enc_health], time.time(), self.p['stall_timeout_s'])
        skew = stream_skew_s(self.imu_health, self.enc_health)
        if skew is not None:
            st.values['stream_skew_s'] = skew
            if abs(skew) > self.p['max_skew_s']:
                st.warn(f'streams {skew:+.3f} s apart in time')
        grew = st.grew('missing_joint', self.missing_joint)
        if grew:
            st.warn(f'{grew} JointState messages without joint {self._joint!r}')
        st.values['encoder_dropped_missing_joint'] = self.missing_joint
        # Gyro gaps of 3+ samples: bridged by releasing the integrated angle's offset (core).
        st.values['imu_gaps_bridged'] = self.core.gaps_released
        st.values['filter_restarts'] = self.core_restarts
        st.values['processing_errors'] = self.processing_errors
        st.values['converged'] = self._converged
        if not self._converged:
            st.warn('filter not converged')
        if self.processing_errors:
            st.error(f'{self.processing_errors} chunks failed in the filter (see log)')
        return st.result()

    def publish_diagnostics(self) -> None:
        """Publish the input health and convergence on ``/diagnostics``."""
        publish_input_health(self)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        self._imu_q.clear()
        self._enc_q.clear()
        for h in (self.imu_health, self.enc_health):
            h.reset()
        self._fed_last = {}
        self.missing_joint = 0
        self.status.reset()
        self._configure()
        self._converged = False
        response.success = True
        response.message = 'filter and input counters reset'
        return response


def main(args=None) -> int:
    """Run the node (Jazzy idiom; exit 2 on an invalid parameter)."""
    return run_node(SwingKfNode, NAME, args=args)


if __name__ == '__main__':
    raise SystemExit(main())
