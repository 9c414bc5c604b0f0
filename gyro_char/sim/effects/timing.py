"""
Timing effects: stamps that differ from sample instants, samples repeated under new stamps.

``time_delay`` and ``timestamp_jitter`` move the stamps; ``stale_samples`` repeats a sample.

The baseline's sampling jitter moves the *sample instants* (values and stamps agree); these
effects move only the *stamps*, which is what a transport latency or a host-side stamp does.
``time_delay`` may put part of its latency inside the gyro instead (``lag_s``: a one-pole
low-pass on the rate values, which also colours the noise); ``timestamp_jitter`` may be
correlated in time (``tau_s``: a first-order Gauss-Markov stamp error, or with ``order`` 2 a
smooth second-order one: a clock offset slewed by a time-sync servo; ``freq_hz``: a resonant
one, the jitter peaking of an underdamped clock servo).
"""
from gyro_char.errors import InputError
from gyro_char.sim.chain import JITTER_CLIP
from gyro_char.sim.effects.base import (describe_without, Effect, markov, one_pole, register,
                                        second_order_gm, table, table_params)
from gyro_char.sim.effects.vibration import resonant_noise
import numpy as np

SPEED_ORDERS = (2, 4, 6, 8, 10, 12, 14)   # orders of the speed-dependent latency


@register
class TimeDelay(Effect):
    """IMU late (or early) by a constant relative to the encoder: stamp shift and/or gyro lag."""

    name = 'time_delay'
    summary = 'constant latency between the gyro and the encoder stamps (optionally a gyro lag)'
    physics = ('Each IMU sample is stamped delay_s after the instant it was taken (transport '
               'and driver latency; negative: the encoder lags instead). Any real value, not '
               'a whole number of samples. On a swing run the gyro angle lags the encoder '
               'angle: residual -delay * phi_dot, in quadrature with the angle, amplitude '
               'A (2 pi / T) delay. With lag_s > 0, lag_s of the latency is a first-order '
               'low-pass inside the gyro (time constant lag_s, backward-Euler form whose '
               'low-frequency delay is lag_s) on every gyro axis, motion and noise alike '
               '(it attenuates and colours the noise above 1 / (2 pi lag_s)); the stamps '
               'then carry the rest, delay_s - lag_s. lag_s = delay_s: a pure gyro filter. '
               'table_rads > 0: the stamp latency also depends on the speed, + sum_n d_n '
               '(T_n(omega / table_rads) - T_n(0)), n = 2, 4, ..., 14 (a driver whose work '
               'grows with the rate, a smoother that adapts to the motion): an even function '
               'of the true rate omega when the sample was taken. '
               'stall_gain > 0: the stamps also carry stall_gain times a host latency trace '
               'given to the run (``simulate_swing(stamp_latency=...)``, one value a sample, '
               's): a host that stamps each sample when it reads it and now and then stalls, '
               "its backlog stamped late in a burst (the trace measured off a record's own "
               'stamps; 1: the samples were taken on time and only stamped late).')
    PARAMS = {'delay_s': (1.0e-3, 's', 'total latency: stamp shift plus the lag'),
              'lag_s': (0.0, 's', 'part of delay_s that is a one-pole gyro lag (>= 0)'),
              'table_rads': (0.0, 'rad/s', 'range of the speed-dependent latency (0: none)'),
              **table_params('d', SPEED_ORDERS, 's', 'speed-dependent latency'),
              'stall_gain': (0.0, '1', "share of the run's stamp-latency trace in the stamps")}

    def check(self):
        if self.lag_s < 0 or self.table_rads < 0 or self.stall_gain < 0:
            raise InputError('time_delay: lag_s, table_rads and stall_gain must be >= 0')

    def describe(self):
        return describe_without(self, 'lag_s', 'table_rads', 'stall_gain',
                                *(f'd{n}' for n in SPEED_ORDERS))

    def output(self, ctx, gyro, accel):
        return one_pole(gyro, self.lag_s, ctx.dt), accel

    def stamps(self, ctx, t):
        late = t + (self.delay_s - self.lag_s)
        if self.table_rads > 0.0 and ctx.true_rate is not None:
            rate = np.interp(t, ctx.t, ctx.true_rate[ctx.axis])
            late = late + table(self, 'd', SPEED_ORDERS, rate, self.table_rads, even=True)
            # A latency falling faster than time passes would reorder the samples: a driver
            # still sends them in order, at least a tenth of an interval apart.
            late = increasing(late, 0.1 * ctx.dt)
        if self.stall_gain > 0.0:
            late = in_order(late + self.stall_gain * stall_trace(ctx, t.size), 0.1 * ctx.dt)
        return late


