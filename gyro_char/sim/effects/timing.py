"""
Timing effects: ``time_delay`` and ``timestamp_jitter`` (stamps differ from sample instants).

The baseline's sampling jitter moves the *sample instants* (values and stamps agree); these
effects move only the *stamps*, which is what a transport latency or a host-side stamp does.
"""
from gyro_char.errors import InputError
from gyro_char.sim.chain import JITTER_CLIP
from gyro_char.sim.effects.base import Effect, register
import numpy as np


@register
class TimeDelay(Effect):
    """IMU stamps late (or early) by a constant relative to the encoder's."""

    name = 'time_delay'
    summary = 'constant latency between the gyro and the encoder stamps'
    physics = ('Each IMU sample is stamped delay_s after the instant it was taken (transport '
               'and driver latency; negative: the encoder lags instead). Any real value, not '
               'a whole number of samples. On a swing run the gyro angle lags the encoder '
               'angle: residual -delay * phi_dot, in quadrature with the angle, amplitude '
               'A (2 pi / T) delay.')
    PARAMS = {'delay_s': (1.0e-3, 's', 'stamp minus sample instant of the IMU samples')}

    def stamps(self, ctx, t):
        return t + self.delay_s


@register
class TimestampJitter(Effect):
    """White Gaussian error on the stamps beyond the baseline sampling jitter."""

    name = 'timestamp_jitter'
    summary = 'random stamp errors (host-side stamping) on IMU and/or encoder'
    physics = ('stamp = sample instant + e, e white Gaussian (sigma_s), clipped at 0.45 of '
               'the sample interval so that stamps stay increasing. The values are unchanged, '
               'so a stream read at its stamps is off by phi_dot * e: on a swing run an extra '
               'angle noise of variance (A 2 pi / T)^2 sigma^2 / 2.')
    PARAMS = {'sigma_s': (50.0e-6, 's', 'standard deviation of the stamp error'),
              'stream': (2.0, '-', '0: IMU, 1: encoder, 2: both')}

    def check(self):
        if self.sigma_s < 0 or self.stream not in (0.0, 1.0, 2.0):
            raise InputError('timestamp_jitter: sigma_s >= 0 and stream in 0, 1, 2')

    def _jitter(self, ctx, t, which):
        if self.stream not in (which, 2.0) or not self.sigma_s or t.size < 2:
            return t
        lim = JITTER_CLIP * float(np.median(np.diff(t)))
        e = self.sigma_s * ctx.rng(f'effect:{self.name}:{self.index}:{which}'
                                   ).standard_normal(t.size)
        return t + np.clip(e, -lim, lim)

    def stamps(self, ctx, t):
        return self._jitter(ctx, t, 0.0)

    def encoder_stamps(self, ctx, t):
        return self._jitter(ctx, t, 1.0)
