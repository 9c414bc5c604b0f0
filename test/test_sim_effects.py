"""Each catalogue effect's signature against theory (Allan, spectrum or swing residual)."""
import math

from gyro_char.errors import InputError
from gyro_char.sim.chain import G0, stand_angle_clean, stand_motion
from gyro_char.sim.config import BenchConfig, noiseless
from gyro_char.sim.effects import build_effects, EFFECTS, parse_effect
from gyro_char.sim.effects.motion import saturate
from gyro_char.sim.effects.sensor import bartlett_kernel, InternalLowpass
from gyro_char.sim.simulator import simulate_static, simulate_swing
import numpy as np
import pytest

CATALOGUE = {
    'internal_lowpass', 'time_delay', 'timestamp_jitter', 'bias_instability',
    'rate_random_walk', 'gauss_markov', 'quantization', 'temperature_drift',
    'scale_factor_nonlinearity', 'scale_factor_asymmetry', 'cross_axis', 'g_sensitivity',
    'vibration', 'resonance', 'encoder_cyclic_error'}
# Names the project added beyond the contract's list (docs/design.md, the catalogue).
EXTENSIONS = {'stale_samples'}


def _quiet(rate=100.0, white=0.0):
    cfg = noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)
    cfg.gyro.static_rate_hz = rate
    cfg.noise['gyro_x']['N'] = white
    return cfg


def _oadev(x, rate, taus):
    allantools = pytest.importorskip('allantools')
    return allantools.oadev(x, rate=rate, data_type='freq', taus=np.asarray(taus))[1]


def test_catalogue_names_are_the_design_contract():
    assert set(EFFECTS) == CATALOGUE | EXTENSIONS
    for cls in EFFECTS.values():
        assert cls.summary and cls.physics and cls.name in CATALOGUE | EXTENSIONS


def test_parse_effect_syntax_and_errors():
    e = parse_effect('time_delay:delay_s=0.0025')
    assert e.delay_s == 0.0025
    assert e.describe() == {'name': 'time_delay', 'params': {'delay_s': 0.0025}}
    assert parse_effect('vibration').params['freq_hz'] == 19.0
    for bad in ('nope', 'time_delay:delay_s', 'time_delay:x=1', 'gauss_markov:tau_s=0',
                'internal_lowpass:taps=2.5', 'vibration:amplitude=nan'):
        with pytest.raises(InputError):
            parse_effect(bad)
    assert [e.name for e in build_effects([{'name': 'quantization', 'params': {}},
                                           'time_delay'])] == ['quantization', 'time_delay']


def test_effect_leaves_the_baseline_noise_of_the_seed_unchanged():
    cfg = BenchConfig.from_preset('adis16405')
    cfg.gyro.output_step = 0.0
    base = simulate_static(cfg, duration=20.0, seed=4)
    tone = simulate_static(cfg, duration=20.0, seed=4,
                           effects=['vibration:freq_hz=7,amplitude=0.01,axis=1'])
    diff = tone.imu.channels['gyro_y'] - base.imu.channels['gyro_y']
    assert np.allclose(np.abs(diff).max(), 0.01, rtol=1e-3)
    assert np.array_equal(tone.imu.channels['gyro_x'], base.imu.channels['gyro_x'])


def test_stale_samples_repeat_a_share_p_with_correlation_p_to_the_lag_and_new_stamps():
    cfg = _quiet(100.0, 1e-3)
    clean = simulate_static(cfg, duration=2000.0, seed=5, channels=['gyro_x'])
    run = simulate_static(cfg, duration=2000.0, seed=5, effects=['stale_samples:p=0.2'],
                          channels=['gyro_x'])
    x, x0 = run.imu.channels['gyro_x'], clean.imu.channels['gyro_x']
    held = x[1:] == x[:-1]
    assert held.mean() == pytest.approx(0.2, abs=0.01)
    # Every sample is a clean one, from the same or an earlier instant; the stamps are new.
    assert np.array_equal(x[1:][~held], x0[1:][~held])
    assert np.array_equal(run.imu.t, clean.imu.t)
    for lag in (1, 2, 3):
        got = np.corrcoef(x[:-lag], x[lag:])[0, 1]
        assert got == pytest.approx(0.2 ** lag, abs=0.01), lag
    assert x.var() == pytest.approx(x0.var(), rel=0.03)
    # Isolated holds: the same share, never two in a row, correlated at lag 1 only.
    run = simulate_static(cfg, duration=2000.0, seed=5, channels=['gyro_x'],
                          effects=['stale_samples:p=0.2,isolated=1'])
    x = run.imu.channels['gyro_x']
    held = x[1:] == x[:-1]
    assert held.mean() == pytest.approx(0.2, abs=0.01)
    assert not np.any(held[1:] & held[:-1])
    assert [np.corrcoef(x[:-k], x[k:])[0, 1] for k in (1, 2, 3)] == pytest.approx(
        [0.2, 0.0, 0.0], abs=0.01)


