"""
Read-out errors of a rate-integrating output: angle quantization, whole or once a frame.

The angle is accumulated and read out in whole steps; the rate is their difference. The
quantization error maps exactly onto the IEEE 952 Q term, added in quadrature to the truth.
"""
from gyro_char.errors import InputError
from gyro_char.sim.effects.base import add_truth_term, axis_param, axis_rows, Effect, register
import numpy as np


@register
class AngleQuantization(Effect):
    """Quantization of the integrated angle (a rate-integrating output): the IEEE Q term."""

    name = 'quantization'
    summary = 'angle (increment) quantization beyond dH: Allan slope -1, sigma^2 = 3 Q^2 / tau^2'
    physics = ('The sensor accumulates angle and outputs whole counts of step_rad per sample: '
               'rate_out = (C_k - C_(k-1)) step / dt with C_k = [theta_k / step]. The angle '
               'error is uniform and white when the per-sample angle increments spread over at '
               'least ~step/2 (rate noise N sqrt(dt) >= step / 2; otherwise it is correlated '
               'and the -1 slope is not formed), so the rate gets the IEEE quantization term '
               'Q = step / sqrt(12). dither = 1: a fresh uniform dither of one step is added '
               'to the angle before each read-out, C_k = [theta_k / step + u_k] (body-dithered '
               'ring-laser gyros, dithered counters): the angle error is then zero-mean and '
               'white whatever the rate noise, of mean variance step^2 / 6, so Q = step / '
               'sqrt(6). frame = M > 1: the whole count is read only every M samples (a coarse '
               'absolute counter re-anchored once a frame, exact increments in between: '
               'keyframe-and-delta angle telemetry): the angle error is held for the frame, '
               'the rate error falls on one sample in M, with nulls every 1 / (M dt) (its PSD '
               '8 var sin^2(pi f M dt) / (M dt) where the error is white from frame to frame; '
               'framed_error_psd); Q is unchanged at tau >= M dt.')
    PARAMS = {'step_rad': (1.0e-5, 'rad', 'angle quantum'),
              'axis': axis_param(),
              'dither': (0.0, '-', '1: one-step uniform dither before each read-out'),
              'frame': (1.0, 'samples', 'samples between absolute read-outs (1: every one)')}

    def check(self):
        axis_rows(self)
        if self.step_rad <= 0:
            raise InputError('quantization: step_rad must be > 0')
        if self.dither not in (0.0, 1.0):
            raise InputError('quantization: dither must be 0 or 1')
        if self.frame < 1.0 or self.frame != int(self.frame):
            raise InputError('quantization: frame must be a whole number >= 1')

    def describe(self):
        out = Effect.describe(self)
        if self.frame == 1.0:
            del out['params']['frame']
        return out

    def output(self, ctx, gyro, accel):
        gyro = gyro.copy()
        rng = self.rng(ctx) if self.dither or self.frame > 1 else None
        m = int(self.frame)
        for r in axis_rows(self):
            theta = np.cumsum(gyro[r]) * ctx.dt / self.step_rad
            if m == 1:
                if self.dither:
                    theta += rng.uniform(0.0, 1.0, theta.size)
                gyro[r] = np.diff(np.floor(theta), prepend=0.0) * (self.step_rad / ctx.dt)
                continue
            # Read-outs at one phase of the frame; the error of each held until the next.
            keys = np.arange(int(rng.integers(0, m)), theta.size, m)
            read = theta[keys] + (rng.uniform(0.0, 1.0, keys.size) if self.dither else 0.0)
            err = np.zeros(theta.size)
            err[keys] = np.floor(read) - theta[keys]
            last = np.zeros(theta.size, dtype=np.int64)
            last[keys] = keys
            held = np.where(np.arange(theta.size) >= keys[0],
                            err[np.maximum.accumulate(last)], 0.0) if keys.size else err
            gyro[r] += np.diff(held, prepend=0.0) * (self.step_rad / ctx.dt)
        return gyro, accel

    def update_truth(self, ctx, truth):
        q = self.step_rad / np.sqrt(6.0 if self.dither else 12.0)
        add_truth_term(truth, axis_rows(self), 'Q', q)


def framed_error_psd(f, step: float, frame: int, dither: float, n_white: float, bias: float,
                     dt: float, harmonics: int = 64) -> np.ndarray:
    """
    Two-sided PSD (per Hz) of the rate error of an angle read once a frame, at ``f``.

    The error E_j of read-out j is differenced once a frame (period T = frame dt): S(f) =
    4 sin^2(pi f T) S_E(2 pi f T) / T. Dithered, E is white of variance step^2 / 6. Plain,
    E = step ([theta / step] - theta / step) of an angle that walks (white rate noise
    ``n_white``) and drifts (``bias``) between read-outs: its Fourier series gives the exact
    autocovariance sum_h step^2 / (2 pi^2 h^2) rho_h^|J| cos(phi_h J), rho_h =
    exp(-2 pi^2 h^2 n_white^2 T / step^2), phi_h = 2 pi h bias T / step, whose spectrum is a
    sum of damped-cosine terms (white once the angle moves a step a frame; narrow at the
    nulls when it moves much less). Harmonics beyond ``harmonics`` are taken as white.
    """
    f = np.asarray(f, dtype=np.float64)
    period = frame * dt
    om = 2.0 * np.pi * f * period
    if dither:
        s_e = np.full_like(f, step * step / 6.0)
    else:
        h = np.arange(1, harmonics + 1, dtype=np.float64)
        amp = step * step / (2.0 * np.pi ** 2 * h * h)
        rho = np.exp(-2.0 * np.pi ** 2 * h * h * n_white ** 2 * period / step ** 2)
        phi = 2.0 * np.pi * h * bias * period / step
        s_e = np.full_like(f, step * step / 12.0 - float(np.sum(amp)))
        for a, r, ph in zip(amp, rho, phi):
            if r < 1e-9:
                s_e += a
                continue
            for x in (om - ph, om + ph):
                s_e += 0.5 * a * (1.0 - r * r) / (1.0 - 2.0 * r * np.cos(x) + r * r)
    return 4.0 * np.sin(0.5 * om) ** 2 * s_e / period
