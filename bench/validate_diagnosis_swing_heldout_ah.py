"""
Held-out swing set AH: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_ag.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-R and AE-AG, and the kinds of
departure differ from shape to shape:

- time_delay: a retrying radio link with an antenna null: the IMU on the arm sends each sample
  in its own packet over a 2.4 GHz link that retries a lost attempt in the next slot (slot s:
  airtime plus acknowledgement wait) and serves the packets in order, the host stamping each
  on delivery, the one-slot airtime calibrated out, the values untouched (``arq_stamps``); the
  loss per attempt is P_FLOOR = 3 % but rises to P_NULL = 50 % while the arm's antenna points
  its null at the receiver, a Gaussian in the tilt about PHI_NULL = 14 deg of sd NULL_SD = 3
  deg (``loss``): a latency of whole retry slots plus the wait behind earlier packets, random,
  heavy-tailed and set by the tilt, with memory where a burst of retries backs the queue up (at
  the weak and strong slots the null's load s / ((1 - P_NULL) dt) is 1.00 and 1.13: the
  backlog builds in the null and drains past it); swings of less than 8 deg never reach the
  null (the loss under 10 % there);
- g_sensitivity: a failover: the IMU's lock-step DSP fails over, hitless, to its backup at one
  moment of the run (a share uniform in FAILOVER = 0.45-0.55 of its span, drawn per run), and
  the backup's table lacks the user's g-compensation: exactly no g-sensitivity before, the raw
  g_y f_y (f_y = g sin(phi)) after (``failover_gate``): one change of regime in mid-run;
- scale_factor_nonlinearity: a peak-detecting drive AGC: the drive loop regulates the drive
  amplitude on a diode peak detector (instant attack, release RELEASE_S = 3 s) whose pick-off
  also carries the sense mode's Coriolis crosstalk, so the drive, and with it the gain, drops by
  k P, P_k = max(|w_k|, P_(k-1) exp(-dt / RELEASE_S)) the held peak of the true rate
  (``peak_envelope``; the read-out noise after it): out = x - k P w: a gain set by the
  largest recent rate, not the present one: held from each mid-swing peak and released through
  the turning point (to 58 % of the peak at the 5 s period, 73 % at 2.5 s) until the rising
  rate catches it: odd lines, lagging those of a memoryless -k |w| w (3f by 8 deg at 5 s, 21 deg
  at 2.5 s; 0.6 of its size at 5 s) and richer in 5f (0.25 and 0.38 of 3f); the swing's pace
  sets the shape (RELEASE_S against the period);
- scale_factor_asymmetry: a sagging sense mass: the push-pull rebalance electrodes of an
  out-of-plane sense mass were balanced with the IMU level, under the full normal load f_z = g;
  tilting relieves the load by g (1 - cos phi), the mass rises off centre and the two
  electrodes' gains part: out = x + k g (1 - cos phi) |w| (``sag_error``, the true rate and
  angle; its bias part left to the IMU's own compensation): a direction-dependent gain coupled
  to the tilt, none on the level (mid-swing) and at the turning points (w = 0), most 55 deg of
  the swing's phase from mid-swing (even lines only; growing as the amplitude cubed);
- timestamp_jitter: bracketed stamps: the driver stamps each encoder sample at the mid-point
  of two clock reads bracketing the register read, and another device's interrupt handler
  lands in the gap before or after the read (each IRQ_SHARE = 4 % of the time, independently),
  moving the stamp by half the handler's length, early or late (log-normal of median m, sd of
  its log IRQ_SPREAD = 0.8, capped at IRQ_MAX = 0.9 of a step; ``irq_errors``): 92.2 % of the
  stamps exact, the others scattered symmetrically, white, kurtosis ~160 (stamps in order);
- encoder_cyclic_error: a detent on a resonant bracket: the encoder is a 512-pole-pair magnetic
  ring read by a head whose flux guide the poles attract, so the head's bracket deflects by a
  sin(2 u + DETENT_PHASE), u = 512 phi, at rest, but the bracket has a tangential mode at
  BRACKET_HZ = 40 Hz, damping BRACKET_ZETA = 0.05, and the detent drives it at 2 x 512
  |phi_dot| / 2 pi (``detent_error``): the static error near the turning points (at the 5 s
  period; at 2.5 s the ringing carries into them), rung up as the swing passes 0.245 rad/s (56
  % of the 5 s swing's peak rate, 28 % at 2.5 s; up to 7.8 a at 5 s, 5.4 a at 2.5 s, ringing
  on after), cut above it: a cyclic error whose size follows a resonance in the speed.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- retrying link: the matched detector on the noise-free angle residual of the mean latency
  profile, rate(t - L(t)) - rate(t) integrated, offset, bias ramp and scale factor fitted out,
  against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the preset's
  stamp jitter (as sets M-R and AE-AG), L(t) from the backlog's law along the settled period
  (``arq_mean``); the latency's random part not counted;
- failover: the matched detector in the rate domain (AF's ``rate_z``, bias and scale factor
  fitted out), the failover at mid-run (its z 0.95-1.05 of that over FAILOVER);
- drive AGC: the lines k = 2..60 of the settled period's error -k P w against s;
- sagging mass: the lines k = 2..60 of the periodic error (``period_lines``) against s;
- bracketed stamps: the stamp error read through the swing's rate (``stamp_z``, as sets E,
  K-R and AE-AG), white of the capped mixture's variance (``irq_variance``);
- detent: the matched detector on the noise-free angle residual, as the link's.
Edges solve z = 4 at the 5 s period, weak and strong z = 25 and 100 (``levels``, 3 digits; at
2.5 s the edges' z are: link 4.0x, drive AGC 2.7x, sagging mass 2.0x, stamps 2.0x, failover
1.0x, detent 0.65x). Physical scale: slots s of 0.375 (edge), 0.502 and 0.565 ms (mean
latencies over the run 0.098, 0.44 and 1.8 ms, at the null 0.79, 5.7 and 20 ms, the largest in a
run 10, 28 and 57 ms); raw g_y of 4.35e-5, 2.72e-4 and 1.09e-3 rad/s/(m/s^2) (0.024, 0.15 and
0.61 deg/s/g) after the failover; AGC couplings k of 5.07e-3, 0.0317 and 0.127 per rad/s (gain
drops at the 5 s swing's peak rate of 0.22 %, 1.4 % and 5.6 %); sag couplings k of 2.13e-3,
0.0133 and 0.0533 per m/s^2 (half the gains' difference at 20 deg 0.13 %, 0.79 % and 3.2 %);
handler medians m of 11.2, 28 and 56.3 us (stamp errors of 2.97, 7.43 and 14.8 us sd, beside
the preset's own 20 us); static detent deflections a of 0.033, 0.21 and 0.83 arcsec (up to 0.26,
1.6 and 6.5 arcsec at the 5 s period) on the 1266 arcsec pole pitch.
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, period_lines, print_levels
from heldout_detect import solved_levels, stamp_z, step_of, swing_scales

import numpy as np

from scipy import signal, special

from validate_diagnosis_swing_heldout_af import increasing, rate_z

from validate_diagnosis_swing_heldout_m import fitted_residual

from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
PHI_NULL, NULL_SD = np.deg2rad(14.0), np.deg2rad(3.0)   # rad: the antenna null's tilt, width
P_NULL, P_FLOOR = 0.5, 0.03             # the link's loss per attempt: in the null; elsewhere
GRID = 16                               # bins a slot in the backlog's law (``arq_mean``)
FAILOVER = (0.45, 0.55)                 # share of the run at which the failover falls
RELEASE_S = 3.0                         # s: the peak detector's release
IRQ_SHARE, IRQ_SPREAD, IRQ_MAX = 0.04, 0.8, 0.9   # per gap; sd of ln(length); cap (steps)
DETENT_PAIRS, DETENT_PHASE = 512, 0.8   # the magnetic ring's pole pairs; the detent's phase
BRACKET_HZ, BRACKET_ZETA = 40.0, 0.05   # the read head bracket's tangential mode
KEY = {'time_delay': 's', 'g_sensitivity': 'gy', 'scale_factor_nonlinearity': 'k',
       'scale_factor_asymmetry': 'k', 'timestamp_jitter': 'm', 'encoder_cyclic_error': 'a'}
TARGETS = (25.0, 100.0, 4.0)            # z of the weak, strong and edge levels
GUESS = {'time_delay': 4e-4, 'g_sensitivity': 1e-4, 'scale_factor_nonlinearity': 1e-2,
         'scale_factor_asymmetry': 1e-3, 'timestamp_jitter': 3e-5, 'encoder_cyclic_error': 1e-6}
SLOPE = {'time_delay': 6.0, 'timestamp_jitter': 2.0}    # first guess of d ln z / d ln x (else 1)


def loss(phi) -> np.ndarray:
    """Return the link's loss per attempt at the tilts ``phi``: P_FLOOR, and P_NULL in the null."""
    x = (np.asarray(phi, float) - PHI_NULL) / NULL_SD
    return P_FLOOR + (P_NULL - P_FLOOR) * np.exp(-0.5 * x * x)


