"""
The diagnosis in one line a reader can act on: consistent, explained, partly or unexplained.

Read off the levels the search itself used: the baseline's gap against the 95th percentile of
what its own twins score (``consistent`` when below), then the final model's gap, judged in
the yardstick its steps were judged in, against the same percentile of the final model's
twins (``explained`` when below, ``partly_explained`` when above). A record that departs from
the baseline while no effect removed significantly more of the gap than noise-fitting would
is ``unexplained``: an effect near detectability (where the ranking is a toss-up between
candidates that all add a little variance) or of a form the catalogue lacks. An effect added
by a check finer than the gap (``seen_finer``: narrow lines) on a record the gap finds
consistent makes it ``explained`` by that effect, the check's evidence quoted.
"""
from typing import Optional, Sequence

CONSISTENT = 'consistent'
EXPLAINED = 'explained'
PARTLY = 'partly_explained'
UNEXPLAINED = 'unexplained'


def verdict(baseline_gap: float, baseline_q95: float, selected: Sequence[str],
            final_gap: float, final_judged: float, final_q95: Optional[float],
            ranking: Sequence[dict], seen_finer: Sequence[dict] = ()) -> dict:
    """
    Return ``{'code', 'text', 'final_gap_judged', 'final_model_q95'}`` (module docstring).

    ``final_gap`` is in the baseline's scatter (``diagnosis.json``'s), ``final_judged`` in
    the yardstick widened where the final model scatters more (a noise process's).
    """
    out = {'final_gap_judged': float(final_judged),
           'final_model_q95': None if final_q95 is None else float(final_q95)}
    if baseline_gap <= baseline_q95 and seen_finer:
        return {'code': EXPLAINED, **out,
                'text': f"within the baseline model's own scatter by the gap ({baseline_gap:.2f}, "
                        f"its twins' 95 % level {baseline_q95:.2f}), but "
                        + '; '.join(s['evidence']['text'] for s in seen_finer)
                        + ': explained by ' + ' + '.join(s['effect'] for s in seen_finer)}
    if baseline_gap <= baseline_q95:
        return {'code': CONSISTENT, **out,
                'text': f"within the baseline model's own scatter (gap {baseline_gap:.2f}, "
                        f"its twins' 95 % level {baseline_q95:.2f}): no unmodelled effect "
                        'is evidenced'}
    if not selected:
        nearest = ', '.join(r['effect'] for r in ranking[:2])
        return {'code': UNEXPLAINED, **out,
                'text': f'departs from the baseline model (gap {baseline_gap:.2f} > '
                        f'{baseline_q95:.2f}) but no catalogue effect removes significantly '
                        f'more of it than another or than noise: an effect near '
                        f'detectability or outside the catalogue (nearest: {nearest}); a '
                        'longer record would tell'}
    names = ' + '.join(selected)
    left = (f"what is left ({final_judged:.2f} in the final model's widened scatter, "
            f"{final_gap:.2f} in the baseline's)")
    if final_q95 is not None and final_judged <= final_q95:
        return {'code': EXPLAINED, **out,
                'text': f"explained by {names}: {left} is within the final model's own "
                        f'95 % level ({final_q95:.2f})'}
    return {'code': PARTLY, **out,
            'text': f"partly explained by {names}: {left} is above the final model's own "
                    f'95 % level ({final_q95:.2f}); a further effect, or a form the '
                    'catalogue lacks'}
