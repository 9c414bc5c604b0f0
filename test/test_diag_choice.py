# The choice among candidates that close the gap comparably (gyro_char/diagnosis/choice.py):
# a Gaussian deviance in each candidate's own closed-form spread, plus ln(n) per parameter.
import bench_script
from gyro_char.diagnosis import choice, engine, static_expect
from gyro_char.diagnosis.fit import Evaluation
import numpy as np


class _Stats:

    def __init__(self, mean, std):
        self.mean, self.std = mean, std


def test_deviance_charges_a_model_for_the_spread_it_adds():
    # A real value 1 from a mean of 0: a spread of 1 scores 1; a spread of 10 makes the miss
    # small (0.01) but pays 2 ln 10 = 4.6 for it; the best spread is the miss itself.
    real = [{'a': np.array([1.0])}]

    def dev(s):
        return choice.deviance(real, Evaluation([], 0.0, [_Stats({'a': np.zeros(1)},
                                                                 {'a': np.array([s])})]))
    assert abs(dev(1.0) - 1.0) < 1e-12
    assert abs(dev(10.0) - (0.01 + 2.0 * np.log(10.0))) < 1e-12
    assert dev(1.0) < dev(0.5) and dev(1.0) < dev(2.0)


def test_criterion_counts_each_effects_free_parameters():
    h = bench_script.load('validate_diagnosis')
    x = h.make_record([], 8192, seed=5)
    p = static_expect.closed_form_problem([x], h.DT, twins=4, seed=6)
    # The counting of the base criterion (the static kind's adds the band kurtosis, which
    # depends on the model's spectrum; its own test is test_diag_wander.py).
    crit = choice.Criterion(p.reals, p.spaces)
    base = p.expect(0, [])
    ev0 = Evaluation([], 0.0, [base])
    ev2 = Evaluation([('gauss_markov', {}), ('baseline_white_noise', {})], 0.0, [base])
    n = sum(np.size(v) for v in p.reals[0].values())
    assert abs(crit(ev2) - crit(ev0) - 3 * np.log(n)) < 1e-9   # sigma, tau_s, order
    # A flicker's upper corner counts only when it is on (corner_hz = 0: no corner), a power
    # law's slope only off its plain value (1 for flicker, 2 for the walk).
    for effect, k in ((('bias_instability', {'B': 1e-4, 'corner_hz': 0.0}), 1),
                      (('bias_instability', {'B': 1e-4, 'corner_hz': 0.5}), 2),
                      (('bias_instability', {'B': 1e-4, 'corner_hz': 0.0, 'alpha': 1.0}), 1),
                      (('bias_instability', {'B': 1e-4, 'corner_hz': 0.0, 'alpha': 1.3}), 2),
                      (('rate_random_walk', {'K': 1e-5, 'alpha': 2.0}), 1),
                      (('rate_random_walk', {'K': 1e-5, 'alpha': 1.7}), 2)):
        ev = Evaluation([effect], 0.0, [base])
        assert abs(crit(ev) - crit(ev0) - k * np.log(n)) < 1e-9


def test_a_strong_random_walk_is_named_so_not_a_gauss_markov_process():
    # Half an hour of a held, Laplace-increment random walk (a shape the catalogue lacks).
    # Gauss-Markov with a free correlation time and the random walk leave the same gap in the
    # baseline's scatter (each only follows this one realization); the gap alone picked
    # gauss_markov here. In their own spreads the random walk is the likelier.
    h = bench_script.load('validate_diagnosis')
    x = h.make_record([('rate_random_walk', 1)], 180000, seed=11)
    p = static_expect.closed_form_problem([x], h.DT, twins=5, seed=28)
    d = engine.run(p, repeats=5, seed=28)
    assert d.selected_effects[:1] == ['rate_random_walk']
    scores = d.steps[0]['criterion']
    assert scores['rate_random_walk'] < scores['gauss_markov']
    assert d.final_gap < 0.7 * d.baseline_gap


def test_criterion_counts_an_alternative_searchs_parameters_and_estimated_values():
    # A comb (vibration's alternative) has a fitted width and a spacing estimated from its
    # lines: two parameters more than a tone.
    h = bench_script.load('validate_diagnosis')
    t = np.arange(8192) * h.DT
    x = h.make_record([], 8192, seed=5) + 2e-3 * sum(
        np.sin(2 * np.pi * (20.0 + 1.5 * k) * t) for k in range(-2, 3))
    p = static_expect.closed_form_problem([x], h.DT, twins=4, seed=6)
    space = {s.name: s for s in p.spaces}['vibration']
    assert [a for a in space.alternatives if a.estimated == ('spacing_hz',)]
    crit = choice.Criterion(p.reals, p.spaces)
    base = p.expect(0, [])
    tone = {'amplitude': 1e-3, 'freq_hz': 20.0}
    score = {k: crit(Evaluation([('vibration', v)], 0.0, [base])) for k, v in (
        ('tone', tone), ('comb', {**tone, 'spacing_hz': 1.5, 'width_hz': 3.0}))}
    n = sum(np.size(v) for v in p.reals[0].values())
    assert abs(score['comb'] - score['tone'] - 2 * np.log(n)) < 1e-9


def test_slow_candidates_that_tie_are_look_alikes_and_the_best_is_named():
    # A plain random walk over 22 min whose four slow candidates (walk, Gauss-Markov, flicker,
    # a warm-up) close the gap alike. With three or more rivals that are not all known
    # look-alikes nothing is named; a warm-up and a slow Gauss-Markov excursion were not a
    # known pair (the run that separates them is the warm-up's: a repeat after a full
    # warm-up), so this walk was left unexplained at a gap of 5.4 (as was held-out set K's
    # walk). Now the criterion's best is named, the others flagged.
    h = bench_script.load('validate_diagnosis')
    n, k = 131072, 1e-4
    rng = np.random.default_rng(296)
    walk = np.cumsum(rng.standard_normal(n)) * k * np.sqrt(h.DT)
    x = h.clean(n, np.random.default_rng(1296)) + walk
    x = np.round(x / h.LSB) * h.LSB
    p = static_expect.closed_form_problem([x], h.DT, twins=8, seed=313)
    d = engine.run(p, repeats=8, seed=313)
    assert d.selected_effects[:1] == ['rate_random_walk']
    flagged = d.ambiguous[0]
    assert flagged['selected'] and set(flagged['effects']) == {
        'rate_random_walk', 'gauss_markov', 'bias_instability', 'temperature_drift'}
    assert 'after a full warm-up' in flagged['separating_run']
