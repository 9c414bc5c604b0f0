# The swing baseline's calibration against the record and the error it leaves in the twins.
from dataclasses import replace

from gyro_char.diagnosis import gap as diag_gap, swing as diag_swing, swing_calibrate
from gyro_char.diagnosis.swing_baseline import fit_baseline, sample_interval
from gyro_char.diagnosis.swing_calibrate import (calibrate_encoder, calibration_shifts,
                                                 turning_power, with_calibration_error)
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
import numpy as np
import pytest


def _run(seed, duration=60.0, rate_hz=200.0):
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': rate_hz},
                                                'stand': {'period_s': 5.0}})
    return simulator.simulate_swing(cfg, duration=duration, seed=seed, channels=('gyro_x',))


def test_the_sample_interval_is_the_stamps_slope_and_counts_dropped_samples():
    # 1 kHz stamps with 20 us jitter over 200 000 samples: the span over the count is off by
    # the two end stamps' jitter (~1.4e-10 s a sample); the slope by ~1e-12.
    rng = np.random.default_rng(3)
    n, dt = 200_000, 1e-3
    t = dt * np.arange(n) + 2e-5 * rng.standard_normal(n)
    t[-1] = dt * (n - 1) + 8e-5                          # an end stamp 4 sigma late
    span = (t[-1] - t[0]) / (n - 1)
    assert abs(span - dt) > 1e-10
    assert abs(sample_interval(t) - dt) < 1e-11
    gapped = np.delete(t, np.arange(5000, 5003))        # three samples lost
    assert abs(sample_interval(gapped) - dt) < 1e-11
    assert abs((gapped[-1] - gapped[0]) / (gapped.size - 1) - dt) > 1e-8


def test_the_turning_point_power_knows_its_own_standard_error():
    # Over 16 runs of 60 s, the reported standard error of the encoder's turning-point power
    # is the power's scatter from run to run (within the 16-run sd's own ~18 % error).
    got = np.array([turning_power(_run(seed).encoder, 5.0) for seed in range(60, 76)])
    scatter = float(np.std(got[:, 0], ddof=1))
    assert np.mean(got[:, 1]) == pytest.approx(scatter, rel=0.5)
    # The power is the encoder's white angle noise at the turning points (ADC, both
    # quantizations, and the stand's amplitude noise, in full there): ~ 3.7e-11 rad^2.
    cfg = BenchConfig.from_preset('adis16405')
    e, st = cfg.encoder, cfg.stand
    white = e.adc_noise ** 2 + e.level_step ** 2 / 12 + e.word_step ** 2 / 12 \
        + st.amplitude_noise ** 2
    assert np.mean(got[:, 0]) == pytest.approx(white, rel=0.1)


def test_each_twin_carries_a_draw_of_the_calibration_error():
    # A clean 2-min 1 kHz run's baseline: its calibrated levels carry a standard error, their
    # shifts move the residual's lag-1 increment correlation by more than the twins' own
    # scatter, and the wrapped twins scatter by sqrt(own^2 + shifts^2) there.
    run = _run(21, duration=120.0, rate_hz=1000.0)
    problem = diag_swing.swing_records_problem([(run.imu, run.encoder, 5.0)])
    base = problem.context[0]
    assert base.encoder_power_sd > 0 and base.n_log_sd > 0
    shifts = calibration_shifts(base, problem.ranges[0])
    assert len(shifts) == 2
    lag1 = np.hypot(shifts[0]['increment_acf'][0], shifts[1]['increment_acf'][0])
    plain = diag_swing.expected_twins(problem.context, problem.ranges, False)
    own = np.std([plain(0, [], 500 + k)['increment_acf'][0] for k in range(24)], ddof=1)
    assert lag1 > own
    wrapped = with_calibration_error(plain, [shifts])
    reps = [wrapped(0, [], 500 + k) for k in range(24)]
    got = diag_gap.sim_stats(reps).std['increment_acf'][0]
    assert got == pytest.approx(np.hypot(own, lag1), rel=0.35)
    # The same seed gets the same draw (every candidate model sees the same error).
    again = wrapped(0, [], 503)
    assert np.array_equal(again['increment_acf'], reps[3]['increment_acf'])
    # A baseline without calibration errors is left as simulated.
    bare = replace(base, encoder_power_sd=0.0, n_log_sd=0.0)
    assert calibration_shifts(bare, problem.ranges[0]) == []


def test_the_encoder_level_is_found_again_after_a_far_first_guess(monkeypatch):
    # A smooth 2 ms encoder stamp error (a servo-slewed clock): the filter's encoder noise
    # lumps in rate x error, ~100 times the ADC noise. One step from there left the level at
    # the first twins' sampling noise; the passes bring it to the clean run's level.
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 200.0},
                                                'stand': {'period_s': 5.0}})
    wander = [{'name': 'timestamp_jitter', 'params': {'sigma_s': 2e-3, 'tau_s': 2.0,
                                                      'order': 2.0, 'stream': 1.0}}]
    run = simulator.simulate_swing(cfg, duration=120.0, seed=8, channels=('gyro_x',),
                                   effects=wander)
    clean = _run(8, duration=120.0)
    base = fit_baseline(run.imu, run.encoder, 5.0)
    assert base.encoder_sigma > 30 * 5e-6
    pinned = calibrate_encoder(base, run.encoder)
    reference = calibrate_encoder(fit_baseline(clean.imu, clean.encoder, 5.0), clean.encoder)
    assert pinned.encoder_sigma == pytest.approx(reference.encoder_sigma, rel=0.1)
    # One pass only (the earlier calibration) is far off: the far twins' sampling noise is
    # ~30 times the ADC power, so the ADC part comes out at 0 (the level of the other white
    # terms alone, 20 % low here) or many times too high.
    monkeypatch.setattr(swing_calibrate, 'ENCODER_PASSES', 1)
    one = calibrate_encoder(base, run.encoder)
    assert abs(one.encoder_sigma / reference.encoder_sigma - 1.0) > 0.15
