"""
Held-out swing set O: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_n.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-N, and the kinds of departure
differ from shape to shape:

- time_delay: interleaving skew: the gyro's converter is two time-interleaved channels, each
  converting at half the output rate, even samples from one and odd from the other, and the
  odd channel's trigger is set d early (a phase-register error; d may exceed the output period,
  the odd stream then older than the even sample before it), so every other rate value is the
  motion at t - d: a mean delay d / 2 and a delay that alternates from sample to sample (an
  image of the motion at the Nyquist frequency), the noise untouched;
- g_sensitivity: a wandering quadrature leak: tilt bends the sense frame and adds a quadrature
  signal q_g f_y (f_y = g sin(phi)); the demodulator's phase error, calibrated to zero on
  average but wandering with the drive loop's temperature (a unit first-order Gauss-Markov
  process u of 60 s), leaks it into the rate: bias c u(t) f_y, a g-sensitivity whose size and
  sign wander at random, zero on average;
- scale_factor_nonlinearity: accumulator overflow: the firmware's decimation filter keeps its
  sum in a 16-bit register scaled for +-R, and a rate beyond R wraps around (two's complement),
  out = ((w + R) mod 2 R) - R on the output value (noise included): exact below R, a jump of
  -2 R sign(w) beyond it: with R above the swing's peak only the noise's excursions at the peak
  wrap (rare, huge spikes); with R below it, every pass over the peak;
- scale_factor_asymmetry: a noisy driver half: the torquer driver's negative half takes its
  current reference from a noisy zener, the positive half from a quiet band-gap, so while the
  rebalance current (the true rate) is negative the gain fluctuates: out = w + e_k w 1(w < 0),
  e_k white of sd eps: no mean error at all, a rate-proportional noise on one direction only
  (heteroscedastic, zero-mean);
- timestamp_jitter: a stepping clock: the host's clock is a PTP slave that steps (does not
  slew) to each new offset measurement, taken from sync messages that reach it over a busy
  network at Poisson times of mean 0.1 s, and each measurement errs by an independent Gaussian
  of sd sigma (clipped at +-0.45 ms, so that the stamps stay in order): the encoder stamps'
  error is piecewise constant with jumps, a kangaroo process, two-sided PSD sigma^2 2 tau /
  (1 + (2 pi f tau)^2), tau = 0.1 s;
- encoder_cyclic_error: coupling backlash: the encoder shaft is driven from the stand through a
  coupling with a play of +-b, so it lags the stand by b in the direction of motion and, after
  each reversal, stays put until the stand has moved 2 b: a play operator, the encoder's error
  a square-ish wave of +-b at the swing frequency with flat spots after every turning point.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine; s_n =
N sqrt(f_s) the gyro's per-sample noise):

- interleaving skew, backlash: matched detector on the noise-free angle residual (the
  integrated rate error; the play's error itself), offset, bias ramp and scale factor fitted
  out, against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the
  preset's stamp jitter;
- quadrature leak: a quadratic detector on the added angle noise: the rate error's two-sided
  PSD c^2 g^2 sum_k a_k^2 / 4 (S_u(f - k f0) + S_u(f + k f0)) (a_k the lines of f_y / g, S_u =
  2 tc / (1 + (2 pi f tc)^2)) over (2 pi f)^2;
- overflow: lines k = 2..60 of the wrap error averaged over the gyro's noise, exactly (one
  wrap at most) 2 R (Phi((-R - w) / s_n) - Phi((w - R) / s_n)), in quadrature, against s;
- noisy half: the optimal variance detector sum over w < 0 of w^2 (r^2 - s_n^2): z = eps^2 (A
  w)^2 sqrt(3 n / 32) / s_n^2 (n samples, half of them on the negative side, E[w^4] = 3 (A
  w)^4 / 8);
- stepping clock: the stamp error read through the swing's rate (``stamp_z``, as sets E and
  K-N).
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: interleaving skews of 0.27 ms (edge), 1.5 and 5 ms; leaks c of
4.3e-5, 2e-4 and 1e-3 (rad/s)/(m/s^2) sd (0.0082, 0.038 and 0.19 deg/s at the swing's end);
overflow ranges R of 0.498, 0.48 and 0.40 rad/s (28.5, 27.5 and 22.9 deg/s; the swing's peak
25.1 deg/s); gain noises of 0.47 %, 2 % and 8 % sd; clock-step errors of 36, 100 and 200 us sd
(the strong level's clip trims 2.4 % of its steps); backlashes of 0.82, 12 and 210 arcsec.
"""
from heldout_detect import encoder_floor, matched_z, quadratic_z, stamp_z, swing_scales
import numpy as np
from scipy import special
from validate_diagnosis_heldout_n import gauss_markov
from validate_diagnosis_swing_heldout_m import fitted_residual
from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
LEAK_TC = 60.0                          # s: the demodulator phase error's correlation time
HOLD_S, STEP_CLIP = 0.1, 4.5e-4         # s: mean time between clock steps; largest step (s)


