"""
Held-out swing set AE: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_r.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-R, and the kinds of departure
differ from shape to shape:

- time_delay: a spike guard tuned on a quieter sensor: the IMU firmware limits how fast its
  output may change, y_k = y_(k-1) + clip(x_k - y_(k-1), +-S dt) (S, rad/s^2, a slew-rate
  limit meant against glitches), on the output value, noise included. The swing itself never
  comes near the limit (its rate changes by at most 0.55 rad/s^2); the gyro's own noise does
  (1 deg/s a sample at 1 kHz), so the limiter clips the noise's steps and, doing so, follows
  the motion late: a nonlinear, noise-driven lag whose size is set by the noise level (a
  one-pole of gain g in the small-signal sense, g = P(|n - m| < S dt) for the noise n of a
  sample under the stationary law of the limiter's error m, delay dt (1 - g) / g), the noise
  left clipped, non-Gaussian and reddened;
- g_sensitivity: a creeping die attach whose creep recovers slowly: the g-induced load on
  the sense element's anchor deflects it at once (bias g_y f_y, f_y = g sin(phi)) and, through
  the viscoelastic attach, by as much again with delay: a creep state c relaxing towards f_y,
  fast (CREEP_LOAD_S = 0.05 s) while the load grows in magnitude (f_y beyond c, same sign)
  and slowly (CREEP_UNLOAD_S = 2 s) while it recovers (a nonlinear, Schapery-like attach:
  loading and recovery at different rates), bias g_y (f_y + c): a direction-dependent
  relaxation, nearly a peak-hold of the tilt, all odd lines of the swing with phase lags
  (integrated from rest CREEP_PRE = 20 s before the run, exact exponential steps of 2 ms);
- scale_factor_nonlinearity: a rebalance loop that winds up: the closed loop's rebalance
  saturates at +-r just below the swing's peak rate, and while it is saturated its integrator
  winds up on the rate it cannot follow; back in range, the loop stays at +-r until the
  integrated error is repaid: the output angle catches up, none is lost (charge balance). The
  debt D = int (w - u) dt is driven back to zero as fast as the range allows, u_k = clip(w_k +
  D_(k-1) / dt_k, -r, r), D_k = D_(k-1) + (w_k - u_k) dt_k (a dead-beat loop; with the range
  just below the peak, D is a Lindley recursion, max(0, D + (w - r) dt)): the rate's peaks
  flattened AND stretched past the crossing back into range (the true rate; the read-out
  noise after it): a saturation with memory, its angle error a short pulse at each peak;
- scale_factor_asymmetry: a polarity relay's contact: the bench reads the gyro's analog
  rate (its zero-rate level subtracted) through a unipolar converter whose negative range is
  switched in by a reed relay at each reversal to negative rate; the relay's contact
  resistance sits in series with the input and differs from closure to closure (log-normal,
  median share a of the input resistance, sd of its log CONTACT_SIGMA = 0.5), so each
  negative half swing is read low by its own gain error: out = w (1 - a e^(0.5 z_j)) while w
  < 0 (true rate; z_j ~ N(0, 1), a new draw at every reversal), untouched while w >= 0: a
  one-sided gain, random from one half swing to the next, held through each;
- timestamp_jitter: self-similar network delays: the encoder's samples reach the host over a
  switched network whose cross traffic is long-range dependent (aggregated on-off sources),
  and each is stamped on arrival, its mean delay calibrated out: the stamp error is
  fractional Gaussian noise of sd sigma and Hurst exponent HURST = 0.8 (autocovariance
  sigma^2 (|k + 1|^1.6 - 2 |k|^1.6 + |k - 1|^1.6) / 2 at lag k samples, a power law k^-0.4,
  PSD ~ f^-0.6: no correlation time at all), drawn exactly by circulant embedding
  (Davies-Harte), stamps kept a twentieth of a step apart;
- encoder_cyclic_error: overdriven tracks: the read head sits close to its 256-line disk
  (CLIP_LINES) and its sine and cosine tracks come out (1 + o) times the range of their
  amplifiers, which clip them at +-1: atan2 then errs only near each track's crest, where it
  is flat-topped, by atan((1 + o) sin v) - v (v the distance from the crest), and not at
  all elsewhere, nor at all until the tracks exceed their range: four bumps a line (lines
  at 4, 8, 12, ... times the line frequency), u = 256 phi + 0.7 (CLIP_PHASE), growing as
  o^(3/2) from the onset.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine; s_n =
N sqrt(f_s) the gyro's per-sample noise):

- spike guard: the limiter's gain g from the stationary law of its error chain against unit
  white noise (m' = n where |n - m| <= l, m +- l beyond, l = S dt / s_n; a 1201-state grid
  over +-6), the delay dt (1 - g) / g (checked against a Monte Carlo run of the limiter on a
  noisy swing), then the matched detector on the noise-free angle residual of that delay,
  offset, bias ramp and scale factor fitted out, against the gyro angle noise N^2 / (2 pi
  f)^2, the encoder's white floor and the preset's stamp jitter (as sets M-R);
- creeping attach: the lines k = 1..60 of the settled periodic bias along the swing, in
  quadrature, against s;
- wind-up: the same matched detector on the noise-free angle residual of u - w (the whole
  run);
- polarity relay: the larger of two z: the mean one-sided gain's lines k = 2..60 (its
  line at f is a scale factor) against s, and the quadratic detector of the half swings'
  gain scatter, var / s_h^2 sqrt(M / 2), s_h^2 = N^2 / (W^2 T_s / 4) the variance of one half
  swing's gain estimate, M = T / T_s half swings of the negative side (the scatter
  dominates from the weak level on);
- network: the stamp error read through the swing's rate (``stamp_z``, as sets E and K-R),
  its two-sided PSD the FFT of the fGn autocovariance over 2^21 lags;
- overdriven tracks: the matched detector on the noise-free angle residual of the error
  (offset, bias ramp and scale factor fitted out), as the spike guard's.
Edges are at z ~ 4 at the 5 s period; weak and strong are several to hundreds of times
further in z. Physical scale: slew limits of 32.8 (edge), 10 and 3 rad/s^2 (1880, 573 and 172
deg/s^2 against the swing's 31; delays 0.19, 1.6 and 6.7 ms); unrelaxed g_y of 2.05e-5, 2e-4
and 1e-3 rad/s/(m/s^2) (0.012, 0.11 and 0.56 deg/s/g; the bias's line at f 0.0059, 0.057 and
0.29 deg/s); rebalance ranges r of 0.4383, 0.436 and 0.42 rad/s (25.11, 24.98 and 24.06 deg/s
against the 25.13 deg/s peak; held 95, 262 and 700 ms a peak, angle debts of 3, 64 and 1190
arcsec at most); median contact shares a of 0.096 %, 0.5 % and 2 % (a 10 mOhm to 0.2 Ohm
contact on a 10 Ohm input); network delay sds of 4.45, 20 and 100 us; track overdrives o of
0.24 %, 2 % and 15 % (errors up to 0.05, 1.2 and 22 arcsec on the 1.4 deg pitch).
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, period_lines, stamp_z, swing_scales
import numpy as np
from scipy import special
from validate_diagnosis_swing_heldout_m import fitted_residual
from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
CHAIN_STATES, CHAIN_SPAN = 1201, 6.0        # slew limiter's error chain: grid, +- span (sd)
CREEP_LOAD_S, CREEP_UNLOAD_S = 0.05, 2.0    # s: creep while the load grows; recovery
CREEP_STEP, CREEP_PRE = 2e-3, 20.0          # s: creep integration step; lead-in before a run
CONTACT_SIGMA = 0.5                         # log-normal spread of the relay's contact
HURST = 0.8                                 # the network delay's Hurst exponent
CLIP_LINES, CLIP_PHASE = 256, 0.7           # lines of the disk; the tracks' phase at 0 rad


def slew_limit(x, step: float) -> np.ndarray:
    """Return y, y_0 = x_0, y_k = y_(k-1) + clip(x_k - y_(k-1), -step, step)."""
    x = np.asarray(x, float)
    if not np.isfinite(step) or x.size == 0:
        return x.copy()
    out = x.tolist()
    prev = out[0]
    for k in range(1, len(out)):
        d = out[k] - prev
        if d > step:
            prev += step
        elif d < -step:
            prev -= step
        else:
            prev = out[k]
        out[k] = prev
    return np.array(out)


@lru_cache(maxsize=32)
def slew_chain(lim: float):
    """
    Return (grid, stationary law) of the limiter's error m against white unit noise.

    m' = m + clip(n - m, -lim, lim), n ~ N(0, 1): m' = n where |n - m| <= lim, else m +- lim
    (the point masses split between the two nearest states, so that their mean is kept).
    """
    v = np.linspace(-CHAIN_SPAN, CHAIN_SPAN, CHAIN_STATES)
    h = v[1] - v[0]
    edges = np.r_[v[0] - h / 2, v[:-1] + h / 2, v[-1] + h / 2]
    lo = np.clip(edges[None, :-1], v[:, None] - lim, v[:, None] + lim)
    hi = np.clip(edges[None, 1:], v[:, None] - lim, v[:, None] + lim)
    trans = special.ndtr(hi) - special.ndtr(lo)
    for sign in (1.0, -1.0):
        target = v + sign * lim
        mass = special.ndtr(-(v + lim)) if sign > 0 else special.ndtr(v - lim)
        pos = np.clip((target - v[0]) / h, 0, CHAIN_STATES - 1)
        i0 = np.minimum(np.floor(pos).astype(int), CHAIN_STATES - 2)
        frac = pos - i0
        rows = np.arange(CHAIN_STATES)
        np.add.at(trans, (rows, i0), mass * (1 - frac))
        np.add.at(trans, (rows, i0 + 1), mass * frac)
    trans /= trans.sum(axis=1, keepdims=True)
    lhs = np.r_[(trans.T - np.eye(CHAIN_STATES))[:-1], np.ones((1, CHAIN_STATES))]
    law = np.linalg.solve(lhs, np.r_[np.zeros(CHAIN_STATES - 1), 1.0])
    return v, law


def slew_gain(lim: float) -> float:
    """Return the small-signal gain g = P(|n - m| < lim) of the limiter (lim in noise sds)."""
    v, law = slew_chain(float(lim))
    return float(law @ (special.ndtr(v + lim) - special.ndtr(v - lim)))


def slew_delay(slew: float, sigma: float, dt: float) -> float:
    """Delay dt (1 - g) / g of the limiter ``slew`` (rad/s^2) on white noise of sd sigma."""
    if not np.isfinite(slew):
        return 0.0
    g = slew_gain(slew * dt / sigma)
    return dt * (1.0 - g) / g


def creep(t, f) -> np.ndarray:
    """
    Return the creep state c at ``t`` of the specific force ``f(t)`` (a callable, m/s^2).

    c relaxes towards f, fast (CREEP_LOAD_S) while the load grows (f beyond c, same sign)
    and slowly (CREEP_UNLOAD_S) while it recovers; integrated on a CREEP_STEP grid from
    CREEP_PRE before t[0] (from rest), exact exponential steps at the mid-step force.
    """
    t = np.asarray(t, float)
    grid = np.arange(t[0] - CREEP_PRE, t[-1] + 2 * CREEP_STEP, CREEP_STEP)
    mid = f(grid[:-1] + CREEP_STEP / 2).tolist()
    fast, slow = np.exp(-CREEP_STEP / CREEP_LOAD_S), np.exp(-CREEP_STEP / CREEP_UNLOAD_S)
    c = [0.0] * grid.size
    s = 0.0
    for k, fm in enumerate(mid):
        load = fm * s >= 0.0 and abs(fm) > abs(s)
        s = fm + (s - fm) * (fast if load else slow)
        c[k + 1] = s
    return np.interp(t, grid, np.array(c))


def windup(t, w, r: float) -> np.ndarray:
    """
    Output u of a loop whose rebalance saturates at +-r with its integrator winding up.

    The debt D = int (w - u) dt grows while the loop is saturated, and the loop drives it back
    to zero as fast as its range allows: u_k = clip(w_k + D_(k-1) / dt_k, -r, r), D_k =
    D_(k-1) + (w_k - u_k) dt_k (a dead-beat loop: in range and with no debt, u = w).
    """
    t, w = np.asarray(t, float), np.asarray(w, float)
    if not np.isfinite(r):
        return w.copy()
    dt = np.diff(t, prepend=t[0] - float(np.median(np.diff(t)))).tolist()
    out = w.tolist()
    debt = 0.0
    for k, (v, h) in enumerate(zip(out, dt)):
        u = v + debt / h
        u = r if u > r else (-r if u < -r else u)
        debt += (v - u) * h
        out[k] = u
    return np.array(out)


def relay_gains(rate, a: float, rng) -> np.ndarray:
    """Gain error a exp(CONTACT_SIGMA z_j) of each negative span j of ``rate``, 0 elsewhere."""
    neg = np.asarray(rate) < 0
    start = np.r_[neg[:1], neg[1:] & ~neg[:-1]]
    j = np.cumsum(start) - 1
    eps = a * np.exp(CONTACT_SIGMA * rng.standard_normal(max(int(start.sum()), 1)))
    return np.where(neg, eps[np.maximum(j, 0)], 0.0)


def fgn_cov(k, hurst: float = HURST) -> np.ndarray:
    """Autocovariance of unit fractional Gaussian noise at integer lags ``k``."""
    k = np.abs(np.asarray(k, float))
    e = 2 * hurst
    return 0.5 * (np.abs(k + 1) ** e - 2 * k ** e + np.abs(k - 1) ** e)


def fgn(n: int, rng, hurst: float = HURST) -> np.ndarray:
    """Return unit fractional Gaussian noise of n samples (Davies-Harte circulant embedding)."""
    m = 2 ** int(np.ceil(np.log2(max(2 * (n - 1), 2))))
    row = fgn_cov(np.r_[np.arange(m // 2 + 1), np.arange(m // 2 - 1, 0, -1)], hurst)
    lam = np.maximum(np.real(np.fft.fft(row)), 0.0)
    z = rng.standard_normal(m) + 1j * rng.standard_normal(m)
    return np.real(np.fft.fft(np.sqrt(lam) * z))[:n] / np.sqrt(m)


def network_stamps(t, sigma: float, rng) -> np.ndarray:
    """Stamps t + sigma x (x unit fGn), kept at least a twentieth of a step apart."""
    t = np.asarray(t, float)
    if not sigma:
        return t.copy()
    s = t + sigma * fgn(t.size, rng)
    gap = 0.05 * float(np.median(np.diff(t)))
    k = np.arange(t.size) * gap
    return np.maximum.accumulate(s - k) + k


@lru_cache(maxsize=1)
def _fgn_table():
    size = 2 ** 21
    row = fgn_cov(np.r_[np.arange(size // 2 + 1), np.arange(size // 2 - 1, 0, -1)])
    psd = np.real(np.fft.fft(row))
    return np.fft.fftshift(np.fft.fftfreq(size)), np.fft.fftshift(psd)


def network_psd(f, sigma: float, rate_hz: float) -> np.ndarray:
    """Two-sided PSD (s^2/Hz) of the stamp error sigma x, x unit fGn at ``rate_hz``."""
    grid, psd = _fgn_table()
    x = np.asarray(f, float) / rate_hz
    return sigma ** 2 / rate_hz * np.interp(x, grid, psd, period=1.0)


def clipped_error(phi, o: float) -> np.ndarray:
    """Angle error of atan2 over tracks (1 + o) (sin u, cos u) clipped at +-1, u = L phi + p."""
    u = CLIP_LINES * np.asarray(phi, float) + CLIP_PHASE
    s = np.clip((1 + o) * np.sin(u), -1.0, 1.0)
    c = np.clip((1 + o) * np.cos(u), -1.0, 1.0)
    return np.angle(np.exp(1j * (np.arctan2(s, c) - u))) / CLIP_LINES


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def limiter(imu_t, gyro, enc_t, enc, stand, rng, slew):
        dt = float(np.median(np.diff(imu_t)))
        return imu_t, slew_limit(gyro, slew * dt), enc_t, enc

    def attach(imu_t, gyro, enc_t, enc, stand, rng, gy):
        def f(s):
            return G0 * np.sin(stand(s)[0])
        return imu_t, gyro + gy * (f(imu_t) + creep(imu_t, f)), enc_t, enc

    def wind(imu_t, gyro, enc_t, enc, stand, rng, r):
        w = stand(imu_t)[1]
        return imu_t, gyro + windup(imu_t, w, r) - w, enc_t, enc

    def relay(imu_t, gyro, enc_t, enc, stand, rng, a):
        w = stand(imu_t)[1]
        return imu_t, gyro - relay_gains(w, a, rng) * w, enc_t, enc

    def network(imu_t, gyro, enc_t, enc, stand, rng, sigma):
        return imu_t, gyro, network_stamps(enc_t, sigma, rng), enc

    def tracks(imu_t, gyro, enc_t, enc, stand, rng, o):
        return imu_t, gyro, enc_t, enc + clipped_error(stand(enc_t)[0], o)

    return {
        'time_delay': (limiter, [{'slew': 10.0}, {'slew': 3.0}, {'slew': 32.8}]),
        'g_sensitivity': (attach, [{'gy': 2e-4}, {'gy': 1e-3}, {'gy': 2.05e-5}]),
        'scale_factor_nonlinearity': (wind, [{'r': 0.436}, {'r': 0.42}, {'r': 0.4383}]),
        'scale_factor_asymmetry': (relay, [{'a': 5e-3}, {'a': 2e-2}, {'a': 9.6e-4}]),
        'timestamp_jitter': (network, [{'sigma': 2e-5}, {'sigma': 1e-4},
                                       {'sigma': 4.45e-6}]),
        'encoder_cyclic_error': (tracks, [{'o': 0.02}, {'o': 0.15}, {'o': 0.00236}]),
    }


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'g_sensitivity':
        def f(u):
            return G0 * np.sin(amp * np.sin(w * u))
        # creep starts CREEP_PRE before t: the period is settled (10 recovery times)
        return float(period_lines(lambda t: p['gy'] * (f(t) + creep(t, f)), w) / s)
    if name == 'scale_factor_asymmetry':
        mean = p['a'] * np.exp(CONTACT_SIGMA ** 2 / 2)
        z_mean = period_lines(lambda t: mean * np.maximum(-amp * w * np.cos(w * t), 0.0), w, 2) / s
        var = p['a'] ** 2 * np.exp(CONTACT_SIGMA ** 2) * np.expm1(CONTACT_SIGMA ** 2)
        seg = n_arw ** 2 / ((amp * w) ** 2 * period_s / 4)     # a half swing's gain variance
        z_scatter = var / seg * np.sqrt(duration / period_s / 2)
        return float(max(z_mean, z_scatter))
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: network_psd(f, p['sigma'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    n = int(duration * rate_hz)
    t = np.arange(n) / rate_hz
    phi = amp * np.sin(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(clipped_error(phi, p['o']), t, phi), rate_hz, n_arw,
                         floor)
    rate = amp * w * np.cos(w * t)
    if name == 'time_delay':
        d = slew_delay(p['slew'], n_arw * np.sqrt(rate_hz), 1.0 / rate_hz)
        err = amp * w * np.cos(w * (t - d)) - rate
    else:
        err = windup(t, rate, p['r']) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)
