# time_delay's gyro lag (lag_s) and timestamp_jitter's correlation time (tau_s) against ground
# truth on simulated runs; both default to 0, which is the earlier effect unchanged.
from dataclasses import replace

from gyro_char.errors import InputError
from gyro_char.sim.config import BenchConfig, noiseless
from gyro_char.sim.effects import parse_effect
from gyro_char.sim.simulator import simulate_swing
import numpy as np
import pytest


def _quiet_swing():
    return noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)


def _quadrature(run, cfg):
    t, g = run.imu.t, run.imu.channels['gyro_x']
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]) * np.diff(t))])
    te, enc = run.encoder.t, run.encoder.channels['encoder']
    inside = (te > t[0] + 0.5) & (te < t[-1] - 0.5)
    w = 2 * np.pi / cfg.stand.period_s
    ts = te[inside]
    cols = np.c_[np.sin(w * ts), np.cos(w * ts), np.ones_like(ts), ts]
    resid = np.interp(ts, t, angle) - enc[inside]
    return np.linalg.lstsq(cols, resid, rcond=None)[0][1] / (cfg.stand.amplitude * w)


@pytest.mark.parametrize('delay, lag', [(2e-3, 2e-3), (3e-3, 1e-3), (4e-4, 4e-4)])
def test_lag_and_stamp_shift_add_up_to_delay_s(delay, lag):
    cfg = _quiet_swing()
    run = simulate_swing(cfg, duration=30.0, seed=1, channels=['gyro_x'],
                         effects=[f'time_delay:delay_s={delay},lag_s={lag}'])
    # The gyro angle lags the encoder's by delay_s, whatever part the one-pole filter takes.
    assert -_quadrature(run, cfg) == pytest.approx(delay, rel=0.01)
    nominal = np.arange(len(run.imu)) / cfg.gyro.rate_hz
    assert np.allclose(run.imu.t - nominal, delay - lag, atol=1e-12)


def test_lag_colours_white_noise_as_a_one_pole_filter():
    quiet = noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)
    noisy = replace(quiet, noise={'gyro_x': {'N': 1e-2}})
    lag, dt = 2.5e-3, 1.0 / quiet.gyro.rate_hz

    def noise(fx):   # the gyro noise alone: noisy minus noise-free run, same seed
        x, y = (simulate_swing(c, duration=200.0, seed=4, channels=['gyro_x'], effects=fx)
                .imu.channels['gyro_x'] for c in (noisy, quiet))
        return x - y
    n0, n1 = noise([]), noise([f'time_delay:delay_s={lag},lag_s={lag}'])
    a = lag / (lag + dt)
    rho = np.sum(n1[1:] * n1[:-1]) / np.sum(n1 * n1)
    # AR(1) of white input: lag-1 autocorrelation a, variance (1 - a) / (1 + a) of the input's.
    assert rho == pytest.approx(a, abs=0.01)
    assert np.var(n1) / np.var(n0) == pytest.approx((1 - a) / (1 + a), rel=0.02)


def test_defaults_are_the_earlier_effects_bit_for_bit():
    cfg = noiseless(BenchConfig.from_preset('adis16405'))
    pairs = [(['time_delay:delay_s=0.002'], ['time_delay:delay_s=0.002,lag_s=0']),
             (['timestamp_jitter:sigma_s=5e-5'], ['timestamp_jitter:sigma_s=5e-5,tau_s=0'])]
    for a, b in pairs:
        ra, rb = (simulate_swing(cfg, duration=10.0, seed=3, channels=['gyro_x'], effects=fx)
                  for fx in (a, b))
        assert np.array_equal(ra.imu.t, rb.imu.t) and np.array_equal(ra.encoder.t, rb.encoder.t)
        assert np.array_equal(ra.imu.channels['gyro_x'], rb.imu.channels['gyro_x'])
    assert parse_effect('time_delay').lag_s == 0.0 and parse_effect('timestamp_jitter').tau_s == 0


@pytest.mark.parametrize('tau', [0.0, 5e-3, 0.05])
def test_correlated_stamp_error_is_gauss_markov(tau):
    cfg = _quiet_swing()
    sigma = 2e-4
    run = simulate_swing(cfg, duration=300.0, seed=5, channels=['gyro_x'],
                         effects=[f'timestamp_jitter:sigma_s={sigma},stream=0,tau_s={tau}'])
    dt = 1.0 / cfg.gyro.rate_hz
    e = run.imu.t - np.arange(len(run.imu)) * dt
    assert np.std(e) == pytest.approx(sigma, rel=0.05 if tau < 0.01 else 0.15)
    for k in (1, 10):
        rho = np.sum(e[k:] * e[:-k]) / np.sum(e * e)
        assert rho == pytest.approx(np.exp(-k * dt / tau) if tau else 0.0, abs=0.03)


