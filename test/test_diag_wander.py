"""A tone whose frequency wanders (``vibration:wander_hz``): closed form, simulator, choice."""
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis import static, static_expect, wander
from gyro_char.diagnosis.band_kurtosis import (band_ranges, expected_kurtosis, record_kurtosis,
                                               steady_envelope)
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.errors import InputError
from gyro_char.sim.effects import EFFECTS
import numpy as np
import pytest
from scipy import signal

DT = 0.01
N_ARW = 2.4 * np.pi / 180.0 / 60.0
SIG = N_ARW / np.sqrt(DT)
BASE = static.StaticBaseline(N=N_ARW, bias=0.0, drift=0.0, lsb=0.0, dt=DT)


@pytest.mark.parametrize('w, tau', [(0.75, 5.0), (0.05, 0.3), (0.2, 1.0)])
def test_envelope_spectrum_has_unit_area_and_its_two_limits(w, tau):
    nu, e = wander.envelope_spectrum(w, tau)
    assert 2.0 * np.trapezoid(e, nu) == pytest.approx(1.0, abs=1e-6)
    beta = (2.0 * np.pi * w * tau) ** 2
    if beta > 100.0:      # slow: the frequency's own Gaussian law
        ref = np.exp(-nu ** 2 / (2.0 * w * w)) / np.sqrt(2.0 * np.pi) / w
        assert e[0] == pytest.approx(ref[0], rel=0.02)
    elif beta < 0.01:     # fast: a Lorentzian of half width beta / (2 pi tau)
        gam = beta / tau
        assert e[0] == pytest.approx(2.0 / gam, rel=0.02)
    assert wander.band_share(0.0, 1e3, 20.0, w, tau) == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize('w, tau', [(0.75, 5.0), (0.05, 0.3)])
def test_simulated_wandering_tone_matches_its_closed_form(w, tau):
    # Band power (Welch, 6 twins of 22 min) and the band kurtosis where the tone stays:
    # -1.5 of its share squared (constant envelope), where a mode's would be 0.
    fx = [('vibration', {'freq_hz': 21.7, 'amplitude': 3.0 * SIG, 'wander_hz': w,
                         'wander_s': tau})]
    spec = model_spectrum(N_ARW, 0.0, DT, fx)
    n = 2 ** 17
    ranges = band_ranges(n, DT)
    powers, kurts = [], []
    for seed in range(6):
        x = static.simulate_twin(BASE, n, fx, seed)
        f, p = signal.welch(x - x.mean(), fs=1.0 / DT, nperseg=2048)
        sel = (f > 15.0) & (f < 28.0)
        powers.append(np.sum(p[sel]) * (f[1] - f[0]))
        kurts.append(record_kurtosis(obs.detrend(x), DT, ranges))
    fine = np.linspace(15.0, 28.0, 20001)
    assert np.mean(powers) == pytest.approx(np.trapezoid(spec.one_sided(fine), fine), rel=0.03)
    mean, sd = expected_kurtosis(spec, n, DT, ranges, spread=True)
    at = int(np.flatnonzero((ranges[:, 0] <= 21.7) & (ranges[:, 1] > 21.7))[0])
    assert mean[at] < -1.3
    assert np.mean(kurts, axis=0)[at] == pytest.approx(mean[at], abs=max(3.0 * sd[at], 0.05))


def test_the_wandering_form_is_offered_only_where_the_envelope_is_steady():
    # A mode's band is Gaussian: the form that could mimic its spectrum is not searched there.
    spec = model_spectrum(N_ARW, 0.0, DT, [])
    tone = static.simulate_twin(BASE, 2 ** 17, [('vibration', {
        'freq_hz': 21.7, 'amplitude': SIG, 'wander_hz': 0.7, 'wander_s': 8.0})], 1)
    mode = static.simulate_twin(BASE, 2 ** 17, [('resonance', {
        'sigma': SIG / np.sqrt(2.0), 'freq_hz': 21.7, 'q': 12.0})], 1)
    clean = static.simulate_twin(BASE, 2 ** 17, [], 1)
    assert steady_envelope(obs.detrend(tone), DT, 21.7, spec)
    assert not steady_envelope(obs.detrend(mode), DT, 21.7, spec)
    assert not steady_envelope(obs.detrend(clean), DT, 21.7, spec)


def test_wander_is_checked():
    with pytest.raises(InputError, match='wander_hz >= 0'):
        EFFECTS['vibration'](wander_hz=-1.0).check()
    with pytest.raises(InputError, match='not to a comb'):
        EFFECTS['vibration'](wander_hz=0.5, spacing_hz=1.0).check()


@pytest.mark.parametrize('effect, named', [
    (('vibration', {'freq_hz': 21.7, 'amplitude': 2.0 * SIG, 'wander_hz': 0.7,
                    'wander_s': 8.0}), 'vibration'),
    (('resonance', {'sigma': 2.0 * SIG, 'freq_hz': 21.7, 'q': 12.0}), 'resonance'),
])
def test_a_wandering_tone_is_vibration_and_a_mode_of_the_same_band_resonance(effect, named):
    # The same band in the spectrum: the steady envelope (band kurtosis) tells them apart.
    x = static.simulate_twin(BASE, 2 ** 17, [effect], 5)
    problem = static_expect.closed_form_problem([x], DT, twins=8, seed=3)
    d = run(problem, repeats=8, seed=3)
    assert d.selected_effects[:1] == [named]
    assert d.final_gap < 0.3 * d.baseline_gap