@pytest.mark.parametrize('taps,stages,dec', [(4, 2, 2), (16, 2, 8), (8, 1, 8), (3, 1, 1)])
def test_internal_lowpass_autocorrelation_and_long_tau_arw(taps, stages, dec):
    rate, white = 100.0, 1e-3
    cfg = _quiet(rate, white)
    fx = f'internal_lowpass:taps={taps},stages={stages},decimation={dec}'
    run = simulate_static(cfg, duration=2000.0, seed=5, effects=[fx], channels=['gyro_x'])
    x = run.imu.channels['gyro_x']
    h = bartlett_kernel(taps, stages)
    for lag in (1, 2):
        want = np.dot(h[:h.size - lag * dec], h[lag * dec:]) / np.dot(h, h) \
            if lag * dec < h.size else 0.0
        got = np.corrcoef(x[:-lag], x[lag:])[0, 1]
        assert got == pytest.approx(want, abs=0.01), (lag, got, want)
    # Per-sample variance: white of density N at the internal rate through h.
    assert x.var() == pytest.approx(white ** 2 * rate * dec * np.dot(h, h), rel=0.02)
    gain = InternalLowpass(taps=taps, stages=stages, decimation=dec).noise_gain(dec)
    assert run.truth['channels']['gyro_x']['N'] == pytest.approx(white * gain)
    taus = np.array([2.0, 10.0])
    got = _oadev(x, rate, taus)
    assert np.allclose(got, white * gain / np.sqrt(taus), rtol=0.06)


def test_internal_lowpass_boxcar_over_the_decimation_keeps_arw():
    assert InternalLowpass(taps=8, stages=1, decimation=8).noise_gain(8) == pytest.approx(1.0)
    assert InternalLowpass(taps=1, stages=1, decimation=4).noise_gain(4) == pytest.approx(2.0)


def _fourier(t, y, w, harmonics=3):
    cols = [np.ones_like(t)]
    for k in range(1, harmonics + 1):
        cols += [np.cos(k * w * t), np.sin(k * w * t)]
    coef, *_ = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)
    return coef


def _swing_cfg():
    return noiseless(BenchConfig.from_preset('adis16405'), keep_errors=False)


def _swing_lines(effect, seed, harmonics=3):
    """Fourier coefficients of a noiseless 20 s swing run's gyro_x, peak rate, ω, sample step."""
    cfg = _swing_cfg()
    run = simulate_swing(cfg, duration=20.0, seed=seed, channels=['gyro_x'], effects=[effect])
    w = 2 * np.pi / cfg.stand.period_s
    c = _fourier(run.imu.t, run.imu.channels['gyro_x'], w, harmonics)
    return c, cfg.stand.amplitude * w, w, float(np.median(np.diff(run.imu.t)))


def test_time_delay_fractional_gives_quadrature_residual():
    cfg = _swing_cfg()
    delay = 3.7e-4       # 0.37 of a 1 kHz sample
    run = simulate_swing(cfg, duration=20.0, seed=1, effects=[f'time_delay:delay_s={delay}'],
                         channels=['gyro_x'])
    t, g = run.imu.t, run.imu.channels['gyro_x']
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]) * np.diff(t))])
    te, enc = run.encoder.t, run.encoder.channels['encoder']
    inside = (te > t[0] + 0.01) & (te < t[-1] - 0.01)
    resid = np.interp(te[inside], t, angle) - enc[inside]
    w = 2 * np.pi / cfg.stand.period_s
    coef = _fourier(te[inside], resid, w, 1)
    w_amp = cfg.stand.amplitude * w
    # phi(t - d) - phi(t) = -d phi_dot(t) = -d A w cos(w t): in quadrature with the angle.
    assert coef[1] == pytest.approx(-w_amp * delay, rel=0.01)
    assert abs(coef[2]) < 0.01 * w_amp * delay


