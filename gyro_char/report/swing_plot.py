"""
``swing.png`` and the human table of a swing-stand run.

Panels: the encoder angle and the integrated gyro angle with their fitted models over the first
periods; both fits' residuals over the whole run; the convergence of the scale-factor error,
bias and bias drift (with their 1-sigma bands) as data accumulate.
"""
from typing import List

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

RAD2DEG = 180.0 / np.pi
MAX_POINTS = 20_000


def _model(theta: np.ndarray, tau: np.ndarray, period_s: float) -> np.ndarray:
    a = 2 * np.pi * tau / period_s
    return (theta[0] * np.cos(a) + theta[1] * np.sin(a) + theta[2] + theta[3] * tau
            + 0.5 * theta[4] * tau ** 2)


def _thin(n: int) -> slice:
    return slice(None, None, max(1, n // MAX_POINTS))


def plot_swing(run, path: str) -> None:
    """Render the four-panel figure of a ``swing_kf.SwingRun`` to ``path``."""
    al, est = run.aligned, run.estimates
    period = al.period_s
    fig, axes = plt.subplots(3, 2, figsize=(13, 10), constrained_layout=True)
    ax = axes[0, 0]
    zoom = 3 * period
    for tau, z, res, label, color in (
            (al.tau_encoder, al.angle_encoder, run.encoder, 'encoder', 'C0'),
            (al.tau_gyro, al.angle_gyro, run.gyro, f'integrated {al.axis}', 'C1')):
        m = tau <= zoom
        ax.plot(tau[m][_thin(m.sum())], RAD2DEG * z[m][_thin(m.sum())], '.', ms=2, color=color,
                label=label)
        fine = np.linspace(0, zoom, 2000)
        ax.plot(fine, RAD2DEG * _model(res.theta, fine, period), '-', lw=1, color='k')
    ax.set(xlabel='t - t_ref [s]', ylabel='angle [deg]',
           title='angles (dots) and fitted models (black), first 3 periods')
    ax.legend(loc='upper right', fontsize=8)

    ax = axes[0, 1]
    for tau, z, res, label in ((al.tau_encoder, al.angle_encoder, run.encoder, 'encoder'),
                               (al.tau_gyro, al.angle_gyro, run.gyro, f'gyro {al.axis}')):
        s = _thin(tau.size)
        ax.plot(tau[s], RAD2DEG * 3600 * (z[s] - _model(res.theta, tau[s], period)), lw=0.5,
                label=label)
    ax.set(xlabel='t - t_ref [s]', ylabel='residual [arcsec]',
           title='residuals (gyro: angle random walk is expected)')
    ax.legend(fontsize=8)

    h = run.history
    t = run.history_tau
    panels = [
        (axes[1, 0], 'scale_factor_error', 100.0, 'scale-factor error [%]'),
        (axes[1, 1], 'bias', RAD2DEG, 'bias [deg/s]'),
        (axes[2, 0], 'bias_drift', RAD2DEG, 'bias drift [deg/s^2]'),
    ]
    for ax, key, k, label in panels:
        if h:
            v = np.array([getattr(e, key).value for e in h]) * k
            s = np.array([getattr(e, key).sigma for e in h]) * k
            ax.fill_between(t, v - s, v + s, alpha=0.3, lw=0)
            ax.plot(t, v, lw=1)
            final = getattr(est, key)
            ax.axhline(final.value * k, color='k', lw=0.5)
            span = max(abs(final.value * k), 1e-12) * 0.5 + 5 * final.sigma * k
            ax.set_ylim(final.value * k - span, final.value * k + span)
        ax.set(xlabel='t - t_ref [s]', ylabel=label, title=f'{label}: estimate +- 1 sigma')
    ax = axes[2, 1]
    ax.axis('off')
    ax.text(0.0, 1.0, '\n'.join(table(est)), va='top', family='monospace', fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def table(est) -> List[str]:
    """Human lines: the estimates in the field's units."""
    def fmt(e, k, unit):
        return f'{e.value * k:+.5g} +- {e.sigma * k:.3g} {unit}'
    lines = [
        f'scale-factor error  {fmt(est.scale_factor_error, 100.0, "%")}',
        f'bias                {fmt(est.bias, RAD2DEG, "deg/s")}',
        f'bias drift          {fmt(est.bias_drift, RAD2DEG, "deg/s^2")}',
        f'amplitude encoder   {fmt(est.amplitude_encoder, RAD2DEG, "deg")}',
        f'amplitude gyro      {fmt(est.amplitude_gyro, RAD2DEG, "deg")}',
        f'period {est.period_s:g} s, samples {est.samples_encoder} encoder + '
        f'{est.samples_gyro} gyro',
    ]
    return lines
