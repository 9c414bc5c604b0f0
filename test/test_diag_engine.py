# The diagnosis engine on a toy problem with known answers: ranking, greedy stop, ambiguity.
from gyro_char.diagnosis import engine as diagnose
from gyro_char.diagnosis.fit import EffectSpace, Param
import numpy as np
import pytest

PATTERN = np.sin(np.linspace(0, 3, 12))
OTHER = np.r_[np.ones(6), -np.ones(6)]


def _problem(real_shift, real_other=0.0, seed=0):
    """Observable block 'a' = noise + d*PATTERN (two look-alike effects) + o*OTHER."""
    def simulate(i, effects, s):
        rng = np.random.default_rng(s)
        a = 0.1 * rng.standard_normal(12)
        for name, p in effects:
            if name in ('time_delay', 'g_sensitivity'):
                a = a + p['k'] * PATTERN
            elif name == 'vibration':
                a = a + p['k'] * OTHER
        return {'a': a}

    rng = np.random.default_rng(1000 + seed)
    real = {'a': 0.1 * rng.standard_normal(12) + real_shift * PATTERN + real_other * OTHER}
    spaces = [EffectSpace(n, [Param('k', 0.01, 10.0)])
              for n in ('time_delay', 'g_sensitivity', 'vibration')]
    return diagnose.Problem(kind='toy', reals=[real], simulate=simulate, spaces=spaces,
                            ranges=[{'a': np.c_[np.arange(12), np.arange(12) + 1.0]}],
                            units={'a': 'bin'})


def test_no_effect_is_selected_when_the_baseline_explains_the_record():
    d = diagnose.run(_problem(0.0), repeats=10)
    assert d.selected_effects == [] and d.steps == []
    assert d.final_gap == d.baseline_gap
    assert len(d.ranking) == 3


def test_look_alike_effects_are_reported_as_ambiguous_with_a_separating_run():
    d = diagnose.run(_problem(2.0), repeats=10)
    assert d.baseline_gap > 5
    assert d.selected_effects[0] in ('time_delay', 'g_sensitivity')
    assert len(d.selected_effects) == 1              # the unrelated effect is not added
    assert abs(d.steps[0]['params']['k'] - 2.0) < 0.2
    amb = d.ambiguous[0]
    assert set(amb['effects']) == {'time_delay', 'g_sensitivity'}
    assert 'second swing period' in amb['separating_run']
    assert d.where[0]['observable'] == 'a'
    js = d.to_json()
    assert js['ambiguous'] and js['gap_metric']


def test_two_effects_are_added_greedily_in_order_of_size():
    d = diagnose.run(_problem(0.0, real_other=1.5), repeats=10)
    assert d.selected_effects == ['vibration']
    d2 = diagnose.run(_problem(3.0, real_other=1.0), repeats=10)
    assert d2.selected_effects[0] in ('time_delay', 'g_sensitivity')
    assert 'vibration' in d2.selected_effects
    assert d2.final_gap < d2.steps[0]['gap_after'] < d2.baseline_gap


def test_excess_gap_removes_the_null_level():
    null = np.array([1.0, 1.2, 0.8, 1.0])          # mean square 1.02
    assert diagnose.excess_gap(1.0, null) == 0.0
    assert diagnose.excess_gap(np.sqrt(9.0 + 1.02), null) == pytest.approx(3.0)


def test_excess_gap_reported_and_shrinks_when_explained():
    d = diagnose.run(_problem(0.0, real_other=1.0), repeats=6, seed=3)
    j = d.to_json()['excess_gap']
    assert j['baseline'] > 5.0 * max(j['final'], 0.1)
    assert j['final'] < d.final_gap


def _misfit_problem(unresolved):
    """Build a toy whose true shape is PATTERN and whose look-alike's is a little off (tilt)."""
    tilt = 1.0 + 0.7 * np.linspace(-1.0, 1.0, 12)

    def simulate(i, effects, s):
        a = 0.1 * np.random.default_rng(s).standard_normal(12)
        for name, p in effects:
            a = a + p['k'] * (PATTERN if name == 'time_delay' else PATTERN * tilt)
        return {'a': a}

    real = {'a': 0.1 * np.random.default_rng(7).standard_normal(12) + 3.0 * PATTERN}
    spaces = [EffectSpace(n, [Param('k', 0.01, 10.0)]) for n in ('time_delay', 'g_sensitivity')]
    return diagnose.Problem(kind='toy', reals=[real], simulate=simulate, spaces=spaces,
                            ranges=[{'a': np.c_[np.arange(12), np.arange(12) + 1.0]}],
                            units={'a': 'bin'}, unresolved=unresolved)


def test_an_unresolved_look_alike_is_flagged_even_when_its_gap_is_clearly_larger():
    # The look-alike's shape misfit puts its gap far above the best's: by the gaps alone it
    # is not a rival. When the records cannot tell the pair apart, it is flagged all the same.
    plain = diagnose.run(_misfit_problem(frozenset()), repeats=10)
    assert plain.selected_effects[0] == 'time_delay' and plain.ambiguous == []
    gaps = {r['effect']: r['gap_after'] for r in plain.ranking}
    assert gaps['g_sensitivity'] > gaps['time_delay'] + 4 * plain.null_gap['std']
    pair = frozenset({'time_delay', 'g_sensitivity'})
    flagged = diagnose.run(_misfit_problem(frozenset({pair})), repeats=10)
    assert flagged.selected_effects[0] == 'time_delay'
    assert set(flagged.ambiguous[0]['effects']) == pair and flagged.ambiguous[0]['selected']
    assert 'second swing period' in flagged.ambiguous[0]['separating_run']
