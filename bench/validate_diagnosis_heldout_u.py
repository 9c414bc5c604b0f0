"""
Held-out set U of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_t.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]; the nine names of sets P-T, with
``stale_samples``); every shape is a physical form unlike the catalogue's, the development
shapes (``validate_diagnosis.py``) and held-out sets A-T, and the kinds of departure differ
from shape to shape:

- internal_lowpass: an elliptic anti-alias filter: the ASIC's digital decimation stage ends in
  a third-order elliptic (Cauer) IIR low-pass, rp dB of passband ripple and ELLIP_RS = 40 dB
  of stopband floor, cut-off wn a fraction of Nyquist (odd order: DC gain 1):
  an equiripple passband, a sharp edge and a transmission zero in the stopband, so a spectral
  cliff with a notch beyond it and a ringing (negative-lobed) impulse response, not a smooth
  roll-off;
- vibration: a spread-spectrum fan: a drive-fed fan (FAN_HZ = 21.7 Hz) whose controller
  dithers its speed with a triangular sweep of +-FAN_DEV = 6 % every SWEEP_S = 20 s (to keep
  off a cabinet resonance), so its unbalance rocks the bench with A sin(phi(t)), phi' = 2 pi
  FAN_HZ (1 + FAN_DEV tri(t / SWEEP_S + p)): a flat-topped band 2.6 Hz wide (a comb of lines
  0.05 Hz apart of near-equal height, the sweep's constant slew), neither a line nor a
  horned sinusoidal-FM spectrum;
- temperature_drift: a gradient transient: after power-on the die's top (the ASIC's heat)
  warms with TAU_FAST = 90 s and its base with the package, TAU_SLOW = 1500 s; the bias
  follows the gradient across the die, A (e^(-t' / TAU_SLOW) - e^(-t' / TAU_FAST)) / g_max,
  t' = t + t0, t0 in 0-60 s: a bias that starts near zero, rises to its peak A at ~240 s and
  then decays slowly (non-monotone, from power-on, no step, no cycle);
- bias_instability: granular flicker: a few traps (TRAPS = 12 a part) with correlation times
  drawn log-uniform on 0.05-2e4 s for each part (each record is another part) and variances
  exponentially distributed about b^2 / TRAPS, each a first-order Gauss-Markov process: 1/f
  only on average over parts; a single record's spectrum is a lumpy sum of a dozen
  Lorentzians that scatters from record to record (a population, not a grid);
- rate_random_walk: a radial walk: the bias goes as the magnitude of the die's in-plane shear
  stress (a quadrature coupling through |s|), whose two components creep independently as
  random walks of intensity K from a stress-free start: R = K |W_2(t)|, a two-dimensional
  Bessel process, dR = K dB + K^2 / (2 R) dt: never negative, Rayleigh-distributed at each
  t, pushed away from zero, locally a walk of intensity K (Allan variance ~ K^2 tau / 3);
- gauss_markov: an occupancy diffusion: the share X of a large but finite set of adsorption
  sites occupied follows a Jacobi (Wright-Fisher) diffusion, dX = (OCC - X) / tc dt + s sqrt(X
  (1 - X)) dW, OCC = 0.15, s^2 = 2 / (tc KAPPA), KAPPA = 3: bounded in [0, 1], a skewed Beta
  (0.45, 2.55) marginal piled up near empty, state-dependent noise vanishing at both ends;
  the drift is linear, so the autocovariance is exactly sd^2 e^(-|u| / tc);
- quantization: a metastable latch: the angle counter (step q) is latched asynchronously, and
  when the angle lies within META = 0.2 step of a code edge the latch resolves to either
  neighbouring code with equal chance: the angle error is uniform on a step but widened by
  random decisions near the edges, variance q^2 (1 / 12 + META^2), white while q << N sqrt(dt)
  (a noisy decision at the edges only, no dither over the whole step);
- resonance: a pump that starts: a pump on the bench starts at an unknown time (uniform over
  ONSET = 30-60 % of the record), spins up over SPIN_S = 60 s, and from then on its flow noise
  drives a mount mode (MODE_HZ = 37.5 Hz, q = MODE_Q = 15) of rms sigma: a band that is absent
  for the first third to two thirds of the record and present after it (non-stationary,
  onset);
- stale_samples: a lossy radio with hold concealment: the sensor's samples reach the logger in
  radio packets of PACKET = 5; the link loses packets in bursts (a Gilbert channel: a bad state
  that loses every packet, mean BURST = 3 packets long, a share p of the time), and the
  receiver conceals each lost packet by holding the last sample received: runs of 5, 10,
  15, ... repeats aligned to the packet grid, clustered at random (not periodic), a share p of
  the record.

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- elliptic: lag-1 autocorrelation rho1 = sum h_k h_(k+1) / sum h^2 of the filter's impulse
  response against 1 / sqrt(n) (as sets B-D; the edge's ripple is 0.02 dB. A sharp cut-off
  is seen better by a full spectral test: sqrt(T int (1 - |H|^2)^2 df) over 0-50 Hz is 38,
  298 and 467 for edge, weak and strong: on that scale the edge is a clear effect);
- spread fan: the flat band's mean excess over white, (A^2 / 2) / B / (2 sigma^2 dt) over B =
  2 FAN_DEV FAN_HZ, times sqrt(T B);
- gradient: matched to the noise-free waveform (t0 = 30 s), mean removed: |s - mean(s)| /
  sigma;
- granular flicker, radial walk, occupancy: Allan variance excess over N^2 / tau in units of
  the white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T / 10]:
  the flicker's mean over parts (``gm_avar`` averaged over log-uniform times), the radial walk
  as K^2 tau / 3 (its martingale part; the drift not counted), the occupancy as ``gm_avar``;
- metastable latch: a white angle error of variance v = q^2 (1 / 12 + META^2): relative Allan
  excess 3 v / (dt N^2) at dt less a tenth of it at 10 dt, against sqrt(3 / n + 40 / (3 n))
  (as sets C, O, T);
- pump onset: the mode's one-sided PSD (its AR(2) autocovariance transformed), mean excess
  over white in the band above half its peak, times sqrt(T_on B), T_on the mean time after
  the onset (0.55 T; the spin-up not counted);
- radio: the exact repeats of the harness's output (rounded to LSB = 0.05 deg/s): the share of
  zero first differences rises from q0 to q0 + p (1 - q0), z = p sqrt(n (1 - q0) / q0) (as
  sets P-T).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
"""

