"""
Motion-dependent effects: scale-factor shape, cross-axis coupling, g-sensitivity, encoder error.

These act on the true inputs (``ctx.true_rate``, ``ctx.specific_force``, the stand angle) and
so show mostly on swing runs. They leave the baseline truth unchanged: their signatures are
harmonics or phase-locked residuals rather than a change of the reported coefficients.
"""
from gyro_char.errors import InputError
from gyro_char.sim.chain import G0
from gyro_char.sim.config import AXES
from gyro_char.sim.effects.base import (describe_without, Effect, one_pole, register, table,
                                        table_params)
import numpy as np
from scipy import signal

# Orders of the tabulated forms (Chebyshev series over a table's range): odd in the rate for
# the nonlinearity (order 1 is the scale factor itself), even for the asymmetry (order 0 is a
# bias), odd in the tilt for the g-sensitivity (order 1 is gy's shape).
ODD_ORDERS = (3, 5, 7, 9, 11, 13, 15)
EVEN_ORDERS = (2, 4, 6, 8, 10, 12, 14, 16)
TILT_ORDERS = (1, 3, 5, 7, 9, 11, 13, 15)


@register
class ScaleFactorNonlinearity(Effect):
    """Quadratic, cubic and fifth-order terms of the rate response; the cubic with memory."""

    name = 'scale_factor_nonlinearity'
    summary = 'rate response with quadratic / cubic / fifth-order terms'
    physics = ('omega_out += k2 omega^2 + k3 omega^3 + k5 omega^5 on every gyro axis (omega: '
               'true rate along that axis). For omega = W cos(wt): k2 gives a DC offset '
               'k2 W^2 / 2 and a 2f line k2 W^2 / 2; k3 gives 3 k3 W^3 / 4 at f (an apparent '
               'scale-factor error 3 k3 W^2 / 4) and a 3f line k3 W^3 / 4; k5 gives '
               '10 k5 W^5 / 16 at f, 5 k5 W^5 / 16 at 3f and k5 W^5 / 16 at 5f. A saturation '
               'or a range switch bends the response beyond a cube: at one peak rate k5 looks '
               'like k3, at two peak rates their lines grow as W^5 and W^3. tau_s > 0 gives '
               'the cubic a memory, as a torquer heated by its own current: the scale factor '
               'follows the power (omega^2) through a thermal lag, omega k3 LP(omega^2); part '
               'of the 3f line and of the change at f then turns into quadrature. '
               'lock_in > 0: the response collapses near zero rate, as a ring laser locks in '
               '(IEEE 528 dead band / lock-in rate; the averaged Adler law): omega_out = '
               'sign(omega) sqrt(omega^2 - lock_in^2) outside the band, 0 inside; odd lines '
               'that a cubic cannot follow, made at the turning points. table_rads > 0: a '
               'tabulated odd deviation of any shape over +-table_rads, omega_out += sum_n '
               'c_n T_n(omega / table_rads), n = 3, 5, ..., 15 (a companding law, a look-up '
               'table residual, a DAC staircase, a soft saturation): on a swing of peak '
               'table_rads, c_n is the rate line at n f. on_output 1: the table bends the '
               'sensed value, noise included (the law of a read-out), not the true rate: its '
               'slope where the rate is scales the noise along the swing (first order in the '
               'noise). range_rads > 0: the output saturates at +range_rads and at '
               '-range_low_rads (0: -range_rads), noise included (a full-scale limit; an '
               'offset converter clips one side first); windup_s > 0: the rate the output '
               'could not follow is owed and paid back once in range (a rebalance loop whose '
               'integrator winds up), the debt forgotten with time constant windup_s '
               '(``saturate``). sf_noise > 0: a white scale-factor noise, omega_out += omega '
               's(t), s of density sf_noise (the gain of a noisy reference or drive); '
               'gate_noise > 0: white noise of that density added wherever |omega| > '
               'noise_gate_rads, and gate_gain: omega_out += gate_gain omega there (a range '
               'switched in above a rate, with its own noise and gain) (``rate_noise``).')
    PARAMS = {'k2': (1.0e-3, '1/(rad/s)', 'quadratic coefficient'),
              'k3': (0.0, '1/(rad/s)^2', 'cubic coefficient'),
              'k5': (0.0, '1/(rad/s)^4', 'fifth-order coefficient'),
              'tau_s': (0.0, 's', 'thermal lag of the cubic term (0: memoryless)'),
              'lock_in': (0.0, 'rad/s', 'lock-in rate: no output below it (0: none)'),
              'table_rads': (0.0, 'rad/s', 'range of the tabulated deviation (0: none)'),
              'on_output': (0.0, '1', '1: the table acts on the sensed value, noise included'),
              'range_rads': (0.0, 'rad/s', 'full-scale limit of the output (0: none)'),
              'range_low_rads': (0.0, 'rad/s', 'negative-side limit (0: range_rads)'),
              'windup_s': (0.0, 's', 'memory of the rate owed while saturated (0: none)'),
              'sf_noise': (0.0, '1/sqrt(Hz)', 'white scale-factor noise density (0: none)'),
              'gate_noise': (0.0, 'rad/s/sqrt(Hz)', 'noise density above the gate (0: none)'),
              'noise_gate_rads': (0.0, 'rad/s', 'rate above which gate_noise is added'),
              'gate_gain': (0.0, '1', 'scale-factor change above noise_gate_rads'),
              **table_params('c', ODD_ORDERS, 'rad/s', 'tabulated deviation')}

    def check(self):
        if min(self.tau_s, self.lock_in, self.table_rads, self.range_rads,
               self.range_low_rads, self.windup_s, self.sf_noise, self.gate_noise,
               self.noise_gate_rads) < 0:
            raise InputError('scale_factor_nonlinearity: tau_s, lock_in, table_rads, '
                             'range_rads, range_low_rads, windup_s, sf_noise, gate_noise and '
                             'noise_gate_rads must be >= 0')

    def describe(self):
        return describe_without(self, 'tau_s', 'lock_in', 'table_rads', 'on_output',
                                'range_rads', 'range_low_rads', 'windup_s', 'sf_noise',
                                'gate_noise', 'noise_gate_rads', 'gate_gain',
                                *(f'c{n}' for n in ODD_ORDERS))

    def sensor(self, ctx, gyro, accel):
        w = ctx.true_rate
        w2 = w * w
        sensed = gyro
        heat = one_pole(w2, self.tau_s, ctx.dt_internal, start='periodic')
        gyro = gyro + w2 * (self.k2 + self.k5 * w * w2) + self.k3 * w * heat
        if self.lock_in > 0.0:
            gyro = gyro + np.sign(w) * np.sqrt(np.maximum(w2 - self.lock_in ** 2, 0.0)) - w
        gyro = gyro + table(self, 'c', ODD_ORDERS, w, self.table_rads,
                            sensed=sensed if self.on_output else None)
        if self.gate_gain:
            gyro = gyro + self.gate_gain * w * (np.abs(w) > self.noise_gate_rads)
        gyro = gyro + rate_noise(self, ctx, rate_noise_level(self.params, w))
        if self.range_rads > 0.0:
            low = self.range_low_rads or self.range_rads
            gyro = np.vstack([saturate(row, (-low, self.range_rads), self.windup_s,
                                       ctx.dt_internal) for row in gyro])
        return gyro, accel


