"""Plain-Python pieces the nodes are built on: stream health, motion, checkpoints, messages."""
import os
import subprocess
import sys

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from gyro_char.errors import InputError
from gyro_char.live.checkpoint import load_checkpoint, PeriodicCheckpoint, save_checkpoint
from gyro_char.live.motion_detect import MotionDetector
from gyro_char.live.stream_health import ACCEPT, DROP, RESTART, stream_skew_s, StreamHealth
from msg_adapters.diagnostics import (
    diagnostic_array, diagnostic_status, level_of, multiarray, parse_key_values,
    parse_multiarray, WARN)
import numpy as np
import pytest
from std_msgs.msg import Float64MultiArray, MultiArrayDimension


def _feed(health, stamps, recv0=100.0, frame=''):
    return [health.admit(s, recv0 + i * 1e-3, frame) for i, s in enumerate(stamps)]


def test_admit_counts_each_bad_input_kind():
    h = StreamHealth('imu', frame_id='imu_link', max_rate_hz=0)
    codes = _feed(h, [1.0, 1.001, 1.001, 0.5, 0.0, float('nan'), 1.002], frame='imu_link')
    assert codes == [ACCEPT, ACCEPT, DROP, DROP, DROP, DROP, ACCEPT]
    assert h.wrong_frame == 0
    assert h.admit(1.003, 101.0, 'other') == DROP
    d = h.as_dict()
    assert d['imu_received'] == 8
    assert d['imu_accepted'] == 3
    assert d['imu_dropped_duplicate'] == 1
    assert d['imu_dropped_backwards'] == 1
    assert d['imu_dropped_zero_stamp'] == 2
    assert d['imu_dropped_wrong_frame'] == 1
    assert h.dropped == 5


def test_flood_is_capped_per_wall_second():
    h = StreamHealth('imu', max_rate_hz=100)
    # 250 messages within 0.25 s of wall time: only 100 pass.
    codes = [h.admit(1.0 + i * 1e-4, 50.0 + i * 1e-3) for i in range(250)]
    assert codes.count(ACCEPT) == 100
    assert h.flood_dropped == 150
    # Next wall-clock second: accepted again.
    assert h.admit(2.0, 51.5) == ACCEPT


def test_stamp_restart_is_accepted_after_a_run_of_backwards_stamps():
    h = StreamHealth('imu', restart_after=10)
    _feed(h, [100.0 + i * 1e-3 for i in range(20)])
    codes = _feed(h, [1.0 + i * 1e-3 for i in range(15)])
    assert codes[:9] == [DROP] * 9
    assert codes[9] == RESTART
    assert codes[10:] == [ACCEPT] * 5
    assert h.restarts == 1


def test_gaps_and_rate_change_on_chunks():
    h = StreamHealth('imu', rate_window=100, gap_factor=3.0, rate_tolerance=0.1)
    t = np.arange(1000) * 1e-3 + 1.0
    t[500:] += 0.05  # 50 samples missing
    prev = None
    gap_at = []
    for i in range(0, 1000, 100):
        gap_at += list(h.observe_chunk(t[i:i + 100], previous_stamp=prev) + i)
        prev = t[i + 99]
    assert gap_at == [500]
    assert h.gaps == 1 and abs(h.gap_time_s - 0.051) < 1e-9
    assert h.as_dict()['imu_rate_hz'] == pytest.approx(1000.0)
    # The sensor switches to 500 Hz: adopted after two windows, counted once.
    t2 = prev + np.arange(1, 1001) * 2e-3
    for i in range(0, 1000, 100):
        h.observe_chunk(t2[i:i + 100], previous_stamp=prev)
        prev = t2[i + 99]
    assert h.rate_changes == 1
    assert h.dt_nominal == pytest.approx(2e-3)
    # Step 2 ms vs nominal 1 ms is below gap_factor: no spurious gaps.
    assert h.gaps == 1


def test_problems_report_only_recent_growth_and_stalls():
    h = StreamHealth('enc')
    assert h.problems(0.0, 1.0) == ['no enc data yet']
    _feed(h, [1.0, 0.5, 1.1])
    first = h.problems(100.002, 1.0)
    assert any('backwards' in p for p in first)
    snap = h.as_dict()
    assert h.problems(100.002, 1.0, previous=snap) == []
    assert h.problems(105.0, 1.0, previous=snap) == ['enc stalled for 5.0 s']


def test_skew_between_streams():
    a, b = StreamHealth('imu'), StreamHealth('enc')
    t = np.arange(100) * 1e-3 + 5.0
    assert stream_skew_s(a, b) is None
    a.observe_chunk(t, receive=t + 1000.002)
    b.observe_chunk(t, receive=t + 1000.003)
    assert stream_skew_s(a, b) == pytest.approx(-0.001)
    b.observe_chunk(t, receive=t + 1000.0 - 0.5)  # encoder now stamped 0.5 s ahead
    assert abs(stream_skew_s(a, b)) > 0.05


def _static(n, dt, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, 0.01, (n, 6))
    x[:, 5] += 9.81
    return np.arange(n) * dt, x