def test_negative_lag_or_correlation_time_is_refused():
    with pytest.raises(InputError):
        parse_effect('time_delay:lag_s=-1e-3')
    with pytest.raises(InputError):
        parse_effect('timestamp_jitter:tau_s=-1')


def test_a_smooth_stamp_error_is_second_order_and_not_clipped():
    # order 2: a clock offset slewed by a servo, 2 ms sd (two sample intervals) over 1 s:
    # stationary, unclipped (a white error is clipped at 0.45 interval), autocorrelation
    # (1 + k / n) e^(-k / n) of the critically damped pair of poles (n = tau / dt), steps
    # far below the interval.
    cfg = _quiet_swing()
    dt = 1.0 / cfg.gyro.rate_hz
    sigma, tau = 2e-3, 1.0
    es = []
    for seed in range(4):
        run = simulate_swing(cfg, duration=300.0, seed=seed, channels=['gyro_x'], effects=[
            f'timestamp_jitter:sigma_s={sigma},stream=0,tau_s={tau},order=2'])
        es.append(run.imu.t - np.arange(len(run.imu)) * dt)
    e = np.concatenate(es)
    assert np.std(e) == pytest.approx(sigma, rel=0.2)
    assert np.max(np.abs(e)) > 2 * dt
    n = tau / dt
    for k in (int(n / 4), int(n)):
        rho = np.mean([np.sum(x[k:] * x[:-k]) / np.sum(x * x) for x in es])
        assert rho == pytest.approx((1 + k / n) * np.exp(-k / n), abs=0.1)
    assert np.max(np.abs(np.diff(es[0]))) < 0.01 * dt
    with pytest.raises(InputError):
        parse_effect('timestamp_jitter:tau_s=1,order=3')


def test_a_resonant_stamp_error_is_the_ar2_band_of_its_centre_and_quality():
    # freq_hz: the jitter peaking of an underdamped clock servo, 25 Hz, q 3, 100 us sd on
    # 1 kHz stamps: its autocorrelation follows the Yule-Walker recursion of the AR(2) whose
    # poles are r e^(+-i 2 pi f0 dt), r = e^(-pi f0 dt / q) (ground truth written here from
    # the definition, not from the generator), and its spectrum peaks near f0.
    cfg = _quiet_swing()
    dt = 1.0 / cfg.gyro.rate_hz
    sigma, f0, q = 1e-4, 25.0, 3.0
    run = simulate_swing(cfg, duration=400.0, seed=6, channels=['gyro_x'], effects=[
        f'timestamp_jitter:sigma_s={sigma},stream=0,freq_hz={f0},q={q}'])
    e = run.imu.t - np.arange(len(run.imu)) * dt
    assert np.all(np.diff(run.imu.t) > 0)
    assert np.std(e) == pytest.approx(sigma, rel=0.05)
    r, th = np.exp(-np.pi * f0 * dt / q), 2 * np.pi * f0 * dt
    a1, a2 = 2 * r * np.cos(th), -r * r
    rho = [1.0, a1 / (1 - a2)]
    for _ in range(60):
        rho.append(a1 * rho[-1] + a2 * rho[-2])
    for k in (5, 10, 20, 40, 60):
        got = np.sum(e[k:] * e[:-k]) / np.sum(e * e)
        assert got == pytest.approx(rho[k], abs=0.04), k
    f = np.fft.rfftfreq(8192, dt)
    psd = np.mean([np.abs(np.fft.rfft(s * np.hanning(8192))) ** 2
                   for s in e[:e.size // 8192 * 8192].reshape(-1, 8192)], axis=0)
    assert f[np.argmax(psd)] == pytest.approx(f0 * np.sqrt(1 - 1 / (2 * q * q)), rel=0.1)
    with pytest.raises(InputError):
        parse_effect('timestamp_jitter:freq_hz=20,q=0.3')
    with pytest.raises(InputError, match='Nyquist'):
        simulate_swing(cfg, duration=5.0, seed=1, channels=['gyro_x'],
                       effects=['timestamp_jitter:sigma_s=1e-5,stream=0,freq_hz=600'])
