"""
The sensor filter in the noise fit on simulated records with a known filter: taps and N.

Static gyro_x records at 100 Hz from the bench simulator with its ``internal_lowpass`` effect
(a boxcar or Bartlett window at an internal rate, then decimation; the simulator's truth N is
the long-tau angle random walk), white noise alone or with flicker and random walk. For each
case and seed: the filter ``--sensor-filter auto`` (or ``auto@RATE``) finds (exact, equivalent:
the same output autocorrelation, or wrong) and N fitted over all tau with that filter (by the
'l1w' and the default 'l1' estimator) and without one ('l1w'), as relative errors against the
truth.

    python bench/sensor_filter_recovery.py                 # 2 h, 3 seeds (a few minutes)
    python bench/sensor_filter_recovery.py --hours 0.5 --seeds 1
"""
import argparse
import time

from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.allan.sensor_filter import SensorFilter
from gyro_char.records import Recording
from gyro_char.sim.config import BenchConfig
from gyro_char.sim.simulator import simulate_static
import numpy as np

# (kind, taps, internal rate multiple, spec given to the fit)
CASES = [('boxcar', 3, 1, 'auto'), ('boxcar', 6, 1, 'auto'), ('bartlett', 4, 1, 'auto'),
         ('bartlett', 3, 2, 'auto'), ('bartlett', 7, 8, 'auto@8x'), ('bartlett', 12, 8, 'auto@8x'),
         ('boxcar', 12, 8, 'auto'), ('bartlett', 7, 8, 'auto')]
MIXES = {'white': {}, 'white+flicker+rw': {'B': 6e-5, 'K': 4e-6}}
N_IN = 2e-3  # rad/sqrt(s) at the internal rate; the truth N is this times the filter's gain


def record(kind: str, taps: int, dec: int, seed: int, duration: float, extra=None):
    """Return (Recording of gyro_x at 100 Hz through internal_lowpass, truth N)."""
    noise = {'N': N_IN, 'B': 0.0, 'K': 0.0, 'Q': 0.0, 'R': 0.0}
    noise.update(extra or {})
    cfg = BenchConfig.from_preset('adis16405', {
        'gyro': {'static_rate_hz': 100.0, 'output_step': 0.0, 'jitter_s': 0.0},
        'noise': {'gyro_x': noise}})
    effects = [] if taps == 1 else [{'name': 'internal_lowpass', 'params': {
        'taps': float(taps), 'stages': 2.0 if kind == 'bartlett' else 1.0,
        'decimation': float(dec), 'accel': 0.0}}]
    run = simulate_static(cfg, duration=duration, seed=seed, effects=effects,
                          channels=('gyro_x',))
    rec = Recording(run.imu.t, {'gyro_x': run.imu.channels['gyro_x']})
    return rec, run.truth['channels']['gyro_x']['N']


def verdict(found, truth: SensorFilter) -> str:
    """Return 'exact', 'equivalent' (same output autocorrelation) or 'wrong'."""
    if found == truth:
        return 'exact'
    if found is not None and np.allclose(found.rho(40), truth.rho(40), atol=1e-9):
        return 'equivalent'
    return 'wrong'


def one(case, mix, seed, hours):
    """Return (verdict, N error: filter + l1w, filter + l1, no filter + l1w) of one record."""
    kind, taps, dec, spec = case
    rec, n_true = record(kind, taps, dec, seed, hours * 3600.0, MIXES[mix])
    res = compute(rec, sensor_filter=spec)
    found = res.sensor_filters['gyro_x'].sensor_filter
    plain = compute(rec)
    n = [fit_result(r, n_boot=10, method=m)['gyro_x'].terms['N'].value
         for r, m in ((res, 'l1w'), (res, 'l1'), (plain, 'l1w'))]
    return (verdict(found, SensorFilter(kind, taps, dec)),) + tuple(v / n_true - 1 for v in n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--hours', type=float, default=2.0)
    ap.add_argument('--seeds', type=int, default=3)
    args = ap.parse_args()
    print(f'{args.hours:g} h at 100 Hz, {args.seeds} seeds per case; N errors: with the filter '
          '(l1w, l1) | without (l1w)')
    worst, worst_l1, found = 0.0, 0.0, []
    for case in CASES:
        for mix in MIXES:
            t0 = time.perf_counter()
            rows = [one(case, mix, 10 * seed + case[1], args.hours) for seed in range(args.seeds)]
            worst = max(worst, max(abs(r[1]) for r in rows))
            worst_l1 = max(worst_l1, max(abs(r[2]) for r in rows))
            found += [r[0] for r in rows]
            print(f'{case[0]:8s} {case[1]:2d}@{case[2]}x {case[3]:8s} {mix:17s} '
                  + ' '.join(f'{r[0]:10s}' for r in rows) + '  N ' + ' '.join(
                      f'{100 * r[1]:+5.2f},{100 * r[2]:+5.2f}|{100 * r[3]:+5.2f} %' for r in rows)
                  + f'  ({time.perf_counter() - t0:.0f} s)', flush=True)
    print(f'filters: {found.count("exact")} exact, {found.count("equivalent")} equivalent, '
          f'{found.count("wrong")} wrong of {len(found)}; largest |N error| with the filter '
          f'{100 * worst:.2f} % (l1w), {100 * worst_l1:.2f} % (l1)')


if __name__ == '__main__':
    main()
