"""
Held-out swing set D: written in session 7 without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_c.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B and C:

- time_delay: an 8 kHz internal rate decimated by a linear-phase windowed-sinc FIR
  of L taps (Kaiser, 400 Hz): the motion is delayed by (L - 1) / 2 internal samples, exactly,
  noise added after it (catalogue stamps; dev 4-tap Lagrange; B one-pole; C integrate-dump);
- g_sensitivity: tilt hysteresis: the bias follows f_y through a play operator (backlash) of
  half width 0.05 g (stick-slip of the die attach): rate-independent, so its lag in angle is
  the same at any swing period (catalogue, dev linear; B f_y f_z; C a linear relaxation);
- scale_factor_nonlinearity: ring-laser lock-in in its averaged (Adler) form: output
  sign(w) sqrt(w^2 - W_L^2) above the lock-in rate W_L, 0 below: a dead band with a
  square-root edge and a -W_L^2 / (2 w) tail (catalogue k2, k3; dev tanh; B knee; C a step);
- scale_factor_asymmetry: a direction-dependent gain (1 +- a) switched by a Schmitt trigger of
  hysteresis +-0.05 rad/s: the gain switches late after every reversal (catalogue a |w|; dev,
  B smoothed; C a comparator offset, early on one side and late on the other);
- timestamp_jitter: encoder stamps extrapolated from a sync pulse every 1 s at the nominal
  interval while the encoder clock is off by delta: a deterministic sawtooth of peak-to-peak
  delta x 1 s, mean removed (catalogue Gaussian; dev uniform white; B a second-order
  Gauss-Markov; C one-sided heavy-tailed latency);
- encoder_cyclic_error: per-revolution errors of the disk: eccentricity 2 a sin(phi + 0.6)
  and a four-lobe mounting deformation a sin(4 phi + 1.9): harmonics of the swing, not chirps
  at line frequencies (catalogue 1st + 2nd on 2048 lines, dev 1st + 3rd on 1000, B 2nd + 4th
  on 512, C triangle on 360).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- FIR delay: the angle residual's cos component A w d, d = (L - 1) / (2 8 kHz), against s / w;
- hysteretic g: the fundamental (in-phase and quadrature) of g_y P(g sin(A sin wt)) in the
  rate, by quadrature over a period, against s;
- lock-in: the 3f line of the rate error at W cos(wt), by quadrature, against s;
- Schmitt asymmetry: the 2f line (magnitude of both phases) of the rate error, against s;
- sync sawtooth, per-revolution errors: deterministic angle residuals (-phi_dot e(t) for the
  stamps, the error's harmonics k >= 2 for the disk; its fundamental is a scale factor) seen
  by a matched detector: z^2 = sum_f |R_f|^2 / (n f_s S_n(f)) over the FFT of the noise-free
  residual on the run's grid, S_n the two-sided angle noise N^2 / (2 pi f)^2 plus the
  encoder's white floor and the preset's stamp jitter (as set C's latency), so lines the gyro
  noise hides at low frequency count little.
Edges are at z ~ 4 at the 5 s period (at 2.5 s: delay 4x, asymmetry, sawtooth and disk ~2x,
hysteresis 1x, lock-in 0.5x: the swing spends less time in its dead band); weak and strong are
4-21x further in z, the sawtooth's 12-63x (100 and 500 ppm: a crystal and an RC clock). The
strong disk error (eccentricity 3 mrad) is a magnetic or low-grade optical encoder's.
"""
from heldout_detect import encoder_floor, matched_z, swing_scales
import numpy as np
from scipy import signal

G0 = 9.80665
FS_INT, FIR_CUT = 8000.0, 400.0    # internal rate and decimation FIR cut-off, Hz
PLAY = 0.05 * G0                   # m/s^2, half width of the tilt hysteresis
SCHMITT = 0.05                     # rad/s, hysteresis of the direction trigger
SYNC = 1.0                         # s, period of the sync pulse
ECC = (2.0, 0.6, 1.0, 1.9)         # eccentricity / a, its phase; four-lobe / a, its phase


def fir_taps(taps: int) -> np.ndarray:
    """Linear-phase decimation FIR of ``taps`` taps at FS_INT, unit DC gain."""
    return signal.firwin(int(taps), FIR_CUT, fs=FS_INT, window=('kaiser', 5.0))


def play(x: np.ndarray, half: float) -> np.ndarray:
    """Play operator (backlash) of half width ``half``, started at its centre."""
    out, y = np.empty_like(x), float(x[0])
    for i, v in enumerate(x.tolist()):
        y = min(max(y, v - half), v + half)
        out[i] = y
    return out


