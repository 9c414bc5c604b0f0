# The diagnosis's one-line verdict: the four readings, from the function and from the engine.
from gyro_char.diagnosis import engine
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.verdict import verdict
import numpy as np
import pytest

RANKING = [{'effect': 'resonance'}, {'effect': 'gauss_markov'}, {'effect': 'vibration'}]
BUMP = np.r_[np.ones(6), -np.ones(6)]


@pytest.mark.parametrize('args, code', [
    ((1.02, 1.08, [], 1.02, 1.02, None), 'consistent'),
    ((1.30, 1.08, [], 1.30, 1.30, None), 'unexplained'),
    ((9.00, 1.08, ['vibration'], 1.20, 1.01, 1.10), 'explained'),
    ((9.00, 1.08, ['vibration'], 3.70, 2.50, 1.10), 'partly_explained'),
])
def test_each_reading_follows_from_the_levels(args, code):
    v = verdict(*args, RANKING)
    assert v['code'] == code
    assert v['final_gap_judged'] == args[4]
    if code == 'unexplained':
        assert 'resonance, gauss_markov' in v['text'] and 'vibration' not in v['text']
    if code in ('explained', 'partly_explained'):
        assert 'vibration' in v['text'] and v['final_model_q95'] == args[5]
        assert f'{args[3]:.2f} in the baseline' in v['text']


def _problem(bump: float, spike: float):
    """Block 'a': noise, plus a fittable bump (``vibration``) and spikes nothing fits."""
    def simulate(i, effects, s):
        a = 0.1 * np.random.default_rng(s).standard_normal(12)
        for name, p in effects:
            a = a + p['k'] * BUMP
        return {'a': a}

    real = 0.1 * np.random.default_rng(77).standard_normal(12) + bump * BUMP
    real[[3, 9]] += spike        # orthogonal to the bump: no k removes any of it
    return engine.Problem(kind='toy', reals=[{'a': real}], simulate=simulate,
                          spaces=[EffectSpace('vibration', [Param('k', 0.01, 10.0)])],
                          ranges=[{'a': np.c_[np.arange(12), np.arange(12) + 1.0]}],
                          units={'a': 'bin'})


@pytest.mark.parametrize('bump, spike, code', [
    (0.0, 0.0, 'consistent'), (1.0, 0.0, 'explained'), (0.0, 3.0, 'unexplained'),
    (1.0, 3.0, 'partly_explained')])
def test_the_engine_reads_a_toy_record_each_way(bump, spike, code):
    d = engine.run(_problem(bump, spike), repeats=12)
    assert d.verdict['code'] == code
    assert d.to_json()['verdict'] == d.verdict
    assert (d.selected_effects == ['vibration']) == (code in ('explained', 'partly_explained'))