def test_motion_detector_silent_on_static_noise_and_finds_a_bump():
    dt = 1e-3
    t, x = _static(300_000, dt)
    d = MotionDetector(dt)
    for i in range(0, t.size, 100):
        d.add(t[i:i + 100], x[i:i + 100])
    assert d.ready and d.event_count == 0
    # A 20 Hz damped knock at 200 s (peak 20x the noise level) on one accel axis only.
    k = np.arange(200_000, 200_300)
    tau = (k - k[0]) * dt
    x[k, 3] += 0.2 * np.exp(-tau / 0.05) * np.sin(2 * np.pi * 20 * tau)
    d = MotionDetector(dt)
    for i in range(0, t.size, 100):
        d.add(t[i:i + 100], x[i:i + 100])
    assert d.event_count == 1
    ev = d.events[0]
    assert ev.channel == 3 and 199.5 <= ev.start_s <= 200.0 <= ev.end_s <= 200.6
    # A slow tilt (mean step) on gyro_y: a second event.
    x[250_000:, 1] += 0.02
    d = MotionDetector(dt)
    for i in range(0, t.size, 100):
        d.add(t[i:i + 100], x[i:i + 100])
    assert d.event_count == 2 and d.events[1].channel == 1


def test_motion_detector_state_round_trip():
    t, x = _static(40_000, 1e-3, seed=3)
    d = MotionDetector(1e-3)
    d.add(t, x)
    d2 = MotionDetector(1e-3)
    d2.load_state(d.state_dict())
    assert d2.ready and np.allclose(d2.ref_var, d.ref_var)


def test_checkpoint_round_trip_and_errors(tmp_path):
    state = {'acc': {'sum': np.arange(5.0), 'n': np.array(7)}, 'dt': 0.001, 'name': 'imu'}
    path = tmp_path / 'sub' / 'ck.npz'
    save_checkpoint(path, state)
    back = load_checkpoint(path)
    assert np.array_equal(back['acc']['sum'], np.arange(5.0))
    assert int(back['acc']['n']) == 7 and float(back['dt']) == 0.001
    assert str(back['name']) == 'imu'
    assert os.listdir(path.parent) == ['ck.npz']  # no temporary left behind
    assert load_checkpoint(tmp_path / 'none.npz') is None
    (tmp_path / 'bad.npz').write_bytes(b'not a zip')
    with pytest.raises(InputError, match='unreadable'):
        load_checkpoint(tmp_path / 'bad.npz')
    with pytest.raises(ValueError):
        save_checkpoint(path, {'a/b': 1})


def test_checkpoint_survives_kill_during_writes(tmp_path):
    """A writer killed with SIGKILL mid-stream leaves a complete, loadable checkpoint."""
    path = tmp_path / 'ck.npz'
    code = (
        'import numpy as np, sys\n'
        'from gyro_char.live.checkpoint import save_checkpoint\n'
        'i = 0\n'
        'while True:\n'
        '    save_checkpoint(sys.argv[1], {"i": i, "x": np.full(200_000, float(i))})\n'
        '    i += 1\n'
        '    print(i, flush=True)\n')
    proc = subprocess.Popen([sys.executable, '-c', code, str(path)], stdout=subprocess.PIPE)
    for _ in range(5):
        proc.stdout.readline()
    proc.kill()
    proc.wait()
    back = load_checkpoint(path)
    assert back['x'].shape == (200_000,) and np.all(back['x'] == float(back['i']))


def test_periodic_checkpoint_timing(tmp_path):
    now = [0.0]
    ck = PeriodicCheckpoint(tmp_path / 'c.npz', 10.0, clock=lambda: now[0])
    assert ck.maybe_write(lambda: {'a': 1})
    now[0] = 9.0
    assert not ck.maybe_write(lambda: {'a': 2})
    now[0] = 10.0
    assert ck.maybe_write(lambda: {'a': 3}) and ck.writes == 2
    assert int(load_checkpoint(ck.path)['a']) == 3


def test_diagnostic_builders_round_trip():
    st = diagnostic_status(DiagnosticStatus, KeyValue, 'swing_kf_node: estimates', WARN,
                           'not converged', 'imu0',
                           {'bias_rad_s': 1.25e-3, 'samples': np.int64(12), 'converged': False,
                            'sigma_rad_s': float('nan')})
    assert level_of(st) == WARN and st.level == DiagnosticStatus.WARN
    vals = parse_key_values(st)
    assert vals['bias_rad_s'] == 1.25e-3 and vals['samples'] == 12 and vals['converged'] == 0
    assert np.isnan(vals['sigma_rad_s'])
    arr = diagnostic_array(DiagnosticArray, DiagnosticArray().header.stamp, [st])
    assert arr.status[0].hardware_id == 'imu0'


def test_multiarray_layout_is_self_describing():
    data = np.arange(2 * 3 * 4, dtype=float).reshape(2, 3, 4)
    labels = [('channel', ['gyro_x', 'gyro_y']), ('quantity', ['tau_s', 'adev', 'x']),
              ('tau_index', None)]
    msg = multiarray(Float64MultiArray, MultiArrayDimension, data, labels)
    assert msg.layout.dim[0].label == 'channel:gyro_x,gyro_y'
    assert [d.stride for d in msg.layout.dim] == [24, 12, 4]
    back, back_labels = parse_multiarray(msg)
    assert np.array_equal(back, data)
    assert back_labels == [('channel', ['gyro_x', 'gyro_y']),
                           ('quantity', ['tau_s', 'adev', 'x']), ('tau_index', None)]
    with pytest.raises(ValueError):
        multiarray(Float64MultiArray, MultiArrayDimension, data, labels[:2])