def test_timestamp_jitter_on_encoder_adds_rate_times_sigma():
    cfg = _swing_cfg()
    sigma = 1e-4
    run = simulate_swing(cfg, duration=200.0, seed=2, channels=['gyro_x'],
                         effects=[f'timestamp_jitter:sigma_s={sigma},stream=1'])
    te = run.encoder.t
    resid = run.encoder.channels['encoder'] - stand_angle_clean(cfg.stand, te)
    w_amp = cfg.stand.amplitude * 2 * np.pi / cfg.stand.period_s
    assert resid.var() == pytest.approx(w_amp ** 2 / 2 * sigma ** 2, rel=0.03)
    nominal = np.arange(len(run.imu)) / cfg.gyro.rate_hz
    assert np.allclose(run.imu.t, nominal)     # IMU stamps untouched


def test_temperature_drift_exponential_recovered():
    from scipy.optimize import curve_fit
    # Noise 5e-5 rad/sqrt(s): the fit's 1-sigma on tau is ~0.5 % (Fisher information).
    cfg = _quiet(100.0, 5e-5)
    run = simulate_static(cfg, duration=1500.0, seed=3, channels=['gyro_x'],
                          effects=['temperature_drift:amplitude=0.002,tau_s=250'])
    x = run.imu.channels['gyro_x'].reshape(-1, 100).mean(axis=1)
    tm = run.imu.t.reshape(-1, 100).mean(axis=1)
    (amp, tau, off), _ = curve_fit(lambda t, a, b, c: a * np.exp(-t / b) + c, tm, x,
                                   p0=(0.001, 100.0, 0.0))
    assert amp == pytest.approx(0.002, rel=0.02)
    assert tau == pytest.approx(250.0, rel=0.02)
    assert abs(off) < 2e-5


def test_temperature_pulse_peaks_at_its_amplitude_and_returns_to_zero():
    # rise_s > 0: a (e^(-s/tau) - e^(-s/rise)) / peak from t0 on, 0 before: its maximum is
    # the amplitude, at s* = tau rise ln(tau / rise) / (tau - rise); rise_s 0 is the step.
    cfg = _quiet(100.0, 0.0)
    amp, tau, rise, t0 = 0.003, 120.0, 30.0, 200.0
    run = simulate_static(cfg, duration=1500.0, seed=3, channels=['gyro_x'],
                          effects=[f'temperature_drift:amplitude={amp},tau_s={tau},'
                                   f'rise_s={rise},t0_s={t0}'])
    x, t = run.imu.channels['gyro_x'], run.imu.t
    x = x - x[-1]
    assert np.all(np.abs(x[t < t0 - 1.0]) < 1e-5)
    s_peak = tau * rise * np.log(tau / rise) / (tau - rise)
    assert x.max() == pytest.approx(amp, rel=1e-3)
    assert t[np.argmax(x)] == pytest.approx(t0 + s_peak, abs=1.0)
    assert abs(x[t > t0 + 10 * tau]).max() < 1e-3 * amp
    assert 'rise_s' in run.truth['effects'][0]['params']
    step = simulate_static(cfg, duration=60.0, seed=3, channels=['gyro_x'],
                           effects=['temperature_drift:amplitude=0.003,tau_s=20'])
    assert 'rise_s' not in step.truth['effects'][0]['params']


def test_bias_instability_floor_and_truth():
    b = 2e-4
    cfg = _quiet(50.0, 1e-5)
    run = simulate_static(cfg, duration=4 * 3600.0, seed=6, channels=['gyro_x'],
                          effects=[f'bias_instability:B={b},axis=0'])
    got = _oadev(run.imu.channels['gyro_x'], 50.0, [10.0, 100.0])
    assert np.allclose(got, b * math.sqrt(2 * math.log(2) / math.pi), rtol=0.15)
    assert run.truth['channels']['gyro_x']['B'] == pytest.approx(b)


def test_rate_random_walk_slope_and_truth():
    k = 1e-4
    cfg = _quiet(50.0, 1e-5)
    run = simulate_static(cfg, duration=3600.0, seed=7, channels=['gyro_x'],
                          effects=[f'rate_random_walk:K={k},axis=0'])
    taus = np.array([10.0, 60.0])
    got = _oadev(run.imu.channels['gyro_x'], 50.0, taus)
    assert np.allclose(got, k * np.sqrt(taus / 3.0), rtol=0.2)
    assert run.truth['channels']['gyro_x']['K'] == pytest.approx(k)


