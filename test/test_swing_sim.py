# End to end on the bench simulator (the paper's model): the swing estimates against the
# simulator's truth, the CLI on a simulated bag-free CSV, and a small, fast version of the
# Monte Carlo method-error study of bench/mc_swing.py.
import json

from gyro_char.cli import main
from gyro_char.io import read_imu, write_bag
from gyro_char.live.swing_online import SwingOnline
from gyro_char.records import Recording
from gyro_char.sim.monte_carlo import monte_carlo, study_config
from gyro_char.sim.simulator import simulate_swing
from gyro_char.swing.filter import estimate_swing
import numpy as np
import pytest


@pytest.mark.parametrize('study', ['fog', 'mems'])
def test_estimates_match_simulator_truth(study):
    cfg = study_config(study)
    sim = simulate_swing(cfg, duration=180.0, seed=7)
    tr = sim.truth['swing']
    res = estimate_swing(sim.imu, sim.encoder, tr['period_s'])
    e = res.estimates
    assert res.aligned.axis == 'gyro_x'
    for key in ('scale_factor_error', 'bias', 'bias_drift'):
        est = getattr(e, key)
        assert abs(est.value - tr[key]) < 4.5 * est.sigma, (key, est, tr[key])
    assert abs(e.amplitude_encoder.value - tr['amplitude']) < 1e-4 * tr['amplitude']
    # The gyro noise level recovered from the residuals is the simulator's N.
    n_true = sim.truth['channels']['gyro_x']['N']
    assert e.noise_gyro_arw == pytest.approx(n_true, rel=0.1)


def test_cli_on_simulated_bag(tmp_path):
    cfg = study_config('fog')
    sim = simulate_swing(cfg, duration=40.0, seed=11)
    bag = tmp_path / 'bag'
    write_bag(str(bag), sim.imu, sim.encoder)
    out = tmp_path / 'out'
    assert main(['swing', str(bag), '--period', '5', '--imu-topic', '/imu/data_raw',
                 '--encoder-topic', '/stand/joint_states', '--out', str(out), '--quiet']) == 0
    data = json.loads((out / 'swing.json').read_text())
    tr = sim.truth['swing']
    for key in ('scale_factor_error', 'bias', 'bias_drift'):
        assert abs(data[key]['value'] - tr[key]) < 4.5 * data[key]['sigma'], key
    assert (out / 'swing.png').exists()


def test_online_on_simulator_streams_matches_offline():
    cfg = study_config('mems')
    sim = simulate_swing(cfg, duration=60.0, seed=3, channels=('gyro_x',))
    off = estimate_swing(sim.imu, sim.encoder, cfg.stand.period_s, axis='x')
    al = off.aligned
    on = SwingOnline(cfg.stand.period_s, t_ref=al.t_ref)
    ti, te = al.t_ref + al.tau_gyro, al.t_ref + al.tau_encoder
    for lo in range(0, ti.size, 997):  # IMU and encoder chunks of different sizes
        on.add_imu(ti[lo:lo + 997], al.rate_gyro[lo:lo + 997])
    for lo in range(0, te.size, 1500):
        on.add_encoder(te[lo:lo + 1500], al.angle_encoder[lo:lo + 1500])
    e_on, e_off = on.estimates(), off.estimates
    for key in ('scale_factor_error', 'bias', 'bias_drift'):
        a, b = getattr(e_on, key), getattr(e_off, key)
        assert a.value == pytest.approx(b.value, rel=1e-6, abs=1e-3 * b.sigma)
        assert a.sigma == pytest.approx(b.sigma, rel=1e-3)


def test_monte_carlo_small():
    # 24 short FOG runs: the errors scatter as the filter's sigma says, and the method error is
    # far inside the paper's 0.999 bounds at this level of noise.
    s = monte_carlo('fog', 24, duration=120.0, seed0=500)
    for key in ('z_sfe', 'z_bias', 'z_drift'):
        assert abs(s[key]['mean']) < 0.8, (key, s[key])
        assert 0.55 < s[key]['std'] < 1.6, (key, s[key])
    lo, hi = s['sfe_pp']['interval_normal']
    assert -0.008 < lo and hi < 0.0498
    assert s['bias_pct']['abs_bound_normal'] < 0.8


def test_random_walk_tuning_beats_plain_tuning():
    # MEMS: the angle random walk dominates the integrated angle's error; modelling it as
    # process noise (Q33 = N^2 dt, R = 0) scatters less than the plain Q = 0, white-R tuning on
    # the same records (see bench/mc_swing.py for the 1000-run figures).
    s = monte_carlo('mems', 16, duration=120.0, seed0=600)
    for key in ('sfe_pp', 'bias_pct', 'drift_pct'):
        assert s[key]['std'] < s['plain_' + key]['std'], key
    assert np.isfinite(s['drift_pct']['std'])


def test_injected_swing_on_real_adis16405_noise(adis_records):
    # Outside reference: the device's real noise (internal smoothing, 0.05 deg/s steps, bias
    # instability) with a known swing added; bench/swing_real_noise.py runs all 22 windows.
    rec = read_imu(str(adis_records[0]), quiet=True)
    m = rec.t < rec.t[0] + 300.0
    t, g = rec.t[m], rec.channels['gyro_x'][m]
    a, period, drho = np.radians(20.0), 5.0, 0.005
    w = 2 * np.pi / period
    rate = g + (1 + drho) * a * w * np.cos(w * (t - t[0]) + 0.7)
    enc = a * np.sin(w * (t - t[0]) + 0.7) + 5e-6 * np.random.default_rng(1).standard_normal(
        t.size)
    e = estimate_swing(Recording(t, {'gyro_x': rate}), Recording(t, {'encoder': enc}),
                       period).estimates
    assert abs(e.scale_factor_error.value - drho) < 4 * e.scale_factor_error.sigma
    assert e.scale_factor_error.sigma < 3e-4
    # Bias and drift against the static record itself: the model's mean rate over the window
    # (bias + drift at mid-window) equals the plain mean of the static samples.
    mid = 0.5 * (t[-1] - t[0])
    assert abs(e.bias.value + e.bias_drift.value * mid - g.mean()) < 0.05 * e.bias.sigma
