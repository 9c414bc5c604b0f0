#!/usr/bin/env python3
"""
When does swing_kf_node's ``converged`` flag turn on? The live filter fed a simulated run.

    python bench/swing_convergence.py --preset adis16405 --seeds 5 --duration 900
    python bench/swing_convergence.py --preset vg910 --seeds 5 --duration 120

Feeds ``SwingOnline`` (the node's core) in steps of ``--step`` seconds of data, judges every
step with ``Convergence`` at the node's default settings (or ``--rel-sigma`` / ``--periods``),
and prints per seed the data time at which the flag turned on and the final sigma / |value| of
each estimate, next to the same data's flag of the earlier rule (amplitudes to 1 %, bias sigma
below the rate amplitude), which switches on within seconds whatever the drift sigma.
"""
import argparse

from gyro_char.live.convergence import Convergence, QUANTITIES
from gyro_char.live.swing_online import SwingOnline
from gyro_char.sim.config import load
from gyro_char.sim.simulator import simulate_swing
import numpy as np


def run_one(preset: str, seed: int, duration: float, step: float, rel: float,
            periods: float) -> dict:
    cfg = load(None, preset)
    run = simulate_swing(cfg, duration=duration, seed=seed)
    period = run.truth['swing']['period_s']
    core = SwingOnline(period)
    conv = Convergence(period, rel_sigma=rel, periods=periods)
    ti, gi = run.imu.t, run.imu.channels['gyro_' + cfg.gyro.axis]
    te, ae = run.encoder.t, run.encoder.channels['encoder']
    first = old_first = None
    for end in np.arange(step, duration + 0.5 * step, step):
        for t, y, add in ((ti, gi, core.add_imu), (te, ae, core.add_encoder)):
            a, b = np.searchsorted(t, [end - step, end])
            add(t[a:b], y[a:b])
        est = core.estimates()
        if conv.update(est, float(end)) and first is None:
            first = float(end)
        if est.converged and old_first is None:
            old_first = float(end)
    ratios = {q: getattr(est, q).sigma / abs(getattr(est, q).value) for q in QUANTITIES}
    return {'first': first, 'old_first': old_first, 'ratios': ratios,
            'drift': run.truth['swing']['bias_drift']}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--preset', default='adis16405')
    ap.add_argument('--seeds', type=int, default=5)
    ap.add_argument('--duration', type=float, default=900.0)
    ap.add_argument('--step', type=float, default=2.5, help='data seconds between judgements')
    ap.add_argument('--rel-sigma', type=float, default=0.25)
    ap.add_argument('--periods', type=float, default=3.0)
    args = ap.parse_args()
    print(f'{args.preset}, {args.duration:g} s runs, rel_sigma {args.rel_sigma:g}, '
          f'{args.periods:g} periods')
    print('seed  converged_at_s  old_rule_at_s  '
          + '  '.join(f'{q}_sigma/|v|' for q in QUANTITIES))
    for seed in range(args.seeds):
        r = run_one(args.preset, seed, args.duration, args.step, args.rel_sigma, args.periods)
        fmt = (lambda v: 'never' if v is None else f'{v:.1f}')
        print(f'{seed:4d}  {fmt(r["first"]):>14}  {fmt(r["old_first"]):>13}  '
              + '  '.join(f'{r["ratios"][q]:.3f}' for q in QUANTITIES))


if __name__ == '__main__':
    main()