def in_order(s: np.ndarray, floor: float) -> np.ndarray:
    """
    Return stamps ``s`` sent in order: each at least ``floor`` after the one before it.

    A reader's stamps r_k = max(s_k, r_(k-1) + floor) (closed form: k floor plus the running
    maximum of s_j - j floor): a stamp held back catches up as soon as its own latency allows,
    where ``increasing`` carries every step it lengthens into all later stamps (its jitter's
    steps below the floor added 1.6 ms of latency over a 15-min run of a stall trace).
    """
    k = np.arange(s.size) * floor
    return k + np.maximum.accumulate(s - k)


def stall_trace(ctx, n: int) -> np.ndarray:
    """Return the run's stamp-latency trace over its ``n`` samples (zeros past its end)."""
    trace = ctx.extras.get('stamp_latency')
    if trace is None:
        raise InputError('time_delay: stall_gain needs a stamp-latency trace '
                         '(simulate_swing(stamp_latency=...))')
    out = np.zeros(n)
    trace = np.asarray(trace, dtype=np.float64)[:n]
    out[:trace.size] = trace
    return out


# A correlated stamp error whose steps stay under this share of the sample interval (sd) is
# slow: a clock offset wandering by milliseconds, not clipped in level (``increasing``).
SLOW = 0.1


def increasing(s: np.ndarray, floor: float) -> np.ndarray:
    """Return stamps ``s`` with every step at least ``floor`` (a step that would go back)."""
    d = np.diff(s)
    if np.all(d >= floor):
        return s
    return s[0] + np.concatenate([[0.0], np.cumsum(np.maximum(d, floor))])