def arq_stamps(t, phi, s: float, rng) -> np.ndarray:
    """
    Return the stamps of samples sent at ``t`` (tilts ``phi``) over the retrying link, slot s.

    Attempt j of sample k fails with ``loss(phi_k)``; K_k failures (geometric) before it gets
    through; the link serves in order: done_k = max(t_k, done_(k-1)) + s (1 + K_k); the stamp
    is done_k - s (the one-slot airtime calibrated out), so at least s after the last one.
    """
    t = np.asarray(t, float)
    if not s:
        return t.copy()
    fails = rng.geometric(1.0 - loss(phi)) - 1
    service = s * (1.0 + fails)
    c = np.cumsum(service)
    return c + np.maximum.accumulate(t - (c - service)) - s


def arq_mean(phi, s: float, step: float, periods: int = 3) -> np.ndarray:
    """
    Return the mean latency E[stamp_k - t_k] along a periodic ``phi`` sampled every ``step``.

    The backlog W_k found by sample k (W_(k+1) = max(0, W_k + s (1 + K_k) - step)) as a law on
    a grid of s / GRID, its service a comb of the geometric law, the step shared between the
    two nearest bins; E[latency_k] = E[W_k] + s p_k / (1 - p_k); the last of ``periods``.
    """
    p = loss(phi)
    out = np.empty(p.size)
    if not s:
        return np.zeros(p.size)
    h = s / GRID
    whole, frac = divmod(step / h, 1.0)
    whole = int(whole)
    law = np.ones(1)
    den = np.zeros(GRID + 1)
    den[0] = 1.0
    for _ in range(periods):
        for k, pk in enumerate(p.tolist()):
            out[k] = law @ (np.arange(law.size) * h) + s * pk / (1.0 - pk)
            tail = int(GRID * 40.0 / -np.log(pk))
            x = np.zeros(law.size + GRID + tail + whole + 2)
            x[GRID:GRID + law.size] = law
            den[GRID] = -pk
            y = signal.lfilter([1.0 - pk], den, x)
            z = (1.0 - frac) * y[whole:] + frac * np.r_[y[whole + 1:], 0.0]
            z[0] += (1.0 - frac) * y[:whole].sum() + frac * y[:whole + 1].sum()
            keep = np.flatnonzero(z > 1e-15)
            law = z[:keep[-1] + 1] / z.sum()
    return out


