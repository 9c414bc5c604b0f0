"""
Held-out swing set H: written blind, without running the diagnosis, run once at the end.

Same interface as ``validate_diagnosis_swing_heldout_g.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets B-G, and the kinds of departure
differ from shape to shape:

- time_delay: a latency step: at a random moment in the middle of the run (30-70 %) the
  driver re-synchronises and from then on stamps each gyro sample d later (stamping moved from
  the interrupt to the read callback): a delay of 0 before and d after, a single step;
- g_sensitivity: a g-dependent scale factor: the specific force along y tilts the proof mass
  and changes the sense gap, so the output is gyro (1 + c f_y), f_y = g sin(phi): a product of
  rate and specific force, all even harmonics of the swing (2f, 4f, ...);
- scale_factor_nonlinearity: an over-compensated dead band: the firmware adds a rate-sign
  offset meant to cancel a dead band that is absent, e tanh(gyro / 0.01 rad/s) on the output
  value (noise included): a jump through zero rate, flat elsewhere;
- scale_factor_asymmetry: a square-law term: an offset of the sense electrodes makes the
  parallel-plate read-out quadratic, output gyro + b gyro^2 (noise included): smooth, even,
  no kink at zero;
- timestamp_jitter: a coarse stamping counter: the encoder's stamps are latched from a free-
  running counter of period tick, truncated to whole ticks (tick not a divisor of the sample
  period): a deterministic, periodic pattern of stamp errors in (-tick, 0];
- encoder_cyclic_error: a rocking read head: friction drags the head against the direction of
  travel, tilting it so the two tracks leave quadrature by +-delta with the sign of the speed:
  a cyclic error at twice the line rate whose sign flips at each turning point.

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N = 1.89 deg/sqrt(h); s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- g-dependent scale factor: harmonics 2, 4, 6 of c g sin(A sin wt) A w cos wt by quadrature, in
  quadrature, against s;
- dead band: the lines k >= 2 of the rate error at A w cos(wt), the offset first averaged over
  the gyro's own noise (sd N sqrt(1 kHz), Gauss-Hermite), in quadrature, against s;
- square law: the 2f line b (A w)^2 / 2 against s;
- latency step, counter, rocking head: matched detector on the noise-free angle residual
  (-phi_dot d for t past the step at mid-run, -phi_dot (e - mean e) for the stamps, the head's
  error with offset and scale fitted out), against the gyro angle noise N^2 / (2 pi f)^2, the
  encoder's white floor and the preset's stamp jitter (as sets D-G).
Edges are at z ~ 4 at the 5 s period; weak and strong are 3-30x further in z. Physical scale:
latency steps of 0.108 (edge), 0.5 and 2 ms; scale-factor changes of 0.14, 1 and 3.9 %/g;
dead-band offsets of 0.011, 0.034 and 0.11 deg/s; square-law terms b of 1.1e-3, 8e-3 and
3e-2 per rad/s; counter ticks of 0.56, 2.44 and 9.77 us (1.79 MHz, 409.6 kHz, 102.4 kHz);
head tilts of 0.39, 2 and 6 mrad of line phase between the tracks.
"""
from heldout_detect import encoder_floor, fourier, matched_z, noise_mean, swing_scales
import numpy as np

G0 = 9.80665
DEAD_WIDTH = 0.01             # rad/s: the rate over which the sign offset is smoothed
SIGNAL_LINES = 2048           # sine-cosine signal periods per turn of the encoder
STEP_AT = (0.3, 0.7)          # the latency step falls in this fraction of the run


def sign_offset(w: np.ndarray, e0: float) -> np.ndarray:
    """Over-compensated dead band: e0 tanh(w / DEAD_WIDTH)."""
    return e0 * np.tanh(np.asarray(w) / DEAD_WIDTH)


def tick_stamps(enc_t: np.ndarray, tick: float, phase: float) -> np.ndarray:
    """Stamps truncated to whole ticks of a free-running counter (counter phase ``phase``)."""
    u = (enc_t - enc_t[0]) / tick + phase
    return enc_t[0] + (np.floor(u) - phase) * tick


