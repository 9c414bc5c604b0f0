#!/usr/bin/env python3
"""
Monte Carlo method error of the swing filter beside the paper's figures (0.999 confidence).

    python bench/mc_swing.py --study fog --runs 1000 --json out/mc_fog.json
    python bench/mc_swing.py --study mems --runs 1000 --json out/mc_mems.json
    python bench/mc_swing.py --study mems --runs 200 --duration 1440     # what halves drift
    python bench/mc_swing.py --study mems --runs 200 --amplitude-scale 2 # what halves d_rho
    python bench/mc_swing.py --study mems --runs 200 --full-noise        # + bias instability

Setups (``gyro_char.sim.monte_carlo``; every number is printed with the result): the simulator's
``vg910`` (FOG) and ``adis16405`` (MEMS) presets - stand A = 20 deg, T = 5 s, 15 min; encoder
d1 = 2 pi / 2^20, d2 = 2 pi / 2^22, ADC noise 3 urad, jitter 20 us; gyro errors from the
paper's Table 1 (scale factor, bias, drift), misalignment 0.5 deg with 0.1 mrad white
instability, N from Table 2 (FOG 0.005 deg/sqrt(h), MEMS 1.89 deg/sqrt(h)), dH FOG 1e-5 rad/s,
MEMS 0.05 deg/s - sampled at the paper's steps (FOG 5 ms, MEMS 3 ms).
"""
import argparse
import json
import time

from gyro_char.progress import progress
from gyro_char.sim.monte_carlo import monte_carlo, PAPER, STUDY

ROWS = (
    ('sfe_pp', 'scale-factor error, error [pp of %]', 'interval', PAPER['scale_factor_error_pp']),
    ('bias_pct', 'bias error [% of set value]', 'abs', PAPER['bias_pct']),
    ('drift_pct', 'bias-drift error [% of set value]', 'abs', PAPER['bias_drift_pct']),
)


def report(s: dict) -> None:
    st = s['setup']
    print(f"study {st['study']} ({st['preset']}): {st['runs']} runs of {st['duration_s']:g} s, "
          f"A {st['amplitude_rad']:.4f} rad, T {st['period_s']:g} s, gyro "
          f"{st['gyro_rate_hz']:.1f} Hz, encoder {st['encoder_rate_hz']:.1f} Hz, "
          f"{'paper model (white gyro noise)' if st['paper_model'] else 'full preset noise'}")
    print(f"  set values: scale-factor error {st['scale_factor_error']:+.4g}, bias "
          f"{st['bias_rad_s']:+.4g} rad/s, drift {st['bias_drift_rad_s2']:+.4g} rad/s^2; "
          f"gyro noise {st['noise']}; dH {st['dH_rad_s']:.3g} rad/s")
    print(f"  {'':36s} {'0.999 interval (empirical)':>28s} {'(normal theory)':>24s}"
          f" {'paper':>18s}   plain tuning (Q=0)")
    for key, label, kind, paper in ROWS:
        v, p = s[key], s['plain_' + key]
        if kind == 'interval':
            emp = '[{:+.5f}; {:+.5f}]'.format(*v['interval_empirical'])
            nor = '[{:+.5f}; {:+.5f}]'.format(*v['interval_normal'])
            pap = '[{:+.4f}; {:+.4f}]'.format(*paper)
            pl = '[{:+.5f}; {:+.5f}]'.format(*p['interval_normal'])
        else:
            emp = f"|err| <= {v['abs_bound_empirical']:.4f}"
            nor = f"|err| <= {v['abs_bound_normal']:.4f}"
            pap = f'{paper:g}'
            pl = f"|err| <= {p['abs_bound_normal']:.4f}"
        print(f'  {label:36s} {emp:>28s} {nor:>24s} {pap:>18s}   {pl}')
    print('  error / filter sigma (calibration, ideal mean 0 std 1): '
          + ', '.join(f"{k[2:]} {s[k]['mean']:+.2f}/{s[k]['std']:.2f}"
                      for k in ('z_sfe', 'z_bias', 'z_drift')))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--study', choices=sorted(STUDY), default='mems')
    ap.add_argument('--runs', type=int, default=1000)
    ap.add_argument('--duration', type=float, default=900.0)
    ap.add_argument('--seed0', type=int, default=0)
    ap.add_argument('--amplitude-scale', type=float, default=1.0)
    ap.add_argument('--full-noise', action='store_true',
                    help="keep the preset's bias instability / rate random walk")
    ap.add_argument('--json', help='write the summary here')
    args = ap.parse_args()
    t0 = time.perf_counter()
    s = monte_carlo(args.study, args.runs, duration=args.duration, seed0=args.seed0,
                    paper_model=not args.full_noise, amplitude_scale=args.amplitude_scale,
                    progress=lambda it: progress(it, total=args.runs, desc=args.study))
    report(s)
    print(f'  ({time.perf_counter() - t0:.0f} s)')
    if args.json:
        with open(args.json, 'w') as fh:
            json.dump(s, fh, indent=1)


if __name__ == '__main__':
    main()