def schmitt(w: np.ndarray, h: float) -> np.ndarray:
    """Return +-1: +1 once ``w`` rose above h, -1 once it fell below -h (sign(w_0) before)."""
    mark = np.where(w > h, 1.0, np.where(w < -h, -1.0, 0.0))
    mark[0] = mark[0] or (1.0 if w[0] >= 0 else -1.0)
    idx = np.maximum.accumulate(np.where(mark != 0, np.arange(w.size), 0))
    return mark[idx]


def lock_in(w: np.ndarray, w_l: float) -> np.ndarray:
    """Averaged RLG output of input rate ``w`` with lock-in rate ``w_l`` (Adler beat)."""
    return np.sign(w) * np.sqrt(np.maximum(w * w - w_l * w_l, 0.0))


def sawtooth(k: np.ndarray, dt: float, delta: float, phase: float = 0.0) -> np.ndarray:
    """Stamp error of sample ``k``: delta (t mod SYNC) less its mean, t = k dt + phase SYNC."""
    return delta * SYNC * (np.mod(k * dt / SYNC + phase, 1.0) - 0.5)


def disk_error(phi: np.ndarray, a: float) -> np.ndarray:
    """Per-revolution encoder error: eccentricity plus four-lobe deformation."""
    return a * (ECC[0] * np.sin(phi + ECC[1]) + ECC[2] * np.sin(4 * phi + ECC[3]))


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def fir_delay(imu_t, gyro, enc_t, enc, stand, rng, taps):
        h = fir_taps(taps)
        rate = stand(imu_t)[1]
        out = sum(hj * stand(imu_t - j / FS_INT)[1] for j, hj in enumerate(h))
        return imu_t, gyro + out - rate, enc_t, enc

    def tilt_hysteresis(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + gy * play(G0 * np.sin(stand(imu_t)[0]), PLAY), enc_t, enc

    def rlg_lock_in(imu_t, gyro, enc_t, enc, stand, rng, w_l):
        w = stand(imu_t)[1]
        return imu_t, gyro + lock_in(w, w_l) - w, enc_t, enc

    def schmitt_asym(imu_t, gyro, enc_t, enc, stand, rng, a):
        w = stand(imu_t)[1]
        return imu_t, gyro + a * w * schmitt(w, SCHMITT), enc_t, enc

    def sync_sawtooth(imu_t, gyro, enc_t, enc, stand, rng, delta):
        step = float(np.median(np.diff(enc_t)))
        e = sawtooth(np.arange(enc_t.size), step, delta, rng.uniform())
        return imu_t, gyro, enc_t + e, enc

    def per_rev(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + disk_error(enc, a)

    return {
        'time_delay': (fir_delay, [{'taps': 17}, {'taps': 65}, {'taps': 4}]),
        'g_sensitivity': (tilt_hysteresis, [{'gy': 1.5e-4}, {'gy': 4e-4}, {'gy': 3.35e-5}]),
        'scale_factor_nonlinearity': (rlg_lock_in, [{'w_l': 0.016}, {'w_l': 0.03},
                                                    {'w_l': 0.0068}]),
        'scale_factor_asymmetry': (schmitt_asym, [{'a': 2.5e-3}, {'a': 1e-2}, {'a': 5.5e-4}]),
        'timestamp_jitter': (sync_sawtooth, [{'delta': 1e-4}, {'delta': 5e-4},
                                             {'delta': 8e-6}]),
        'encoder_cyclic_error': (per_rev, [{'a': 4e-4}, {'a': 1.5e-3}, {'a': 9.7e-5}]),
    }


def lines(err, amp: float, k: int, m: int = 200000) -> float:
    """Magnitude of harmonic ``k`` of ``err(W cos(theta), theta)`` over one period (settled)."""
    th = np.arange(2 * m) * 2 * np.pi / m                  # two periods: the second is settled
    y = err(amp * np.cos(th), th)[m:]
    th = th[m:]
    return float(2 * np.hypot(np.mean(y * np.cos(k * th)), np.mean(y * np.sin(k * th))))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'time_delay':
        return amp * w * (p['taps'] - 1) / (2 * FS_INT) / (s / w)
    if name == 'g_sensitivity':
        return p['gy'] * lines(lambda r, th: play(G0 * np.sin(amp * np.sin(th)), PLAY),
                               amp * w, 1, 20000) / s
    if name == 'scale_factor_nonlinearity':
        return lines(lambda r, th: lock_in(r, p['w_l']) - r, amp * w, 3) / s
    if name == 'scale_factor_asymmetry':
        return p['a'] * lines(lambda r, th: r * schmitt(r, SCHMITT), amp * w, 2) / s
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        residual = -rate * sawtooth(np.arange(t.size), 1.0 / rate_hz, p['delta'])
    else:
        residual = disk_error(phi, p['a'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    return matched_z(residual, rate_hz, n_arw, floor)
