"""
allan_node: Allan variance and IEEE 952 noise terms of a live static IMU record.

Per message the callback checks the stamp (``StreamHealth.admit``) and appends the six SI
channels to a deque; a timer drains it into ``AllanLive`` (segmented streaming accumulator,
motion detector) every ``processing_period_s`` and writes an atomic checkpoint every
``checkpoint_period_s``. ``~/compute`` publishes the Allan curve at once and runs the noise fit
in a worker thread (it takes seconds; ingestion goes on meanwhile), then publishes ``~/noise``
and, with ``output_dir`` set, writes the files of ``gyro-char allan`` for the channels whose
fit succeeded (a failed channel is reported on ``~/noise``, in the diagnostics and the log).
On a stop signal the fit is cancelled between two bootstrap refits and joined before the last
checkpoint is written.
"""
from collections import deque
from dataclasses import replace
import math
import os
import threading
import time
from typing import Any, Dict, List, Optional

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from gyro_char.allan.sensor_filter import parse_spec
from gyro_char.errors import InputError
from gyro_char.live.allan_live import AllanLive, return_freed_memory
from gyro_char.live.checkpoint import load_checkpoint, PeriodicCheckpoint
from gyro_char.live.status import InputStatus
from gyro_char.live.stream_health import DROP, RESTART, StreamHealth
from gyro_char.nodes.common import (declare, InvalidParameter, LATCHED_1, Param,
                                    publish_input_health, RELIABLE_10, run_node, sensor_qos,
                                    split_at_markers, status_name, validate)
from gyro_char.records import IMU_CHANNELS
from msg_adapters import imu_sample
from msg_adapters.diagnostics import (
    diagnostic_array, diagnostic_status, ERROR, multiarray, OK)
from msg_adapters.noise import curve_array, fit_values, record_values
import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from std_srvs.srv import Trigger

NAME = 'allan_node'

PARAMS = [
    Param('imu_topic', 'imu/data_raw', 'sensor_msgs/Imu input topic', read_only=True),
    Param('channels', list(IMU_CHANNELS), 'IMU channels to accumulate and fit (as gyro-char '
          'allan --channels)', read_only=True, choices=IMU_CHANNELS),
    Param('input_queue_depth', 5000, 'subscription history depth (best effort)',
          read_only=True, low=10, high=1000000),
    Param('rate_hz', 0.0, 'IMU sample rate (Hz); 0 = median interval of the first samples',
          read_only=True, low=0.0, high=1e6),
    Param('m_max', 2 ** 18, 'largest averaging factor (tau_max = m_max / rate); memory is '
          '~ 2 m_max x 6 doubles', read_only=True, low=16, high=2 ** 24),
    Param('feed_chunk', 2000, 'samples per accumulator update (each costs O(m_max))',
          read_only=True, low=1, high=10 ** 7),
    Param('processing_period_s', 0.1, 'chunk timer period (s)', read_only=True, low=0.001,
          high=10.0),
    Param('checkpoint_path', '', 'accumulator checkpoint (.npz); resumed at start when it '
          'exists ("" = no checkpoints)', read_only=True),
    Param('checkpoint_period_s', 60.0, 'seconds between checkpoints (at most this much data '
          'is lost on a crash)', low=0.1, high=86400.0),
    Param('output_dir', '', 'if set, ~/compute also writes the files of gyro-char allan here'),
    Param('fit_method', 'l1', 'noise fit estimator', choices=('l1', 'l1w', 'weighted')),
    Param('fit_bootstrap', 50, 'bootstrap curves for the 68 % intervals of the fit', low=2,
          high=1000),
    Param('fit_tau_min_s', 0.0, 'fit only tau >= this (s); 0 = all', low=0.0, high=1e6),
    Param('sensor_filter', 'none', "the sensor's output filter in the noise fit: none, "
          'boxcar:TAPS[@RATE] or bartlett:TAPS[@RATE] (RATE: 8x or Hz); auto needs the '
          'samples (gyro-char allan)'),
    Param('frame_id', '', 'expected Imu header.frame_id ("" = accept any)'),
    Param('hardware_id', '', 'hardware_id reported in /diagnostics ("" = the resolved IMU '
          'topic name, which differs per instance)'),
    Param('stall_timeout_s', 1.0, 'the input silent this long is reported stalled (s)',
          low=0.01, high=3600.0),
    Param('max_rate_hz', 20000.0, 'messages per second above which the excess is dropped as '
          'a flood (0 = no limit)', low=0.0, high=1e6),
    Param('motion_block_s', 0.5, 'motion detector block length (s)', read_only=True,
          low=0.01, high=60.0),
    Param('motion_variance_ratio', 4.0, 'block variance / reference variance that flags '
          'motion', read_only=True, low=1.0, high=1e6),
    Param('motion_mean_sigmas', 10.0, 'block-mean step, in reference scatters, that flags '
          'motion', read_only=True, low=1.0, high=1e6),
    Param('period_s', 0.0, 'stand period; ignored by allan_node (accepted for a common '
          'parameter file)', low=0.0, high=1e6),
]
SPECS = {p.name: p for p in PARAMS}


