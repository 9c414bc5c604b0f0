"""Band kurtosis: its closed form against draws and the simulator, and what it tells apart."""
from gyro_char.diagnosis import band_kurtosis as bk
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis import static
from gyro_char.diagnosis.spectra import model_spectrum
import numpy as np
import pytest
from scipy import signal

DT = 0.01
N = 2 ** 15
NOISE = 1e-3                       # white rate noise density, rad/s/sqrt(Hz)
SIG = NOISE / np.sqrt(DT)          # per sample


def _ranges():
    return bk.band_ranges(N, DT)


def _draws(make, count=80, seed=5):
    rng = np.random.default_rng(seed)
    return np.array([bk.record_kurtosis(obs.detrend(make(rng)), DT, _ranges())
                     for _ in range(count)])


@pytest.mark.parametrize('amplitude', [0.0, 0.5, 2.0])
def test_mean_and_spread_equal_draws_of_white_noise_and_a_tone(amplitude):
    f0 = 23.1
    t = np.arange(N) * DT
    fx = [('vibration', {'freq_hz': f0, 'amplitude': amplitude * SIG})] if amplitude else []
    mean, sd = bk.expected_kurtosis(model_spectrum(NOISE, 0.0, DT, fx), N, DT, _ranges(),
                                    spread=True)
    k = _draws(lambda rng: SIG * rng.standard_normal(N) + amplitude * SIG * np.sin(
        2 * np.pi * f0 * t + rng.uniform(0, 2 * np.pi)))
    got, got_sd = k.mean(axis=0), k.std(axis=0, ddof=1)
    assert np.all(np.abs(got - mean) < 4.0 * sd / np.sqrt(len(k)) + 1e-4), (got, mean)
    # 80 draws: the sample sd within about 25 % of the closed form's.
    np.testing.assert_allclose(got_sd, sd, rtol=0.3)
    band = int(f0 // 5) - 1
    assert mean[band] == pytest.approx(
        -1.5 * (0.5 * (amplitude * SIG) ** 2) ** 2
        / (0.5 * (amplitude * SIG) ** 2 + 2 * SIG ** 2 * DT * 5.0) ** 2, rel=1e-3)


def test_two_equal_lines_in_one_band_read_half_a_single_lines_kurtosis():
    fx = [('vibration', {'freq_hz': 31.0, 'amplitude': 1e-2, 'freq2_hz': 32.3,
                         'amplitude2': 1e-2})]
    mean = bk.expected_kurtosis(model_spectrum(1e-9, 0.0, DT, fx), N, DT, _ranges())
    assert mean[int(31.0 // 5) - 1] == pytest.approx(-0.75, abs=1e-6)
    k = _draws(lambda rng: sum(1e-2 * np.sin(2 * np.pi * f * np.arange(N) * DT
                                             + rng.uniform(0, 2 * np.pi))
                               for f in (31.0, 32.3)) + 1e-9 * rng.standard_normal(N),
               count=40)
    assert k[:, int(31.0 // 5) - 1].mean() == pytest.approx(-0.75, abs=0.05)


def test_a_wandering_tone_and_a_mode_of_the_same_spectrum_are_told_apart():
    # A tone whose frequency wanders over +-1 Hz about 22 Hz (a hunting pump) and band noise
    # through a resonator of about that width: their spectra are alike, their kurtosis not.
    t = np.arange(N) * DT
    b, a = signal.iirpeak(22.0, 11.0, fs=1.0 / DT)

    def wandering(rng):
        f = 22.0 + 1.0 * np.sin(2 * np.pi * t / 13.0 + rng.uniform(0, 6.3))
        return SIG * rng.standard_normal(N) + 2 * SIG * np.sin(2 * np.pi * np.cumsum(f) * DT)

    def mode(rng):
        x = signal.lfilter(b, a, rng.standard_normal(N))
        return SIG * rng.standard_normal(N) + 2 * SIG * x / x.std()

    band = int(22.0 // 5) - 1
    k_tone, k_mode = _draws(wandering, 20)[:, band], _draws(mode, 20)[:, band]
    sd = bk.expected_kurtosis(model_spectrum(NOISE, 0.0, DT, []), N, DT, _ranges(),
                              spread=True)[1][band]
    assert k_tone.mean() < -1.0                        # steady envelope: near -1.5
    assert abs(k_mode.mean()) < 4 * sd                 # Gaussian: 0
    assert k_mode.mean() - k_tone.mean() > 15 * sd     # 2^15 samples; 90 sd on 2 h


LOWPASS = ('internal_lowpass', {'taps': 7.0, 'stages': 2.0, 'decimation': 8.0})
TWIN_CASES = {
    'baseline': [],
    'resonance': [('resonance', {'sigma': 5e-3, 'freq_hz': 19.9, 'q': 25.0}), LOWPASS],
    'gauss_markov_2': [('gauss_markov', {'sigma': 3e-3, 'tau_s': 0.05, 'order': 2.0})],
    'vibration_comb': [('vibration', {'amplitude': 2e-3, 'freq_hz': 20.3, 'spacing_hz': 1.3,
                                      'width_hz': 4.0}), LOWPASS],
    'vibration_tones': [('vibration', {'amplitude': 4e-3, 'freq_hz': 21.8, 'freq2_hz': 13.1,
                                       'amplitude2': 6e-3, 'freq3_hz': 33.3,
                                       'amplitude3': 2e-3}), LOWPASS],
    'quantization': [('quantization', {'step_rad': 2e-4, 'dither': 1.0})],
}


@pytest.mark.parametrize('name', list(TWIN_CASES))
def test_closed_form_equals_the_simulators_twins(name):
    # The bench simulator's twins (the output step's rounding included) of catalogue models.
    n, reps = 2 ** 14, 10
    base = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=0.05 * np.pi / 180.0,
                                 dt=DT)
    effects = TWIN_CASES[name]
    ranges = bk.band_ranges(n, DT)
    mean, sd = bk.expected_kurtosis(model_spectrum(base.N, base.lsb, DT, effects), n, DT,
                                    ranges, spread=True)
    k = np.array([bk.record_kurtosis(obs.detrend(static.simulate_twin(base, n, effects, 40 + j)),
                                     DT, ranges) for j in range(reps)])
    tol = 4.5 * np.maximum(k.std(axis=0, ddof=1), sd) / np.sqrt(reps) + 1e-6
    assert np.all(np.abs(k.mean(axis=0) - mean) < tol), (name, mean, k.mean(axis=0))
    ratio = np.median(k.std(axis=0, ddof=1) / np.maximum(sd, 1e-12))
    assert 0.55 < ratio < 1.6, (name, ratio)
    if name == 'vibration_tones':       # the lines' bands read well below 0
        assert mean.min() < -0.3
