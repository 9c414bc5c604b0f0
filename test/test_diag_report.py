# The diagnosis figure has a panel for every observable block, however many the kind has.
import os

from gyro_char.diagnosis import engine as diagnose
from gyro_char.diagnosis.fit import EffectSpace, Param
from gyro_char.report.diagnosis_plot import plot_diagnosis, TITLES
import numpy as np

SWING_BLOCKS = ('quadrature', 'harmonic_2f', 'harmonic_3f', 'residual_psd',
                'encoder_lines', 'rate_locked', 'increment_acf', 'scale_factor_shift')


def _toy(blocks):
    sizes = {b: (1 if b in ('quadrature', 'scale_factor_shift')
                 else 2 if b.startswith('harmonic') else 4) for b in blocks}

    def simulate(i, effects, s):
        rng = np.random.default_rng(s)
        out = {b: 0.1 * rng.standard_normal(n) for b, n in sizes.items()}
        for _, p in effects:
            out['residual_psd'] = out['residual_psd'] + p['k']
        return out

    real = simulate(0, [('vibration', {'k': 1.0})], 99)
    ranges = {b: np.c_[np.arange(1, n + 1), np.arange(1, n + 1) + 1.0]
              for b, n in sizes.items()}
    return diagnose.Problem(kind='toy', reals=[real], simulate=simulate,
                            spaces=[EffectSpace('vibration', [Param('k', 0.01, 10.0)])],
                            ranges=[ranges], units=dict.fromkeys(blocks, 'Hz')), ranges


def test_every_swing_block_gets_a_panel(tmp_path):
    problem, ranges = _toy(SWING_BLOCKS)
    d = diagnose.run(problem, repeats=5, seed=2)
    assert d.selected_effects == ['vibration']
    png = str(tmp_path / 'diag.png')
    titles = plot_diagnosis(d, ranges, png, title='toy')
    assert os.path.getsize(png) > 10_000
    for b in SWING_BLOCKS:
        assert TITLES[b] in titles
    assert any(t.startswith('gap (rms z') for t in titles)
    assert len(titles) == len(SWING_BLOCKS) + 1
