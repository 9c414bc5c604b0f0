#!/usr/bin/env python3
"""
Swing filter speed: the batch path against a plain filterpy predict/update loop, same run.

    python bench/bench_swing_kf.py [--duration 900] [--subset 20000] [--full]

Data: the bench simulator's ADIS16405 preset, 1 kHz IMU and 1 kHz encoder (900 k samples per
stream for 15 min). Timed, best of ``--repeat``:

- batch: ``estimate_swing`` on the two Recordings - the whole offline run (validation,
  alignment, period and axis checks, gyro integration, both filters, estimates);
- filterpy: ``SwingKalman`` (filterpy ``KalmanFilter``, Phi per step, one predict + update per
  sample) over the first ``--subset`` samples of each stream, extrapolated linearly to the
  full record (its cost per sample is constant); ``--full`` runs it over everything instead;
- online: ``SwingOnline`` fed one sample per call as a node's callbacks would, over 60 s of the
  record; reported as the fraction of one core that 1 kHz + 1 kHz real-time input costs.

Prints the ratio filterpy / batch (target >= 20) and the batch time (target <= 1 s), and checks
that filterpy and batch agree on the subset.
"""
import argparse

from gyro_char import swing_batch
from gyro_char.bench_sim import simulate_swing
from gyro_char.swing_align import integrate
from gyro_char.swing_kf import estimate_swing, SwingKalman
from gyro_char.swing_model import SwingNoise
from gyro_char.swing_online import SwingOnline
import numpy as np
from timing import best_of


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--duration', type=float, default=900.0)
    ap.add_argument('--subset', type=int, default=20000)
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--full', action='store_true', help='run filterpy over the whole record')
    args = ap.parse_args()

    run = simulate_swing('adis16405', duration=args.duration, seed=0, channels=('gyro_x',))
    imu, enc = run.imu, run.encoder
    period = run.truth['swing']['period_s']
    n_total = len(imu) + len(enc)
    print(f'record: {args.duration:g} s, {len(imu)} IMU + {len(enc)} encoder samples')

    t_batch, res = best_of(lambda: estimate_swing(imu, enc, period, axis='x'), args.repeat)
    noise = SwingNoise(res.encoder.noise, res.gyro.noise)

    al = res.aligned
    m = len(al.tau_gyro) if args.full else min(args.subset, len(al.tau_gyro))
    me = len(al.tau_encoder) if args.full else min(args.subset, len(al.tau_encoder))
    z_g = integrate(al.tau_gyro[:m], al.rate_gyro[:m])

    def filterpy_loop():
        e = SwingKalman('encoder', period, noise.encoder_sigma).run(
            al.tau_encoder[:me], al.angle_encoder[:me])
        g = SwingKalman('gyro', period, noise.gyro_arw).run(al.tau_gyro[:m], z_g)
        return e.result(), g.result()

    t_fp_sub, (fp_e, fp_g) = best_of(filterpy_loop, 1)
    t_fp = t_fp_sub * n_total / (m + me)

    # Same subset through the fast kernel: the two must agree (state and covariance).
    b_e, _ = swing_batch.run('encoder', al.tau_encoder[:me], al.angle_encoder[:me], period,
                             noise.encoder_sigma)
    b_g, _ = swing_batch.run('gyro', al.tau_gyro[:m], z_g, period, noise.gyro_arw)
    worst = 0.0
    for a, b in ((fp_e, b_e), (fp_g, b_g)):
        sd = np.sqrt(np.diag(b.P))
        worst = max(worst, np.max(np.abs(a.x - b.x) / sd),
                    np.max(np.abs(a.P - b.P) / np.outer(sd, sd)))

    # Online, one sample per call (a node's callbacks), over 60 s of the record.
    n_on = min(60_000, len(al.tau_gyro), len(al.tau_encoder))

    def online():
        o = SwingOnline(period, noise, t_ref=al.t_ref)
        tg, rg = al.t_ref + al.tau_gyro[:n_on], al.rate_gyro[:n_on]
        te, ae = al.t_ref + al.tau_encoder[:n_on], al.angle_encoder[:n_on]
        for i in range(n_on):
            o.add_imu(tg[i:i + 1], rg[i:i + 1])
            o.add_encoder(te[i:i + 1], ae[i:i + 1])
            if i % 1000 == 999:  # estimates at 1 Hz, as the node publishes them
                o.estimates()
        return o.estimates()

    t_on, _ = best_of(online, 1)
    span = al.tau_gyro[n_on - 1] - al.tau_gyro[0]

    scope = 'measured on the whole record' if args.full else \
        f'measured on {m + me} samples, extrapolated x{n_total / (m + me):.1f}'
    print(f'batch (estimate_swing, whole run): {t_batch:.3f} s   [target <= 1 s]')
    print(f'filterpy predict/update loop:      {t_fp:.1f} s   ({scope}; '
          f'{1e6 * t_fp_sub / (m + me):.1f} us/sample)')
    print(f'ratio filterpy / batch:            {t_fp / t_batch:.0f}x   [target >= 20x]')
    print(f'filterpy vs batch on the subset:   max |diff| {worst:.1e} posterior sigma '
          '(state and covariance)')
    print(f'online, 1 sample per call:         {100 * t_on / span:.1f} % of a core for '
          '1 kHz IMU + 1 kHz encoder   [target < 25 %]')
    e = res.estimates
    tr = run.truth['swing']
    print(f'estimates vs truth: scale-factor error {100 * e.scale_factor_error.value:+.4f} % '
          f'(truth {100 * tr["scale_factor_error"]:+.4f} %)')


if __name__ == '__main__':
    main()