def test_gauss_markov_variance_correlation_and_allan():
    sigma, tc, rate = 1e-3, 2.0, 50.0
    cfg = _quiet(rate, 0.0)
    run = simulate_static(cfg, duration=4000.0, seed=8, channels=['gyro_x'],
                          effects=[f'gauss_markov:sigma={sigma},tau_s={tc},axis=0'])
    x = run.imu.channels['gyro_x']
    assert x.var() == pytest.approx(sigma ** 2, rel=0.1)
    lag = 25     # 0.5 s
    assert np.corrcoef(x[:-lag], x[lag:])[0, 1] == pytest.approx(math.exp(-0.5 / tc),
                                                                 abs=0.03)
    taus = np.array([0.5, 2.0, 10.0])
    q = 2 * sigma ** 2 / tc
    want = np.sqrt(q * tc ** 2 / taus * (1 - tc / (2 * taus) * (
        3 - 4 * np.exp(-taus / tc) + np.exp(-2 * taus / tc))))
    assert np.allclose(_oadev(x, rate, taus), want, rtol=0.1)


def test_angle_quantization_gives_q_term():
    # Per-sample angle increments of sigma N sqrt(dt) = step / 2: the quantization error of
    # the angle is then uniform and white (its lag-1 correlation ~ exp(-2 pi^2 / 4) < 0.01),
    # the condition of the IEEE Q term; 3 Q^2 / tau^2 = N^2 / tau at tau = dt.
    step, white, rate = 2e-5, 1e-4, 100.0
    cfg = _quiet(rate, white)
    run = simulate_static(cfg, duration=1000.0, seed=9, channels=['gyro_x'],
                          effects=[f'quantization:step_rad={step},axis=0'])
    x = run.imu.channels['gyro_x']
    q = step / math.sqrt(12.0)
    taus = np.array([0.01, 0.03, 0.1])
    want = np.sqrt(white ** 2 / taus + 3 * q ** 2 / taus ** 2)
    assert np.allclose(_oadev(x, rate, taus), want, rtol=0.05)
    assert run.truth['channels']['gyro_x']['Q'] == pytest.approx(q)
    assert np.allclose(np.round(x * 0.01 / step), x * 0.01 / step)


def test_vibration_line_amplitude_and_frequency():
    rate, amp, f = 200.0, 0.01, 19.3
    cfg = _quiet(rate, 1e-4)
    run = simulate_static(cfg, duration=100.0, seed=10, channels=['gyro_x'],
                          effects=[f'vibration:freq_hz={f},amplitude={amp},axis=0'])
    x = run.imu.channels['gyro_x']
    from scipy.signal import periodogram
    freqs, psd = periodogram(x, fs=rate, window='hann', scaling='spectrum')
    peak = np.argmax(psd)
    assert freqs[peak] == pytest.approx(f, abs=0.02)
    coef = _fourier(run.imu.t, x, 2 * np.pi * f, 1)
    assert math.hypot(coef[1], coef[2]) == pytest.approx(amp, rel=0.01)


def test_vibration_comb_lines_sit_on_the_lattice_under_the_lorentzian_envelope():
    rate, amp, f, spacing, width = 200.0, 0.01, 30.3, 1.25, 2.5
    cfg = _quiet(rate, 1e-4)
    run = simulate_static(cfg, duration=100.0, seed=10, channels=['gyro_x'],
                          effects=[f'vibration:freq_hz={f},amplitude={amp},spacing_hz='
                                   f'{spacing},width_hz={width},axis=0'])
    x = run.imu.channels['gyro_x']
    for k in (-3, -1, 0, 2, 5):
        coef = _fourier(run.imu.t, x, 2 * np.pi * (f + k * spacing), 1)
        want = amp / math.sqrt(1.0 + (k * spacing / width) ** 2)
        assert math.hypot(coef[1], coef[2]) == pytest.approx(want, rel=0.02), k
    between = _fourier(run.imu.t, x, 2 * np.pi * (f + 0.5 * spacing), 1)
    assert math.hypot(between[1], between[2]) < 0.01 * amp


