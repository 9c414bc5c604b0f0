"""An angle read once a frame (``quantization:frame=M``): simulator, closed form, start, fit."""
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.band_kurtosis import non_gaussian_bands
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.diagnosis.starts import frame_start
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS, SimContext
import numpy as np
import pytest
from scipy import signal
from static_twin_base import BASE, check_twin_means, DT, LSB, N_ARW


def framed(step, frame, dither=1.0):
    return ('quantization', {'step_rad': step, 'dither': dither, 'frame': float(frame)})


def test_errors_fall_on_one_sample_a_frame_and_the_angle_stays_within_a_step():
    with pytest.raises(InputError, match='whole number'):
        EFFECTS['quantization'](frame=2.5).check()
    assert 'frame' not in EFFECTS['quantization'](step_rad=1e-4).describe()['params']
    assert EFFECTS['quantization'](frame=10.0).describe()['params']['frame'] == 10.0
    n, step = 20000, 5e-4
    gyro = np.random.default_rng(4).normal(0.0, N_ARW / np.sqrt(DT), (3, n))
    effect = EFFECTS['quantization'](step_rad=step, frame=10.0, axis=0.0)
    y, _ = effect.output(SimContext(config=None, kind='static', seed=4, dt=DT), gyro,
                         np.zeros((3, n)))
    assert np.array_equal(y[1:], gyro[1:])                    # axis 0 only
    touched = np.flatnonzero(np.abs(y[0] - gyro[0]) > 1e-12)
    assert touched.size > 0.9 * n / 10 and np.unique(touched % 10).size == 1
    angle_error = np.cumsum(y[0] - gyro[0]) * DT
    assert np.max(np.abs(angle_error)) <= step * (1 + 1e-9)
    # Read at the frame's phase, the angle is a whole number of steps.
    read = np.cumsum(y[0])[touched] * DT / step
    np.testing.assert_allclose(read, np.round(read), atol=1e-6)


@pytest.mark.parametrize('step, dither, bias', [
    (2e-3, 1.0, 0.0),     # dithered: the held error is white across frames
    (2e-3, 0.0, 0.0),     # coarse: the angle moves 0.1 step a frame, the error correlated
    (2e-3, 0.0, 3e-3),    # ... and drifts through the steps with the bias
    (5e-4, 0.0, 0.0)])    # fine: nearly white
def test_twin_psd_is_the_closed_forms_comb_of_nulls(step, dither, bias):
    n, m = 2 ** 19, 10
    base = static.StaticBaseline(N=N_ARW, bias=bias, drift=0.0, lsb=LSB, dt=DT)
    x = static.simulate_twin(base, n, [framed(step, m, dither)], 2)
    f, px = signal.welch(x - x.mean(), fs=1.0 / DT, nperseg=4096)
    spec = model_spectrum(N_ARW, LSB, DT, [framed(step, m, dither)], bias=bias)
    plain = model_spectrum(N_ARW, LSB, DT, [], bias=bias)
    band = (f > 0.5) & (f < 49.5)
    want = spec.one_sided(f[band])
    assert np.median(np.abs(px[band] / want - 1.0)) < 0.06
    # Its nulls every 10 Hz: the PSD there falls to the floor without the read-out.
    null = np.argmin(np.abs(f - 20.0))
    assert px[null] == pytest.approx(plain.one_sided(f[null:null + 1])[0], rel=0.35)
    assert np.median(px[band]) > 2.0 * px[null]


@pytest.mark.parametrize('dither', [0.0, 1.0])
def test_expected_observables_equal_the_twins_means_the_short_tau_scatter_is_wider(dither):
    # After a smoothing filter; coarse (the error correlated from frame to frame) or dithered.
    effects = [framed(2e-3, 10, dither),
               ('internal_lowpass', {'taps': 7.0, 'stages': 2.0, 'decimation': 8.0})]
    twins, sd = check_twin_means(effects)
    # The spreads are Gaussian: one sample in ten carries the error, and the Allan deviations
    # below the frame scatter 2-7x wider than they say (documented; the Welch bins do not).
    adev_ratio = np.array([t['adev'] for t in twins]).std(axis=0, ddof=1) / sd['adev']
    assert adev_ratio[0] > 2.0
    psd_ratio = np.median(np.array([t['psd'] for t in twins]).std(axis=0, ddof=1) / sd['psd'])
    assert 0.6 < psd_ratio < 1.8


def test_start_finds_the_frame_and_stays_silent_on_smooth_shapes():
    x = static.simulate_twin(BASE, 720000, [framed(5e-4, 10, dither=0.0)], 5)
    step, m, floor = frame_start(obs.welch_psd(x, DT), DT)
    assert m == 10 and step == pytest.approx(5e-4, rel=0.2)
    # The floor at the nulls is the white rate noise's (one-sided 2 N^2, a median of chi^2).
    assert floor == pytest.approx(2 * N_ARW ** 2, rel=0.1)
    assert static.white_level(x, DT) == pytest.approx(floor, rel=1e-6)   # detrended first
    for effects in ([], [('internal_lowpass', {'taps': 5.0, 'stages': 2.0, 'decimation': 8.0})],
                    [('resonance', {'sigma': 0.04, 'freq_hz': 25.0, 'q': 4.0})],
                    [('quantization', {'step_rad': 4e-4})]):
        y = static.simulate_twin(BASE, 720000, effects, 6)
        assert frame_start(obs.welch_psd(y, DT), DT) is None, effects


def test_a_framed_read_out_is_named_quantization_with_its_frame():
    x = static.simulate_twin(BASE, 720000, [framed(1e-3, 10)], 7)
    d = run(static_expect.closed_form_problem([x], DT, twins=8, seed=3), repeats=8, seed=3)
    assert d.selected_effects[:1] == ['quantization']
    fitted = d.refined['params']['quantization']
    assert fitted.get('frame') == 10.0
    assert d.final_gap < 0.1 * d.baseline_gap


def test_band_kurtosis_says_a_framed_read_out_is_not_gaussian_where_it_is_selected():
    # Sparse coarse steps: every 5 Hz band's excess kurtosis near +3 (the check's expectation
    # is Gaussian); with the read-out in the model the warning names it as a possible cause.
    effects = [framed(2e-3, 10, dither=0.0)]
    x = static.simulate_twin(BASE, 2 ** 18, effects, 5)
    plain = non_gaussian_bands(x, DT, model_spectrum(N_ARW, LSB, DT, []))
    named = non_gaussian_bands(x, DT, model_spectrum(N_ARW, LSB, DT, effects))
    assert len(plain) == len(named) >= 5
    assert all(b['excess_kurtosis'] > 1.0 for b in named)
    assert all('read-out once a frame' in b['meaning'] for b in named)
    assert not any('read-out once a frame' in b['meaning'] for b in plain)
