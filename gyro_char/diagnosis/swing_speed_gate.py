"""
Forms of the swing candidates switched by the stand's speed: an encoder error seen fast only.

An interpolator that skips its correction above a speed, or a tracking loop that falls behind
when the signal frequency L |rate| / 2 pi grows, leaves the encoder's cyclic error in the fast
part of each half-swing and none near the turning points. Fitted without the gate, the
cyclic error's twin puts its line at every speed: its increment correlation (a chirp down to
0 Hz) and its slow ``rate_locked`` bins disagree with the record's, and the twin scored worse
than the baseline on a strong gated error (3.91 -> 4.20).
"""
from dataclasses import replace
from typing import List, Sequence

from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.diagnosis.swing_baseline import SwingBaseline

GATE = (0.05, 0.95)       # the speed gate searched: fractions of the smallest, largest peak


def with_speed_gate(spaces: List[EffectSpace],
                    bases: Sequence[SwingBaseline]) -> List[EffectSpace]:
    """
    Give the encoder cyclic error a form present only above a stand speed ``gate_rads``.

    Offered where the records show a line (``swing_spaces.with_lines`` gave the search a
    line count); the gate is searched from a twentieth of the smallest peak rate (as good
    as always on) up to just under the largest, its other parameters as the plain form's.
    """
    lo = GATE[0] * min(b.peak_rate for b in bases)
    hi = GATE[1] * max(b.peak_rate for b in bases)
    out = []
    for sp in spaces:
        if sp.name == 'encoder_cyclic_error' and any(p.name == 'lines' for p in sp.params):
            gate = Param('gate_rads', lo, hi, off_at='lo', init=0.5 * (lo + hi))
            form = replace(sp, params=list(sp.params) + [gate], alternatives=())
            sp = replace(sp, alternatives=tuple(sp.alternatives) + (form,))
        out.append(sp)
    return out
