# The swing filter: the fast path (SRIF, batch and chunk-wise online) against the per-sample
# filterpy Kalman filter on the same data, and the estimates against known truth. The data are
# generated inline from the model equations of docs/method.md section 1 (unit tests of the filter;
# end-to-end runs on the bench simulator are in test_swing_sim.py).
from pathlib import Path
import sys

from gyro_char.live.swing_online import SwingOnline
from gyro_char.records import Recording
from gyro_char.swing import batch as swing_batch
from gyro_char.swing.align import integrate
from gyro_char.swing.filter import estimate_swing, SwingKalman
from gyro_char.swing.model import SwingNoise, transition
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'bench'))

from bench_swing_kf import distance, exact_posterior  # noqa: E402,I100 - bench is no package

T = 2.0
TRUTH = {'A': 0.15, 'rho': 0.004, 'bias': 0.02, 'drift': 3e-5, 'enc_sigma': 2e-5, 'arw': 2e-4}


def make_run(seed=0, duration=60.0, dt_g=0.002, dt_e=0.003, jitter=0.1, truth=TRUTH,
             t0=1000.0, axis=0, rrw=0.0):
    """Stand angle, encoder (white noise), gyro rates (white noise; + rate random walk)."""
    rng = np.random.default_rng(seed)
    w = 2 * np.pi / T

    def stamps(dt):
        n = int(duration / dt)
        return t0 + np.arange(n) * dt + jitter * dt * rng.uniform(-0.5, 0.5, n)

    psi, phi0, stand_drift = rng.uniform(0, 2 * np.pi), 0.01, 1e-5
    te, tg = stamps(dt_e), stamps(dt_g)
    angle = (truth['A'] * np.sin(w * (te - t0) + psi) + phi0 + stand_drift * (te - t0)
             + truth['enc_sigma'] * rng.standard_normal(te.size))
    rate = ((1 + truth['rho']) * (truth['A'] * w * np.cos(w * (tg - t0) + psi) + stand_drift)
            + truth['bias'] + truth['drift'] * (tg - t0)
            + truth['arw'] / np.sqrt(dt_g) * rng.standard_normal(tg.size))
    if rrw:
        rate += rrw * np.sqrt(dt_g) * np.cumsum(rng.standard_normal(tg.size))
    chans = {f'gyro_{a}': 1e-3 * rng.standard_normal(tg.size) for a in 'xyz'}
    chans['gyro_' + 'xyz'[axis]] = rate
    imu = Recording(tg, chans, source='model')
    enc = Recording(te, {'encoder': angle}, source='model')
    return imu, enc


def _agree(a, b, tol):
    sd = np.sqrt(np.diag(b.P))
    assert np.all(np.abs(a.x - b.x) <= tol * sd), (a.x, b.x)
    assert np.max(np.abs(a.P - b.P) / np.outer(sd, sd)) <= tol


@pytest.mark.parametrize('kind', [swing_batch.ENCODER, swing_batch.GYRO])
def test_filterpy_recursive_filter_matches_batch(kind):
    imu, enc = make_run(seed=1, duration=16.0)
    if kind == swing_batch.ENCODER:
        tau, z, noise = enc.t - enc.t[0], enc.channels['encoder'], TRUTH['enc_sigma']
    else:
        tau = imu.t - imu.t[0]
        z, noise = integrate(tau, imu.channels['gyro_x']), TRUTH['arw']
    ref = SwingKalman(kind, T, noise).run(tau, z).result()
    fast, _ = swing_batch.run(kind, tau, z, T, noise)
    # State and covariance at the last sample, to 1e-3 of the posterior sigma (the covariance
    # form of the per-sample filter loses a few digits to the diffuse prior; the SRIF does not).
    _agree(ref, fast, 1e-3)
    assert ref.tau == fast.tau and ref.samples == fast.samples


@pytest.mark.parametrize('kind', [swing_batch.ENCODER, swing_batch.GYRO])
def test_batch_matches_exact_posterior_on_a_record_shorter_than_a_period(kind):
    # 0.4 period with a 5 urad encoder: the posterior is ~1e-10 of the prior's variance and the
    # states are nearly collinear, where filterpy's float64 covariance form drifts by up to a
    # posterior sigma (bench/bench_swing_kf.py --duration 60 --subset 2000). The SRIF must match
    # the posterior computed in exact rational arithmetic.
    imu, enc = make_run(seed=4, duration=0.8, truth=dict(TRUTH, enc_sigma=5e-6))
    if kind == swing_batch.ENCODER:
        tau, z, noise = enc.t - enc.t[0], enc.channels['encoder'], 5e-6
    else:
        tau = imu.t - imu.t[0]
        z, noise = integrate(tau, imu.channels['gyro_x']), TRUTH['arw']
    x_ex, p_ex = exact_posterior(kind, tau, z, T, noise)
    corr = p_ex / np.sqrt(np.outer(np.diag(p_ex), np.diag(p_ex)))
    assert np.max(np.abs(corr - np.eye(5))) > 0.99  # the ill-conditioned regime indeed
    fast, _ = swing_batch.run(kind, tau, z, T, noise)
    assert distance(fast.x, fast.P, x_ex, p_ex) < 1e-6