def test_vibration_second_and_third_tones_have_their_own_amplitudes():
    cfg = _quiet(200.0, 1e-4)
    run = simulate_static(cfg, duration=100.0, seed=10, channels=['gyro_x'],
                          effects=['vibration:freq_hz=30,amplitude=0.01,freq2_hz=17.5,'
                                   'amplitude2=0.004,freq3_hz=41,amplitude3=0,axis=0'])
    x = run.imu.channels['gyro_x']
    for f, want in ((30.0, 0.01), (17.5, 0.004), (41.0, 0.0)):
        coef = _fourier(run.imu.t, x, 2 * np.pi * f, 1)
        assert math.hypot(coef[1], coef[2]) == pytest.approx(want, abs=2e-4), f


def test_scale_factor_nonlinearity_harmonics():
    k2, k3 = 0.02, 0.05
    c, big_w, _, _ = _swing_lines(f'scale_factor_nonlinearity:k2={k2},k3={k3}', 11)
    assert c[0] == pytest.approx(k2 * big_w ** 2 / 2, rel=1e-3)
    assert c[1] == pytest.approx(big_w + 3 * k3 * big_w ** 3 / 4, rel=1e-4)
    assert c[3] == pytest.approx(k2 * big_w ** 2 / 2, rel=1e-3)
    assert c[5] == pytest.approx(k3 * big_w ** 3 / 4, rel=1e-3)


def test_scale_factor_fifth_order_term_harmonics():
    k5 = 0.4
    c, big_w, _, _ = _swing_lines(f'scale_factor_nonlinearity:k2=0,k5={k5}', 11, 5)
    # cos^5 = (10 cos + 5 cos 3x + cos 5x) / 16
    assert c[1] == pytest.approx(big_w + 10 * k5 * big_w ** 5 / 16, rel=1e-5)
    assert c[5] == pytest.approx(5 * k5 * big_w ** 5 / 16, rel=1e-3)
    assert c[9] == pytest.approx(k5 * big_w ** 5 / 16, rel=1e-2)
    assert abs(c[0]) < 1e-4 * k5 * big_w ** 5 and abs(c[3]) < 1e-4 * k5 * big_w ** 5


def _one_pole_gain(tau, dt, w):
    """Complex gain of the backward-Euler one-pole at angular frequency ``w``."""
    a = tau / (tau + dt)
    return (1.0 - a) / (1.0 - a * np.exp(-1j * w * dt))


def test_self_heating_cubic_puts_its_lines_through_the_thermal_lag():
    # w = W cos: k3 w LP(w^2) = k3 W^3 / 2 cos + k3 W^3 / 4 Re[H(2w) (e^{i w t} + e^{3 i w t})]
    k3, tau = 0.2, 0.4
    c, big_w, w, dt = _swing_lines(f'scale_factor_nonlinearity:k2=0,k3={k3},tau_s={tau}', 11)
    h = _one_pole_gain(tau, dt, 2 * w)
    assert abs(h) < 0.75         # the lag matters at 2f
    line = k3 * big_w ** 3 / 4
    assert c[1] == pytest.approx(big_w + 2 * line + line * h.real, rel=1e-4)
    assert c[2] == pytest.approx(-line * h.imag, rel=1e-2)
    assert c[5] == pytest.approx(line * h.real, rel=1e-2)
    assert c[6] == pytest.approx(-line * h.imag, rel=1e-2)
    assert EFFECTS['scale_factor_nonlinearity'](k3=k3).describe()['params'].keys() == {
        'k2', 'k3', 'k5'}    # tau_s at 0 left out of truth.json, as before it existed


def test_lock_in_rate_follows_the_adler_law_in_every_odd_line():
    # omega_out = sign(w) sqrt(w^2 - L^2) outside |w| < L, 0 inside: Fourier lines by quadrature
    from scipy import integrate
    lock = 0.08
    c, big_w, _, _ = _swing_lines(f'scale_factor_nonlinearity:k2=0,lock_in={lock}', 13, 5)

    def law(th):
        x = big_w * np.cos(th)
        return np.sign(x) * np.sqrt(max(x * x - lock * lock, 0.0))

    edge = np.arccos(lock / big_w)
    cuts = [edge, np.pi - edge, np.pi + edge, 2 * np.pi - edge]
    for h, k in ((1, 1), (3, 5), (5, 9)):
        want = integrate.quad(lambda th: law(th) * np.cos(h * th), 0, 2 * np.pi, points=cuts,
                              limit=200)[0] / np.pi
        assert c[k] == pytest.approx(want, rel=2e-3, abs=1e-4 * big_w)
    assert abs(c[5]) > 0.01 * big_w and abs(c[0]) < 1e-4 * big_w and abs(c[3]) < 1e-4 * big_w


