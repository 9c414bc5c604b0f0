"""The paper's swing model fitted to one record: the baseline every swing twin starts from."""
from dataclasses import dataclass, field
from typing import Optional, Sequence, Tuple

from gyro_char.diagnosis.twins import output_step
from gyro_char.records import Recording
from gyro_char.sim.config import BenchConfig
from gyro_char.swing.filter import estimate_swing
import numpy as np

PRESET = 'adis16405'  # the twins' structure: the fitted numbers override what matters
OUTLIER_MADS = 8.0    # stamps this many median absolute departures off their line: not jitter
TRIM_MIN = 3          # stamps at least kept for the refit


@dataclass
class SwingBaseline:
    """The paper's swing model fitted to one record (SI)."""

    period_s: float
    amplitude: float
    scale_factor_error: float
    bias: float
    drift: float
    N: float
    encoder_sigma: float
    lsb: float
    dt: float
    encoder_dt: float
    duration: float
    axis: str
    # This record's own Kalman estimate (``scale_factor_error`` is what the twin uses: the
    # gyro's one scale-factor error, pooled over the records diagnosed together).
    record_scale_factor_error: float = 0.0
    record_scale_factor_sigma: float = 0.0
    samples: int = 0                # gyro samples analysed (0: not set)
    gyro_start: float = 0.0         # gyro stamps' offset into the encoder interval, s
    # The gyro's static noise terms beyond the white N (IEEE bias instability and rate random
    # walk): a swing record does not pin them (``swing.static_noise``), the twin carries them.
    B: float = 0.0
    K: float = 0.0
    # Standard error of the encoder's white-noise power as calibrated on the record's turning
    # points (``swing_calibrate``); 0 when not calibrated.
    encoder_power_sd: float = 0.0
    # Standard error of log N as calibrated on the residual's gyro band; 0 when not calibrated.
    n_log_sd: float = 0.0
    # The record's IMU stamp latency laid on the twin's samples (s) where its stamps show
    # host stalls (``swing_stalls``), else None: what a stall form puts into a twin's stamps.
    stamp_latency: Optional[np.ndarray] = field(default=None, compare=False, repr=False)

    @property
    def stall_trace(self) -> np.ndarray:
        """Return the stamp latency a twin's stall form carries: the record's, or none."""
        return np.zeros(0) if self.stamp_latency is None else self.stamp_latency

    @property
    def peak_rate(self) -> float:
        return 2.0 * np.pi * self.amplitude / self.period_s

    def to_json(self) -> dict:
        units = {'period_s': 's', 'amplitude': 'rad', 'peak_rate': 'rad/s',
                 'scale_factor_error': '1', 'record_scale_factor_error': '1',
                 'record_scale_factor_sigma': '1', 'bias': 'rad/s', 'drift': 'rad/s^2',
                 'N': 'rad/s^0.5', 'B': 'rad/s', 'K': 'rad/s^1.5', 'encoder_sigma': 'rad',
                 'encoder_power_sd': 'rad^2', 'n_log_sd': '1', 'lsb': 'rad/s', 'dt': 's',
                 'encoder_dt': 's', 'duration': 's'}
        return {k: {'value': float(getattr(self, k)), 'unit': u} for k, u in units.items()}


def sample_numbers(t: np.ndarray) -> np.ndarray:
    """
    Return each stamp's sample number on the nominal grid, dropped samples counted.

    An interval of about k median intervals is k samples (at least one); with no positive
    median interval, one sample a stamp. A long interval is not always a loss: a host that
    stalls stamps its backlog late, in a burst after the stall, every sample kept (15 000
    burst steps of an eighth of an interval on a 15-min 1 kHz run with 207 stalls of 66 ms;
    counted as losses they made the interval 1.4 % short). Of the two numberings, losses
    counted or none, the one that puts the stamps nearer a straight line (``_line_misfit``).
    """
    d = np.diff(np.asarray(t, dtype=np.float64))
    med = float(np.median(d)) if d.size else 0.0
    plain = np.arange(d.size + 1, dtype=np.float64)
    if not med > 0:
        return plain
    lost = np.concatenate([[0.0], np.cumsum(np.maximum(np.round(d / med), 1.0))])
    if lost[-1] == plain[-1] or _line_misfit(t, lost) <= _line_misfit(t, plain):
        return lost
    return plain


def _line_slope(k: np.ndarray, t: np.ndarray) -> float:
    """Return the least-squares slope of the stamps ``t`` on the sample numbers ``k``."""
    k0, t0 = k - k.mean(), t - t.mean()
    return float(np.dot(k0, t0) / np.dot(k0, k0))


def _line_misfit(t: np.ndarray, k: np.ndarray) -> float:
    """Return the median absolute departure of the stamps ``t`` from their line on ``k``."""
    res = (t - t.mean()) - _line_slope(k, t) * (k - k.mean())
    return float(np.median(np.abs(res)))


