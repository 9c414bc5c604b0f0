"""
Overlapping Allan variance speed: gyro_char.allan vs allantools.oadev, measured in one run.

3.6 M rate samples (5 h at 200 Hz), the paper's tau grid. Each timing is the best of
``--repeat`` runs; ours includes the mean removal and the cumulative sum. The numba kernel is
compiled (or loaded from its cache) by a warm-up call on a short series first, which is timed
and printed separately. Also prints the largest relative difference from allantools.

    python bench/bench_allan.py
"""
import argparse
import time

import allantools
from gyro_char.allan.kernel import m_grid, numba, overlapping_avar
import numpy as np
from timing import best_of


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('-n', type=int, default=3_600_000)
    ap.add_argument('--dt', type=float, default=0.005)
    ap.add_argument('--repeat', type=int, default=3)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    rate = 0.01 + 1e-3 * rng.standard_normal(args.n)
    m = m_grid(args.n)
    taus = m * args.dt
    print(f'{args.n} samples, paper grid: {m.size} taus ({taus[0]:g} .. {taus[-1]:g} s), '
          f'numba {"available" if numba is not None else "MISSING"}')
    t0 = time.perf_counter()
    overlapping_avar(rate[:1000], args.dt)
    print(f'warm-up (numba compile or cache load): {time.perf_counter() - t0:.2f} s')

    ref = allantools.oadev(rate, rate=1.0 / args.dt, data_type='freq', taus=taus)

    def peer():
        return allantools.oadev(rate, rate=1.0 / args.dt, data_type='freq', taus=taus)

    t_ref, _ = best_of(peer, args.repeat)
    t_ours, _ = best_of(lambda: overlapping_avar(rate, args.dt, m=m), args.repeat)
    t_numpy, _ = best_of(lambda: overlapping_avar(rate, args.dt, m=m, use_numba=False), 1)
    _, avar, _ = overlapping_avar(rate, args.dt, m=m)
    diff = float(np.max(np.abs(avar / ref[1] ** 2 - 1.0)))
    print(f'allantools.oadev          : {t_ref:7.3f} s')
    print(f'gyro_char (numba kernel)  : {t_ours:7.3f} s   speed-up x{t_ref / t_ours:.1f}')
    print(f'gyro_char (numpy fallback): {t_numpy:7.3f} s   speed-up x{t_ref / t_numpy:.1f}')
    print(f'max |avar / allantools - 1| = {diff:.2e}')


if __name__ == '__main__':
    main()