def saturate(v: np.ndarray, limits: tuple, windup_s: float, dt: float) -> np.ndarray:
    """
    Output of a loop that follows ``v`` within ``limits`` (low, high) and owes what it could not.

    u_k = clip(v_k + a D_(k-1) / dt, low, high), D_k = a D_(k-1) + (v_k - u_k) dt, with
    a = exp(-dt / windup_s): in range and out of debt u = v; saturated, the debt grows and is
    paid back at the full range once v returns (``windup_s`` 0: a plain clip; long: the angle
    is kept whole, a dead-beat loop). Sample by sample only where a saturation ends; along
    the limit the debt is one ``lfilter`` run, ended where the loop comes back in range.
    """
    low, high = limits
    out = np.clip(v, low, high)
    if windup_s <= 0.0 or not np.any(out != v):
        return out
    out = v.copy()
    a = float(np.exp(-dt / windup_s))
    over = np.flatnonzero((v > high) | (v < low))
    n, k, debt = v.size, 0, 0.0
    while k < n:
        if debt == 0.0:   # the next sample out of range starts a saturation
            j = int(np.searchsorted(over, k))
            if j == over.size:
                break
            k = int(over[j])
        x = v[k] + a * debt / dt
        if low <= x <= high:   # back in range: the rest of the debt is paid at once
            out[k], debt, k = x, 0.0, k + 1
            continue
        side, sgn = (high, 1.0) if x > high else (low, -1.0)
        span = 256
        while True:   # debt along the limit: D_j = a D_(j-1) + (v_j - side) dt
            seg = v[k:k + span]
            owed = signal.lfilter([1.0], [1.0, -a], (seg - side) * dt, zi=[a * debt])[0]
            prev = np.r_[debt, owed[:-1]]
            past = np.flatnonzero((seg + a * prev / dt - side) * sgn <= 0.0)
            stop = int(past[0]) if past.size else seg.size
            out[k:k + stop] = side
            debt = float(prev[stop]) if past.size else float(owed[-1])
            k, span = k + stop, 2 * span
            if past.size or k >= n:
                break
    return out