def failover_gate(t, rng) -> np.ndarray:
    """Return True from the failover on: a share uniform in FAILOVER of the run's span."""
    t = np.asarray(t, float)
    return t >= t[0] + rng.uniform(*FAILOVER) * (t[-1] - t[0])


def peak_envelope(w, step: float) -> np.ndarray:
    """Return the peak detector's P_k = max(|w_k|, P_(k-1) exp(-step / RELEASE_S)), P_(-1) = 0."""
    r = np.arange(np.size(w)) * (step / RELEASE_S)
    with np.errstate(divide='ignore'):
        return np.exp(np.maximum.accumulate(np.log(np.abs(np.asarray(w, float))) + r) - r)


def sag_error(phi, w, k: float) -> np.ndarray:
    """Return the rate error k g (1 - cos phi) |w| (gains 1 +- k g (1 - cos phi) for +-w)."""
    return k * G0 * (1.0 - np.cos(np.asarray(phi, float))) * np.abs(np.asarray(w, float))


def irq_errors(n: int, m: float, step: float, rng) -> np.ndarray:
    """
    Return n stamp errors (P_2 B_2 - P_1 B_1) / 2 of bracketed stamps.

    B_1, B_2 Bernoulli(IRQ_SHARE) (a handler in the gap before or after the register read),
    P log-normal of median m, sd of its log IRQ_SPREAD, capped at IRQ_MAX steps.
    """
    hit = rng.random((2, n)) < IRQ_SHARE
    dur = np.minimum(m * np.exp(IRQ_SPREAD * rng.standard_normal((2, n))), IRQ_MAX * step)
    return 0.5 * (hit[1] * dur[1] - hit[0] * dur[0])


def irq_stamps(t, m: float, rng) -> np.ndarray:
    """Return the stamps t + ``irq_errors`` (kept in order)."""
    t = np.asarray(t, float)
    if not m:
        return t.copy()
    step = step_of(t)
    return increasing(t + irq_errors(t.size, m, step, rng), step)


def irq_variance(m: float, step: float) -> float:
    """Return the variance (q E[P^2] - q^2 E[P]^2) / 2 of ``irq_errors`` (capped log-normal)."""
    if not m:
        return 0.0
    cap, sd, q = IRQ_MAX * step, IRQ_SPREAD, IRQ_SHARE
    u = np.log(cap / m) / sd

    def moment(j):
        return (m ** j * np.exp(0.5 * (j * sd) ** 2) * special.ndtr(u - j * sd)
                + cap ** j * special.ndtr(-u))
    return float(0.5 * (q * moment(2) - q * q * moment(1) ** 2))


