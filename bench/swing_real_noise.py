#!/usr/bin/env python3
"""
The swing filter on the real ADIS16405's noise: a known swing injected into real static records.

    python bench/swing_real_noise.py [--axis x] [--window 900]

Each real static ADIS16405 record (shared/data beside the clone, 100 Hz, 2.8 h) is cut into
15-min windows.
Into each window's gyro rate a swing of known scale-factor error is added,
(1 + drho) A w cos(w t + psi0) with A = 20 deg, T = 5 s, drho = 0.5 %, psi0 random; the encoder
is the same swing sampled at the IMU stamps with 5 urad white noise. The gyro's own errors are
then the real ones: its internal smoothing, output quantization, bias instability and
whatever else the device does. Printed per window and summarised: the scale-factor error
against the injected value (in units of its sigma), and the bias and drift estimates, whose
true values are unknown but whose scatter across windows can be set beside their sigmas.
"""
import argparse
import glob
import os

from gyro_char.io import read_imu
from gyro_char.records import Recording
from gyro_char.swing.filter import estimate_swing
import numpy as np

DATA = os.path.join(os.path.dirname(__file__), '..', '..', 'shared', 'data', 'adis16405')
A, T, DRHO, ENC_SIGMA = np.radians(20.0), 5.0, 0.005, 5e-6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--axis', default='x', choices=('x', 'y', 'z'))
    ap.add_argument('--window', type=float, default=900.0)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    w = 2 * np.pi / T
    rows = []
    for path in sorted(glob.glob(os.path.join(DATA, '*.csv.gz'))):
        rec = read_imu(path, quiet=True)
        t_all, g_all = rec.t, rec.channels[f'gyro_{args.axis}']
        for lo in np.arange(t_all[0], t_all[-1] - args.window, args.window):
            m = (t_all >= lo) & (t_all < lo + args.window)
            t, g = t_all[m], g_all[m]
            psi = rng.uniform(0, 2 * np.pi)
            rate = g + (1 + DRHO) * A * w * np.cos(w * (t - lo) + psi)
            enc = A * np.sin(w * (t - lo) + psi) + ENC_SIGMA * rng.standard_normal(t.size)
            res = estimate_swing(Recording(t, {f'gyro_{args.axis}': rate}),
                                 Recording(t, {'encoder': enc}), T, axis=args.axis)
            e = res.estimates
            rows.append((e.scale_factor_error.value, e.scale_factor_error.sigma, e.bias.value,
                         e.bias.sigma, e.bias_drift.value, e.bias_drift.sigma,
                         res.gyro.low_frequency_ratio or np.nan, e.noise_gyro_arw))
            print(f'{os.path.basename(path)} {lo - t_all[0]:7.0f} s: d_rho error '
                  f'{100 * (e.scale_factor_error.value - DRHO):+.4f} % '
                  f'(sigma {100 * e.scale_factor_error.sigma:.4f}), bias '
                  f'{np.degrees(e.bias.value):+.4f} +- {np.degrees(e.bias.sigma):.4f} deg/s, '
                  f'drift {np.degrees(e.bias_drift.value):+.2e} +- '
                  f'{np.degrees(e.bias_drift.sigma):.1e} deg/s^2, LF ratio '
                  f'{res.gyro.low_frequency_ratio or float("nan"):.2f}')
    r = np.array(rows)
    z = (r[:, 0] - DRHO) / r[:, 1]
    print(f'\n{len(r)} windows of {args.window:g} s, gyro_{args.axis}, injected d_rho '
          f'{100 * DRHO:g} %:')
    print(f'  d_rho error: mean {100 * (r[:, 0].mean() - DRHO):+.4f} %, std '
          f'{100 * r[:, 0].std(ddof=1):.4f} %; error/sigma mean {z.mean():+.2f} std '
          f'{z.std(ddof=1):.2f}')
    for name, i in (('bias', 2), ('drift', 4)):
        print(f'  {name}: scatter across windows (std) {np.degrees(r[:, i].std(ddof=1)):.3e}, '
              f'median reported sigma {np.degrees(np.median(r[:, i + 1])):.3e} '
              f'(ratio {r[:, i].std(ddof=1) / np.median(r[:, i + 1]):.2f}; deg/s, deg/s^2)')
    print(f'  gyro white noise N: {np.degrees(np.median(r[:, 7])) * 60:.3f} deg/sqrt(h) '
          f'(median); low-frequency ratio median {np.nanmedian(r[:, 6]):.2f}')


if __name__ == '__main__':
    main()
