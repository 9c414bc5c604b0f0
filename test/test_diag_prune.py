"""
Backward elimination after the greedy steps (``greedy.prune``).

An effect selected early is dropped once the later ones explain what it stood in for (a
warm-up fitted to the trend of a random walk's one realization); an effect the record needs
stays.
"""
from gyro_char.diagnosis import gap as diag_gap
from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.engine import objective_for, run
from gyro_char.diagnosis.fit import fit_effect
from gyro_char.diagnosis.greedy import backfit, fit_on_top, prune
import numpy as np

DT = 0.01
N = 2 ** 17
BASE = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=0.05 * np.pi / 180.0, dt=DT)
WALK = ('rate_random_walk', {'K': 1e-4})


def forced(x, names):
    """Fit ``names`` one on top of the other in this order, refit jointly, then prune."""
    problem = static_expect.closed_form_problem([x], DT, twins=8, seed=3)
    objective = objective_for(problem, [3000 + k for k in range(8)])
    nparams, base = fit_effect(objective, [], problem.nuisance)
    objective.set_reference(base)
    nuisance = (problem.nuisance.name, nparams)
    spaces = {s.name: s for s in problem.spaces}
    selected = []
    for name in names:
        params, nuisance, ev = fit_on_top(objective, problem, selected, nuisance, spaces[name])
        selected.append((name, params))
    selected, nuisance, ev = backfit(objective, problem, selected, nuisance, ev)
    null = diag_gap.null_gaps(base.stats)
    return prune(objective, problem, selected, nuisance, ev, base,
                 2.0 * float(np.std(null, ddof=1)), float(np.quantile(null, 0.95)))


def test_a_warm_up_standing_in_for_a_walks_trend_is_dropped():
    x = static.simulate_twin(BASE, N, [WALK], 2)
    selected, _, ev, dropped = forced(x, ['temperature_drift', 'rate_random_walk'])
    assert [n for n, _ in selected] == ['rate_random_walk']
    assert [d['effect'] for d in dropped] == ['temperature_drift']
    assert dropped[0]['cost'] <= dropped[0]['needed'] and ev.gap == dropped[0]['gap_without']


def test_a_warm_up_the_record_has_stays_beside_the_walk():
    warm = ('temperature_drift', {'amplitude': 1.5e-2, 'tau_s': 300.0})
    x = static.simulate_twin(BASE, N, [WALK, warm], 2)
    selected, _, _, dropped = forced(x, ['temperature_drift', 'rate_random_walk'])
    assert [n for n, _ in selected] == ['temperature_drift', 'rate_random_walk']
    assert dropped == []


def test_the_static_kind_prunes_and_reports_what_it_dropped():
    x = static.simulate_twin(BASE, N, [WALK], 2)
    d = run(static_expect.closed_form_problem([x], DT, twins=8, seed=3), repeats=8, seed=3)
    assert 'rate_random_walk' in d.selected_effects
    assert isinstance(d.refined['dropped'], list)
    assert not set(d.selected_effects) & {r['effect'] for r in d.refined['dropped']}
