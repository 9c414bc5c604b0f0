"""
Held-out swing set G: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_f.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-F, and the kinds of departure
differ from shape to shape:

- time_delay: clock skew: the IMU's stamps are rebuilt from its sample counter at the nominal
  rate while its oscillator runs off by eps (ppm), so the gyro is late by eps (t - t_0): a
  delay that grows through the run from 0 (catalogue stamps / gyro lag; dev Lagrange; B
  one-pole; C integrate-dump; D FIR; E isolator: constant delays; F the encoder late,
  dispersively);
- g_sensitivity: sense-mass stops: the g-induced deflection of the sense mass is limited by
  its stops, so the bias follows g_y f_s tanh(f_y / f_s), f_s = 1.6 m/s^2 (the swing's
  peak f_y is 3.35 m/s^2): linear for small tilts, saturated at the ends of the swing; the
  fundamental is cut and odd harmonics appear (catalogue, dev: linear; B f_y f_z; C
  relaxation; D play; E bilinear; F lever arm);
- scale_factor_nonlinearity: a mode crossing: at one input rate (0.3 rad/s, 17 deg/s) a
  spurious mode crosses the sense frequency, leaving a local resonance-shaped anomaly in the
  transfer curve, e0 sign(w) / (1 + ((|w| - 0.3) / 0.02)^2) rad/s, on the gyro's output
  value (noise included): a localised, odd transfer error, zero elsewhere (catalogue
  polynomial; dev tanh; B knee; C range switch; D lock-in; E lagged cubic; F periodic ripple);
- scale_factor_asymmetry: a loose contact: the catalogue's a |w|, present only while a
  contact in one half of the torquer driver is open; the contact opens and closes at
  exponential times (mean dwell 90 s both ways): an intermittent asymmetry, on for half the
  time on average (catalogue constant; dev, B smoothed; C offset; D Schmitt; E after-effect;
  F warming: never switching off);
- timestamp_jitter: a double-buffered read-out: the encoder's samples alternate between two
  buffers whose triggers are skew apart, so the stamps are alternately skew / 2 early and
  late: a deterministic line at the encoder's Nyquist frequency (catalogue Gaussian; dev
  uniform; B Gauss-Markov; C heavy-tailed; D sync sawtooth; E packets; F data-dependent);
- encoder_cyclic_error: multiplexed tracks: one converter reads the sine track skew / 2
  before the stamp and the cosine track skew / 2 after it (2048 signal periods a turn), so
  at speed the tracks are out of quadrature by eps = L phi_dot skew and the interpolated
  angle errs by ~-(eps / 2) cos(2 L phi) / L: a cyclic error whose size follows the speed,
  none at the turning points (catalogue, dev, B: fixed line harmonics; C triangle; D
  per-revolution; E random per line; F a local spot).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- stops: the fundamental of g_y f_s tanh(g sin(A sin wt) / f_s), by quadrature, against s;
- mode crossing: the lines k >= 2 of the rate error (k = 1 is a scale factor) at the rate A w
  cos(wt), the anomaly first averaged over the gyro's own noise (sd N sqrt(1 kHz), Gauss-
  Hermite), summed in quadrature (a matched detector), against s;
- loose contact: the 2f line of the expected a |w| (half the time on): 0.5 a 4 A w / (3 pi),
  against s;
- clock skew, double buffer, multiplexed tracks: matched detector on the noise-free angle
  residual (-phi_dot eps t for the skew, -phi_dot e for the stamps, the tracks' error with
  offset and scale fitted out), against the gyro angle noise N^2 / (2 pi f)^2, the encoder's
  white floor and the preset's stamp jitter (as sets D-F).
Edges are at z ~ 4 at the 5 s period (at 2.5 s: clock skew 2.3x, loose contact 2x,
multiplexed tracks 1.9x, double buffer 1.3x, stops 1x, mode crossing 0.7x); weak and strong
are 3.5-25x further in z. Physical scale: clock errors of 0.165 ppm (edge), 1 and 4 ppm (a
TCXO's), 0.15-3.6 ms late at 900 s; g_y 5.7e-5 to 5e-4 rad/s/(m/s^2) (0.032-0.28 deg/s/g);
anomalies of 0.022, 0.11 and 0.34 deg/s; asymmetries of 0.11 %, 0.4 % and 1 %; buffer skews
of 0.25, 1 and 4 us; track skews of 0.52, 2.5 and 10 us (a multiplexed converter's).
"""
from heldout_detect import encoder_floor, fourier, matched_z, noise_mean, swing_scales
import numpy as np

G0 = 9.80665
SAT_FORCE = 1.6               # m/s^2: specific force at which the sense mass meets its stops
BUMP_AT, BUMP_WIDTH = 0.3, 0.02       # rad/s: the mode crossing's rate and its half width
CONTACT_DWELL = 90.0          # s: mean dwell of the driver contact, open and closed alike
SIGNAL_LINES = 2048           # sine-cosine signal periods per turn of the encoder


