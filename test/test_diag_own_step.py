# A greedy step taken in a candidate's own scatter (gyro_char/diagnosis/step_choice.py):
# where no candidate closes the gap in the common scatter but the record stands well above the
# model's own level, a process that holds the departure in its own spread is selected when
# the choice criterion prefers it to the model so far.
import bench_script
from gyro_char.diagnosis import engine, static_expect, step_choice
from gyro_char.diagnosis.choice import INDISTINGUISHABLE


def test_a_random_walk_no_mean_curve_follows_is_named_by_its_own_scatter():
    # Forty-four minutes of held-out set Z's slip-weakening walk (clustered slips; a spent
    # set): the gap stands at 1.73 against a null 95 % level near 1.2, but no candidate's
    # mean curve follows this one realization closely enough to pass the greedy bar, and
    # session 24's code named nothing. In its own scatter the walk holds the record, and the
    # criterion prefers it to the baseline by far more than a bare mention.
    h = bench_script.load('validate_diagnosis')
    z = bench_script.load('validate_diagnosis_heldout_z').shapes(h.DT, h.SIG, h.N_ARW)
    x = h.make_record([('rate_random_walk', 1)], 2 ** 18, 7, z)
    p = static_expect.closed_form_problem([x], h.DT, twins=8, seed=24)
    d = engine.run(p, repeats=8, seed=24)
    assert d.selected_effects[:1] == ['rate_random_walk']
    step = d.steps[0]
    before = step['own_scatter']['criterion_before']
    assert step['criterion']['rate_random_walk'] < before - INDISTINGUISHABLE
    assert d.baseline_gap - d.null_gap['q95'] > d.null_gap['shrink_needed']
    # Its gap in the common scatter moved by less than the greedy bar: the step is the
    # own-scatter one, not the usual one.
    gap_after = [r['gap_after'] for r in d.ranking if r['effect'] == 'rate_random_walk'][0]
    assert d.baseline_gap - gap_after <= d.null_gap['shrink_needed']


class _Untouchable:
    """Anything the gated step must not evaluate."""

    def __getattr__(self, name):
        raise AssertionError(f'own_step evaluated {name} below its gate')


def test_the_own_scatter_step_is_not_tried_near_the_models_own_level():
    # At the edge (the gap within the greedy bar of the model's own 95 % level), a mode
    # fitted to a chance excess in one band wins the criterion, which has no null level of
    # its own: the step is not tried there, and nothing is evaluated.
    ghost = _Untouchable()
    assert step_choice.own_step(ghost, ghost, [], ghost, {}, ['resonance'], [],
                                gap_now=1.25, bar=1.08, needed=0.2) is None