def head_error(phi: np.ndarray, rate: np.ndarray, delta: float) -> np.ndarray:
    """Angle error of a head whose tracks leave quadrature by delta sign(rate) (+-delta/2 each)."""
    u = SIGNAL_LINES * phi
    half = 0.5 * delta * np.sign(rate)
    read = np.arctan2(np.sin(u - half), np.cos(u + half))
    return np.angle(np.exp(1j * (read - u))) / SIGNAL_LINES


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def latency_step(imu_t, gyro, enc_t, enc, stand, rng, delay):
        at = imu_t[0] + rng.uniform(*STEP_AT) * (imu_t[-1] - imu_t[0])
        return imu_t + delay * (imu_t >= at), gyro, enc_t, enc

    def g_scale(imu_t, gyro, enc_t, enc, stand, rng, c):
        return imu_t, gyro * (1 + c * G0 * np.sin(stand(imu_t)[0])), enc_t, enc

    def dead_band(imu_t, gyro, enc_t, enc, stand, rng, e0):
        return imu_t, gyro + sign_offset(gyro, e0), enc_t, enc

    def square_law(imu_t, gyro, enc_t, enc, stand, rng, b):
        return imu_t, gyro + b * gyro * gyro, enc_t, enc

    def counter(imu_t, gyro, enc_t, enc, stand, rng, tick):
        return imu_t, gyro, tick_stamps(enc_t, tick, rng.uniform()), enc

    def rocking_head(imu_t, gyro, enc_t, enc, stand, rng, delta):
        return imu_t, gyro, enc_t, enc + head_error(enc, stand(enc_t)[1], delta)

    return {
        'time_delay': (latency_step, [{'delay': 5e-4}, {'delay': 2e-3}, {'delay': 1.08e-4}]),
        'g_sensitivity': (g_scale, [{'c': 1e-3}, {'c': 4e-3}, {'c': 1.39e-4}]),
        'scale_factor_nonlinearity': (dead_band, [{'e0': 6e-4}, {'e0': 2e-3},
                                                  {'e0': 1.84e-4}]),
        'scale_factor_asymmetry': (square_law, [{'b': 8e-3}, {'b': 3e-2}, {'b': 1.08e-3}]),
        'timestamp_jitter': (counter, [{'tick': 1 / 409.6e3}, {'tick': 1 / 102.4e3},
                                       {'tick': 5.6e-7}]),
        'encoder_cyclic_error': (rocking_head, [{'delta': 2e-3}, {'delta': 6e-3},
                                                {'delta': 3.94e-4}]),
    }


def smoothed_offset(w: np.ndarray, e0: float, s_n: float) -> np.ndarray:
    """Mean of ``sign_offset`` over the gyro's own noise (sd s_n) at the true rate ``w``."""
    return noise_mean(lambda v: sign_offset(v, e0), w, s_n)


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    if name == 'g_sensitivity':
        def err(r, th):
            return p['c'] * G0 * np.sin(amp * np.sin(th)) * r
        return float(np.sqrt(sum(fourier(err, amp * w, k) ** 2 for k in (2, 4, 6)))) / s
    if name == 'scale_factor_nonlinearity':
        s_n = n_arw * np.sqrt(rate_hz)
        th = np.arange(4096) * 2 * np.pi / 4096
        c = np.fft.rfft(smoothed_offset(amp * w * np.cos(th), p['e0'], s_n)) / th.size
        return float(2 * np.linalg.norm(c[2:61]) / s)
    if name == 'scale_factor_asymmetry':
        return p['b'] * (amp * w) ** 2 / 2 / s
    floor = encoder_floor(enc, rate_hz)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'time_delay':
        residual = -rate * p['delay'] * (t >= duration / 2)
    elif name == 'encoder_cyclic_error':
        residual = head_error(phi, rate, p['delta'])
        residual -= np.polyval(np.polyfit(phi, residual, 1), phi)   # offset, scale factor
    else:
        e = tick_stamps(t, p['tick'], 0.0) - t
        residual = -rate * (e - e.mean())
    return matched_z(residual, rate_hz, n_arw,
                     floor + (amp * w) ** 2 / 2 * enc.jitter_s ** 2 / rate_hz)