def sat_force(f_y: np.ndarray) -> np.ndarray:
    """Deflection-limited specific force: f_s tanh(f_y / f_s)."""
    return SAT_FORCE * np.tanh(f_y / SAT_FORCE)


def bump(w: np.ndarray, e0: float) -> np.ndarray:
    """Transfer error of a mode crossing: an odd Lorentzian of height e0 at |w| = BUMP_AT."""
    return e0 * np.sign(w) / (1 + ((np.abs(w) - BUMP_AT) / BUMP_WIDTH) ** 2)


def contact(n: int, dt: float, rng) -> np.ndarray:
    """0 / 1 state of an intermittent contact, exponential dwells of mean CONTACT_DWELL."""
    flip = rng.random(n) < 1.0 - np.exp(-dt / CONTACT_DWELL)
    flip[0] = rng.random() < 0.5
    return (np.cumsum(flip) % 2).astype(float)


def mux_error(phi: np.ndarray, rate: np.ndarray, skew: float) -> np.ndarray:
    """
    Return the angle error of an interpolator with one multiplexed converter.

    It samples the sine track skew/2 before the stamp and the cosine track skew/2 after it.
    """
    u = SIGNAL_LINES * phi
    half = SIGNAL_LINES * rate * skew / 2
    read = np.arctan2(np.sin(u - half), np.cos(u + half))
    return np.angle(np.exp(1j * (read - u))) / SIGNAL_LINES


def ping_pong(n: int, skew: float, first: int) -> np.ndarray:
    """Stamp errors of a double-buffered read-out: -skew/2, +skew/2 alternately."""
    return skew / 2 * np.where((np.arange(n) + first) % 2 == 0, -1.0, 1.0)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def clock_skew(imu_t, gyro, enc_t, enc, stand, rng, ppm):
        return imu_t + ppm * 1e-6 * (imu_t - imu_t[0]), gyro, enc_t, enc

    def mass_stops(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + gy * sat_force(G0 * np.sin(stand(imu_t)[0])), enc_t, enc

    def mode_crossing(imu_t, gyro, enc_t, enc, stand, rng, e0):
        return imu_t, gyro + bump(gyro, e0), enc_t, enc

    def loose_contact(imu_t, gyro, enc_t, enc, stand, rng, a):
        dt = float(np.median(np.diff(imu_t)))
        u = contact(imu_t.size, dt, rng)
        return imu_t, gyro + a * u * np.abs(stand(imu_t)[1]), enc_t, enc

    def double_buffer(imu_t, gyro, enc_t, enc, stand, rng, skew):
        return imu_t, gyro, enc_t + ping_pong(enc_t.size, skew, rng.integers(2)), enc

    def muxed_tracks(imu_t, gyro, enc_t, enc, stand, rng, skew):
        return imu_t, gyro, enc_t, enc + mux_error(enc, stand(enc_t)[1], skew)

    return {
        'time_delay': (clock_skew, [{'ppm': 1.0}, {'ppm': 4.0}, {'ppm': 0.165}]),
        'g_sensitivity': (mass_stops, [{'gy': 2e-4}, {'gy': 5e-4}, {'gy': 5.71e-5}]),
        'scale_factor_nonlinearity': (mode_crossing, [{'e0': 2e-3}, {'e0': 6e-3},
                                                      {'e0': 3.89e-4}]),
        'scale_factor_asymmetry': (loose_contact, [{'a': 4e-3}, {'a': 1e-2}, {'a': 1.11e-3}]),
        'timestamp_jitter': (double_buffer, [{'skew': 1e-6}, {'skew': 4e-6}, {'skew': 2.45e-7}]),
        'encoder_cyclic_error': (muxed_tracks, [{'skew': 2.5e-6}, {'skew': 1e-5},
                                                {'skew': 5.16e-7}]),
    }


def smoothed_bump(w: np.ndarray, e0: float, s_n: float) -> np.ndarray:
    """Mean of ``bump`` over the gyro's own noise (sd s_n) at the true rate ``w``."""
    return noise_mean(lambda v: bump(v, e0), w, s_n)


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'g_sensitivity':
        def f_y(r, th):
            return p['gy'] * sat_force(G0 * np.sin(amp * np.sin(th)))
        return fourier(f_y, amp * w, 1) / s
    if name == 'scale_factor_nonlinearity':
        s_n = n_arw * np.sqrt(rate_hz)
        th = np.arange(4096) * 2 * np.pi / 4096
        c = np.fft.rfft(smoothed_bump(amp * w * np.cos(th), p['e0'], s_n)) / th.size
        return float(2 * np.linalg.norm(c[2:61]) / s)
    if name == 'scale_factor_asymmetry':
        return p['a'] * 0.5 * 4 * amp * w / (3 * np.pi) / s
    floor = encoder_floor(enc, rate_hz)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        residual = -rate * p['ppm'] * 1e-6 * t
    elif name == 'encoder_cyclic_error':
        residual = mux_error(phi, rate, p['skew'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    else:
        residual = -rate * ping_pong(t.size, p['skew'], 0)
    return matched_z(residual, rate_hz, n_arw,
                     floor + (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz)