def interleave(t, d: float) -> np.ndarray:
    """Return the sampling instants: t on even samples, t - d on odd ones."""
    t = np.asarray(t, float)
    return t - d * (np.arange(t.size) % 2)


def wrap(x, r: float) -> np.ndarray:
    """Two's-complement wrap of x into [-r, r): ((x + r) mod 2 r) - r."""
    return np.mod(np.asarray(x, float) + r, 2 * r) - r


def wrap_mean(w, r: float, s_n: float) -> np.ndarray:
    """Mean wrap error 2 r (Phi((-r - w) / s_n) - Phi((w - r) / s_n)) at true rates w."""
    w = np.asarray(w, float)
    return 2 * r * (special.ndtr((-r - w) / s_n) - special.ndtr((w - r) / s_n))


def clock_steps(n: int, sigma: float, rate_hz: float, rng) -> np.ndarray:
    """Piecewise-constant stamp error: new N(0, sigma^2) levels (clipped) at Poisson times."""
    dur = n / rate_hz
    jumps = np.cumsum(rng.exponential(HOLD_S, int(3 * dur / HOLD_S) + 20))
    levels = np.clip(sigma * rng.standard_normal(jumps.size + 1), -STEP_CLIP, STEP_CLIP)
    return levels[np.searchsorted(jumps, np.arange(n) / rate_hz, side='right')]


def step_psd(f, sigma: float) -> np.ndarray:
    """Two-sided PSD sigma^2 2 tau / (1 + (2 pi f tau)^2) of ``clock_steps`` (tau = HOLD_S)."""
    return sigma ** 2 * 2 * HOLD_S / (1 + (2 * np.pi * np.asarray(f, float) * HOLD_S) ** 2)


def backlash(phi, b: float) -> np.ndarray:
    """Play operator of half width b on phi, starting at phi_0."""
    out = np.empty(len(phi))
    y = float(phi[0])
    for k, v in enumerate(np.asarray(phi, float).tolist()):
        y = min(max(y, v - b), v + b)
        out[k] = y
    return out


def fy_lines(amp: float, w: float, kmax: int = 9) -> np.ndarray:
    """Sine amplitudes a_1..a_kmax of f_y / g = sin(amp sin(w t))."""
    th = np.arange(4096) * 2 * np.pi / 4096
    c = np.fft.rfft(np.sin(amp * np.sin(th))) / th.size
    return 2 * np.abs(c[1:kmax + 1])