def _loop(v, limits, windup_s, dt):
    """Run the saturating loop sample by sample (the recursion ``saturate`` solves in spans)."""
    a = math.exp(-dt / windup_s) if windup_s > 0 else 0.0
    out, debt = np.empty_like(v), 0.0
    for k, x in enumerate(v):
        out[k] = min(max(x + a * debt / dt, limits[0]), limits[1])
        debt = a * debt + (x - out[k]) * dt
    return out


@pytest.mark.parametrize('windup_s', [0.0, 0.004, 0.5, 50.0])
def test_saturating_loop_equals_its_recursion_sample_by_sample(windup_s):
    dt = 1e-3
    t = np.arange(30000) * dt
    rng = np.random.default_rng(4)
    v = 0.44 * np.cos(2 * np.pi * t / 2.5) + 0.02 * rng.standard_normal(t.size)
    for limits in ((-0.2, 0.2), (-0.42, 0.42), (-0.6, 0.6), (-0.45, 0.38)):
        got = saturate(v, limits, windup_s, dt)
        assert np.allclose(got, _loop(v, limits, windup_s, dt), rtol=0, atol=1e-12), limits
        assert limits[0] - 1e-15 <= np.min(got) and np.max(got) <= limits[1] + 1e-15
    assert np.array_equal(saturate(v, (-1.0, 1.0), windup_s, dt), v)   # never out of range


def test_full_scale_limit_clips_the_output_and_a_wound_up_loop_keeps_the_angle():
    # Noiseless 20 s swing, peak 0.44 rad/s: clipped at 0.35 the crests are flat; wound up
    # (a debt kept 1e6 s) the output also stays at the limit past the crest until the angle
    # has caught up, so over a half swing the angle is the plain run's.
    cfg = _swing_cfg()
    runs = [simulate_swing(cfg, duration=20.0, seed=3, channels=['gyro_x'], effects=fx)
            for fx in ([], ['scale_factor_nonlinearity:k2=0,range_rads=0.35'],
                       ['scale_factor_nonlinearity:k2=0,range_rads=0.35,windup_s=1e6'])]
    plain, clip, wound = (r.imu.channels['gyro_x'] for r in runs)
    assert np.max(plain) > 0.43 and np.max(np.abs(clip)) == pytest.approx(0.35, abs=1e-12)
    assert np.array_equal(clip, np.clip(plain, -0.35, 0.35))
    held = [np.sum(np.abs(x) >= 0.35 - 1e-12) for x in (clip, wound)]
    assert held[1] > 1.3 * held[0]
    # Over one half swing, zero crossing to zero crossing (out of debt at both): the clip
    # loses angle, the wound-up loop none.
    step = float(np.median(np.diff(runs[0].imu.t)))
    quarter = int(round(cfg.stand.period_s / 4 / step))
    half = slice(quarter, quarter + 2 * quarter)
    angle = [np.sum(x[half]) for x in (plain, clip, wound)]
    assert abs(angle[2] - angle[0]) < 1e-6 * abs(angle[0])
    assert abs(angle[1] - angle[0]) > 1e-2 * abs(angle[0])
    assert 'range_rads' not in EFFECTS['scale_factor_nonlinearity'](k3=0.1).describe()[
        'params']


def test_relaxing_asymmetry_shifts_the_second_harmonic_and_keeps_f_clean():
    # a w LP(sign w), sign(cos) = sum over odd m of b_m cos(m w t): only even lines;
    # 2f from m = 1 and 3: (a W / 2) (b_1 H(w) + b_3 H(3 w)), DC (a W / 2) Re b_1 H(w).
    a, tau = 0.01, 0.3
    c, big_w, w, dt = _swing_lines(f'scale_factor_asymmetry:a={a},tau_s={tau}', 12)
    b1, b3 = 4 / np.pi, -4 / (3 * np.pi)
    h1, h3 = _one_pole_gain(tau, dt, w), _one_pole_gain(tau, dt, 3 * w)
    two_f = 0.5 * a * big_w * (b1 * h1 + b3 * h3)
    assert c[0] == pytest.approx(0.5 * a * big_w * (b1 * h1).real, rel=1e-2)
    assert c[3] == pytest.approx(two_f.real, rel=2e-2)
    assert c[4] == pytest.approx(-two_f.imag, rel=2e-2)
    assert abs(c[2]) < 1e-3 * a * big_w and c[1] == pytest.approx(big_w, rel=1e-5)


