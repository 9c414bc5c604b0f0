"""The swing Nyquist screen: chi-square on clean runs, the size of known alternating errors."""
import json

import bench_script
from gyro_char.cli import main
from gyro_char.diagnosis.swing_nyquist import BLOCK, MIN_BLOCKS, nyquist_screen, screen_warning
from gyro_char.diagnosis.swing_residuals import residuals
from gyro_char.io.bag_write import write_bag
from gyro_char.records import ENCODER_CHANNEL, Recording
from gyro_char.sim.config import BenchConfig, load
from gyro_char.sim.simulator import simulate_swing
from gyro_char.swing.align import integrate
import numpy as np
import pytest

K2 = 0.0156          # per rad/s: a quadratic term k2 w^2 (0.68 % of the 20 deg, 5 s peak rate)
RUNS = {}


def clean_run(seed):
    """Return (t, rate, th) of a clean 120 s run of the default bench, gyro x at 1 kHz."""
    if seed not in RUNS:
        run = simulate_swing(duration=120.0, seed=seed, channels=('gyro_x',))
        imu, enc = run.imu, run.encoder
        res = residuals(imu.t, imu.channels['gyro_x'], enc.t, enc.channels[ENCODER_CHANNEL],
                        load().stand.period_s)
        RUNS[seed] = (imu.t[res.idx_g], imu.channels['gyro_x'][res.idx_g], res.th,
                      res.peak_rate)
    return RUNS[seed]


def chopped(t, th, peak_rate, k2=K2, phase=0):
    """Return k2 w^2 re-signed at every output sample (w from the swing phase)."""
    k = np.arange(t.size)
    w = peak_rate * np.cos(th)
    return np.where((k + phase) % 2 == 0, 1.0, -1.0) * k2 * w * w


def test_clean_runs_follow_chi2_on_5_dof_and_do_not_warn():
    cfg = BenchConfig.from_preset('adis16405')
    white = cfg.noise['gyro_x']['N'] * np.sqrt(1000.0)
    out = [nyquist_screen(*clean_run(seed)[:3]) for seed in range(6)]
    assert all(s['tested'] and s['dof'] == 5 and not s['flagged'] for s in out)
    assert all(screen_warning('record 1', s) is None for s in out)
    assert 1.1 < np.mean([s['chi2'] for s in out]) < 8.9          # 5 +- 3 sd of a mean of 6
    # The noise level at Nyquist is the white gyro noise's (per sample), from block means.
    assert np.median([s['noise_rad_s'] for s in out]) == pytest.approx(white, rel=0.12)


@pytest.mark.parametrize('k2,phase', [(K2, 0), (K2, 1), (K2 / 4, 0)])
def test_an_alternating_quadratic_term_is_found_at_its_size(k2, phase):
    t, x, th, peak = clean_run(1)
    err = chopped(t, th, peak, k2, phase)
    s = nyquist_screen(t, x + err, th)
    assert s['flagged'] and s['p_value'] < 1e-10
    truth = float(np.sqrt(np.mean(err * err)))
    # The fitted component's rms against the truth, within 4 sd of its noise.
    sd = s['noise_rad_s'] * np.sqrt(5.0 / x.size)
    assert abs(s['rms_rad_s'] - truth) < 4 * sd + 0.02 * truth
    warning = screen_warning('record 2', s)
    assert 'Nyquist' in warning and warning.startswith('record 2: ')


def test_dropped_samples_keep_the_parity_and_smooth_or_stamp_errors_do_not_warn():
    t, x, th, peak = clean_run(2)
    err = chopped(t, th, peak)
    keep = np.random.default_rng(0).random(t.size) > 0.01     # 1 % of the samples lost
    s = nyquist_screen(t[keep], (x + err)[keep], th[keep])
    assert s['flagged']
    assert s['rms_rad_s'] == pytest.approx(np.sqrt(np.mean(err * err)), rel=0.1)
    w = peak * np.cos(th)
    for quiet in (nyquist_screen(t, x + K2 * w * w, th),          # the same term, not chopped
                  nyquist_screen(t * (1 + 1e-4) + 2e-5 * np.random.default_rng(1).standard_normal(
                      t.size), x, th)):                           # late, jittered stamps
        assert quiet['tested'] and not quiet['flagged'], quiet


def test_short_or_non_finite_input_is_not_tested():
    t, x, th, _ = clean_run(3)
    n = MIN_BLOCKS * BLOCK
    short = nyquist_screen(t[:n], x[:n], th[:n])
    assert not short['tested'] and f'need {n}' in short['reason']
    bad = x.copy()
    bad[100] = np.nan
    assert nyquist_screen(t, bad, th) == {'tested': False, 'reason': 'non-finite gyro samples'}
    assert screen_warning('record 1', short) is None


def test_the_bench_screen_flags_set_ajs_chopped_term_and_not_its_delay():
    # bench/screen_swing.py on 60 s harness records (the study runs them at 15 min).
    bench = bench_script.load('screen_swing')
    shapes = bench.harness.held_out_shapes(1000.0, 'aj')
    chop = bench.screen([('scale_factor_nonlinearity', 1)], 11, shapes, 60.0)
    delay = bench.screen([('time_delay', 1)], 11, shapes, 60.0)
    assert chop['flagged'] and chop['rms_rad_s'] == pytest.approx(1.84e-3, rel=0.1)
    assert delay['tested'] and not delay['flagged']


def test_diagnose_warns_of_a_chopped_term_on_a_real_bag(tmp_path, capsys):
    # A 60 s, 200 Hz swing run with a chopped k2 w^2, written as a real bag and diagnosed.
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': 200.0}})
    run = simulate_swing(cfg, duration=60.0, seed=3)
    imu, enc = run.imu, run.encoder
    res = residuals(imu.t, imu.channels['gyro_x'], enc.t, enc.channels[ENCODER_CHANNEL],
                    cfg.stand.period_s)
    err = np.zeros(imu.t.size)
    err[res.idx_g] = chopped(imu.t[res.idx_g], res.th, res.peak_rate)
    channels = dict(imu.channels, gyro_x=imu.channels['gyro_x'] + err)
    bag = str(tmp_path / 'chopped')
    write_bag(bag, Recording(imu.t, channels, imu.source), enc)
    out = tmp_path / 'out'
    assert main(['diagnose', '--kind', 'swing', bag, '--out', str(out), '--repeats', '4',
                 '--quiet']) == 0
    d = json.loads((out / 'diagnosis.json').read_text())
    screen = d['per_record'][0]['rate_nyquist']
    assert screen['flagged'] and screen['rms_rad_s'] == pytest.approx(
        np.sqrt(np.mean(err[res.idx_g] ** 2)), rel=0.15)
    assert [w for w in d['warnings'] if w.startswith('record 1: ') and 'Nyquist' in w]
    assert 'WARNING: record 1: the gyro rate carries a component at its Nyquist' in (
        capsys.readouterr().out)


def test_the_integrated_angle_cannot_see_a_chopped_term():
    # Why the screen exists: the trapezoid integral every swing block reads nulls the Nyquist
    # carrier. 15 min at 1 kHz, 20 deg at 5 s: 1.8e-3 rad/s rms of rate leaves < 1e-9 rad.
    t = np.arange(900_000) * 1e-3
    th = 2 * np.pi * t / 5.0
    err = chopped(t, th, np.deg2rad(20.0) * 2 * np.pi / 5.0)
    assert np.sqrt(np.mean(err * err)) == pytest.approx(1.84e-3, rel=0.01)
    assert np.sqrt(np.mean(integrate(t, err) ** 2)) < 1e-9