@register
class TimestampJitter(Effect):
    """Gaussian error on the stamps beyond the baseline sampling jitter: white or correlated."""

    name = 'timestamp_jitter'
    summary = 'random stamp errors (host-side stamping) on IMU and/or encoder'
    physics = ('stamp = sample instant + e, e Gaussian (sigma_s), clipped at 0.45 of '
               'the sample interval so that stamps stay increasing. The values are unchanged, '
               'so a stream read at its stamps is off by phi_dot * e: on a swing run an extra '
               'angle noise of variance (A 2 pi / T)^2 sigma^2 / 2. tau_s = 0: e white; '
               'tau_s > 0: a stationary first-order Gauss-Markov process of correlation time '
               'tau_s (a slowly wandering stamp error: its angle error is coherent over '
               'tau_s and shows as lines in the encoder residual). A slow error (steps of '
               'sd at most 0.1 sample interval, e.g. a time-sync servo slewing the clock by '
               'milliseconds) is not clipped in level; its stamps are kept increasing. '
               'order = 2: the correlated error is second-order Gauss-Markov (the pole '
               'twice): a clock offset that a servo slews without steps, PSD ~ f^-4. '
               'freq_hz > 0 (tau_s and order then unused): the error is band-limited around '
               'freq_hz with quality q, the AR(2) resonance of ``resonance``: the jitter '
               'peaking of a clock disciplined by an underdamped servo (a PLL or a PTP '
               'loop tuned fast), flat below freq_hz, peaked at it, falling as f^-4 above.')
    PARAMS = {'sigma_s': (50.0e-6, 's', 'standard deviation of the stamp error'),
              'stream': (2.0, '-', '0: IMU, 1: encoder, 2: both'),
              'tau_s': (0.0, 's', 'correlation time of the stamp error (0: white)'),
              'order': (1.0, '-', 'with tau_s: 1 first-order Gauss-Markov, 2 smooth (second)'),
              'freq_hz': (0.0, 'Hz', 'centre of a resonant stamp error (0: none)'),
              'q': (2.0, '-', 'with freq_hz: quality factor of the resonance (>= 0.5)')}

    def check(self):
        if self.sigma_s < 0 or self.stream not in (0.0, 1.0, 2.0) or self.tau_s < 0 \
                or self.order not in (1.0, 2.0) or self.freq_hz < 0 or self.q < 0.5:
            raise InputError('timestamp_jitter: sigma_s >= 0, tau_s >= 0, stream in 0, 1, 2, '
                             'order 1 or 2, freq_hz >= 0 and q >= 0.5')

    def describe(self):
        out = describe_without(self, 'tau_s', 'freq_hz')
        if self.order == 1.0 or self.freq_hz:
            out['params'].pop('order', None)
        if not self.freq_hz:
            out['params'].pop('q', None)
        return out

    def _jitter(self, ctx, t, which):
        if self.stream not in (which, 2.0) or not self.sigma_s or t.size < 2:
            return t
        dt = float(np.median(np.diff(t)))
        lim = JITTER_CLIP * dt
        rng = ctx.rng(f'effect:{self.name}:{self.index}:{which}')
        if self.freq_hz:
            if self.freq_hz >= 0.5 / dt:
                raise InputError(f'timestamp_jitter: freq_hz {self.freq_hz:g} is at or above '
                                 f'the Nyquist frequency of the stream, {0.5 / dt:g} Hz')
            e = resonant_noise(rng, t.size, self.freq_hz, self.q, dt)
        else:
            e = rng.standard_normal(t.size)
            if self.tau_s:
                phi = float(np.exp(-float(t[-1] - t[0]) / (t.size - 1) / self.tau_s))
                e = (second_order_gm(phi, e, (e[0], rng.standard_normal()))
                     if self.order == 2.0 else markov(e, phi))
        e *= self.sigma_s
        if (self.tau_s or self.freq_hz) and float(np.std(np.diff(e))) <= SLOW * dt:
            return increasing(t + e, (1.0 - JITTER_CLIP) * dt)
        return t + np.clip(e, -lim, lim)

    def stamps(self, ctx, t):
        return self._jitter(ctx, t, 0.0)

    def encoder_stamps(self, ctx, t):
        return self._jitter(ctx, t, 1.0)


def hold_chain(p: float, run: float):
    """
    Return (a, c) of held samples in runs: P(hold | none before), P(hold | hold).

    Runs of mean length ``run`` (c = 1 - 1 / run) with a held share ``p`` (a / (1 - c + a)).
    """
    return p / (run * (1.0 - p)), 1.0 - 1.0 / run