import heldout_detect
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar

import numpy as np

from scipy import signal

from validate_diagnosis_heldout_p import BIAS, repeat_share

from validate_diagnosis_heldout_t import ar2_rho, ar2_series

ELLIP_RS = 40.0                                     # dB: stopband floor
FAN_HZ, FAN_DEV, SWEEP_S = 21.7, 0.06, 20.0         # fan speed, its dither, sweep period
TAU_FAST, TAU_SLOW = 90.0, 1500.0                   # s: die top and base warm-up times
TRAPS, TRAP_TAUS = 12, (0.05, 2e4)                  # traps a part; their times' range, s
OCC, KAPPA = 0.15, 3.0                              # mean occupancy; Beta shape alpha + beta
META = 0.2                                          # steps: the latch's metastable window
ONSET, SPIN_S = (0.3, 0.6), 60.0                    # pump start (share of record); spin-up
MODE_HZ, MODE_Q = 37.5, 15.0                        # the mount mode the pump drives
PACKET, BURST = 5, 3.0                              # samples a packet; mean lost burst, packets


def ellip_ba(wn: float, rp: float) -> tuple:
    """Return (b, a) of the third-order elliptic low-pass: cut-off wn of Nyquist, ripple rp dB."""
    return signal.ellip(3, rp, ELLIP_RS, wn)


def ellip_r1(wn: float, rp: float, taps: int = 1 << 16) -> float:
    """Lag-1 autocorrelation of the elliptic filter's output on white input."""
    b, a = ellip_ba(wn, rp)
    imp = np.zeros(taps)
    imp[0] = 1.0
    h = signal.lfilter(b, a, imp)
    return float(np.dot(h[1:], h[:-1]) / np.dot(h, h))


def tri(u) -> np.ndarray:
    """Return the unit triangle wave of period 1, in [-1, 1]."""
    u = np.mod(u, 1.0)
    return 4 * np.abs(u - 0.5) - 1


def spread_tone(n: int, amplitude: float, dt: float, phase: float, sweep: float) -> np.ndarray:
    """Return A sin(phi), phi' = 2 pi FAN_HZ (1 + FAN_DEV tri(t / SWEEP_S + sweep))."""
    t = np.arange(n) * dt
    freq = FAN_HZ * (1 + FAN_DEV * tri(t / SWEEP_S + sweep))
    return amplitude * np.sin(2 * np.pi * np.cumsum(freq) * dt + phase)


def gradient(n: int, amplitude: float, dt: float, start: float) -> np.ndarray:
    """Return A (e^(-t' / TAU_SLOW) - e^(-t' / TAU_FAST)) / g_max, t' = t + start."""
    t = np.arange(n) * dt + start
    peak = np.log(TAU_SLOW / TAU_FAST) * TAU_FAST * TAU_SLOW / (TAU_SLOW - TAU_FAST)
    g_max = np.exp(-peak / TAU_SLOW) - np.exp(-peak / TAU_FAST)
    return amplitude * (np.exp(-t / TAU_SLOW) - np.exp(-t / TAU_FAST)) / g_max