@lru_cache(maxsize=8)
def bracket_filter(fs: float):
    """Return (b, a) of the bracket w^2 / (s^2 + 2 zeta w s + w^2), bilinear prewarped at fs."""
    wb = 2.0 * fs * np.tan(np.pi * BRACKET_HZ / fs)
    return signal.bilinear([wb * wb], [1.0, 2.0 * BRACKET_ZETA * wb, wb * wb], fs)


def detent_error(t, phi, a: float) -> np.ndarray:
    """
    Return the head's deflection (rad) at the samples: the detent through the bracket.

    The static deflection a sin(2 DETENT_PAIRS phi + DETENT_PHASE) along the true angle,
    through ``bracket_filter`` at the samples' rate, started settled on the first sample.
    """
    phi = np.asarray(phi, float)
    if not a:
        return np.zeros(phi.size)
    b, den = bracket_filter(1.0 / step_of(t))
    f = a * np.sin(2 * DETENT_PAIRS * phi + DETENT_PHASE)
    return signal.lfilter(b, den, f, zi=signal.lfilter_zi(b, den) * f[0])[0]


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def retried(imu_t, gyro, enc_t, enc, stand, rng, s):
        return arq_stamps(imu_t, stand(imu_t)[0], s, rng), gyro, enc_t, enc

    def failed_over(imu_t, gyro, enc_t, enc, stand, rng, gy):
        gate = failover_gate(imu_t, rng)
        return imu_t, gyro + gy * G0 * np.sin(stand(imu_t)[0]) * gate, enc_t, enc

    def peak_held(imu_t, gyro, enc_t, enc, stand, rng, k):
        w = stand(imu_t)[1]
        return imu_t, gyro - k * peak_envelope(w, step_of(imu_t)) * w, enc_t, enc

    def sagging(imu_t, gyro, enc_t, enc, stand, rng, k):
        return imu_t, gyro + sag_error(*stand(imu_t), k), enc_t, enc

    def bracketed(imu_t, gyro, enc_t, enc, stand, rng, m):
        return imu_t, gyro, irq_stamps(enc_t, m, rng), enc

    def detented(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + detent_error(enc_t, stand(enc_t)[0], a)

    return {
        'time_delay': (retried, [{'s': 5.02e-4}, {'s': 5.65e-4}, {'s': 3.75e-4}]),
        'g_sensitivity': (failed_over, [{'gy': 2.72e-4}, {'gy': 1.09e-3}, {'gy': 4.35e-5}]),
        'scale_factor_nonlinearity': (peak_held, [{'k': 0.0317}, {'k': 0.127}, {'k': 5.07e-3}]),
        'scale_factor_asymmetry': (sagging, [{'k': 0.0133}, {'k': 0.0533}, {'k': 2.13e-3}]),
        'timestamp_jitter': (bracketed, [{'m': 2.8e-5}, {'m': 5.63e-5}, {'m': 1.12e-5}]),
        'encoder_cyclic_error': (detented, [{'a': 1.01e-6}, {'a': 4.03e-6}, {'a': 1.61e-7}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    per = int(round(period_s * rate_hz))                     # samples a period
    if name == 'scale_factor_nonlinearity':
        rate = amp * w * np.cos(w * np.arange(2 * per) / rate_hz)
        err = (-p['k'] * peak_envelope(rate, 1.0 / rate_hz) * rate)[per:]
        return float(2 * np.linalg.norm((np.fft.rfft(err) / per)[2:61]) / s)
    if name == 'scale_factor_asymmetry':
        def err(u):
            return sag_error(amp * np.sin(w * u), amp * w * np.cos(w * u), p['k'])
        return float(period_lines(err, w, 2) / s)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        v = irq_variance(p['m'], 1.0 / rate_hz)
        return stamp_z(lambda f: np.full(np.shape(f), v / rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    n = int(duration * rate_hz)
    t = np.arange(n) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(detent_error(t, phi, p['a']), t, phi), rate_hz,
                         n_arw, floor)
    if name == 'g_sensitivity':
        late = t >= 0.5 * (t[0] + t[-1])
        return rate_z(p['gy'] * G0 * np.sin(phi) * late, rate, n_arw, rate_hz)
    lat = np.resize(arq_mean(phi[:per], p['s'], 1.0 / rate_hz), n)
    err = amp * w * np.cos(w * (t - lat)) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)


def levels(names=None, digits: int = 3) -> dict:
    """Return ``{name: [weak, strong, edge]}`` solved for z = TARGETS, to ``digits`` digits."""
    return solved_levels(detectability, KEY, GUESS, TARGETS, names, slope=SLOPE,
                         limit={'time_delay': 1.25}, digits=digits)


if __name__ == '__main__':
    print_levels(levels(), detectability)
