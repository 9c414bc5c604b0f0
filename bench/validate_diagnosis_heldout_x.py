"""
Held-out set X of static effect shapes: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_heldout_w.py`` (``shapes(dt, sig, n_arw)``, levels
[weak, strong, edge of detectability on a 2 h record]; the nine names of sets P-W, with
``stale_samples``); every shape is a physical form unlike the catalogue's, the development
shapes (``validate_diagnosis.py``) and held-out sets A-W, and the kinds of departure differ
from shape to shape:

- internal_lowpass: a motor notch: the IMU's own filter chain carries a programmable notch
  (as MEMS parts for drones do), set to the robot's motor frequency NOTCH_HZ = 29.3 Hz: a
  second-order IIR notch (``iirnotch``) of -3 dB width bw, H(z) = (1 - 2 cos w0 z^-1 + z^-2)
  / (1 - 2 r cos w0 z^-1 + r^2 z^-2) up to a gain, started in steady state: unity gain at DC
  and at Nyquist and everywhere else but a hole of depth zero and width bw at the notch,
  1 - |H|^2 a Lorentzian of half width bw / 2; the kernel is a unit spike less a slowly
  decaying cosine (a band-stop, not a roll-off: no smoothing of the high band, no delay);
- vibration: two drives beating as the die warms: the crosstalk between two resonators' drive
  loops on one die (two gyros of the triad, drive frequencies ~20 Hz apart) leaves a tone at
  their difference frequency, and their tempcos differ, so the beat drifts as the die warms
  after power-on: A sin(phi(t') + p), phi' = 2 pi (BEAT_END_HZ + (BEAT_START_HZ - BEAT_END_HZ)
  e^(-t' / BEAT_WARM_S)), t' = t + t0, t0 in 0-60 s: a constant-amplitude tone whose
  frequency settles exponentially from 23.2 Hz to 19.6 Hz (20.9 Hz at 600 s, 19.78 Hz at
  1800 s, within 10 mHz of 19.6 Hz for the last hour): a line that forms as the record goes
  on, on a one-sided skirt reaching up to the cold frequency (not a fixed tone, a linear chirp, a
  sweep, a wander, a coast-down that dies out or an FM);
- temperature_drift: a chattering thermal contact: a grounding finger closes on the module's
  lid as the warm-up (1 - e^(-t' / WARM_S), WARM_S = 900 s) expands the bracket, and the bench's
  micro-vibration makes it touch and let go at random while the gap is near zero; the contact
  stress moves the bias between -A / 2 (open) and +A / 2 (closed): the state is redrawn at
  Poisson times (mean DWELL_S = 25 s apart), closed with chance p(t') = expit((warmth -
  CONTACT_T) / CONTACT_W), CONTACT_T = 0.75 (1248 s after power-on), CONTACT_W = 0.04: a
  two-level bias that chatters for ~10 minutes around 1250 s (5-21 switches, 13 on average,
  a different pattern each record) and stays closed almost always after; its mean path is the
  redraw-lagged p (E[state] 0.37 at 1200 s, 0.94 at 1800 s): a noisy, probabilistic step
  (not a deterministic step, a lagged step, a warm-up, a cycle or a bump);
- bias_instability: stretched-exponential polarisation noise: the die attach's polymer below
  its glass transition relaxes by the Kohlrausch-Williams-Watts law, and (fluctuation-
  dissipation) its polarisation noise, which reaches the sense electrodes, has the same
  correlation: b^2 exp(-(|u| / KWW_S)^KWW_BETA), KWW_S = 100 s, KWW_BETA = 0.15: Gaussian,
  stationary, one continuous stretched relaxation (in effect a one-sided stable law of
  rates, not a grid of Lorentzians, a fractional integrator, switching or events), drawn
  exactly by circulant embedding (the covariance is convex, so the embedding is
  non-negative); its Allan deviation is flat within +-0.03 in log slope from 0.6 to 300 s
  (1/f-like) and falls beyond; 22 % of b^2 decorrelates within one sample (the law's infinitely
  steep start);
- rate_random_walk: sub-diffusion in a viscoelastic adhesive: the stress on the sense element
  is pushed about by the bench's thermal agitation inside a viscoelastic (power-law) adhesive,
  whose memory makes it sub-diffusive: fractional Brownian motion of Hurst SUB_H = 0.3 (the
  generalized Langevin equation of a gel), E[(y(t + u) - y(t))^2] = c^2 (u / 1 s)^(2 SUB_H),
  from zero at the record's start, drawn exactly (circulant embedding of fractional Gaussian
  noise, cumulated): anti-persistent, scale-free increments; Allan variance proportional to
  tau^0.6 at every tau (log slope 0.3 in deviation, between flicker's 0 and a walk's 0.5;
  not a Brownian walk, a persistent fBm, a walk with a reset, a recovery time or jumps);
- gauss_markov: a softened flexure's Brownian motion: an electrostatic spring softening tunes
  the linear stiffness of a suspension flexure out, leaving its cubic (Duffing) stiffness, and
  the flexure's thermal (Brownian) motion in the overdamped squeeze film, which reaches the
  rate through the quadrature, is motion in a purely quartic well: dU = -lam U^3 dt + sqrt(2
  lam) dW (Euler at dt), scaled to sd ``sd``, started in the stationary law e^(-u^4 / 4)
  (platykurtic: kurtosis 2.19): a nonlinear restoring force, quick to pull back large
  excursions and slow near zero, so its autocovariance is the generator's spectrum, sd^2
  sum_k w_k e^(-k-th rate u) (98.4 % in the slowest mode, 1.5 % at 6 times its rate, ...;
  ``quartic_modes``), lam set so the slowest time is tc (every earlier set kept a linear
  drift and an exact exponential);
- quantization: a half-carried remainder: the DSP requantizes each sample's angle increment to
  the step q and carries the remainder to the next sample, but keeps it in half-step units and
  adds it back unscaled (a units slip), so only CARRY = 1/2 of each remainder is carried on:
  u_k = x_k dt / q + e_(k-1) / 2, word round(u_k), e_k = u_k - round(u_k) (uniform, white):
  the rate error -(q / dt) (e_k - e_(k-1) / 2) is half angle quantization, half rate
  quantization (lag-1 correlation -0.4, not -0.5 nor 0), the angle error no longer bounded
  (a walk of the lost halves): Allan excess (v / dt^2) (1 / (4 m) + 3 / (2 m^2)), v = q^2 /
  12, a tau^-1 and a tau^-2 part together (not full error feedback, dither, shaping or a
  step that changes);
- resonance: a fin near flutter: a sheet-metal fin on the bench stand sits in the HVAC jet, its
  bending mode (FIN_HZ = 14.2 Hz) driven by the jet's turbulence (white force of constant
  intensity); as the blower ramps up to full flow over its first RAMP_S = 3600 s the
  aerodynamic (negative) damping eats the structural one, the damping falling linearly from
  q = Q_START = 10 to q = 125 (DROP = 92 %) and then holding: the mode narrows twelvefold and
  its variance grows twelvefold (critical slowing down towards flutter; rms over the record
  sigma, 1.28 sigma in the second hour); built block by block (BLOCK = 5 s) as a complex
  first-order mode, output its real part: a line that sharpens and grows, its record-mean
  spectrum a narrow peak on a broad pedestal (not a fixed mode, a frequency sweep, an onset, a
  gate, a switch or a modulation);
- stale_samples: a check that fails on ones: a marginal SPI data line (a weak pull-up, a slow
  rising edge) corrupts each 1 bit of the 16-bit two's complement rate word (LSB = 0.05
  deg/s) with chance eps, the driver's CRC catches it and republishes the last good sample:
  a sample is held with chance 1 - (1 - eps)^popcount(word), and since a negative word carries
  the sign extension's ones (12-16 of them for the records' small negative words, 1-5 for the
  positive ones) the holds come mostly where the rate is negative: a bit-pattern-dependent,
  sign-dependent hold rule (the record's mean moves up: the negative samples are replaced),
  holds independent from sample to sample given the words (not a periodic freeze, a
  magnitude deadband, a clock, a packet, a latency or a poll phase).

Edge levels (``detectability`` gives z for any level; N = n_arw, sigma = sig, T = n dt, 2 h):

- motor notch: the quadratic detector of a PSD deficit, sqrt(T int_0^(1 / 2 dt) (1 -
  |H|^2)^2 df) (a periodogram's bins weighted by the deficit 1 - |H|^2; pi T bw / 4 for a
  narrow notch);
- drive beat: the energy detector matched to the beat's own periodogram (t0 = 30 s): sqrt(sum_k
  w_k^2), w_k = |FFT(s)_k|^2 / (n sigma^2) over the bins 0 < f < 1 / 2 dt (z goes as A^2);
- chattering contact: matched to its mean path A (E[state] - 1/2) (t0 = 30 s), mean removed:
  |s - mean(s)| / sigma;
- polarisation noise, sub-diffusion, softened flexure: Allan variance excess over N^2 / tau in
  units of the white spread N^2 / tau sqrt(2 / edf), edf = 1.5 T / tau, best tau in [10 dt, T
  / 10]: the first two exactly from their covariance (variogram) on the sample grid
  (``cov_avar``: AVAR(m) = 1/2 sum_k r_k C(k dt), r the Haar window's autocorrelation), the
  flexure as its modes' ``gm_avar``;
- half carry: the rate error's autocovariance (lag 0 v (1 + 1/4) / dt^2, lag 1 -v / (2 dt^2),
  v = q^2 / 12): relative Allan excess at dt less at 10 dt, against sqrt(3 / n + 40 / (3 n))
  (as sets E, I, S, W);
- fin: its record-mean PSD (``fin_psd``: the blocks' Lorentzians and their mirrors, averaged),
  its mean excess over white in the band above half its peak, times sqrt(T B);
- failed checks: the exact repeats of the harness's output (rounded to LSB): the share of zero
  first differences rises from q0 by p (1 - q0), p = E[1 - (1 - eps)^popcount] over the
  records' word law (``crc_share``), z = p sqrt(n (1 - q0) / q0) (as sets P-W).
Edges are set at z ~ 4; weak and strong are several to hundreds of times further in z.
Physical scale: notches of width 2.8 mHz (edge, Q 10350), 0.3 Hz (Q 98) and 4 Hz (Q 7.3; the
gain at 10 and 45 Hz still 0.998); beats of A 0.0053, 0.017 and 0.057 deg/s; contacts of A
0.0053, 0.11 and 0.34 deg/s; polarisation noise of 24, 83 and 250 deg/h sd; sub-diffusions of
c 8.8e-6, 4e-5 and 2e-4 rad/s in 1 s (rms changes of 0.0072, 0.033 and 0.16 deg/s in 2 h);
flexures of 0.0099, 0.057 and 0.14 deg/s sd (tc 2 s, 2 s and 20 s); carried steps q of 5.9,
14 and 41 arcsec (the last above the angle's 14 arcsec walk a sample: its remainders no
longer quite uniform); fins of 0.011, 0.046 and 0.17 deg/s rms; bit-error chances eps of
1.6e-4, 2e-3 and 1e-2 a 1 bit (holds 0.09 %, 1.1 % and 5.5 % of the samples).
"""
from functools import lru_cache
import math