def stamp_grid(t: np.ndarray) -> Tuple[np.ndarray, float]:
    """
    Return the stamps' sample numbers (``sample_numbers``) and their mean interval.

    The interval is the least-squares slope on the sample numbers, not the span over the
    count: that carries the two end stamps' jitter whole (10-20 us over a 15-min run at
    1 kHz), and a twin whose gyro and encoder intervals differ by it drifts through a
    quarter of the interpolation phase; its residual's increment correlation moved by 2.4
    times its own scatter. The slope is refitted without the stamps far off the line (a
    stall's late backlog: its bursts of latency bent the slope by 3e-7, a quarter interval
    over the run); white jitter keeps them all. Fewer than 3 stamps, or stamps that do not
    advance: the span over the count.
    """
    t = np.asarray(t, dtype=np.float64)
    k = sample_numbers(t)
    if t.size < 3 or not float(np.median(np.diff(t))) > 0:
        return k, float(t[-1] - t[0]) / max(t.size - 1, 1)
    slope = _line_slope(k, t)
    res = (t - t.mean()) - slope * (k - k.mean())
    dev = np.abs(res - np.median(res))
    keep = dev <= OUTLIER_MADS * np.median(dev)
    if TRIM_MIN < np.count_nonzero(keep) < t.size:
        slope = _line_slope(k[keep], t[keep])
    return k, slope


def sample_interval(t: np.ndarray) -> float:
    """Return the mean interval of the stamps ``t`` (``stamp_grid``: dropped samples counted)."""
    return stamp_grid(t)[1]


def static_noise(channel: str, preset: str = PRESET) -> dict:
    """
    Return the gyro's bias instability B and rate random walk K for the twin: the preset's.

    The paper's swing model has white noise only, and a swing record cannot pin B and K: the
    residual fit takes out a bias and a drift, and what is left of a flicker and a random walk
    lies in the few lowest residual-PSD bins, below the swing frequency's neighbourhood where
    the harmonics sit. Left out, the twins missed that low-frequency power (a whole 15-min run
    read it as a misfit that timestamp_jitter soaked up: a false alarm). They are a static
    characterisation's numbers (``gyro-char allan`` on a static record of the same gyro), so
    the twin takes them from the configuration it is compared with, as it takes the encoder's
    level and word steps; a caller with measured values passes its own ``bases``.
    """
    terms = BenchConfig.from_preset(preset).noise.get(channel, {})
    return {'B': float(terms.get('B', 0.0)), 'K': float(terms.get('K', 0.0))}


def fit_baseline(imu: Recording, encoder: Recording, period_s: float,
                 axis: Optional[str] = None) -> SwingBaseline:
    """Fit the paper's swing model to one record (the 5-state Kalman filter's estimates)."""
    run = estimate_swing(imu, encoder, period_s, axis)
    al = run.aligned
    # Mean sample intervals, not medians: a twin whose encoder and gyro rates differ by a
    # jitter-sized amount drifts through the interpolation phase and reshapes the residual PSD.
    dt = sample_interval(al.tau_gyro)
    lsb = output_step(al.rate_gyro)
    est = run.estimates
    # The filter's N covers the output rounding too (lsb^2 dt / 12); the twin adds it back.
    n2 = est.noise_gyro_arw ** 2 - lsb ** 2 * dt / 12.0
    return SwingBaseline(
        period_s=float(period_s), amplitude=float(est.amplitude_encoder.value),
        scale_factor_error=float(est.scale_factor_error.value), bias=float(est.bias.value),
        record_scale_factor_error=float(est.scale_factor_error.value),
        record_scale_factor_sigma=float(est.scale_factor_error.sigma),
        drift=float(est.bias_drift.value),
        N=float(np.sqrt(max(n2, 0.01 * est.noise_gyro_arw ** 2))),
        encoder_sigma=float(est.noise_encoder_rad), lsb=lsb, dt=dt,
        encoder_dt=sample_interval(al.tau_encoder),
        duration=float(min(al.tau_gyro[-1], al.tau_encoder[-1])) + dt,
        axis=al.axis.replace('gyro_', ''), gyro_start=stamp_offset(imu.t, encoder.t),
        **static_noise(al.axis))


def stamp_offset(t_g: np.ndarray, t_e: np.ndarray, count: int = 4096) -> float:
    """
    Where the gyro stamps fall in the encoder's sample interval at the start of the overlap (s).

    The residual interpolates the encoder at the gyro stamps: how much of the encoder's
    white noise passes into it, and how it correlates from sample to sample, depend on that
    position (at one rate, a gyro stamp 0.2 intervals after each encoder sample smooths the
    encoder noise: measured lag-1 increment correlation z = 98 on a 15-min 1 kHz run against
    twins whose stamps coincided). The circular mean of the first ``count`` positions.
    """
    lo = max(t_g[0], t_e[0])
    te = t_e[t_e >= lo]
    tg = t_g[t_g >= lo][:count]
    if te.size < 2 or tg.size < 1:
        return 0.0
    # The mean interval over the whole record: a median of jittered intervals is off by
    # parts in 1e4, which over thousands of samples moves the phase by whole cycles.
    dte = sample_interval(te)
    j = np.arange(min(te.size, count))
    grid = float(np.mean(te[:j.size] - j * dte))     # the encoder's grid, not one stamp
    ph = np.exp(2j * np.pi * (tg - grid) / dte)
    return float(np.angle(np.mean(ph)) % (2.0 * np.pi) / (2.0 * np.pi) * dte)


def pooled_scale_factor(bases: Sequence[SwingBaseline]) -> Tuple[float, float]:
    """Inverse-variance mean of the records' Kalman scale-factor errors, and its sigma."""
    sf = np.array([b.record_scale_factor_error for b in bases])
    sig = np.array([b.record_scale_factor_sigma for b in bases])
    if np.any(sig <= 0) or not np.all(np.isfinite(sig)):
        return float(np.mean(sf)), float(np.std(sf) / np.sqrt(sf.size))
    w = 1.0 / sig ** 2
    return float(np.sum(w * sf) / np.sum(w)), float(1.0 / np.sqrt(np.sum(w)))
