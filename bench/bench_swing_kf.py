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
that filterpy and batch agree on the subset. Both are also compared with ``exact_posterior``, the
same posterior in rational arithmetic, on the first ``--exact`` samples: on a record shorter than
a swing period (``--duration 60 --subset 2000``: 2 s of a 5 s period) filterpy's float64
covariance form is off by about one posterior sigma while the batch SRIF matches the exact
posterior to 1e-10 sigma; see ``exact_posterior``.
"""
import argparse
from fractions import Fraction

from gyro_char.live.swing_online import SwingOnline
from gyro_char.sim.simulator import simulate_swing
from gyro_char.swing import batch as swing_batch
from gyro_char.swing.align import integrate
from gyro_char.swing.filter import estimate_swing, SwingKalman
from gyro_char.swing.model import GYRO_ANCHOR_S, PRIOR_SD, regressor, SwingNoise, transition
import numpy as np
from timing import best_of


def _solve(a, b):
    """Gauss-Jordan elimination on Fractions: (A^-1, A^-1 b)."""
    n = len(b)
    m = [a[i][:] + [Fraction(int(i == j)) for j in range(n)] + [b[i]] for i in range(n)]
    for c in range(n):
        p = next(r for r in range(c, n) if m[r][c] != 0)
        m[c], m[p] = m[p], m[c]
        m[c] = [v / m[c][c] for v in m[c]]
        for r in range(n):
            if r != c and m[r][c] != 0:
                f = m[r][c]
                m[r] = [u - f * v for u, v in zip(m[r], m[c])]
    return [row[n:2 * n] for row in m], [row[2 * n] for row in m]


def exact_posterior(kind: str, tau: np.ndarray, z: np.ndarray, period_s: float, noise: float):
    """
    Return the filter's X and P at the last sample, computed in exact rational arithmetic.

    The measurement rows of ``swing_batch``'s module doc (encoder samples; gyro anchor, first
    sample and increments) are built from the float64 regressors, data and weights (the weights
    1 / (noise^2 dt) rounded to float64: a 1e-16 relative change of the model) and the normal
    equations with the prior are accumulated and solved with ``fractions.Fraction``: the only
    rounding after that is the final conversion. Neither float64 filter's conditioning enters,
    which is what a record shorter than one period needs: there the posterior variance is ~1e-10
    of the prior's and the five states are correlated to 0.998, so the covariance-form update
    (filterpy) loses most of its 16 digits in the least-determined direction. About 0.2 ms per
    sample.
    """
    g = [[Fraction(v) for v in regressor(t, period_s)] for t in tau]
    zf = [Fraction(v) for v in z]
    if kind == swing_batch.ENCODER:
        w = Fraction(1.0 / noise ** 2)
        rows = [(gi, zi, w) for gi, zi in zip(g, zf)]
    else:
        dt = np.diff(tau, prepend=tau[0] - GYRO_ANCHOR_S)  # the anchor's variance N^2 x 1 s
        w = [Fraction(v) for v in 1.0 / (noise ** 2 * dt)]
        rows = [(g[i], zf[i], w[i]) for i in range(min(2, len(g)))]
        rows += [([u - v for u, v in zip(g[i], g[i - 1])], zf[i] - zf[i - 1], w[i])
                 for i in range(2, len(g))]
    a = [[Fraction(0)] * 5 for _ in range(5)]
    b = [Fraction(0)] * 5
    for i in range(5):
        a[i][i] = 1 / Fraction(PRIOR_SD[i]) ** 2
    for u, y, wi in rows:
        wu = [wi * v for v in u]
        for i in range(5):
            b[i] += wu[i] * y
            for j in range(i, 5):
                a[i][j] += wu[i] * u[j]
    for i in range(5):
        for j in range(i):
            a[i][j] = a[j][i]
    p_theta, theta = _solve(a, b)
    m = [[Fraction(v) for v in row] for row in transition(tau[-1], period_s)]
    offset = [Fraction(0)] * 5
    if kind == swing_batch.GYRO and len(tau) >= 2:  # X3 carries the random walk: swing_batch
        m[2] = [u - v for u, v in zip(m[2], g[-1])]
        offset[2] = zf[-1]
    x = [sum(m[i][k] * theta[k] for k in range(5)) + offset[i] for i in range(5)]
    mp = [[sum(m[i][k] * p_theta[k][j] for k in range(5)) for j in range(5)] for i in range(5)]
    p = [[sum(mp[i][k] * m[j][k] for k in range(5)) for j in range(5)] for i in range(5)]
    return np.array([float(v) for v in x]), np.array([[float(v) for v in r] for r in p])


def distance(x, p, x_ref, p_ref) -> float:
    """Largest state or covariance difference, in posterior sigma of the reference."""
    sd = np.sqrt(np.diag(p_ref))
    return float(max(np.max(np.abs(x - x_ref) / sd),
                     np.max(np.abs(p - p_ref) / np.outer(sd, sd))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--duration', type=float, default=900.0)
    ap.add_argument('--subset', type=int, default=20000)
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--full', action='store_true', help='run filterpy over the whole record')
    ap.add_argument('--exact', type=int, default=2000,
                    help='samples per stream compared with the exact-arithmetic posterior')
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
    worst = max(distance(a.x, a.P, b.x, b.P) for a, b in ((fp_e, b_e), (fp_g, b_g)))

    # Both against the exact-arithmetic posterior on the first --exact samples of each stream.
    k = min(args.exact, m, me)
    off = {'batch': 0.0, 'filterpy': 0.0}
    for kind, tau, z, sigma in (('encoder', al.tau_encoder[:k], al.angle_encoder[:k],
                                 noise.encoder_sigma),
                                ('gyro', al.tau_gyro[:k], z_g[:k], noise.gyro_arw)):
        x_ex, p_ex = exact_posterior(kind, tau, z, period, sigma)
        b, _ = swing_batch.run(kind, tau, z, period, sigma)
        f = SwingKalman(kind, period, sigma).run(tau, z).result()
        off['batch'] = max(off['batch'], distance(b.x, b.P, x_ex, p_ex))
        off['filterpy'] = max(off['filterpy'], distance(f.x, f.P, x_ex, p_ex))

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
    print(f'vs the exact-arithmetic posterior:  batch {off["batch"]:.1e}, filterpy '
          f'{off["filterpy"]:.1e} posterior sigma (first {k} samples of each stream; '
          f'{al.tau_encoder[k - 1]:.3g} s of a {period:g} s period)')
    print(f'online, 1 sample per call:         {100 * t_on / span:.1f} % of a core for '
          '1 kHz IMU + 1 kHz encoder   [target < 25 %]')
    e = res.estimates
    tr = run.truth['swing']
    print(f'estimates vs truth: scale-factor error {100 * e.scale_factor_error.value:+.4f} % '
          f'(truth {100 * tr["scale_factor_error"]:+.4f} %)')


if __name__ == '__main__':
    main()
