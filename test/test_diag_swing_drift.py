# The swing waveform screen (gyro_char/diagnosis/swing_drift.py) on bench-simulator runs of
# known content: the clean runs' statistic sits at its degrees of freedom, an effect that
# changes along the run is flagged at its own harmonic, the same effect held constant is not.
from gyro_char.diagnosis.swing_drift import drift_screen, drift_warning, record_drift
from gyro_char.diagnosis.swing_residuals import residuals
from gyro_char.records import ENCODER_CHANNEL, Recording
from gyro_char.sim.chain import stand_rate_clean
from gyro_char.sim.config import BenchConfig
from gyro_char.sim.simulator import simulate_swing
import numpy as np
import pytest

PERIOD = 2.5            # 200 s runs hold 80 periods: six segments of 12 and more


def _run(seed, duration=200.0, extra=None):
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 200.0},
                                                'stand': {'period_s': PERIOD}})
    run = simulate_swing(cfg, duration=duration, seed=seed, channels=('gyro_x',))
    imu = run.imu
    if extra is not None:
        w = stand_rate_clean(cfg.stand, imu.t)
        x = imu.channels['gyro_x'] + extra(imu.t / duration, w)
        imu = Recording(imu.t, {'gyro_x': x}, imu.source)
    return imu, run.encoder


def _screen(seed, **kw):
    return record_drift(*_run(seed, **kw), 'x', PERIOD)


def test_clean_runs_sit_at_the_degrees_of_freedom_and_are_not_flagged():
    s = [_screen(seed) for seed in range(8)]
    assert all(x['tested'] and not x['flagged'] for x in s)
    dof = s[0]['dof']
    assert dof == 40 and s[0]['noise_dof'] == 48
    stat = np.array([x['statistic'] for x in s])
    # F(40, 48) scaled by 40: mean 40 x 48 / 46, sd about 14 a draw.
    assert abs(stat.mean() - 40 * 48 / 46) < 3 * 14 / np.sqrt(len(s))
    assert all(drift_warning('record 1', x) is None for x in s)


def test_a_fading_asymmetry_is_flagged_at_2f_and_the_same_held_constant_is_not():
    a = 0.02
    fading = _screen(4, extra=lambda u, w: a * np.exp(-3 * u) * np.abs(w))
    assert fading['flagged']
    worst = max(fading['harmonics'], key=lambda h: h['chi2'])
    assert worst['k'] == 2 and worst['change_rad'] > 3 * worst['noise_rad']
    text = drift_warning('record 1', fading)
    assert text.startswith('record 1: the swing residual') and 'harmonic 2' in text
    # The constant effect at the fading one's mean strength: a line, but the same in every
    # segment.
    held = _screen(4, extra=lambda u, w: a * (1 - np.exp(-3)) / 3 * np.abs(w))
    assert held['tested'] and not held['flagged']


def test_a_scale_factor_ramp_is_flagged_in_phase():
    ramp = _screen(5, extra=lambda u, w: 0.01 * u * w)
    assert ramp['flagged']
    assert max(ramp['harmonics'], key=lambda h: h['chi2'])['k'] == 1


def test_short_or_broken_runs_are_not_tested_and_say_why():
    short = _screen(6, duration=60.0)
    assert not short['tested'] and 'need 180 s' in short['reason']
    imu, enc = _run(7)
    res = residuals(imu.t, imu.channels['gyro_x'], enc.t, enc.channels[ENCODER_CHANNEL],
                    PERIOD)
    res.r[100] = np.nan
    bad = drift_screen(res, PERIOD)
    assert bad == {'tested': False, 'reason': 'non-finite residual'}
    assert drift_warning('record 1', bad) is None


@pytest.mark.parametrize('segment', [0, 5])
def test_a_change_in_one_segment_alone_is_seen(segment):
    # A scale factor that jumps for the first or the last sixth of the run only.
    def step(u, w):
        return np.where((u >= segment / 6) & (u < (segment + 1) / 6), 0.004 * w, 0.0)
    s = _screen(8, extra=step)
    assert s['flagged']


def test_the_bench_screen_flags_set_ajs_forming_half_and_not_a_clean_run():
    # bench/screen_swing.py --screen drift on 200 s harness records at 2.5 s (the study runs
    # 15 min at 5 s): set AJ's gain error that fades with negative travel.
    import bench_script
    bench = bench_script.load('screen_swing')
    shapes = bench.harness.held_out_shapes(1000.0, 'aj')
    formed = bench.screen([('scale_factor_asymmetry', 1)], 11, shapes, 200.0, 'drift', PERIOD)
    clean = bench.screen([], 11, shapes, 200.0, 'drift', PERIOD)
    assert formed['flagged'] and clean['tested'] and not clean['flagged']
    # a e(t) w on w < 0 alone is a e(t) (w - |w|) / 2: its in-phase half, a scale factor
    # that changes, shows most.
    assert max(formed['harmonics'], key=lambda h: h['chi2'])['k'] == 1
