"""
``allan.png`` and the human table of the noise terms (deg/sqrt(h), deg/h, ...).

One log-log panel per sensor kind (gyro, accel): sigma(tau) of each channel with its 68 % band,
the fitted model and each selected term (formula (4)'s lines, the white term through the sensor
filter when one is used, Markov bumps), over the fitted taus.
"""
from typing import Dict, List

from gyro_char.allan.fit import NoiseFit
from gyro_char.allan.kernel import AllanResult
from gyro_char.allan.model import TERMS
from gyro_char.units import HUMAN_UNITS, RATE_UNITS, to_human
import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

TERM_STYLE = {'R': ':', 'K': '--', 'B': '-.', 'N': (0, (5, 1, 1, 1)), 'Q': (0, (1, 3)),
              'M': (0, (3, 1, 1, 1, 1, 1))}


def plot_allan(res: AllanResult, fits: Dict[str, NoiseFit], path: str, title: str = '') -> None:
    """Render the Allan deviation curves, bands and fits of every channel to ``path``."""
    kinds = [k for k in ('gyro', 'accel') if any(c.startswith(k) for c in res.channels)]
    fig, axes = plt.subplots(1, len(kinds), figsize=(7.5 * len(kinds), 6), squeeze=False)
    for ax, kind in zip(axes[0], kinds):
        for c, name in enumerate(res.channels):
            if not name.startswith(kind):
                continue
            line, = ax.loglog(res.tau, res.adev[:, c], lw=1.6, label=name)
            color = line.get_color()
            if res.adev_lo is not None:
                ax.fill_between(res.tau, res.adev_lo[:, c], res.adev_hi[:, c], color=color,
                                alpha=0.2, lw=0)
            fit = fits.get(name)
            if fit is None:
                continue
            tau = fit.tau  # only over the fitted range (see --tau-min)
            ax.loglog(tau, np.sqrt(fit.model_avar(tau)), color=color, lw=1, alpha=0.9)
            for term, avar in fit.term_avars(tau).items():
                ax.loglog(tau, np.sqrt(avar), color=color, lw=0.8, ls=TERM_STYLE[term[0]],
                          alpha=0.8)
        top = np.nanmax(res.adev_hi if res.adev_hi is not None else res.adev)
        low = np.nanmin(res.adev_lo if res.adev_lo is not None else res.adev)
        ax.set_ylim(low / 2.0, top * 2.0)
        ax.set_xlabel('tau [s]')
        ax.set_ylabel(f'Allan deviation [{RATE_UNITS[kind]}]')
        ax.grid(True, which='both', alpha=0.3)
        handles, labels = ax.get_legend_handles_labels()
        extra = [plt.Line2D([], [], color='k', lw=1, label='fitted model')]
        extra += [plt.Line2D([], [], color='k', lw=0.8, ls=TERM_STYLE[t], label=f'{t} term')
                  for t in TERMS]
        extra.append(plt.Line2D([], [], color='k', lw=0.8, ls=TERM_STYLE['M'],
                                label='Markov term'))
        ax.legend(handles + extra, labels + [h.get_label() for h in extra], fontsize=8,
                  ncol=2)
        ax.set_title(f'{kind}: overlapping Allan deviation, 68 % band')
    if title:
        fig.suptitle(title, fontsize=10)
    # Fixed margins: tight_layout measured every tick label (1.5 s of a 3 h run's ~10 s CPU).
    fig.subplots_adjust(left=0.1 / len(kinds), right=1.0 - 0.03 / len(kinds), bottom=0.09,
                        top=0.9 if title else 0.94, wspace=0.2)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(fits: Dict[str, NoiseFit]) -> List[str]:
    """Return the human table: one row per channel, '<' marks an upper bound (unresolved)."""
    lines = []
    for kind in ('gyro', 'accel'):
        names = [n for n in fits if fits[n].kind == kind]
        if not names:
            continue
        units = HUMAN_UNITS[kind]
        head = f'{"channel":9s}' + ''.join(
            f'{t + " [" + units[t][1] + "]":>26s}' for t in ('N', 'B', 'K', 'Q', 'R'))
        lines.append(head)
        for name in names:
            cells = []
            for t in ('N', 'B', 'K', 'Q', 'R'):
                est = fits[name].terms[t]
                value = to_human(t, kind, est.value)
                if est.resolved:
                    lo, hi = (to_human(t, kind, v) for v in est.ci68)
                    cells.append(f'{value:.4g} ({lo:.3g}..{hi:.3g})')
                else:
                    cells.append(f'< {value:.3g}')
            lines.append(f'{name:9s}' + ''.join(f'{c:>26s}' for c in cells))
            for m in fits[name].markov:  # IEEE 952 Annex C terms (--markov)
                sigma = to_human('B', kind, m.sigma.value)
                lines.append(f'{"":9s}Markov term: T_c {m.tau_c:.4g} s, sigma '
                             f'{"" if m.sigma.resolved else "< "}{sigma:.4g} {units["B"][1]}')
        lines.append('')
    lines.append("value (68 % interval); '< x': term not resolved by the record, x is an upper "
                 'bound. B is the IEEE coefficient (flat floor of sigma = 0.664 B).')
    return lines
