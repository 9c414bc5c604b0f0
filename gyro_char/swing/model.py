"""
The paper's 5-state swing model (docs/method.md section 1) and the estimates (1)-(3) it yields.

State at time t (tau = t - t_ref, the common reference epoch of both filters):
X1 = A sin(w tau + psi0), X2 = A cos(w tau + psi0), X3 = phi0 + w0 tau + wdot0 tau^2/2,
X4 = w0 + wdot0 tau, X5 = wdot0, with w = 2 pi / T. Measurement z = X1 + X3.

Because the model's parameters are constants, ``H Phi(tau) X(t_ref) = g(tau) . X(t_ref)`` with
``g = [cos w tau, sin w tau, 1, tau, tau^2/2]``: every filter here is parameterised by
theta = X(t_ref), from which the state at any later stamp follows by ``Phi``.

Noise model (Q, R), derived from the sensors instead of hand-tuned:

- encoder: white angle noise, R = sigma_enc^2 (level and word quantization d1^2/12 + d2^2/12,
  ADC noise), Q = 0 (the stand's swing parameters are constants of the run);
- integrated gyro angle: the rate's white noise (and its output quantization, also white in
  rate) integrates into an angle random walk, so it is process noise on X3 with
  Q33 = N^2 dt_i (N the rate noise density, rad/sqrt(s)) and R = 0 after the first sample
  (whose variance N^2 * 1 s is arbitrary: the integration constant is absorbed by phi0).

``None`` for a noise level means "estimate it from the fit residuals" (the estimates do not depend
on the noise scale, only their sigmas do).
"""
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Optional

import numpy as np

# Diffuse prior on theta = X(t_ref): (X1, X2, X3, X4, X5) in rad, rad, rad, rad/s, rad/s^2.
PRIOR_SD = np.array([1.0, 1.0, 1.0, 1.0, 0.01])
# Variance of the gyro filter's first measurement, in units of N^2 (seconds): see module doc.
GYRO_ANCHOR_S = 1.0
# Time unit of the scaled regressors (numerical conditioning of tau and tau^2/2 columns).
TIME_SCALE_S = 100.0
# Block length (swing periods) of the gyro's low-frequency noise check (swing_batch).
LONG_BLOCK_PERIODS = 10.0


def transition(dt: float, period_s: float) -> np.ndarray:
    """Phi for one step of ``dt`` seconds (docs/method.md; per step: non-uniform sampling)."""
    a = 2.0 * np.pi * dt / period_s
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0.0, 0.0, 0.0],
                     [-s, c, 0.0, 0.0, 0.0],
                     [0.0, 0.0, 1.0, dt, 0.5 * dt * dt],
                     [0.0, 0.0, 0.0, 1.0, dt],
                     [0.0, 0.0, 0.0, 0.0, 1.0]])


H = np.array([[1.0, 0.0, 1.0, 0.0, 0.0]])
E3 = np.array([0.0, 0.0, 1.0, 0.0, 0.0])


def regressor(tau: float, period_s: float) -> np.ndarray:
    """g(tau) with ``z(t_ref + tau) = g . X(t_ref)`` (unscaled)."""
    a = 2.0 * np.pi * tau / period_s
    return np.array([np.cos(a), np.sin(a), 1.0, tau, 0.5 * tau * tau])


def scaling() -> np.ndarray:
    """D with ``g = D u``: the scaled regressors u use tau / TIME_SCALE_S."""
    ts = TIME_SCALE_S
    return np.array([1.0, 1.0, 1.0, ts, ts * ts])


def prior_information_sqrt() -> np.ndarray:
    """Upper-triangular square root of the prior information on the scaled parameters D theta."""
    return np.diag(1.0 / (scaling() * PRIOR_SD))


@dataclass
class SwingNoise:
    """Noise levels: encoder white angle noise (rad) and gyro rate noise density (rad/sqrt(s))."""

    encoder_sigma: Optional[float] = None
    gyro_arw: Optional[float] = None

    @staticmethod
    def from_sensors(encoder_d1: float = 0.0, encoder_d2: float = 0.0,
                     encoder_adc_sigma: float = 0.0, gyro_arw: float = 0.0,
                     gyro_dh: float = 0.0, gyro_dt: float = 0.0) -> 'SwingNoise':
        """
        Derive the filter noise from sensor specifications.

        Quantization steps add step^2/12 each; the gyro's output quantization ``gyro_dh`` (rad/s)
        sampled every ``gyro_dt`` s is white rate noise of density dH * sqrt(dt / 12).
        """
        enc_var = encoder_d1 ** 2 / 12 + encoder_d2 ** 2 / 12 + encoder_adc_sigma ** 2
        gyro_var = gyro_arw ** 2 + gyro_dh ** 2 * gyro_dt / 12
        return SwingNoise(float(np.sqrt(enc_var)) if enc_var > 0 else None,
                          float(np.sqrt(gyro_var)) if gyro_var > 0 else None)


@dataclass
class Estimate:
    """A value with its 1-sigma from the filter covariance, in SI ``unit``."""

    value: float
    sigma: float
    unit: str


