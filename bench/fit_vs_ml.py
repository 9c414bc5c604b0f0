"""
K accuracy of the Allan fit against an efficient reference: exact Gaussian maximum likelihood.

Static records of white rate noise N plus rate random walk K (``gyro_char.sim.noise_gen``) are
exactly a local-level model: y_t = mu_t + e_t, var e = N^2 / dt; mu_(t+1) = mu_t + w_t,
var w = K^2 dt. Its exact Gaussian likelihood comes from the Kalman filter's prediction errors
(diffuse start on the first sample); with the noise ratio q = var w / var e the scale is
profiled out, so the maximum likelihood is a one-dimensional search over log q (a grid, then
a bounded Brent step). ML is asymptotically efficient: no estimator of K from the same record
does better on average, so the Allan fit's K error is judged next to it.

For each mix (the white / random-walk crossover tau_c = sqrt(3) N / K) and rate: ``--seeds``
records of ``--hours``; the fit (``gyro_char.allan.fit``, default estimator 'l1' and 'l1w')
and ML estimate K and N; the median |relative error| of each is printed, per mix and overall.
Where the fit reports K unresolved its value is an upper bound, not an estimate: the summary
gives the median over all records and over the records where the fit resolved K.

    python bench/fit_vs_ml.py                    # 4 h, 100 and 200 Hz, 5 mixes, 6 seeds
    python bench/fit_vs_ml.py --hours 1 --seeds 2 --rates 100
"""
import argparse
import time

from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.records import Recording
from gyro_char.sim.noise_gen import generate
import numba
import numpy as np
from scipy import optimize

N_TRUE = 1e-3  # rad/sqrt(s)
CROSSOVERS = (30.0, 100.0, 300.0, 1000.0, 3000.0)  # s: where K's line meets N's


@numba.njit(cache=False)  # cache files break when loaded both as a script and as a module
def _kalman(y, q):  # pragma: no cover - compiled
    # Local level with var e = 1: returns (sum v^2 / F, sum log F) over t >= 1.
    mu, p = y[0], 1.0  # diffuse prior: after the first observation P = var e
    ssq, slog = 0.0, 0.0
    for t in range(1, y.size):
        pp = p + q
        f = pp + 1.0
        v = y[t] - mu
        ssq += v * v / f
        slog += np.log(f)
        k = pp / f
        mu += k * v
        p = pp * (1.0 - k)
    return ssq, slog


def profile_loglik(y: np.ndarray, q: float):
    """Return (profile log-likelihood, ML var e) of the local-level model at ratio ``q``."""
    ssq, slog = _kalman(y, q)
    n = y.size - 1
    s2 = ssq / n
    return -0.5 * (n * np.log(s2) + slog), s2


def ml_local_level(rate: np.ndarray, dt: float) -> dict:
    """Return the ML estimates {'N', 'K'} (SI) of white + random-walk rate samples."""
    y = np.asarray(rate, dtype=np.float64) - np.mean(rate)

    def cost(log_q):
        return -profile_loglik(y, float(np.exp(log_q)))[0]

    grid = np.linspace(np.log(1e-20), np.log(1e-2), 45)
    vals = [cost(g) for g in grid]
    i = int(np.argmin(vals))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    sol = optimize.minimize_scalar(cost, bounds=(lo, hi), method='bounded',
                                   options={'xatol': 1e-4})
    q = float(np.exp(sol.x))
    s2 = profile_loglik(y, q)[1]
    return {'N': float(np.sqrt(s2 * dt)), 'K': float(np.sqrt(q * s2 / dt))}


def one_record(crossover: float, rate_hz: float, hours: float, seed: int, methods):
    """Return {estimator: {'N': rel. error, 'K': rel. error}} on one simulated record."""
    dt = 1.0 / rate_hz
    n = int(round(hours * 3600.0 * rate_hz))
    k_true = np.sqrt(3.0) * N_TRUE / crossover
    rate = generate(n, dt, N=N_TRUE, K=k_true, rng=np.random.default_rng(seed))
    out = {'ml': ml_local_level(rate, dt)}
    out['ml']['resolved'] = True
    res = compute(Recording(np.arange(n) * dt, {'gyro_x': rate}))
    for m in methods:
        fit = fit_result(res, method=m, n_boot=10, seed=seed)['gyro_x']
        out[m] = {t: fit.terms[t].value for t in ('N', 'K')}
        out[m]['resolved'] = fit.terms['K'].resolved
    return {e: {'N': v['N'] / N_TRUE - 1.0, 'K': v['K'] / k_true - 1.0,
                'resolved': v['resolved']} for e, v in out.items()}


def study(hours, rates, seeds, methods, crossovers=CROSSOVERS, quiet=False):
    """Return {estimator: [(crossover, rate, seed, N err, K err, K resolved), ...]}."""
    rows = {e: [] for e in ('ml',) + tuple(methods)}
    for tc in crossovers:
        for rate_hz in rates:
            for seed in range(seeds):
                t0 = time.perf_counter()
                errs = one_record(tc, rate_hz, hours, 1000 * int(tc) + seed, methods)
                for e, v in errs.items():
                    rows[e].append((tc, rate_hz, seed, v['N'], v['K'], v['resolved']))
                if not quiet:
                    print(f'tau_c {tc:6g} s {rate_hz:5g} Hz seed {seed}: ' + '  '.join(
                        f'{e} K {100 * v["K"]:+6.1f} % N {100 * v["N"]:+5.2f} %'
                        for e, v in errs.items()) + f'  ({time.perf_counter() - t0:.1f} s)',
                        flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--hours', type=float, default=4.0)
    ap.add_argument('--rates', default='100,200', help='sample rates, Hz')
    ap.add_argument('--seeds', type=int, default=6)
    ap.add_argument('--methods', default='l1,l1w')
    args = ap.parse_args()
    methods = tuple(args.methods.split(','))
    rates = [float(r) for r in args.rates.split(',')]
    print(f'N = {N_TRUE} rad/sqrt(s); K from the crossover tau_c = sqrt(3) N / K; '
          f'{args.hours:g} h records')
    rows = study(args.hours, rates, args.seeds, methods)
    print()
    fit_ok = {e: [x[5] for x in r] for e, r in rows.items()}
    for e, r in rows.items():
        a = np.array([x[3:5] for x in r])
        per_mix = '  '.join(
            f'{tc:g} s: {100 * np.median(np.abs([x[4] for x in r if x[0] == tc])):.1f} %'
            for tc in CROSSOVERS)
        print(f'{e:5s} median |K error| {100 * np.median(np.abs(a[:, 1])):5.1f} %, '
              f'|N error| {100 * np.median(np.abs(a[:, 0])):5.2f} %, K resolved '
              f'{sum(fit_ok[e])}/{len(r)}   per mix: {per_mix}')
    for m in methods:  # on the records where that estimator resolved K, both estimators
        ok = fit_ok[m]
        k_fit = [abs(x[4]) for x, o in zip(rows[m], ok) if o]
        k_ml = [abs(x[4]) for x, o in zip(rows['ml'], ok) if o]
        if k_fit:
            print(f'records where {m} resolved K ({len(k_fit)}): median |K error| {m} '
                  f'{100 * np.median(k_fit):.1f} %, ml {100 * np.median(k_ml):.1f} %')


if __name__ == '__main__':
    main()
