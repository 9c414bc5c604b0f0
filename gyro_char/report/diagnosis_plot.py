"""
Plots of a sim-to-real diagnosis: real vs baseline vs baseline+effects on each observable.

One figure per diagnosed channel: a panel per observable block with the real record, the
baseline twins' mean and 16-84 % scatter band, and the final model's (baseline + selected
effects); a last panel with the gap before / after each candidate effect alone and after the
greedy steps, against the gap the sim scores against itself.
"""
from typing import Dict, List

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402
import numpy as np  # noqa: E402

TITLES = {'adev': 'Allan deviation (log10 rad/s) vs τ (s)',
          'psd': 'PSD (log10 (rad/s)²/Hz) vs f (Hz)',
          'tone': 'tone prominence (log10) vs band centre (Hz)',
          'acf': 'autocorrelation vs lag (samples)',
          'drift': 'early mean − late mean (rad/s) vs span (s)',
          'quadrature': 'swing residual: cos θ component (rad)',
          'harmonic_2f': 'swing residual: 2θ components (rad)',
          'harmonic_3f': 'swing residual: 3θ components (rad)',
          'residual_psd': 'residual rate PSD (log10 (rad/s)²/Hz) vs f (Hz)',
          'encoder_lines': 'encoder residual vs angle: peak (log10 rad) vs lines/rev',
          'rate_locked': 'rate-locked stamp variance (asinh σ²/µs²) vs |cos θ|',
          'rate_sign': 'increments² at negative less positive rate, over both, vs |cos θ|',
          'rate_acf': 'lag-1 increment product less the slowest bin’s, over ms, vs |cos θ|',
          'increment_acf': 'residual increments: autocorrelation vs lag (s)',
          'scale_factor_shift': "scale factor minus run 1's vs peak rate (rad/s)"}
LOG_X = {'adev', 'psd', 'drift', 'residual_psd', 'encoder_lines'}
COLUMNS = 3
# Tick labels of the blocks whose elements are components rather than points of a curve.
COMPONENTS = {'quadrature': ['cos θ'], 'harmonic_2f': ['sin 2θ', 'cos 2θ'],
              'harmonic_3f': ['sin 3θ', 'cos 3θ']}


def _x(block: str, ranges: np.ndarray) -> np.ndarray:
    lo, hi = ranges[:, 0], ranges[:, 1]
    if block in ('psd', 'residual_psd'):
        return np.sqrt(lo * hi)
    if block in COMPONENTS:
        return np.arange(lo.size, dtype=float)
    if block in ('drift', 'scale_factor_shift'):
        return hi
    return 0.5 * (lo + hi)


def _band(ax, x, repeats: List[Dict[str, np.ndarray]], block: str, color: str, label: str):
    stack = np.array([r[block] for r in repeats], dtype=float)
    lo, mid, hi = np.percentile(stack, [16, 50, 84], axis=0)
    if x.size <= 2:  # a component or two (swing harmonics): points with 16-84 % bars
        shift = (0.12 if block in COMPONENTS else 0.0) * (1 if color == 'C2' else -1)
        ax.errorbar(x + shift, mid, yerr=[mid - lo, hi - mid],
                    fmt='o', color=color, ms=5, capsize=4, label=label)
        return
    unscored = np.ptp(stack, axis=0) == 0
    lo[unscored] = mid[unscored] = hi[unscored] = np.nan
    ax.fill_between(x, lo, hi, color=color, alpha=0.25, lw=0)
    ax.plot(x, mid, '-', color=color, lw=1.2, label=label)


def plot_diagnosis(diag, ranges: Dict[str, np.ndarray], path: str,
                   title: str = '') -> List[str]:
    """Render one channel's ``diagnose.Diagnosis`` (first record) to ``path``; panel titles."""
    blocks = list(diag.reals[0].keys())
    # A panel per block plus the gap chart, however many blocks the kind has.
    rows = -(-(len(blocks) + 1) // COLUMNS)
    fig, axes = plt.subplots(rows, COLUMNS, figsize=(15, 4.25 * rows), constrained_layout=True,
                             squeeze=False)
    axes = axes.ravel()
    base = diag.evaluations['baseline'].stats[0]
    final = diag.evaluations['final'].stats[0]
    label = 'baseline + ' + ', '.join(diag.selected_effects) if diag.selected_effects else None
    for ax, block in zip(axes, blocks):
        x = _x(block, ranges[block])
        _band(ax, x, base.repeats, block, 'C0', 'baseline (paper model) twins')
        if label:
            _band(ax, x, final.repeats, block, 'C2', label)
        real = np.asarray(diag.reals[0][block], dtype=float).copy()
        # Elements a block keeps but does not score (constant in every twin and the record,
        # e.g. line bands above the encoder's angle Nyquist) are left out of the curve.
        stack = np.array([r[block] for r in base.repeats])
        real[(np.ptp(stack, axis=0) == 0) & (real == stack[0])] = np.nan
        if block in COMPONENTS:
            ax.plot(x, real, 'kD', ms=6, label='real record')
            ax.set_xticks(x)
            if x.size == len(COMPONENTS[block]):
                ax.set_xticklabels(COMPONENTS[block])
            ax.set_xlim(x[0] - 0.5, x[-1] + 0.5)
        else:
            ax.plot(x, real, 'k.-', lw=0.8, ms=4, label='real record')
        if block in LOG_X:
            ax.set_xscale('log')
            ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title(TITLES.get(block, block), fontsize=9)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    ax = axes[len(blocks)]
    names = ['baseline'] + [r['effect'] for r in diag.ranking] + ['selected']
    gaps = [diag.baseline_gap] + [r['gap_after'] for r in diag.ranking] + [diag.final_gap]
    colors = ['C0'] + ['C1'] * len(diag.ranking) + ['C2']
    ax.barh(range(len(names)), gaps, color=colors)
    ax.axvline(diag.null_gap['q95'], color='k', ls='--', lw=1,
               label='sim vs itself (95 %)')
    ax.set_yticks(range(len(names)))
    ax.set_yticklabels(names, fontsize=8)
    ax.invert_yaxis()
    if max(gaps) > 10 * min(gaps):
        ax.set_xscale('log')
    ax.set_title('gap (rms z, sim scatter units): alone and selected', fontsize=9)
    ax.legend(fontsize=8)
    for extra in axes[len(blocks) + 1:]:
        extra.set_visible(False)
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=90)
    drawn = [a.get_title() for a in axes if a.get_visible()]
    plt.close(fig)
    return drawn