def granular(n: int, b: float, dt: float, rng) -> np.ndarray:
    """Return TRAPS Gauss-Markov traps summed: times log-uniform, variances ~ Exp(b^2 / TRAPS)."""
    lo, hi = np.log(TRAP_TAUS[0]), np.log(TRAP_TAUS[1])
    out = np.zeros(n)
    for _ in range(TRAPS):
        tc = np.exp(rng.uniform(lo, hi))
        sd = b * np.sqrt(rng.exponential() / TRAPS)
        a = np.exp(-dt / tc)
        w = rng.standard_normal(n) * np.sqrt(1 - a * a)
        w[0] = rng.standard_normal()
        out += sd * signal.lfilter([1.0], [1.0, -a], w)
    return out


def granular_avar(tau, b: float, points: int = 400) -> np.ndarray:
    """Return the mean Allan variance of ``granular`` over parts (log-uniform times)."""
    tcs = np.geomspace(TRAP_TAUS[0], TRAP_TAUS[1], points)
    return np.mean([gm_avar(tau, b, tc) for tc in tcs], axis=0)


def radial_walk(n: int, k: float, dt: float, rng) -> np.ndarray:
    """Return K |W_2|: the magnitude of two independent walks of intensity k, from zero."""
    s = k * np.sqrt(dt)
    wx = np.cumsum(s * rng.standard_normal(n))
    wy = np.cumsum(s * rng.standard_normal(n))
    return np.hypot(wx, wy)