def test_scale_factor_asymmetry_dc_and_second_harmonic():
    a = 0.01
    c, big_w, _, _ = _swing_lines(f'scale_factor_asymmetry:a={a}', 12)
    assert c[0] == pytest.approx(2 * a * big_w / np.pi, rel=1e-3)
    assert c[1] == pytest.approx(big_w, rel=1e-5)
    assert c[3] == pytest.approx(4 * a * big_w / (3 * np.pi), rel=1e-2)


def test_cross_axis_coupling_slope():
    cfg = _swing_cfg()
    run = simulate_swing(cfg, duration=10.0, seed=13, channels=['gyro_x', 'gyro_y', 'gyro_z'],
                         effects=['cross_axis:yx=0.003,zx=-0.001'])
    _, rate, _ = stand_motion(cfg.stand, run.imu.t, np.random.default_rng(0))
    for name, m in (('gyro_y', 0.003), ('gyro_z', -0.001)):
        slope = np.dot(run.imu.channels[name], rate) / np.dot(rate, rate)
        assert slope == pytest.approx(m, rel=1e-9)


def test_g_sensitivity_in_phase_with_angle():
    cfg = _swing_cfg()
    gy, gz = 1e-4, 5e-5
    run = simulate_swing(cfg, duration=10.0, seed=14, channels=['gyro_x'],
                         effects=[f'g_sensitivity:gy={gy},gz={gz}'])
    t = run.imu.t
    _, rate, _ = stand_motion(cfg.stand, t, np.random.default_rng(0))
    phi = stand_angle_clean(cfg.stand, t)
    extra = run.imu.channels['gyro_x'] - rate
    design = np.column_stack([G0 * np.sin(phi), G0 * np.cos(phi)])
    coef, *_ = np.linalg.lstsq(design, extra, rcond=None)
    assert np.allclose(coef, [gy, gz], rtol=1e-9)


def test_encoder_cyclic_error_locked_to_angle():
    cfg = _swing_cfg()
    lines, a1, a2 = 1024.0, 4e-6, 1.5e-6
    run = simulate_swing(cfg, duration=10.0, seed=15, channels=['gyro_x'],
                         effects=[f'encoder_cyclic_error:lines={lines},a1={a1},a2={a2},'
                                  f'p1=0.3,p2=-1.0'])
    phi = stand_angle_clean(cfg.stand, run.encoder.t)
    err = run.encoder.channels['encoder'] - phi
    x = lines * phi
    design = np.column_stack([np.sin(x), np.cos(x), np.sin(2 * x), np.cos(2 * x)])
    c, *_ = np.linalg.lstsq(design, err, rcond=None)
    assert math.hypot(c[0], c[1]) == pytest.approx(a1, rel=1e-6)
    assert math.atan2(c[1], c[0]) == pytest.approx(0.3, abs=1e-6)
    assert math.hypot(c[2], c[3]) == pytest.approx(a2, rel=1e-6)


def test_encoder_cyclic_error_third_and_fourth_harmonics():
    # The tracks' own distortion: lines at 3 L and 4 L with their phases; unset, absent
    # from describe() (earlier truth.json unchanged).
    cfg = _swing_cfg()
    run = simulate_swing(cfg, duration=10.0, seed=15, channels=['gyro_x'],
                         effects=['encoder_cyclic_error:lines=500,a1=0,a2=0,a3=3e-6,a4=2e-6,'
                                  'p3=0.5,p4=-0.7'])
    phi = stand_angle_clean(cfg.stand, run.encoder.t)
    x = 500.0 * phi
    design = np.column_stack([f(k * x) for k in (1, 2, 3, 4) for f in (np.sin, np.cos)])
    c, *_ = np.linalg.lstsq(design, run.encoder.channels['encoder'] - phi, rcond=None)
    assert np.allclose(c[:4], 0.0, atol=1e-12)
    assert math.hypot(c[4], c[5]) == pytest.approx(3e-6, rel=1e-6)
    assert math.atan2(c[5], c[4]) == pytest.approx(0.5, abs=1e-6)
    assert math.hypot(c[6], c[7]) == pytest.approx(2e-6, rel=1e-6)
    assert math.atan2(c[7], c[6]) == pytest.approx(-0.7, abs=1e-6)
    plain = EFFECTS['encoder_cyclic_error']().describe()['params']
    assert 'a3' not in plain and 'p4' not in plain
