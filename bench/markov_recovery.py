"""
Markov terms in the noise fit (``--markov 2``): recovery where they exist, false keeps where not.

Part 1: static gyro_x records at 100 Hz from the bench simulator, white noise plus its
``gauss_markov`` effect (sigma, T_c): the Markov terms the fit keeps, their T_c and sigma
against the truth, and N. Part 2: records that formula (4) describes exactly
(``gyro_char.sim.noise_gen``: white; white + flicker; white + random walk; all five terms): how
often a Markov term is kept anyway (a false keep), and whether N, B, K then move.

    python bench/markov_recovery.py                  # 1 h records, 6 seeds (a few minutes)
    python bench/markov_recovery.py --hours 2 --seeds 3
"""
import argparse

from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.records import Recording
from gyro_char.sim.config import BenchConfig
from gyro_char.sim.noise_gen import generate
from gyro_char.sim.simulator import simulate_static
import numpy as np

MARKOV = [(6e-4, 20.0), (3e-4, 100.0), (1e-3, 5.0)]  # (sigma rad/s, T_c s) over N = 1e-3
NULLS = {'white': {'N': 1e-3}, 'white+flicker': {'N': 1e-3, 'B': 2e-4},
         'white+rw': {'N': 1e-3, 'K': 2e-5},
         'all five': {'N': 1e-3, 'B': 2e-4, 'K': 2e-5, 'Q': 3e-4, 'R': 1e-8}}


def gm_record(sigma: float, tc: float, seed: int, hours: float) -> Recording:
    """Return a simulated static gyro_x record: white N = 1e-3 plus a Gauss-Markov rate."""
    cfg = BenchConfig.from_preset('adis16405', {
        'gyro': {'static_rate_hz': 100.0, 'output_step': 0.0, 'jitter_s': 0.0},
        'noise': {'gyro_x': {'N': 1e-3, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}}})
    effect = {'name': 'gauss_markov', 'params': {'sigma': sigma, 'tau_s': tc, 'axis': 0.0}}
    run = simulate_static(cfg, duration=hours * 3600.0, seed=seed, effects=[effect],
                          channels=('gyro_x',))
    return Recording(run.imu.t, {'gyro_x': run.imu.channels['gyro_x']})


def recovery(sigma, tc, seeds, hours, method='l1'):
    """Return per seed (number kept, T_c / truth, sigma / truth, N / truth) of the closest."""
    rows = []
    for seed in range(seeds):
        fit = fit_result(compute(gm_record(sigma, tc, seed, hours)), n_boot=20,
                         markov=2, method=method)['gyro_x']
        if not fit.markov:
            rows.append((0, np.nan, np.nan, fit.terms['N'].value / 1e-3))
            continue
        best = min(fit.markov, key=lambda m: abs(np.log(m.tau_c / tc)))
        rows.append((len(fit.markov), best.tau_c / tc, best.sigma.value / sigma,
                     fit.terms['N'].value / 1e-3))
    return rows


def false_keeps(truth, seeds, hours, dt=0.02):
    """Return per seed (Markov terms kept, {term: with / without Markov} for N, B, K)."""
    n = int(hours * 3600.0 / dt)
    rows = []
    for seed in range(seeds):
        rate = generate(n, dt, rng=np.random.default_rng(500 + seed), **truth)
        res = compute(Recording(np.arange(n) * dt, {'gyro_x': rate}))
        with_m = fit_result(res, n_boot=10, markov=2)['gyro_x']
        plain = fit_result(res, n_boot=10)['gyro_x']
        moved = {t: (with_m.fitted[t] / plain.fitted[t] if plain.fitted[t] else np.nan)
                 for t in ('N', 'B', 'K')}
        rows.append((len(with_m.markov), moved))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--hours', type=float, default=1.0)
    ap.add_argument('--seeds', type=int, default=6)
    args = ap.parse_args()
    print(f'Part 1: white N = 1e-3 rad/sqrt(s) + gauss_markov, {args.hours:g} h at 100 Hz, '
          f'{args.seeds} seeds, --markov 2, fit l1')
    for sigma, tc in MARKOV:
        rows = recovery(sigma, tc, args.seeds, args.hours)
        kept = [r[0] for r in rows]
        ratio = np.array([r[1:] for r in rows], dtype=float)
        found = ratio[np.isfinite(ratio[:, 0])]
        ranges = (f'T_c/truth {found[:, 0].min():.2f}..{found[:, 0].max():.2f}, sigma/truth '
                  f'{found[:, 1].min():.2f}..{found[:, 1].max():.2f}, ' if found.size else '')
        print(f'  sigma {sigma:g} rad/s, T_c {tc:g} s: kept {kept}; {ranges}N/truth '
              f'{np.min(ratio[:, 2]):.4f}..{np.max(ratio[:, 2]):.4f}', flush=True)
    print(f'Part 2: records formula (4) describes, {args.hours:g} h at 50 Hz, {args.seeds} seeds')
    total, kept = 0, 0
    for name, truth in NULLS.items():
        rows = false_keeps(truth, args.seeds, args.hours)
        total += len(rows)
        kept += sum(1 for r in rows if r[0])
        moved = [f'{t} x{r[1][t]:.2f}' for r in rows if r[0] for t in r[1]
                 if np.isfinite(r[1][t]) and abs(r[1][t] - 1.0) > 0.01]
        print(f'  {name:14s}: Markov kept in {sum(1 for r in rows if r[0])}/{len(rows)}'
              + (f'; moved: {", ".join(moved)}' if moved else ''), flush=True)
    print(f'false keeps: {kept}/{total}')


if __name__ == '__main__':
    main()