import heldout_detect
from heldout_detect import allan_taus, allan_z, band_excess, gm_avar

import numpy as np

from scipy import fft, linalg, signal, special

from validate_diagnosis_heldout_p import BIAS, LSB, repeat_share

NOTCH_HZ = 29.3                                     # the motor notch's centre, Hz
BEAT_START_HZ, BEAT_END_HZ = 23.4, 19.6             # the drives' beat, cold and warm, Hz
BEAT_WARM_S = 600.0                                 # s: the die's warm-up (the beat's drift)
WARM_S, CONTACT_T, CONTACT_W = 900.0, 0.75, 0.04    # warm-up; the contact's place and spread
DWELL_S = 25.0                                      # s: mean time between contact redraws
KWW_S, KWW_BETA = 100.0, 0.15                      # the polymer's relaxation time and stretch
SUB_H = 0.3                                         # Hurst exponent of the stress sub-diffusion
CARRY = 0.5                                         # share of the remainder carried on
FIN_HZ, Q_START, DROP = 14.2, 10.0, 0.92            # the fin's mode; q at the start; damping lost
RAMP_S = 3600.0                                     # s: the blower's ramp to full flow
BLOCK = 500                                         # samples a damping step of the fin
WORD_BITS = 16                                      # the rate word: two's complement, LSB