@register
class ScaleFactorAsymmetry(Effect):
    """Different scale factors for positive and negative rates, switched at once or relaxing."""

    name = 'scale_factor_asymmetry'
    summary = 'scale factor (1 + a) for positive, (1 - a) for negative rates'
    physics = ('omega_out += a |omega|. For omega = W cos(wt): a DC offset 2 a W / pi and '
               'even harmonics (2f: 4 a W / (3 pi)); no change at f. tau_s > 0: the gain '
               'relaxes to its new side after each reversal (a direction memory, as the '
               'after-effect of a torquer magnet), omega_out += a omega LP(sign omega): the '
               '2f line turns partly into quadrature and falls; still no line at f. '
               'table_rads > 0: a tabulated even difference of any shape over +-table_rads, '
               'omega_out += sum_n c_n (T_n(omega / table_rads) - T_n(0)), n = 2, 4, ..., 16 '
               '(a one-sided gain, a diode, a driver half that saturates first): on a swing '
               'of peak table_rads, c_n is the rate line at n f; on_output 1: it bends the '
               'sensed value, noise included. sf_noise > 0: a white scale-factor noise on '
               'negative rates only, omega_out += min(omega, 0) s(t), s of density sf_noise '
               '(one driver half noisier than the other) (``rate_noise``).')
    PARAMS = {'a': (1.0e-3, '1', 'half the difference of the two scale factors'),
              'tau_s': (0.0, 's', 'relaxation time of the switch after a reversal (0: at once)'),
              'table_rads': (0.0, 'rad/s', 'range of the tabulated difference (0: none)'),
              'on_output': (0.0, '1', '1: the table acts on the sensed value, noise included'),
              'sf_noise': (0.0, '1/sqrt(Hz)', 'scale-factor noise density on negative rates'),
              **table_params('c', EVEN_ORDERS, 'rad/s', 'tabulated difference')}

    def check(self):
        if min(self.tau_s, self.table_rads, self.sf_noise) < 0:
            raise InputError('scale_factor_asymmetry: tau_s, table_rads and sf_noise must be '
                             '>= 0')

    def describe(self):
        return describe_without(self, 'tau_s', 'table_rads', 'on_output', 'sf_noise',
                                *(f'c{n}' for n in EVEN_ORDERS))

    def sensor(self, ctx, gyro, accel):
        w = ctx.true_rate   # w sign(w) is |w| exactly: tau_s 0 is the switch at once
        side = one_pole(np.sign(w), self.tau_s, ctx.dt_internal, start='periodic')
        extra = table(self, 'c', EVEN_ORDERS, w, self.table_rads, even=True,
                      sensed=gyro if self.on_output else None)
        noise = rate_noise(self, ctx, rate_noise_level(self.params, w, one_sided=True))
        return gyro + self.a * w * side + extra + noise, accel


def rate_noise_level(params: dict, w: np.ndarray, one_sided: bool = False):
    """
    Return the density (rad/s/sqrt(Hz)) of a rate-dependent white noise at rates ``w``.

    ``sf_noise`` |w| (a scale-factor noise; ``one_sided``: on negative rates only) plus
    ``gate_noise`` wherever |w| > ``noise_gate_rads``; None where both are off. The
    diagnosis reads the same function for the noise power a twin's N gives up.
    """
    sf, gate = float(params.get('sf_noise', 0.0)), float(params.get('gate_noise', 0.0))
    if not sf and not gate:
        return None
    level = sf * (np.maximum(-w, 0.0) if one_sided else np.abs(w))
    if gate:
        level = level + gate * (np.abs(w) > float(params.get('noise_gate_rads', 0.0)))
    return level


def rate_noise(effect: Effect, ctx, level) -> np.ndarray:
    """White rate noise of density ``level`` (per sample, per axis) at the internal rate."""
    if level is None:
        return 0.0
    return level / np.sqrt(ctx.dt_internal) * effect.rng(ctx).standard_normal(level.shape)


@register
class CrossAxis(Effect):
    """Non-orthogonality: each gyro axis senses a fraction of the other axes' rates."""

    name = 'cross_axis'
    summary = 'misalignment coupling of rate into the other gyro axes'
    physics = ('omega_out_i += sum_j m_ij omega_j (j != i), m_ij small angles in rad (datasheet '
               'axis-to-axis misalignment). On a swing run the off-axis gyros show the swing '
               'rate scaled by m_ij, in phase with the rate.')
    PARAMS = {f'{a}{b}': (2.0e-3 if (a, b) in (('y', 'x'), ('z', 'x')) else 0.0, 'rad',
                          f'sensitivity of gyro {a} to rate about {b}')
              for a in AXES for b in AXES if a != b}

    def sensor(self, ctx, gyro, accel):
        gyro = gyro.copy()
        for i, a in enumerate(AXES):
            for j, b in enumerate(AXES):
                if i != j and self.params[a + b]:
                    gyro[i] += self.params[a + b] * ctx.true_rate[j]
        return gyro, accel


