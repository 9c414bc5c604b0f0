"""Simulated-record plots: the measured Allan deviation beside the simulator's truth."""
from typing import Optional

from gyro_char.allan.model import model_avar
from gyro_char.units import DEG
import matplotlib
import numpy as np

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402,I100

DPH = 3600.0 / DEG  # rad/s -> deg/h


def plot_allan_vs_truth(allan: dict, truth: dict, path: str,
                        noise: Optional[dict] = None) -> None:
    """
    Plot each gyro channel's measured ADEV (68 % band) and the truth's closed-form curve.

    ``allan`` is allan.json, ``truth`` truth.json, ``noise`` (optional) noise.json whose fitted
    model (resolved terms only) is drawn dashed; deg/h against tau in seconds.
    """
    names = [c for c in ('gyro_x', 'gyro_y', 'gyro_z') if c in allan.get('channels', {})]
    fig, axes = plt.subplots(1, max(1, len(names)), figsize=(5 * max(1, len(names)), 4),
                             squeeze=False, sharey=True)
    for ax, name in zip(axes[0], names):
        cur = allan['channels'][name]
        tau = np.asarray(cur['tau_s'], dtype=float)
        ax.fill_between(tau, np.asarray(cur['adev_lo']) * DPH, np.asarray(cur['adev_hi']) * DPH,
                        color='C0', alpha=0.25, lw=0)
        ax.loglog(tau, np.asarray(cur['adev']) * DPH, 'C0', lw=1.2, label='measured (68 %)')
        terms = truth['channels'].get(name)
        if terms:
            ax.loglog(tau, np.sqrt(model_avar(tau, terms)) * DPH, 'k', lw=1.0,
                      label='truth, formula (4)')
        fit = (noise or {}).get('channels', {}).get(name)
        if fit:
            # Unresolved terms are upper bounds, not estimates: only resolved ones are drawn.
            # (formula (4)'s five terms; the channel's extra fields are not terms)
            coeffs = {t: fit[t]['value'] for t in ('N', 'B', 'K', 'Q', 'R')
                      if t in fit and fit[t].get('resolved', True)}
            ax.loglog(tau, np.sqrt(model_avar(tau, coeffs)) * DPH, 'C3--', lw=1.0,
                      label='fitted (resolved terms)')
        ax.set_title(name)
        ax.set_xlabel('tau, s')
        ax.grid(True, which='both', alpha=0.3)
    axes[0][0].set_ylabel('Allan deviation, deg/h')
    axes[0][0].legend(fontsize=8)
    fig.suptitle(f'Static record ({truth.get("preset")}, seed {truth.get("seed")}): '
                 'Allan deviation vs simulator truth')
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