def occupancy(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Return the Jacobi diffusion's occupancy, scaled to sd about OCC (Euler, kept in [0, 1])."""
    h = dt / tc
    s = np.sqrt(2 * h / KAPPA)
    g = (s * rng.standard_normal(n)).tolist()
    x = float(rng.beta(KAPPA * OCC, KAPPA * (1 - OCC)))
    out = [0.0] * n
    for k in range(n):
        x += (OCC - x) * h + g[k] * (x * (1 - x)) ** 0.5
        x = -x if x < 0 else (2 - x if x > 1 else x)
        out[k] = x
    scale = sd / np.sqrt(OCC * (1 - OCC) / (KAPPA + 1))
    return scale * (np.array(out) - OCC)


def latch(x: np.ndarray, dt: float, q: float, rng) -> np.ndarray:
    """Return the rate of the latched angle reads: within META of an edge, either code."""
    theta = np.cumsum(np.asarray(x, float) * dt) / q + rng.uniform()
    code = np.round(theta)
    u = theta - code
    flip = (0.5 - np.abs(u) < META) & (rng.uniform(size=u.size) < 0.5)
    code = code + np.where(flip, np.sign(u), 0.0)
    return np.diff(code, prepend=np.round(theta[0] - x[0] * dt / q)) * q / dt


def mode_psd(sigma: float, dt: float, lags: int = 4096, nfft: int = 2 ** 21):
    """Return the one-sided PSD of the unit-variance AR(2) mode times sigma^2, as a function."""
    cov = sigma * sigma * ar2_rho(MODE_HZ, MODE_Q, dt, lags)
    two = np.zeros(nfft)
    two[:lags] = cov
    two[-lags + 1:] = cov[1:][::-1]
    spec = 2 * dt * np.fft.rfft(two).real
    grid = np.fft.rfftfreq(nfft, dt)
    return lambda f: np.interp(f, grid, spec)


def pump(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Return the mode of rms sigma, off before the pump starts and ramped over SPIN_S."""
    start = rng.uniform(*ONSET) * n * dt
    t = np.arange(n) * dt
    env = np.clip((t - start) / SPIN_S, 0.0, 1.0)
    return sigma * env * ar2_series(n, MODE_HZ, MODE_Q, dt, rng)


def radio(x: np.ndarray, p: float, rng) -> np.ndarray:
    """Return x with the Gilbert channel's lost packets held at the last sample received."""
    n = x.size
    packets = -(-n // PACKET)
    leave = 1.0 / BURST
    enter = p / (BURST * (1 - p))
    bad = np.zeros(packets, bool)
    state = rng.uniform() < p
    draws = rng.uniform(size=packets).tolist()
    for j in range(packets):
        bad[j] = state
        state = (draws[j] >= leave) if state else (draws[j] < enter)
    lost = np.repeat(bad, PACKET)[:n]
    idx = np.where(lost, -1, np.arange(n))
    idx = np.maximum.accumulate(idx)
    return x[np.maximum(idx, 0)]


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def elliptic(x, rng, wn, rp):
        """Third-order elliptic anti-alias low-pass."""
        b, a = ellip_ba(wn, rp)
        zi = signal.lfilter_zi(b, a) * x[0]
        return signal.lfilter(b, a, x, zi=zi)[0]

    def spread_fan(x, rng, amplitude):
        """Fan with a triangular speed dither."""
        return x + spread_tone(x.size, amplitude, dt, rng.uniform(0, 2 * np.pi), rng.uniform())

    def die_gradient(x, rng, amplitude):
        """Die gradient after power-on."""
        return x + gradient(x.size, amplitude, dt, rng.uniform(0, 60))

    def granular_flicker(x, rng, b):
        """Sum a dozen random traps."""
        return x + granular(x.size, b, dt, rng)

    def radial(x, rng, k):
        """Magnitude of a two-dimensional stress walk."""
        return x + radial_walk(x.size, k, dt, rng)

    def sites(x, rng, sd, tc):
        """Jacobi occupancy diffusion."""
        return x + occupancy(x.size, sd, tc, dt, rng)

    def metastable(x, rng, q):
        """Asynchronously latched angle counter."""
        return latch(x, dt, q, rng)

    def pump_mode(x, rng, sigma):
        """Mount mode driven from the pump's start."""
        return x + pump(x.size, sigma, dt, rng)

    def lossy_radio(x, rng, p):
        """Bursty packet loss, held."""
        return radio(x, p, rng)

    return {
        'internal_lowpass': (elliptic, [{'wn': 0.7, 'rp': 0.5}, {'wn': 0.35, 'rp': 1.0},
                                        {'wn': 0.9925, 'rp': 0.02}]),
        'vibration': (spread_fan, [{'amplitude': 2e-3}, {'amplitude': 8e-3},
                                   {'amplitude': 3.85e-4}]),
        'temperature_drift': (die_gradient, [{'amplitude': 1e-3}, {'amplitude': 4e-3},
                                             {'amplitude': 1.165e-4}]),
        'bias_instability': (granular_flicker, [{'b': 3.5e-4}, {'b': 1.4e-3}, {'b': 9.7e-5}]),
        'rate_random_walk': (radial, [{'k': 6e-6}, {'k': 3e-5}, {'k': 2.03e-6}]),
        'gauss_markov': (sites, [{'sd': 1e-3, 'tc': 3.0}, {'sd': 2e-3, 'tc': 30.0},
                                 {'sd': 1.55e-4, 'tc': 3.0}]),
        'quantization': (metastable, [{'q': 1e-4}, {'q': 3e-4}, {'q': 1.67e-5}]),
        'resonance': (pump_mode, [{'sigma': 1.5e-3}, {'sigma': 6e-3}, {'sigma': 4.4e-4}]),
        'stale_samples': (lossy_radio, [{'p': 0.01}, {'p': 0.05}, {'p': 9e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    # Checked against a small Monte Carlo on harness records (white + bias, the shape, rounded
    # to the LSB; 2 h, seeds 100-103; "paired": less the same statistic on the same seed's
    # clean record), edge and weak level, analytic in brackets: elliptic, lag-1 correlation x
    # sqrt(n), paired 3.83 +- 0.14 (4.00) and 271.5 +- 0.7 (271.7); radio, zero-difference
    # share in units of the white spread sqrt(q0 (1 - q0) / n), paired 3.6 +- 0.8 (4.00) and
    # 45.0 +- 1.9 (44.4), the bursts' clustering widening the spread. The other shapes' z are
    # the closed forms of the module docstring, not checked by Monte Carlo in this session.
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return float(ellip_r1(p['wn'], p['rp']) * np.sqrt(n))
    if name == 'vibration':
        width = 2 * FAN_DEV * FAN_HZ
        ex = p['amplitude'] ** 2 / 2 / width / (2 * sig * sig * dt)
        return float(ex * np.sqrt(big_t * width))
    if name == 'temperature_drift':
        s = gradient(n, p['amplitude'], dt, 30.0)
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        v = p['q'] ** 2 * (1 / 12 + META ** 2)
        rel = 3 * v / (dt * nn) * (1 - 1 / 10)
        return float(rel / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(mode_psd(p['sigma'], dt), dt, sig)
        return float(ex * np.sqrt(big_t * (1 - np.mean(ONSET)) * width))
    if name == 'stale_samples':
        q0 = repeat_share(sig)
        return float(p['p'] * np.sqrt(n * (1 - q0) / q0))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = granular_avar(tau, p['b'])
    elif name == 'rate_random_walk':
        excess = p['k'] ** 2 * tau / 3
    else:
        excess = gm_avar(tau, p['sd'], p['tc'])
    return allan_z(excess, tau, nn, big_t)


def self_check(n: int = 720000) -> None:
    """Build the 27 records as the harness does and time them (``heldout_detect``)."""
    heldout_detect.self_check(shapes, detectability, BIAS, n)


if __name__ == '__main__':
    self_check()
