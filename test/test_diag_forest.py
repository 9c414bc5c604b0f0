"""A forest of steady lines (many machines at fixed speeds): found, fitted, told from a mode."""
from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.spectra import model_spectrum
from gyro_char.diagnosis.static_bands import FOREST_MIN, forest_space, forest_start
from gyro_char.sim.effects import EFFECTS
import numpy as np
import pytest
from static_twin_base import BASE, DT, LSB, N_ARW

N = 720000
FANS = np.random.default_rng(5).uniform(23.0, 25.5, 14)


def fans(amplitude=3e-4):
    """Return a vibration of 14 unrelated tones of one amplitude, 23-25.5 Hz (a rack of fans)."""
    p = {'freq_hz': float(FANS[0]), 'amplitude': amplitude}
    for j, f in enumerate(FANS[1:], start=2):
        p[f'freq{j}_hz'], p[f'amplitude{j}'] = float(f), amplitude
    return ('vibration', p)


def test_a_vibration_takes_up_to_32_tones_and_describes_only_the_first_six_when_absent():
    eff = EFFECTS['vibration'](**fans()[1])
    assert sorted(f for f, _ in eff.lines()) == pytest.approx(sorted(FANS))
    plain = EFFECTS['vibration']().describe()['params']
    assert 'freq6_hz' in plain and 'freq7_hz' not in plain
    assert eff.describe()['params']['freq14_hz'] == pytest.approx(FANS[13])


def test_the_forest_is_found_line_by_line_and_a_mode_or_white_noise_show_none():
    x = static.simulate_twin(BASE, N, [fans()], 3)
    forest = forest_start(x, DT)
    assert forest is not None and FOREST_MIN <= len(forest) <= FANS.size
    got = np.sort([d['frequency_hz'] for d in forest])
    assert np.min(np.abs(got[:, None] - FANS[None, :]), axis=1) == pytest.approx(
        np.zeros(got.size), abs=0.005)
    # Each line's amplitude as measured carries its mean square (3e-4 rad/s, sinc(f dt)).
    space = forest_space(forest, lambda eff: model_spectrum(N_ARW, LSB, DT, eff))
    assert not space.params and len(space.estimated) == 2 * len(forest)
    amps = [v for k, v in space.fixed.items() if k.startswith('amplitude')]
    assert np.median(amps) == pytest.approx(3e-4 * np.sinc(24.0 * DT), rel=0.15)
    for effects in ([('resonance', {'sigma': 3e-3, 'freq_hz': 24.0, 'q': 30.0})], []):
        assert forest_start(static.simulate_twin(BASE, N, effects, 4), DT) is None


def test_a_forest_is_named_vibration_where_a_mode_fills_its_band_as_well():
    x = static.simulate_twin(BASE, N, [fans()], 6)
    problem = static_expect.closed_form_problem([x], DT, twins=8, seed=3)
    mode = [('resonance', {'sigma': 1.1e-3, 'freq_hz': 24.3, 'q': 30.0})]
    forest = [('vibration', forest_space(forest_start(x, DT), problem.expect.spectrum).fixed)]
    # The fine scan's lines cost the mode, not the forest that makes them: more than the
    # forest's two estimated parameters a line cost it over the mode's three.
    choose = problem.choose
    extra = (len(forest[0][1]) - 3) * choose.log_n             # two parameters a line
    assert choose.line_deviance(mode) - choose.line_deviance(forest) > extra > 0
    d = run(problem, repeats=8, seed=3)
    assert d.selected_effects[:1] == ['vibration']
    assert d.final_gap < 1.5 < d.baseline_gap