def test_phi_composes_over_nonuniform_steps():
    steps = np.array([0.001, 0.0031, 0.0005, 0.7])
    prod = np.eye(5)
    for dt in steps:
        prod = transition(dt, T) @ prod
    assert np.allclose(prod, transition(steps.sum(), T), atol=1e-12)


def test_online_chunks_match_batch_state_and_covariance():
    imu, enc = make_run(seed=2, duration=40.0)
    t_ref = max(imu.t[0], enc.t[0])
    noise = SwingNoise(TRUTH['enc_sigma'], TRUTH['arw'])
    res = estimate_swing(imu, enc, T, axis='x', noise=noise)
    al = res.aligned
    online = SwingOnline(T, noise, t_ref=t_ref)
    rng = np.random.default_rng(0)
    ig, ie = 0, 0
    while ig < al.tau_gyro.size or ie < al.tau_encoder.size:
        k = int(rng.integers(1, 900))
        online.add_imu(t_ref + al.tau_gyro[ig:ig + k], al.rate_gyro[ig:ig + k])
        online.add_encoder(t_ref + al.tau_encoder[ie:ie + k // 2],
                           al.angle_encoder[ie:ie + k // 2])
        ig, ie = ig + k, ie + k // 2
    enc_state, gyro_state = online.states()
    _agree(enc_state, res.encoder, 1e-6)
    _agree(gyro_state, res.gyro, 1e-6)
    est = online.estimates()
    assert est.scale_factor_error.value == pytest.approx(res.estimates.scale_factor_error.value,
                                                         rel=1e-9, abs=1e-12)
    assert est.samples == res.estimates.samples


def test_estimates_match_truth_within_sigma():
    imu, enc = make_run(seed=3, duration=120.0)
    est = estimate_swing(imu, enc, T).estimates  # noise levels estimated from residuals
    for key, true in (('scale_factor_error', TRUTH['rho']), ('bias', TRUTH['bias']),
                      ('bias_drift', TRUTH['drift'])):
        e = getattr(est, key)
        assert abs(e.value - true) < 4 * e.sigma, (key, e, true)
        assert e.sigma < 0.2 * abs(true), (key, e)
    # The noise levels recovered from the residuals are the ones that made the data.
    assert est.noise_encoder_rad == pytest.approx(TRUTH['enc_sigma'], rel=0.05)
    assert est.noise_gyro_arw == pytest.approx(TRUTH['arw'], rel=0.05)
    assert est.converged


def test_sigmas_from_covariance_are_calibrated():
    # 40 independent runs: errors / reported sigma must scatter with unit standard deviation.
    z = []
    for seed in range(40):
        imu, enc = make_run(seed=100 + seed, duration=20.0, dt_g=0.004, dt_e=0.004)
        est = estimate_swing(imu, enc, T).estimates
        z.append([(est.scale_factor_error.value - TRUTH['rho']) / est.scale_factor_error.sigma,
                  (est.bias.value - TRUTH['bias']) / est.bias.sigma,
                  (est.bias_drift.value - TRUTH['drift']) / est.bias_drift.sigma])
    z = np.array(z)
    assert np.all(np.abs(z.mean(axis=0)) < 0.6), z.mean(axis=0)
    assert np.all((z.std(axis=0) > 0.7) & (z.std(axis=0) < 1.35)), z.std(axis=0)


def test_low_frequency_noise_check_scales_bias_sigmas():
    # White rate noise: the check finds the low-frequency level equal to the white one.
    imu, enc = make_run(seed=8, duration=240.0, dt_g=0.004, dt_e=0.004)
    white = estimate_swing(imu, enc, T)
    assert white.gyro.low_frequency_ratio == pytest.approx(1.0, abs=0.4)
    # A rate random walk (not in the filter's model) raises it; bias and drift sigmas follow,
    # the scale-factor sigma (set at the swing frequency) hardly changes.
    imu, enc = make_run(seed=8, duration=240.0, dt_g=0.004, dt_e=0.004, rrw=5e-5)
    walk = estimate_swing(imu, enc, T)
    k = walk.gyro.rate_sigma_scale
    assert k > 2.0 and k == walk.gyro.low_frequency_ratio
    assert walk.estimates.bias.sigma > 0.9 * k * white.estimates.bias.sigma
    assert walk.estimates.scale_factor_error.sigma == pytest.approx(
        white.estimates.scale_factor_error.sigma, rel=0.2)
    assert any('bias and drift sigmas scaled' in n for n in walk.estimates.notes)


def test_online_drops_and_counts_bad_samples():
    online = SwingOnline(T)
    online.add_imu([0.0, 0.01, 0.01, 0.005, 0.02, 0.03], [0.1, 0.2, 0.3, 0.4, np.nan, 0.5])
    online.add_encoder([0.0, 0.01], [0.0, 0.1])
    assert online.rejected == (0, 3)
    assert any('3 samples dropped' in n for n in online.estimates().notes)
    online.reset()
    assert online.rejected == (0, 0)
    assert not online.estimates().converged