@dataclass
class FilterResult:
    """One filter's final state: X and P at ``tau`` (s after t_ref), and what it was fed."""

    x: np.ndarray
    P: np.ndarray
    tau: float
    samples: int
    noise: float          # the noise level used (rad for the encoder, rad/sqrt(s) for the gyro)
    noise_estimated: bool
    # The deterministic model's parameters X(t_ref) (without the gyro's random walk), for plots.
    theta: Optional[np.ndarray] = None
    # Gyro: scale on the bias/drift sigmas from the low-frequency noise check
    # (swing_batch.low_frequency_scale) and the measured ratio (None: not checked).
    rate_sigma_scale: float = 1.0
    low_frequency_ratio: Optional[float] = None

    def amplitude(self) -> Estimate:
        a = float(np.hypot(self.x[0], self.x[1]))
        j = np.array([self.x[0], self.x[1], 0.0, 0.0, 0.0]) / max(a, 1e-300)
        return Estimate(a, float(np.sqrt(max(j @ self.P @ j, 0.0))), 'rad')

    def w0(self) -> Estimate:
        """w0_hat = X4 - X5 tau: the rate offset at t_ref."""
        j = np.array([0.0, 0.0, 0.0, 1.0, -self.tau])
        sigma = float(np.sqrt(max(j @ self.P @ j, 0.0))) * self.rate_sigma_scale
        return Estimate(float(j @ self.x), sigma, 'rad/s')

    def wdot0(self) -> Estimate:
        sigma = float(np.sqrt(max(self.P[4, 4], 0.0))) * self.rate_sigma_scale
        return Estimate(float(self.x[4]), sigma, 'rad/s^2')


@dataclass
class SwingEstimates:
    """The paper's estimates (1)-(3) plus what they rest on."""

    scale_factor_error: Estimate
    bias: Estimate
    bias_drift: Estimate
    amplitude_encoder: Estimate
    amplitude_gyro: Estimate
    period_s: float
    samples_encoder: int
    samples_gyro: int
    converged: bool
    noise_encoder_rad: float = float('nan')
    noise_gyro_arw: float = float('nan')
    notes: List[str] = field(default_factory=list)

    @property
    def samples(self) -> int:
        return self.samples_encoder + self.samples_gyro

    def to_json(self) -> Dict:
        """Return the ``swing.json`` contract of docs/design.md (exactly these keys)."""
        out = {k: asdict(getattr(self, k)) for k in
               ('scale_factor_error', 'bias', 'bias_drift', 'amplitude_encoder',
                'amplitude_gyro')}
        out['scale_factor_error']['unit'] = '1'
        out['period_s'] = float(self.period_s)
        out['samples'] = int(self.samples)
        return out


def _own(gyro: Estimate, enc: Estimate, rho: Estimate) -> Estimate:
    """
    Return the gyro's own rate error: gyro - (1 + rho) * encoder.

    The gyro senses the stand's own axis drift through its scale factor, so the paper's plain
    difference (2)/(3) keeps rho times the stand's drift (e.g. 1.85 % of 2e-6 rad/s for a FOG,
    a third of its 15-min bias sigma); scaling the encoder term by (1 + rho) removes it.
    """
    k = 1.0 + rho.value
    var = gyro.sigma ** 2 + (k * enc.sigma) ** 2 + (enc.value * rho.sigma) ** 2
    return Estimate(gyro.value - k * enc.value, float(np.sqrt(var)), gyro.unit)


def combine(enc: FilterResult, gyro: FilterResult, period_s: float,
            notes: Optional[List[str]] = None, gyro_gain: float = 1.0) -> SwingEstimates:
    """
    Estimates (1)-(3) from the two filters (independent sensors: variances add).

    Bias and drift are (2) and (3) with the stand's drift as the gyro sees it removed: the
    gyro term minus (1 + rho) times the encoder term (``_own``).

    ``gyro_gain`` is the integration rule's gain at the swing period (``swing_align.
    trapezoid_gain``); the gyro amplitude is divided by it.

    ``converged`` is True when both amplitudes are determined to better than 1 % (1 sigma) and the
    bias to better than the rate amplitude: a rough "enough data" flag for live use.
    """
    notes = list(notes or [])
    if gyro.rate_sigma_scale > 1.0:
        notes.append(f'gyro noise over {LONG_BLOCK_PERIODS:g}-period blocks is '
                     f'{gyro.rate_sigma_scale:.2f}x the white level (bias instability / rate '
                     'random walk): bias and drift sigmas scaled by that factor (still a lower '
                     'bound for flicker noise)')
    a_e, a_g = enc.amplitude(), gyro.amplitude()
    a_g = Estimate(a_g.value / gyro_gain, a_g.sigma / gyro_gain, a_g.unit)
    rho = a_g.value / a_e.value - 1.0 if a_e.value > 0 else float('nan')
    rho_sigma = float(np.hypot(a_g.sigma / a_e.value, a_g.value * a_e.sigma / a_e.value ** 2)) \
        if a_e.value > 0 else float('nan')
    sfe = Estimate(float(rho), rho_sigma, '1')
    bias = _own(gyro.w0(), enc.w0(), sfe)
    converged = bool(a_e.value > 0 and a_g.value > 0
                     and a_e.sigma < 0.01 * a_e.value and a_g.sigma < 0.01 * a_g.value
                     and bias.sigma < 2 * np.pi / period_s * a_e.value)
    return SwingEstimates(
        scale_factor_error=sfe, bias=bias, bias_drift=_own(gyro.wdot0(), enc.wdot0(), sfe),
        amplitude_encoder=a_e, amplitude_gyro=a_g, period_s=float(period_s),
        samples_encoder=enc.samples, samples_gyro=gyro.samples, converged=converged,
        noise_encoder_rad=enc.noise, noise_gyro_arw=gyro.noise, notes=notes)