def notch(bw: float, dt: float) -> tuple:
    """Return (b, a) of the second-order IIR notch at NOTCH_HZ, -3 dB width ``bw`` Hz."""
    return signal.iirnotch(NOTCH_HZ, NOTCH_HZ / bw, fs=1.0 / dt)


def notched(x: np.ndarray, bw: float, dt: float) -> np.ndarray:
    """Return x through the notch, started in steady state on the first sample."""
    b, a = notch(bw, dt)
    return signal.lfilter(b, a, x, zi=signal.lfilter_zi(b, a) * x[0])[0]


def notch_z(bw: float, dt: float, big_t: float, points: int = 400001) -> float:
    """Return sqrt(T int_0^(1 / 2 dt) (1 - |H|^2)^2 df): the deficit's quadratic detector."""
    b, a = notch(bw, dt)
    half = bw / 2
    lo, hi = np.arctan(-NOTCH_HZ / half), np.arctan((0.5 / dt - NOTCH_HZ) / half)
    phi = np.linspace(lo, hi, points)
    f = NOTCH_HZ + half * np.tan(phi)
    h2 = np.abs(signal.freqz(b, a, worN=f, fs=1.0 / dt)[1]) ** 2
    return float(np.sqrt(big_t * np.trapezoid((1 - h2) ** 2 * half / np.cos(phi) ** 2, phi)))


