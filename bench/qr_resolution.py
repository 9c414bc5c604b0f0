"""
How often a static record resolves Q and R, and how far unresolved upper bounds sit above truth.

Synthetic records (``gyro_char.sim.noise_gen``) at ``--rate`` Hz hold white noise N, flicker B,
random walk K, quantization Q and a ramp R; Q and R are set relative to the others so that their
visibility depends on the record: Q crosses N at tau_QN = 3 Q^2 / N^2 (``--q-cross``, s; at or
below one sample it is hidden under N), R crosses K at tau_RK = 2 K^2 / (3 R^2)
(``--r-cross``, s; beyond half the record it is hidden under K). For each record length and seed
the default fit ('l1') says whether Q and R are resolved; for those that are not, the reported
upper bound is compared with the truth (bound / truth >= 1 when the bound is honest).

Prints a table per length and writes ``qr_resolution.png`` (resolved share; bound / truth) to
``--out``.

    python bench/qr_resolution.py --out docs/figures       # 0.5-8 h, 6 seeds, Q meets N at 5 ms
    python bench/qr_resolution.py --hours 0.5,1 --seeds 2
"""
import argparse
import os
import time

from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.records import Recording
from gyro_char.sim.noise_gen import generate
import numpy as np

N_TRUE, B_TRUE, K_TRUE = 1e-3, 5e-5, 1e-5  # rad/sqrt(s), rad/s, rad/s/sqrt(s)


def truth(q_cross: float, r_cross: float) -> dict:
    """Return the five coefficients with Q and R placed by their crossovers (s)."""
    return {'N': N_TRUE, 'B': B_TRUE, 'K': K_TRUE,
            'Q': N_TRUE * float(np.sqrt(q_cross / 3.0)),
            'R': K_TRUE * float(np.sqrt(2.0 / (3.0 * r_cross)))}


def one_record(hours: float, rate_hz: float, seed: int, coeffs: dict) -> dict:
    """Return {term: (resolved, value / truth)} for Q and R of one simulated record."""
    dt = 1.0 / rate_hz
    n = int(round(hours * 3600.0 * rate_hz))
    rate = generate(n, dt, rng=np.random.default_rng(seed), **coeffs)
    res = compute(Recording(np.arange(n) * dt, {'gyro_x': rate}))
    fit = fit_result(res, n_boot=20, seed=seed)['gyro_x']
    return {t: (fit.terms[t].resolved, fit.terms[t].value / coeffs[t]) for t in ('Q', 'R')}


def study(hours, rate_hz, seeds, coeffs, quiet=False):
    """Return {hours: {term: [(resolved, ratio), ...]}}."""
    out = {}
    for h in hours:
        out[h] = {'Q': [], 'R': []}
        for seed in range(seeds):
            t0 = time.perf_counter()
            for t, v in one_record(h, rate_hz, 100 * seed + int(10 * h), coeffs).items():
                out[h][t].append(v)
            if not quiet:
                print(f'{h:5g} h seed {seed}: ' + '  '.join(
                    f'{t} {"resolved" if r else "bound"} {v:.3g}x'
                    for t, (r, v) in ((t, out[h][t][-1]) for t in ('Q', 'R')))
                    + f'  ({time.perf_counter() - t0:.1f} s)', flush=True)
    return out


def summary(rows) -> list:
    """Return per-length lines: resolved share, bound / truth of the unresolved (median, min)."""
    lines = []
    for h, terms in rows.items():
        cells = []
        for t, vals in terms.items():
            res = [r for r, _ in vals]
            bounds = [v for r, v in vals if not r]
            cell = f'{t} resolved {sum(res)}/{len(res)}'
            if bounds:
                cell += (f', bound/truth median {np.median(bounds):.3g} '
                         f'(min {np.min(bounds):.3g}, max {np.max(bounds):.3g})')
            cells.append(cell)
        lines.append(f'{h:5g} h: ' + ';  '.join(cells))
    return lines


def plot(rows, path: str, title: str) -> None:
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    hours = np.array(list(rows))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    for t, marker in (('Q', 'o'), ('R', 's')):
        share = [np.mean([r for r, _ in rows[h][t]]) for h in hours]
        a1.semilogx(hours, share, marker=marker, label=t)
        for h in hours:
            b = [v for r, v in rows[h][t] if not r]
            a2.loglog([h] * len(b), b, marker, alpha=0.6, color='C0' if t == 'Q' else 'C1',
                      label=t if h == hours[0] or not a2.get_legend_handles_labels()[1] else None)
    for ax in (a1, a2):
        ax.set_xticks(hours)
        ax.set_xticklabels([f'{h:g}' for h in hours])
        ax.minorticks_off()
    a1.set_xlabel('record length [h]')
    a1.set_ylabel('share of records resolving the term')
    a1.set_ylim(-0.05, 1.05)
    a1.legend()
    a1.grid(True, which='both', alpha=0.3)
    a2.axhline(1.0, color='k', lw=0.8)
    a2.set_xlabel('record length [h]')
    a2.set_ylabel('unresolved: upper bound / truth')
    handles, labels = a2.get_legend_handles_labels()
    keep = {lab: hnd for hnd, lab in zip(handles, labels)}
    a2.legend(keep.values(), keep.keys())
    a2.grid(True, which='both', alpha=0.3)
    fig.suptitle(title, fontsize=9)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--hours', default='0.5,1,2,4,8')
    ap.add_argument('--rate', type=float, default=100.0, help='sample rate, Hz')
    ap.add_argument('--seeds', type=int, default=6)
    ap.add_argument('--q-cross', type=float, default=0.005, help='tau where Q meets N (s)')
    ap.add_argument('--r-cross', type=float, default=1800.0, help='tau where R meets K (s)')
    ap.add_argument('--out', default='.', help='directory for qr_resolution.png')
    args = ap.parse_args()
    coeffs = truth(args.q_cross, args.r_cross)
    title = (f'{args.rate:g} Hz, {args.seeds} seeds: N {N_TRUE:g}, B {B_TRUE:g}, K {K_TRUE:g}, '
             f'Q {coeffs["Q"]:.3g} (meets N at {args.q_cross:g} s), R {coeffs["R"]:.3g} '
             f'(meets K at {args.r_cross:g} s), SI')
    print(title)
    rows = study([float(h) for h in args.hours.split(',')], args.rate, args.seeds, coeffs)
    print('\n'.join(summary(rows)))
    os.makedirs(args.out, exist_ok=True)
    plot(rows, os.path.join(args.out, 'qr_resolution.png'), title)
    print(f'wrote {os.path.join(args.out, "qr_resolution.png")}')


if __name__ == '__main__':
    main()