@register
class StaleSamples(Effect):
    """The driver republishes the previous sample now and then: values held, stamps new."""

    name = 'stale_samples'
    summary = 'output samples that repeat the previous one (a driver reading a stale register)'
    physics = ('Each output sample (gyro and accelerometer together) is, with probability p, '
               'the previous sample repeated under a new stamp: a host loop that reads the '
               'sensor slightly faster than it updates, a DMA race. The sample it replaces is '
               'lost. Holds are independent (runs of several possible), or with isolated = 1 '
               'never two in a row (a read loop a little faster than the sensor), or in runs '
               'of mean length run (run > 0: a register frozen for several samples while the '
               'sensor is busy, the share of held samples still p). On white '
               'rate noise the lag-m correlation is p^|m| (independent) or p at lag 1 only '
               '(isolated), the variance kept: the PSD tilts up at low frequency and down at '
               'Nyquist. On a swing run the holds average to a delay of about p dt. With '
               'gate > 0 the holds are chosen by the data instead: a driver guarding against '
               'bus glitches keeps its last gyro output wherever the new one jumps by more '
               'than the gate, so the largest steps are held back (the share follows from '
               'the gate and the noise; the variance drops).')
    PARAMS = {'p': (0.05, '-', 'probability that a sample repeats the previous one'),
              'isolated': (0.0, '-', '1: never two holds in a row (p < 0.5), 0: independent'),
              'run': (0.0, 'samples', 'mean length of a run of holds (>= 1; 0: independent '
                                      'or isolated holds as set by isolated)'),
              'gate': (0.0, 'rad/s', 'glitch gate: each gyro axis republishes its last output '
                                     'wherever the new sample differs from it by more than '
                                     'this (p, isolated and run then unused); 0: off')}

    def check(self):
        if not self.gate >= 0.0:
            raise InputError('stale_samples: gate >= 0 (rad/s)')
        if self.gate:
            return
        if not 0.0 <= self.p < (0.5 if self.isolated else 1.0):
            raise InputError('stale_samples: p in [0, 1), below 0.5 with isolated = 1')
        if self.run and (self.run < 1.0 or self.p > self.run / (1.0 + self.run)):
            raise InputError('stale_samples: run >= 1 and p <= run / (1 + run)')

    def output(self, ctx, gyro, accel):
        if self.gate:
            return np.vstack([gated(row, self.gate) for row in gyro]), accel
        n = gyro.shape[1]
        rng = self.rng(ctx)
        if self.run:
            held = self._runs(n, rng)
        elif self.isolated:
            # The chain P(hold | none before) = p / (1 - p), P(hold | hold) = 0 (stationary
            # share p): in every run of candidates, holds alternate from its first sample.
            cand = rng.random(n) < self.p / (1.0 - self.p)
            cand[0] = False
            start = np.maximum.accumulate(np.where(cand, 0, np.arange(n)))
            held = cand & ((np.arange(n) - start) % 2 == 1)
        else:
            held = rng.random(n) < self.p
            held[0] = False
        src = np.maximum.accumulate(np.where(held, 0, np.arange(n)))
        return gyro[:, src], accel[:, src]

    def _runs(self, n: int, rng) -> np.ndarray:
        """Held flags of the Markov chain: fresh runs of mean 1 / a, held runs of mean run."""
        a, c = hold_chain(self.p, self.run)
        pairs = int(n * a / (1.0 - self.p) * 1.2) + 16     # enough fresh / held run pairs

        def draw():                                        # lengths >= 1
            hold = rng.geometric(1.0 - c, pairs) if c > 0.0 else np.ones(pairs, dtype=int)
            return np.column_stack([rng.geometric(min(a, 1.0), pairs), hold]).ravel()
        lengths = draw()
        while lengths.sum() < n:                           # rare: draw more pairs
            lengths = np.r_[lengths, draw()]
        flags = np.repeat(np.tile([False, True], lengths.size // 2), lengths)[:n]
        return flags


def gated(x: np.ndarray, gate: float) -> np.ndarray:
    """
    Return ``x`` through a glitch gate: the last output kept while a sample is beyond ``gate``.

    y_k = x_k if |x_k - y_(k-1)| <= gate, else y_(k-1). Only the samples after a step larger
    than the gate can start a hold, so the loop runs over the holds alone.
    """
    y = np.array(x, dtype=np.float64)
    starts = np.flatnonzero(np.abs(np.diff(y)) > gate) + 1
    k = 0
    for j in starts:
        if j < k:                       # inside a hold already handled
            continue
        ref, k = y[j - 1], j
        while k < y.size and abs(y[k] - ref) > gate:
            y[k] = ref
            k += 1
    return y