def beat_phase(t) -> np.ndarray:
    """Return the beat's phase 2 pi int f dt at t after power-on (f settling with BEAT_WARM_S)."""
    t = np.asarray(t, float)
    return 2 * np.pi * (BEAT_END_HZ * t + (BEAT_START_HZ - BEAT_END_HZ) * BEAT_WARM_S
                        * -np.expm1(-t / BEAT_WARM_S))


@lru_cache(maxsize=4)
def beat_unit_z(n: int, dt: float, sig: float) -> float:
    """Return the energy detector's z of the unit-amplitude beat (t0 = 30 s); z goes as A^2."""
    s = np.sin(beat_phase(np.arange(n) * dt + 30.0))
    w = np.abs(np.fft.rfft(s)[1:(n - 1) // 2 + 1]) ** 2 / (n * sig ** 2)
    return float(np.sqrt(np.sum(w * w)))


def warmth(t) -> np.ndarray:
    """Return the die's warm-up 1 - e^(-t / WARM_S) at t after power-on."""
    return -np.expm1(-np.asarray(t, float) / WARM_S)


def contact_p(t) -> np.ndarray:
    """Return the chance that the finger touches at t: a logistic in the die's warmth."""
    return special.expit((warmth(t) - CONTACT_T) / CONTACT_W)


def chatter(n: int, dt: float, t0: float, rng) -> np.ndarray:
    """Return the contact state (0, 1) at t0 + k dt: redrawn ~ contact_p at Poisson times."""
    end = t0 + n * dt
    times = np.cumsum(rng.exponential(DWELL_S, int(end / DWELL_S * 1.5) + 50))
    while times[-1] < end:                                     # rare: draw more
        times = np.r_[times, times[-1] + np.cumsum(rng.exponential(DWELL_S, 100))]
    times = times[times < end]
    states = np.r_[0.0, (rng.uniform(size=times.size) < contact_p(times)).astype(float)]
    return states[np.searchsorted(times, t0 + np.arange(n) * dt, side='right')]


def contact_mean(n: int, dt: float, t0: float = 30.0) -> np.ndarray:
    """Return E[state] on the record: contact_p smoothed at the redraw rate from power-on."""
    pre = int(round(t0 / dt))
    a = np.exp(-dt / DWELL_S)
    p = contact_p((np.arange(pre + n) + 0.5) * dt)
    return signal.lfilter([1 - a], [1.0, -a], p)[pre:]


def circulant_gauss(cov: np.ndarray, rng) -> np.ndarray:
    """Return n samples of a Gaussian series of autocovariance cov[0..n], circulant-embedded."""
    c = np.r_[cov, cov[-2:0:-1]]
    lam = np.clip(fft.fft(c).real, 0.0, None)
    z = rng.standard_normal(c.size) + 1j * rng.standard_normal(c.size)
    return fft.fft(np.sqrt(lam / c.size) * z).real[:cov.size - 1]


def kww_cov(u, b: float) -> np.ndarray:
    """Return the polarisation's autocovariance b^2 exp(-(|u| / KWW_S)^KWW_BETA)."""
    return b * b * np.exp(-(np.abs(np.asarray(u, float)) / KWW_S) ** KWW_BETA)


def haar_lag(m: int) -> tuple:
    """Return (lags 0..2m-1, weights) with AVAR(m) = sum_k weight_k C(k) for a covariance C."""
    k = np.arange(2 * m)
    r = np.where(k <= m, (2 * m - 3 * k), -(2 * m - k)) / m ** 2
    r[0] = 2.0 / m
    return k, np.where(k == 0, 0.5, 1.0) * r


def cov_avar(tau, cov_fn, dt: float) -> np.ndarray:
    """Return the exact Allan variance at tau (m = round(tau / dt) samples) of a covariance."""
    out = []
    for tt in np.atleast_1d(tau):
        k, wt = haar_lag(max(int(round(tt / dt)), 1))
        out.append(np.sum(wt * cov_fn(k * dt)))
    return np.array(out)


def fgn_cov(n: int) -> np.ndarray:
    """Return the unit fractional Gaussian noise's autocovariance at lags 0..n (Hurst SUB_H)."""
    k = np.arange(n + 1, dtype=float)
    h2 = 2 * SUB_H
    return 0.5 * (np.abs(k + 1) ** h2 - 2 * k ** h2 + np.abs(k - 1) ** h2)


def sub_diffusion(n: int, c: float, dt: float, rng) -> np.ndarray:
    """Return fractional Brownian motion of variogram c^2 (u / 1 s)^(2 SUB_H), from zero."""
    return np.cumsum(circulant_gauss(fgn_cov(n), rng)) * c * dt ** SUB_H


def sub_diffusion_avar(tau, c: float, dt: float) -> np.ndarray:
    """Return the Allan variance of ``sub_diffusion``: -sum_k r_k D(k dt) / 2 (D the variogram)."""
    def minus_half_variogram(u):
        return -0.5 * c * c * np.abs(u) ** (2 * SUB_H)
    return cov_avar(tau, minus_half_variogram, dt)


@lru_cache(maxsize=2)
def quartic_modes(points: int = 1601, span: float = 5.0) -> tuple:
    """
    Return (mu_k, w_k, var) of dU = -U^3 dt + sqrt(2) dW, the flexure in units of its well.

    mu_k the generator's decay rates, w_k the weights of U's autocovariance sum_k w_k
    e^(-mu_k t), var U's variance (sum w_k). The generator discretised as a birth-death chain
    on a grid (rates e^(-dV / 2) / h^2, V = u^4 / 4, detailed balance with e^(-V)),
    symmetrised: off-diagonal 1 / h^2.
    """
    u = np.linspace(-span, span, points)
    h = u[1] - u[0]
    v = u ** 4 / 4
    up = np.r_[np.exp(-(v[1:] - v[:-1]) / 2), 0.0] / h ** 2
    down = np.r_[0.0, np.exp(-(v[:-1] - v[1:]) / 2)] / h ** 2
    ev, vec = linalg.eigh_tridiagonal(-(up + down), np.full(points - 1, 1.0 / h ** 2))
    pi = np.exp(-v)
    pi /= pi.sum()
    w = (u * np.sqrt(pi)) @ vec
    keep = ev < -1e-9
    return -ev[keep][::-1], (w[keep] ** 2)[::-1], float(np.sum(pi * u * u))


def quartic_well(n: int, sd: float, tc: float, dt: float, rng) -> np.ndarray:
    """Return the flexure's position in its quartic well (Euler), sd ``sd``, slowest time tc."""
    mu, _, var = quartic_modes()
    lam = 1.0 / (tc * mu[0])
    kick = (np.sqrt(2 * lam * dt) * rng.standard_normal(n)).tolist()
    # the start from the stationary law e^(-u^4 / 4) (by inverse CDF on a grid)
    grid = np.linspace(-5, 5, 20001)
    cdf = np.cumsum(np.exp(-grid ** 4 / 4))
    u = float(np.interp(rng.uniform() * cdf[-1], cdf, grid))
    step = lam * dt
    out = []
    append = out.append
    for g in kick:
        u = u - step * u * u * u + g
        append(u)
    return sd / np.sqrt(var) * np.array(out)


def half_carry(x: np.ndarray, dt: float, q: float, rng) -> np.ndarray:
    """Return the rate words of a requantizer that carries only CARRY of each remainder on."""
    u = np.asarray(x, float) * dt / q
    out = []
    append = out.append
    e = rng.uniform(-0.5, 0.5)
    for uk in u.tolist():
        v = uk + CARRY * e
        w = math.floor(v + 0.5)
        e = v - w
        append(w)
    return np.array(out, float) * (q / dt)


def carry_rel(q: float, m: int, dt: float, n_arw: float) -> float:
    """Return the rate error's Allan variance at m dt relative to white's, N^2 / (m dt)."""
    v = q * q / 12
    r0, r1 = v * (1 + CARRY ** 2) / dt ** 2, -CARRY * v / dt ** 2
    return (r0 / m + (2 * m - 3) * r1 / m ** 2) * m * dt / n_arw ** 2


def fin_blocks(n: int, dt: float) -> tuple:
    """Return the fin's pole radius and its variance gain 1 / (2 (1 - r^2)) for each block."""
    t = (np.arange(0, n, BLOCK) + BLOCK / 2) * dt
    zeta = (1 - DROP * np.minimum(t / RAMP_S, 1.0)) / (2 * Q_START)
    r = np.exp(-2 * np.pi * FIN_HZ * dt * zeta)
    return r, 1.0 / (2 * (1 - r * r))


def fin(n: int, sigma: float, dt: float, rng) -> np.ndarray:
    """Return the fin's rocking, its damping falling block by block, rms sigma over the record."""
    r, gain = fin_blocks(n, dt)
    g = sigma / np.sqrt(np.mean(gain))
    a = r * np.exp(2j * np.pi * FIN_HZ * dt)
    w = (rng.standard_normal(n) + 1j * rng.standard_normal(n)) / np.sqrt(2)
    z = np.sqrt(gain[0]) * (rng.standard_normal() + 1j * rng.standard_normal())   # stationary
    out = np.empty(n, complex)
    for j, aj in enumerate(a):
        s = slice(j * BLOCK, min((j + 1) * BLOCK, n))
        out[s] = signal.lfilter([1.0], [1.0, -aj], w[s], zi=[aj * z])[0]
        z = out[s][-1]
    return g * out.real


def fin_psd(sigma: float, dt: float, n: int):
    """Return the fin's mean one-sided PSD over the record as a function of f."""
    r, gain = fin_blocks(n, dt)
    g2 = sigma ** 2 / np.mean(gain)
    # Blocks after the ramp share one pole: each distinct pole once, weighted by its count.
    r, count = np.unique(r, return_counts=True)
    weight = count / count.sum()

    def psd(f):
        # |1 - r e^(i th)|^2 = 1 - 2 r cos th + r^2, in real arithmetic and in chunks of f
        # (the complex form over 200001 frequencies x the blocks took ~8 s a call).
        f = np.asarray(f, float)
        out = np.empty(f.shape)
        flat, res = f.ravel(), out.reshape(-1)
        for k in range(0, flat.size, 4096):
            fk = flat[k:k + 4096, None]
            lor = sum(1.0 / (1.0 - 2.0 * r * np.cos(2 * np.pi * (FIN_HZ + s * fk) * dt) + r * r)
                      for s in (-1.0, 1.0))
            res[k:k + 4096] = lor @ weight
        return g2 * dt / 2 * out
    return psd


def popcount(words: np.ndarray) -> np.ndarray:
    """Return the number of 1 bits of each WORD_BITS-bit two's complement word."""
    v = np.asarray(words, np.int64) & ((1 << WORD_BITS) - 1)
    count = np.zeros(v.shape, np.int64)
    for bit in range(WORD_BITS):
        count += (v >> bit) & 1
    return count


def crc_holds(x: np.ndarray, eps: float, rng) -> np.ndarray:
    """Return x with each sample whose word fails its check replaced by the last good one."""
    words = np.round(np.asarray(x, float) / LSB)
    fail = rng.uniform(size=x.size) < -np.expm1(popcount(words) * np.log1p(-eps))
    fail[0] = False
    return x[np.maximum.accumulate(np.where(fail, 0, np.arange(x.size)))]


def crc_share(eps: float, sig: float) -> float:
    """Return the share of samples held: E[1 - (1 - eps)^popcount] over the words' law."""
    j = np.arange(np.floor((BIAS - 12 * sig) / LSB), np.ceil((BIAS + 12 * sig) / LSB) + 1)
    p = np.diff(special.ndtr((np.r_[j - 0.5, j[-1] + 0.5] * LSB - BIAS) / sig))
    return float(np.sum(p * -np.expm1(popcount(j) * np.log1p(-eps))))


def shapes(dt: float, sig: float, n_arw: float) -> dict:
    """Return ``{name: (generator, [weak, strong, edge])}`` for the sample time ``dt``."""
    def motor_notch(x, rng, bw):
        """Filter the record by the IMU's notch."""
        return notched(x, bw, dt)

    def drive_beat(x, rng, amplitude):
        """Add the drives' beat, drifting as the die warms."""
        t = np.arange(x.size) * dt + rng.uniform(0, 60)
        return x + amplitude * np.sin(beat_phase(t) + rng.uniform(0, 2 * np.pi))

    def contact(x, rng, amplitude):
        """Add the bias step of a chattering thermal contact."""
        return x + amplitude * (chatter(x.size, dt, rng.uniform(0, 60), rng) - 0.5)

    def relaxation(x, rng, b):
        """Add the polymer's stretched-exponential polarisation noise."""
        cov = kww_cov(np.arange(x.size + 1) * dt, b)
        return x + circulant_gauss(cov, rng)

    def viscoelastic(x, rng, c):
        """Add the stress's sub-diffusion."""
        return x + sub_diffusion(x.size, c, dt, rng)

    def softened(x, rng, sd, tc):
        """Add the softened flexure's Brownian motion."""
        return x + quartic_well(x.size, sd, tc, dt, rng)

    def carry(x, rng, q):
        """Requantize, carrying only part of each remainder."""
        return half_carry(x, dt, q, rng)

    def flutter(x, rng, sigma):
        """Add the fin's mode losing its damping."""
        return x + fin(x.size, sigma, dt, rng)

    def crc(x, rng, eps):
        """Hold the words that fail their check."""
        return crc_holds(x, eps, rng)

    return {
        'internal_lowpass': (motor_notch, [{'bw': 0.3}, {'bw': 4.0}, {'bw': 2.83e-3}]),
        'vibration': (drive_beat, [{'amplitude': 3e-4}, {'amplitude': 1e-3},
                                   {'amplitude': 9.3e-5}]),
        'temperature_drift': (contact, [{'amplitude': 2e-3}, {'amplitude': 6e-3},
                                        {'amplitude': 9.33e-5}]),
        'bias_instability': (relaxation, [{'b': 4e-4}, {'b': 1.2e-3}, {'b': 1.15e-4}]),
        'rate_random_walk': (viscoelastic, [{'c': 4e-5}, {'c': 2e-4}, {'c': 8.77e-6}]),
        'gauss_markov': (softened, [{'sd': 1e-3, 'tc': 2.0}, {'sd': 2.5e-3, 'tc': 20.0},
                                    {'sd': 1.73e-4, 'tc': 2.0}]),
        'quantization': (carry, [{'q': 7e-5}, {'q': 2e-4}, {'q': 2.87e-5}]),
        'resonance': (flutter, [{'sigma': 8e-4}, {'sigma': 3e-3}, {'sigma': 1.856e-4}]),
        'stale_samples': (crc, [{'eps': 2e-3}, {'eps': 1e-2}, {'eps': 1.555e-4}]),
    }


def detectability(name: str, params: dict, dt: float, sig: float, n_arw: float,
                  n: int = 720000) -> float:
    """Analytic z (sigmas above the white baseline's spread) of one level (module docstring)."""
    # Checked against a small Monte Carlo of each statistic on harness records (white + bias,
    # the shape, rounded to the LSB; 2 h, seeds 100-107 unless said; "paired": less the same
    # statistic on the same seed's clean record), edge and weak level, analytic in brackets:
    # motor notch, deficit-weighted periodogram, paired, 3.83 +- 0.27 (4.00) and 41.1 +- 0.3
    # (41.2); drive beat, its energy detector, paired, 3.67 +- 0.39 (4.00, spread 1.1: the
    # settled line carries most of the weight) and 40.4 +- 1.3 (41.6); contact, matched
    # projection, paired, 4.05 +- 0.05 (4.00) and 86.7 +- 0.9 (85.7); polarisation noise,
    # sub-diffusion, softened flexure, paired Allan z at the best tau (720, 720 and 7.9 s),
    # 3.78 +- 0.15 (4.00; 256 seeds), 45.6 +- 2.8 (48.4; 64 seeds); 3.72 +- 0.15 (4.00; 256
    # seeds, the same white records as the line before), 77.5 +- 5.6 (83.2; 64 seeds); 3.87
    # +- 0.21 (4.00), 133.0 +- 2.2 (133.6), and their Allan variances alone (no noise) at 1,
    # 10, 100 and 720 s, mean over paths / analytic: polarisation 0.999-1.07 (100 paths,
    # +-0.001-0.05), sub-diffusion 0.999-1.055 (100 paths, +-0.001-0.05), flexure 0.91-1.01
    # (12 paths, +-0.004-0.08); half carry, relative Allan excess at dt less at 10 dt,
    # paired, 4.03 +- 0.06 (3.99) and 23.55 +- 0.10 (23.75); fin, Welch band excess (L =
    # 16384), paired, 3.88 +- 0.18 (4.00) and 74.1 +- 1.2 (74.3) (with the damping falling
    # to the record's end, Welch's dropped last 73 s held 11 % of the peak: hence the ramp
    # that holds); failed checks, the share of zero first differences, paired, 3.93 +- 0.05
    # (3.99) and 51.1 +- 0.2 (50.9).
    big_t, nn, p = n * dt, n_arw ** 2, params
    if name == 'internal_lowpass':
        return notch_z(p['bw'], dt, big_t)
    if name == 'vibration':
        return beat_unit_z(n, dt, sig) * p['amplitude'] ** 2
    if name == 'temperature_drift':
        s = p['amplitude'] * contact_mean(n, dt)
        return float(np.linalg.norm(s - s.mean()) / sig)
    if name == 'quantization':
        rel = carry_rel(p['q'], 1, dt, n_arw) - carry_rel(p['q'], 10, dt, n_arw)
        return float(rel / np.sqrt(3 / n + 40 / (3 * n)))
    if name == 'resonance':
        ex, width = band_excess(fin_psd(p['sigma'], dt, n), dt, sig)
        return float(ex * np.sqrt(big_t * width))
    if name == 'stale_samples':
        q0 = repeat_share(sig)
        return float(crc_share(p['eps'], sig) * np.sqrt(n * (1 - q0) / q0))
    tau = allan_taus(dt, big_t)
    if name == 'bias_instability':
        excess = cov_avar(tau, lambda u: kww_cov(u, p['b']), dt)
    elif name == 'rate_random_walk':
        excess = sub_diffusion_avar(tau, p['c'], dt)
    else:
        mu, w, var = quartic_modes()
        lam = 1.0 / (p['tc'] * mu[0])
        excess = sum(gm_avar(tau, p['sd'] * np.sqrt(wk / var), 1.0 / (lam * mk))
                     for mk, wk in zip(mu, w) if wk > 1e-12 * var)
    return allan_z(excess, tau, nn, big_t)


def self_check(n: int = 720000) -> None:
    """Build the 27 records as the harness does and time them (``heldout_detect``)."""
    heldout_detect.self_check(shapes, detectability, BIAS, n)


if __name__ == '__main__':
    self_check()