def leak_psd(f, c: float, amp: float, w: float) -> np.ndarray:
    """Two-sided PSD of the rate error c u(t) g sin(phi): lines of f_y spread by u's Lorentzian."""
    f = np.asarray(f, float)
    f0 = w / (2 * np.pi)
    s_u = lambda v: 2 * LEAK_TC / (1 + (2 * np.pi * v * LEAK_TC) ** 2)  # noqa: E731
    out = np.zeros_like(f)
    for k, a in enumerate(fy_lines(amp, w), start=1):
        out += (c * G0 * a) ** 2 / 4 * (s_u(f - k * f0) + s_u(f + k * f0))
    return out


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def skew(imu_t, gyro, enc_t, enc, stand, rng, d):
        return imu_t, gyro + stand(interleave(imu_t, d))[1] - stand(imu_t)[1], enc_t, enc

    def leak(imu_t, gyro, enc_t, enc, stand, rng, c):
        u = gauss_markov(imu_t.size, LEAK_TC, 1.0 / rate_hz, rng)
        return imu_t, gyro + c * u * G0 * np.sin(stand(imu_t)[0]), enc_t, enc

    def overflow(imu_t, gyro, enc_t, enc, stand, rng, r):
        return imu_t, wrap(gyro, r), enc_t, enc

    def half(imu_t, gyro, enc_t, enc, stand, rng, eps):
        rate = stand(imu_t)[1]
        return imu_t, gyro + eps * rng.standard_normal(gyro.size) * np.minimum(rate, 0), \
            enc_t, enc

    def daemon(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, enc_t + clock_steps(enc_t.size, sigma, rate_hz, rng), enc

    def play(imu_t, gyro, enc_t, enc, stand, rng, b):
        phi = stand(enc_t)[0]
        return imu_t, gyro, enc_t, enc + backlash(phi, b) - phi

    return {
        'time_delay': (skew, [{'d': 1.5e-3}, {'d': 5e-3}, {'d': 2.7e-4}]),
        'g_sensitivity': (leak, [{'c': 2e-4}, {'c': 1e-3}, {'c': 4.28e-5}]),
        'scale_factor_nonlinearity': (overflow, [{'r': 0.48}, {'r': 0.40}, {'r': 0.4976}]),
        'scale_factor_asymmetry': (half, [{'eps': 0.02}, {'eps': 0.08}, {'eps': 4.65e-3}]),
        'timestamp_jitter': (daemon, [{'sigma': 1e-4}, {'sigma': 2e-4},
                                      {'sigma': 3.6e-5}]),
        'encoder_cyclic_error': (play, [{'b': 6e-5}, {'b': 1e-3}, {'b': 3.98e-6}]),
    }


def leak_grid(w: float, rate_hz: float) -> np.ndarray:
    """Frequencies for the leak's quadratic detector: fine about each line, coarse elsewhere."""
    f0 = w / (2 * np.pi)
    fine = [s * (k * f0 + np.linspace(-0.05, 0.05, 4001)) for k in range(1, 10)
            for s in (1, -1)]
    return np.unique(np.concatenate(fine + [np.linspace(-rate_hz / 2, rate_hz / 2, 20001)]))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    s_n = n_arw * np.sqrt(rate_hz)
    n = int(duration * rate_hz)
    if name == 'scale_factor_nonlinearity':
        th = np.arange(4096) * 2 * np.pi / 4096
        c = np.fft.rfft(wrap_mean(amp * w * np.cos(th), p['r'], s_n)) / th.size
        return float(2 * np.linalg.norm(c[2:61]) / s)
    if name == 'scale_factor_asymmetry':
        return float(p['eps'] ** 2 * (amp * w) ** 2 * np.sqrt(3 * n / 32) / s_n ** 2)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: step_psd(f, p['sigma']), amp * w, w / (2 * np.pi), n_arw,
                       floor, duration, rate_hz, 400001)
    if name == 'g_sensitivity':
        f = leak_grid(w, rate_hz)
        s_r = leak_psd(f, p['c'], amp, w) / np.maximum((2 * np.pi * f) ** 2, 1e-30)
        return quadratic_z(s_r, f, n_arw, floor, duration)
    t = np.arange(n) / rate_hz
    phi = amp * np.sin(w * t)
    if name == 'encoder_cyclic_error':
        err = backlash(phi, p['b']) - phi
        return matched_z(angle_residual(err, t, phi), rate_hz, n_arw, floor)
    err = amp * w * (np.cos(w * interleave(t, p['d'])) - np.cos(w * t))
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