@register
class GSensitivity(Effect):
    """Gyro bias proportional to the specific force (linear-acceleration effect)."""

    name = 'g_sensitivity'
    summary = 'gyro bias proportional to specific force'
    physics = ('omega_out_i += gx f_x + gy f_y + gz f_z on every gyro axis (f: specific force '
               'in the sensor frame, m/s^2). Datasheet: 0.05 deg/s/g for the ADIS16405, '
               '~9e-5 rad/s per m/s^2. On a stand tilting about x, f_y = g sin(phi): a '
               'residual in phase with the angle (like a delay would be with the rate). '
               'table_mps2 > 0: a tabulated bias of any odd shape in the specific force of '
               'the tilt across the swing axis, f_t = g sin(phi): += sum_n t_n T_n(f_t / '
               'table_mps2), n = 1, 3, ..., 15 (a softening flexure, a coarse compensation '
               'table, a wavy suspension).')
    PARAMS = {'gx': (0.0, 'rad/s/(m/s^2)', 'sensitivity to f_x'),
              'gy': (9.0e-5, 'rad/s/(m/s^2)', 'sensitivity to f_y'),
              'gz': (0.0, 'rad/s/(m/s^2)', 'sensitivity to f_z'),
              'table_mps2': (0.0, 'm/s^2', 'range of the tabulated bias (0: none)'),
              **table_params('t', TILT_ORDERS, 'rad/s', 'tabulated bias')}

    def check(self):
        if self.table_mps2 < 0:
            raise InputError('g_sensitivity: table_mps2 must be >= 0')

    def describe(self):
        return describe_without(self, 'table_mps2', *(f't{n}' for n in TILT_ORDERS))

    def sensor(self, ctx, gyro, accel):
        f = ctx.specific_force
        extra = self.gx * f[0] + self.gy * f[1] + self.gz * f[2]
        if self.table_mps2 > 0.0 and ctx.angle is not None:
            extra = extra + table(self, 't', TILT_ORDERS, G0 * np.sin(ctx.angle),
                                  self.table_mps2)
        return gyro + extra[None, :], accel


@register
class EncoderCyclicError(Effect):
    """Sine-cosine interpolation error of the encoder, periodic in the angle."""

    name = 'encoder_cyclic_error'
    summary = 'encoder error locked to angle (sine-cosine interpolation error)'
    physics = ('A sine-cosine encoder with L lines per revolution interpolates within each '
               'signal period 2 pi / L; amplitude/offset/phase imbalance of the two tracks '
               'gives errors at 1x and 2x the signal frequency, distortion of the tracks '
               '(harmonics in the sine and cosine, clipped crests) at 3x and 4x: phi_read = '
               'phi + sum_k a_k sin(k L phi + p_k), k = 1..4. On a swing the error is a chirp '
               'following the rate (frequency k L |phi_dot| / 2 pi). gate_rads > 0: the error '
               'is there only while the stand turns faster than gate_rads (an interpolator '
               'whose correction table is skipped above a speed, or a tracking loop that '
               'falls behind): a cyclic error in the fast part of each half-swing only.')
    PARAMS = {'lines': (2048.0, '1/rev', 'signal periods per revolution L'),
              'a1': (5.0e-6, 'rad', 'first-harmonic amplitude'),
              'a2': (2.0e-6, 'rad', 'second-harmonic amplitude'),
              'p1': (0.0, 'rad', 'first-harmonic phase'),
              'p2': (0.0, 'rad', 'second-harmonic phase'),
              'a3': (0.0, 'rad', 'third-harmonic amplitude'),
              'a4': (0.0, 'rad', 'fourth-harmonic amplitude'),
              'p3': (0.0, 'rad', 'third-harmonic phase'),
              'p4': (0.0, 'rad', 'fourth-harmonic phase'),
              'gate_rads': (0.0, 'rad/s', 'the error only above this stand speed (0: always)')}

    def check(self):
        if self.lines <= 0:
            raise InputError('encoder_cyclic_error: lines must be > 0')
        if self.gate_rads < 0:
            raise InputError('encoder_cyclic_error: gate_rads must be >= 0')

    def describe(self):
        return describe_without(self, 'a3', 'a4', 'p3', 'p4', 'gate_rads')

    def encoder_angle(self, ctx, t, angle):
        x = self.lines * angle
        on = 1.0
        if self.gate_rads > 0.0:
            if ctx.stand_rate is None:
                raise InputError('encoder_cyclic_error: gate_rads needs a swing run')
            on = np.abs(ctx.stand_rate(t)) > self.gate_rads
        out = angle
        for k in (1, 2, 3, 4):
            a = getattr(self, f'a{k}')
            if a != 0.0:
                out = out + on * a * np.sin(k * x + getattr(self, f'p{k}'))
        return out