class FitCancelled(Exception):
    """The noise fit was abandoned because the node is stopping."""


def sensor_filter_reason(values: Dict[str, Any]) -> Optional[str]:
    """Return why ``sensor_filter`` is refused (None when valid): a bad spec, or ``auto``."""
    try:
        spec = parse_spec(values.get('sensor_filter', 'none'))
    except InputError as exc:
        return str(exc)
    if spec.mode == 'auto':
        return ('sensor_filter auto needs the samples, which the node does not keep: give '
                'the filter (e.g. bartlett:7@8x) or run gyro-char allan --sensor-filter auto')
    return None


class AllanNode(Node):
    """Thin rclpy front door to ``AllanLive`` and the noise fit."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NAME, **kwargs)
        return_freed_memory()  # day-long runs: keep the accumulator's temporaries off the RSS
        self.p = declare(self, PARAMS)
        p = self.p
        reason = sensor_filter_reason(p)
        if reason:
            raise InvalidParameter(reason)
        self._columns = [IMU_CHANNELS.index(c) for c in p['channels']]
        self.live = AllanLive(
            p['channels'], rate_hz=p['rate_hz'], m_max=p['m_max'], feed_chunk=p['feed_chunk'],
            motion={'block_s': p['motion_block_s'],
                    'variance_ratio': p['motion_variance_ratio'],
                    'mean_sigmas': p['motion_mean_sigmas']})
        self.health = StreamHealth('imu', frame_id=p['frame_id'], max_rate_hz=p['max_rate_hz'])
        self._q: deque = deque()
        self.status = InputStatus()
        self._fit_thread: Optional[threading.Thread] = None
        self._fit_lock = threading.Lock()
        self._cancel = threading.Event()
        self.fit_status = 'no fit yet'
        self.processing_errors = 0
        self.checkpoint_errors = 0
        self.resumed_samples = 0
        self.checkpoint = None
        if p['checkpoint_path']:
            self.checkpoint = PeriodicCheckpoint(p['checkpoint_path'],
                                                 p['checkpoint_period_s'])
            self._resume()
        sub = self.create_subscription(Imu, p['imu_topic'], self._on_imu,
                                       sensor_qos(p['input_queue_depth']))
        self.imu_topic = sub.topic_name  # resolved: namespace and remapping applied
        self.curve_pub = self.create_publisher(Float64MultiArray, '~/allan_curve', LATCHED_1)
        self.noise_pub = self.create_publisher(DiagnosticArray, '~/noise', LATCHED_1)
        self.diag_pub = self.create_publisher(DiagnosticArray, '/diagnostics', RELIABLE_10)
        self.create_service(Trigger, '~/compute', self._on_compute)
        self.create_service(Trigger, '~/reset', self._on_reset)
        self.create_timer(p['processing_period_s'], self.process)
        self.create_timer(1.0, self.publish_diagnostics)
        self.add_on_set_parameters_callback(self._validate)
        self.add_post_set_parameters_callback(self._apply)

    # -- parameters ----------------------------------------------------------------------------

    def _validate(self, params: List[Any]):
        return validate(SPECS, params, cross_check=sensor_filter_reason, current=self.p)

    def _apply(self, params: List[Any]) -> None:
        self.p.update({q.name: q.value for q in params if q.name in SPECS})
        self.health.frame_id = self.p['frame_id']
        self.health.max_rate_hz = self.p['max_rate_hz']
        if self.checkpoint is not None:
            self.checkpoint.period_s = self.p['checkpoint_period_s']

    @property
    def hardware_id(self) -> str:
        """Return the hardware_id of this node's statuses (default: the IMU topic)."""
        return self.p['hardware_id'] or self.imu_topic

    # -- checkpoints ---------------------------------------------------------------------------

    def _resume(self) -> None:
        path = self.checkpoint.path
        try:
            state = load_checkpoint(path)
            if state is None:
                return
            self.live.load_state(state['live'])
        except (InputError, KeyError, ValueError) as exc:
            aside = f'{path}.unusable-{int(time.time())}'
            os.replace(path, aside)
            self.checkpoint_errors += 1
            self.get_logger().error(f'checkpoint not resumed ({exc}); moved to {aside}')
            self.live.reset()
            return
        self.resumed_samples = self.live.n_samples
        self.get_logger().info(
            f'resumed {self.resumed_samples} samples from {path} (last stamp '
            f'{self.live.last_t:.6f} s)')

    def write_checkpoint(self) -> None:
        """Write the accumulator state now (atomic; a failure is counted and reported)."""
        try:
            self.checkpoint.write({'live': self.live.state_dict()})
        except OSError as exc:
            self.checkpoint_errors += 1
            self.get_logger().error(f'checkpoint write failed: {exc}',
                                    throttle_duration_sec=30.0)

    # -- per message: O(1) ---------------------------------------------------------------------

    def _on_imu(self, msg: Imu) -> None:
        t, values = imu_sample(msg)
        code = self.health.admit(t, time.time(), msg.header.frame_id)
        if code == DROP:
            return
        if code == RESTART:
            self._q.append(None)
        self._q.append((t, *(values[i] for i in self._columns)))

    # -- per chunk -----------------------------------------------------------------------------

    def process(self) -> None:
        """Drain the queue into the accumulator; checkpoint when due. Never raises."""
        try:
            n = len(self._q)
            items = [self._q.popleft() for _ in range(n)]
            for i, run in enumerate(split_at_markers(items)):
                if i > 0:
                    self.live.restart_stamps()
                if run:
                    arr = np.array(run, dtype=np.float64)
                    before = self.live.non_finite
                    self.live.add(arr[:, 0], arr[:, 1:])
                    self.health.count_non_finite(self.live.non_finite - before)
        except (InputError, ValueError, ArithmeticError, IndexError) as exc:
            self.processing_errors += 1
            self.get_logger().error(f'chunk dropped: {exc!r}', throttle_duration_sec=10.0)
        if self.checkpoint is not None and self.checkpoint.due():
            self.write_checkpoint()

    # -- compute -------------------------------------------------------------------------------

    def _on_compute(self, request: Trigger.Request, response: Trigger.Response):
        self.process()
        try:
            res = self.live.result()
        except InputError as exc:
            response.success, response.message = False, str(exc)
            return response
        self.curve_pub.publish(self.curve_message(res))
        with self._fit_lock:
            if self._fit_thread is not None and self._fit_thread.is_alive():
                response.success = False
                response.message = ('Allan curve published; a noise fit is still running, '
                                    'call again when ~/noise has been published')
                return response
            self._fit_thread = threading.Thread(target=self._fit_and_publish, args=(res,))
            self._fit_thread.start()
        response.success = True
        response.message = (f'Allan curve of {res.n_samples} samples published on '
                            f'~/allan_curve; noise fit running, result on ~/noise')
        return response

    def curve_message(self, res) -> Float64MultiArray:
        """Return the curve as (channel, quantity, tau) with self-describing labels."""
        return multiarray(Float64MultiArray, MultiArrayDimension, *curve_array(res))

    def fit(self, res) -> Dict[str, Any]:
        """Fit every channel (``allan.fit.fit_result``); a failing channel is reported."""
        from gyro_char.allan.fit import fit_result
        fits, failed = {}, {}
        for c, name in enumerate(res.channels):
            one = replace(res, avar=res.avar[:, [c]], edf=res.edf[:, [c]],
                          alpha=res.alpha[:, [c]], adev_lo=res.adev_lo[:, [c]],
                          adev_hi=res.adev_hi[:, [c]], channels=(name,))
            try:
                # seed c: the same draws as fit_result on all channels at once.
                fits[name] = fit_result(one, method=self.p['fit_method'],
                                        tau_min=self.p['fit_tau_min_s'] or None,
                                        n_boot=self.p['fit_bootstrap'], seed=c,
                                        sensor_filter=self.p['sensor_filter'],
                                        interrupt=self._interrupt)[name]
            except (ValueError, ArithmeticError, IndexError) as exc:
                failed[name] = str(exc)
        return {'fits': fits, 'failed': failed}

    def _interrupt(self) -> None:
        if self._cancel.is_set():
            raise FitCancelled()

    def stop_fit(self) -> None:
        """Cancel a running noise fit and wait for its thread (the node is stopping)."""
        self._cancel.set()
        with self._fit_lock:
            thread = self._fit_thread
        if thread is not None:
            thread.join()

    def destroy_node(self) -> None:
        """Cancel and join a running fit first: it publishes through this node."""
        self.stop_fit()
        super().destroy_node()

    def noise_message(self, res, fitted: Dict[str, Any]) -> DiagnosticArray:
        """Return one status per channel: N, B, K, Q, R (SI in the keys) with intervals."""
        statuses = []
        for name in res.channels:
            values, fit = record_values(res), fitted['fits'].get(name)
            if fit is None:
                level, message = ERROR, 'fit failed: ' + fitted['failed'].get(name, '?')
            else:
                values.update(fit_values(fit))
                level, message = OK, (f'{fit.method} fit on {res.n_samples} samples '
                                      f'({values["duration_s"]:.6g} s); unresolved terms are '
                                      'upper bounds')
            statuses.append(diagnostic_status(
                DiagnosticStatus, KeyValue, status_name(self, f'noise {name}'), level, message,
                self.hardware_id, values))
        return diagnostic_array(DiagnosticArray, self.get_clock().now().to_msg(), statuses)

    def _fit_and_publish(self, res) -> None:
        started = time.monotonic()
        try:
            fitted = self.fit(res)
            self.noise_pub.publish(self.noise_message(res, fitted))
            status = f'fit of {res.n_samples} samples done in {time.monotonic() - started:.1f} s'
            failed = fitted['failed']
            if failed:
                status += '; failed: ' + '; '.join(f'{n} ({why})' for n, why in failed.items())
            out = self.p['output_dir']
            if out and fitted['fits']:
                from gyro_char.report.allan_outputs import write_outputs
                write_outputs(out, res, fitted['fits'], self.imu_topic,
                              title=f'{NAME}: {res.n_samples} samples at '
                                    f'{1.0 / res.dt:.6g} Hz, fit {self.p["fit_method"]}')
                status += f'; files written to {out} ({", ".join(fitted["fits"])})'
            elif out:
                status += '; no files written (no channel fitted)'
            log = self.get_logger().warning if failed else self.get_logger().info
        except FitCancelled:
            status = 'fit cancelled: the node is stopping'
            log = self.get_logger().info
        except Exception as exc:  # noqa: B902 - a worker thread must report, never vanish
            status = f'fit/output failed: {exc!r}'
            log = self.get_logger().error
        self.fit_status = status
        log(status)

    # -- diagnostics ---------------------------------------------------------------------------

    def health_status(self) -> tuple:
        """Return (level, message, values) for /diagnostics."""
        st = self.status.begin()
        st.streams([self.health], time.time(), self.p['stall_timeout_s'])
        summary = self.live.summary()
        st.values.update(summary)
        if summary.get('motion_events'):
            st.warn(f'motion detected {summary["motion_events"]} times (last '
                    f'{summary["motion_last_start_s"]:.3f}..'
                    f'{summary["motion_last_end_s"]:.3f} s): not a static record')
        if st.grew('off_rate', self.live.off_rate_samples) > 0:
            st.warn(f'rate changed to {self.live.off_rate_hz:.6g} Hz: those samples are '
                    'not accumulated (call ~/reset to restart at the new rate)')
        new_gaps = st.grew('gaps', self.live.gaps)
        if new_gaps > 0:
            st.warn(f'{new_gaps} new stamp gaps (segments pooled, see gap_time_s)')
        st.values['resumed_samples'] = self.resumed_samples
        st.values['processing_errors'] = self.processing_errors
        st.values['checkpoint_errors'] = self.checkpoint_errors
        if self.checkpoint is not None:
            st.values['checkpoint_writes'] = self.checkpoint.writes
            age = self.checkpoint.age_s()
            st.values['checkpoint_age_s'] = math.nan if age is None else age
        if self.processing_errors or self.checkpoint_errors:
            st.error('processing/checkpoint errors (see log)')
        st.values['fit_status'] = self.fit_status
        return st.result()

    def publish_diagnostics(self) -> None:
        """Publish the input health, accumulation state and motion on /diagnostics."""
        publish_input_health(self)

    def _on_reset(self, request: Trigger.Request, response: Trigger.Response):
        self._q.clear()
        self.live.reset()
        self.health.reset()
        self.status.reset()
        self.resumed_samples = 0
        if self.checkpoint is not None:
            self.write_checkpoint()
        response.success = True
        response.message = 'accumulator, motion detector and input counters cleared'
        return response


def _stop(node: AllanNode) -> None:
    node.stop_fit()
    if node.checkpoint is not None:
        node.process()
        node.write_checkpoint()


def main(args=None) -> int:
    """Run the node (Jazzy idiom; exit 2 on an invalid parameter)."""
    return run_node(AllanNode, NAME, on_exit=_stop, args=args)


if __name__ == '__main__':
    raise SystemExit(main())
