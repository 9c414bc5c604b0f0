"""
The fast kernel of the swing filter: a square-root information filter (SRIF) over chunks.

For this model (constant parameters; for the gyro, a random walk on X3 observed without white
noise) the Kalman filter's state at the last sample is an exact linear function of
theta = X(t_ref), and the filter's information about theta is a sum over measurement rows:

- encoder sample i:   z_i            = g(tau_i) . theta + v_i,         var sigma_enc^2
- gyro sample 0:      z_0            = g(tau_0) . theta + v_0,         var N^2 * GYRO_ANCHOR_S
- gyro sample 1:      z_1            = g(tau_1) . theta + w_1,         var N^2 dt_1
- gyro sample i >= 2: z_i - z_{i-1}  = (g_i - g_{i-1}) . theta + w_i, var N^2 dt_i

(the random walk's increments w_i are independent). Each chunk of rows is folded into a 6x6
upper-triangular factor by one LAPACK QR (Householder, numerically stable: no normal
equations), so a 900 k-sample record costs a few tens of milliseconds and the per-chunk online
path is the same code. The residual sum of squares is the factor's last diagonal element
squared, which gives the noise level when it is not supplied. The state and covariance at the
last sample are then X_N = M theta + e3 z_N, P_N = M P_theta M^T with M = Phi(tau_N) for the
encoder and M = Phi(tau_N) - e3 g_N^T for the gyro (N >= 1), exactly what the recursive filter
(``swing_kf.SwingKalman``) carries; tests check the two agree.

Gaps in the gyro stamps (dropped messages, stalls): the motion during a gap is unknown, so the
angle integrated across it carries an unknown offset. A gyro step longer than
GAP_RELEASE_FACTOR times the reference interval (the median step of the first chunk) therefore
contributes no increment row: that is exactly the recursive filter with infinite process noise
on X3 in that predict step (the offset is released and re-learned from the following samples,
A, phase, bias and drift carry over), and X_N = M theta + e3 z_N stays exact because z_N - g_N
theta is the accumulated offset whatever it includes. The noise-level blocks skip increments
that span a released gap. Steps of up to 3 intervals (1-2 dropped samples) stay integrated:
their trapezoid error, about h^3 w^3 A / 12, is 1.6 nrad at h = 3 ms for the stand presets'
A = 20 deg, T = 5 s, 35 times below the angle noise N sqrt(h) of a FOG with N = 1e-6
rad/sqrt(s) (55 nrad) and 2e4 times below a MEMS's; releasing would cost an increment of
information per gap for nothing, and sample-clock jitter stays far below 3.5 intervals.
"""
from dataclasses import dataclass, field
from typing import Optional, Tuple

from gyro_char.swing.model import (E3, FilterResult, GYRO_ANCHOR_S, LONG_BLOCK_PERIODS,
                                   prior_information_sqrt, regressor, scaling, TIME_SCALE_S,
                                   transition)
import numpy as np
from scipy.linalg.lapack import dgeqrf
from scipy.stats import chi2

ENCODER = 'encoder'
GYRO = 'gyro'
NOISE_BLOCK = 64  # gyro samples per increment when estimating N from the residuals
MIN_BLOCKS = 20
QR_ROWS = 1024
MIN_LONG_BLOCKS = 8
GAP_RELEASE_FACTOR = 3.5  # a gyro step longer than this many reference intervals releases X3


def encoder_rows(tau: np.ndarray, z: np.ndarray, period_s: float):
    """Scaled regressor rows U (n x 5), observations y and sqrt-weights (unit noise)."""
    a = (2.0 * np.pi / period_s) * tau
    s = tau / TIME_SCALE_S
    u = np.column_stack([np.cos(a), np.sin(a), np.ones_like(s), s, 0.5 * s * s])
    return u, z, np.ones_like(z)


def increment_rows(t0: np.ndarray, t1: np.ndarray, z0: np.ndarray, z1: np.ndarray,
                   period_s: float):
    """Rows for angle increments z1 - z0 over [t0, t1], variance N^2 (t1 - t0), unit N."""
    w = 2.0 * np.pi / period_s
    dt = t1 - t0
    # Differences by product identities: no cancellation between nearby cos/sin values.
    mid, half = 0.5 * w * (t1 + t0), 0.5 * w * dt
    sh = np.sin(half)
    s1, s0 = t1 / TIME_SCALE_S, t0 / TIME_SCALE_S
    du = np.column_stack([-2.0 * np.sin(mid) * sh, 2.0 * np.cos(mid) * sh, np.zeros_like(dt),
                          s1 - s0, 0.5 * (s1 + s0) * (s1 - s0)])
    return du, z1 - z0, 1.0 / np.sqrt(dt)


def gyro_rows(tau: np.ndarray, z: np.ndarray, period_s: float, start_index: int,
              prev: Optional[Tuple[float, float]], released: Optional[np.ndarray] = None):
    """
    Rows for gyro samples ``start_index ...`` (see module doc), unit noise density.

    ``prev`` is (tau, z) of the sample before this chunk (None when ``start_index`` is 0);
    samples flagged in ``released`` follow a gap and get a zero-weight row (module doc).
    """
    # Pad with the previous sample (or a dummy one step back: its row is never used).
    p_tau, p_z = prev if prev is not None else (tau[0] - 1.0, z[0])
    du, dz, sw = increment_rows(np.concatenate([[p_tau], tau[:-1]]), tau,
                                np.concatenate([[p_z], z[:-1]]), z, period_s)
    k = start_index + np.arange(len(tau))
    if k[0] < 2:
        # Samples 0 (anchor) and 1 are absolute rows; later samples are increments.
        u_abs, _, _ = encoder_rows(tau, z, period_s)
        absolute = k < 2
        du[absolute] = u_abs[absolute]
        dz[absolute] = z[absolute]
        sw[k == 0] = 1.0 / np.sqrt(GYRO_ANCHOR_S)
    if released is not None:
        sw[released] = 0.0
    return du, dz, sw


class Srif:
    """Square-root information (data only, unit noise) of the scaled parameters and the RSS."""

    def __init__(self) -> None:
        self.r = np.zeros((0, 6))
        self.rows = 0

    def add(self, u: np.ndarray, y: np.ndarray, sw: np.ndarray) -> None:
        if len(y) == 0:
            return
        rows = np.empty((len(y), 6))
        rows[:, :5] = u * sw[:, None]
        rows[:, 5] = y * sw
        # Blocks of QR_ROWS rows, each stacked under the current factor: cache-sized LAPACK
        # calls that stay single-threaded (multi-threaded BLAS on a loaded box is far slower).
        for lo in range(0, len(y), QR_ROWS):
            blk = rows[lo:lo + QR_ROWS]
            k = self.r.shape[0]
            a = np.empty((k + len(blk), 6), order='F')
            a[:k] = self.r
            a[k:] = blk
            qr, _, _, info = dgeqrf(a, overwrite_a=1)
            if info != 0:
                raise ArithmeticError(f'QR failed (LAPACK info {info})')
            self.r = np.triu(qr[:6])
        self.rows += int(np.count_nonzero(sw))  # zero-weight (released) rows carry nothing

    @property
    def rss(self) -> float:
        """Residual sum of squares of the data-only least-squares fit (unit noise)."""
        return float(self.r[5, 5] ** 2) if self.r.shape[0] == 6 else 0.0

    def noise_scale(self, factor: float = 1.0) -> Optional[float]:
        """Noise level from the residuals, sqrt(factor RSS / (rows - 5)); None if undetermined."""
        if self.rows <= 5:
            return None
        return float(np.sqrt(factor * self.rss / (self.rows - 5)))

    def solve(self, noise: float) -> Tuple[np.ndarray, np.ndarray]:
        """Return theta = X(t_ref) and its covariance, with the prior and data noise ``noise``."""
        prior = np.zeros((5, 6))
        prior[:, :5] = prior_information_sqrt()
        r = np.linalg.qr(np.vstack([prior, self.r / noise]), mode='r')
        r5 = r[:5, :5]
        # 5x5: numpy's inverse is ~50x cheaper per call than scipy's triangular solve here.
        r_inv = np.linalg.inv(r5)
        theta_u = r_inv @ r[:5, 5]
        d = scaling()
        return theta_u / d, (r_inv @ r_inv.T) / np.outer(d, d)


@dataclass
class StreamState:
    """What a filter needs beyond its factor: sample count, last (tau, z), noise setting."""

    kind: str
    noise: Optional[float]
    count: int = 0
    last_tau: float = float('nan')
    last_z: float = float('nan')
    # Gyro noise-level estimation on block increments (see ``gyro_noise``).
    blocks: Srif = field(default_factory=Srif)
    knot_tau: float = float('nan')
    knot_z: float = float('nan')
    # Low-frequency check on increments over LONG_BLOCK_PERIODS swing periods (time-defined).
    long_blocks: Srif = field(default_factory=Srif)
    long_knot: Tuple[float, float, int] = (float('nan'), float('nan'), -1)
    # Gap release (module doc): reference interval, gaps released so far (the segment index).
    dt_ref: float = float('nan')
    gaps: int = 0
    knot_gaps: int = 0
    long_knot_gaps: int = 0


def gap_steps(st: StreamState, tau: np.ndarray) -> np.ndarray:
    """
    Flag the gyro samples of a chunk that end a step longer than the release limit.

    The reference interval is the median step of the first chunk with two samples; a chunk's
    first step is from the stream's last sample. Does not change the counters (``fold`` does).
    """
    prev = st.last_tau if st.count else np.nan
    steps = np.diff(tau, prepend=prev)
    if not np.isfinite(st.dt_ref):
        pos = steps[np.isfinite(steps) & (steps > 0)]
        if pos.size:
            st.dt_ref = float(np.median(pos))
    with np.errstate(invalid='ignore'):
        return steps > GAP_RELEASE_FACTOR * st.dt_ref


def _span_rows(kt, kz, kg, period_s):
    """Increment rows between successive knots, zero weight where a released gap lies between."""
    u, y, sw = increment_rows(kt[:-1], kt[1:], kz[:-1], kz[1:], period_s)
    sw[kg[1:] != kg[:-1]] = 0.0
    return u, y, sw


def _fold_blocks(st: StreamState, tau: np.ndarray, z: np.ndarray, seg: np.ndarray,
                 period_s: float) -> None:
    """Add the increments between every NOISE_BLOCK-th gyro sample (global index) to st.blocks."""
    k = st.count + np.arange(len(tau))
    knots = k % NOISE_BLOCK == 0
    kt, kz, kg = tau[knots], z[knots], seg[knots]
    if np.isfinite(st.knot_tau):
        kt, kz = np.concatenate([[st.knot_tau], kt]), np.concatenate([[st.knot_z], kz])
        kg = np.concatenate([[st.knot_gaps], kg])
    if kt.size >= 2:
        st.blocks.add(*_span_rows(kt, kz, kg, period_s))
    if kt.size:
        st.knot_tau, st.knot_z, st.knot_gaps = float(kt[-1]), float(kz[-1]), int(kg[-1])


def _fold_long_blocks(st: StreamState, tau: np.ndarray, z: np.ndarray, seg: np.ndarray,
                      period_s: float) -> None:
    """Add increments between the first samples of successive time blocks to st.long_blocks."""
    idx = np.floor(tau / (LONG_BLOCK_PERIODS * period_s)).astype(np.int64)
    first = np.empty(idx.size, dtype=bool)
    first[0] = idx[0] != st.long_knot[2]
    first[1:] = idx[1:] != idx[:-1]
    kt, kz, kg = tau[first], z[first], seg[first]
    if st.long_knot[2] >= 0:
        kt = np.concatenate([[st.long_knot[0]], kt])
        kz = np.concatenate([[st.long_knot[1]], kz])
        kg = np.concatenate([[st.long_knot_gaps], kg])
    if kt.size >= 2:
        st.long_blocks.add(*_span_rows(kt, kz, kg, period_s))
    if kt.size:
        st.long_knot = (float(kt[-1]), float(kz[-1]), int(idx[-1]))
        st.long_knot_gaps = int(kg[-1])


def low_frequency_scale(st: StreamState, noise: float) -> Tuple[float, Optional[float]]:
    """
    Sigma scale for the gyro's bias and drift, and the measured low-frequency noise ratio.

    The filter's noise model is white rate noise; a gyro's bias instability (flicker) and rate
    random walk add power at low frequencies, which is where bias and drift are estimated. The
    residual increments over blocks of LONG_BLOCK_PERIODS periods measure the noise density
    there; when it exceeds ``noise`` significantly (chi-square test at 95 %), bias and drift
    sigmas are scaled by the ratio. Returns (1, None) with fewer than MIN_LONG_BLOCKS blocks.
    """
    rows = st.long_blocks.rows
    if rows < MIN_LONG_BLOCKS:
        return 1.0, None
    ratio = st.long_blocks.noise_scale() / noise
    dof = rows - 5
    return (ratio if ratio ** 2 > chi2.ppf(0.95, dof) / dof else 1.0), ratio


def gyro_noise(srif: Srif, st: StreamState) -> Optional[float]:
    """
    Rate noise density N from the residuals of the integrated gyro angle.

    Trapezoid integration makes consecutive increments' errors correlated (MA(1): per-sample
    variance N^2 dt / 2, long-run N^2 dt), and a sensor's own smoothing correlates them further,
    so N is measured on increments over NOISE_BLOCK samples, where those short correlations
    have averaged out. Short records (< MIN_BLOCKS blocks) use the per-sample residuals with the
    white-noise trapezoid factor 2.
    """
    if st.blocks.rows >= MIN_BLOCKS:
        return st.blocks.noise_scale()
    return srif.noise_scale(factor=2.0)


def fold(srif: Srif, st: StreamState, tau: np.ndarray, z: np.ndarray, period_s: float) -> None:
    """Add one chunk of stamps (s after t_ref) and angles (rad) of one stream."""
    if len(tau) == 0:
        return
    if st.kind == ENCODER:
        srif.add(*encoder_rows(tau, z, period_s))
    else:
        prev = None if st.count == 0 else (st.last_tau, st.last_z)
        released = gap_steps(st, tau)
        srif.add(*gyro_rows(tau, z, period_s, st.count, prev, released))
        seg = st.gaps + np.cumsum(released)
        _fold_blocks(st, tau, z, seg, period_s)
        _fold_long_blocks(st, tau, z, seg, period_s)
        st.gaps = int(seg[-1])
    st.count += len(tau)
    st.last_tau, st.last_z = float(tau[-1]), float(z[-1])


def result(srif: Srif, st: StreamState, period_s: float,
           noise_override: Optional[float] = None) -> FilterResult:
    """Return the filter's state and covariance at its last sample (module doc)."""
    noise = noise_override if noise_override is not None else st.noise
    estimated = noise is None
    if estimated:
        noise = (srif.noise_scale() if st.kind == ENCODER else gyro_noise(srif, st)) or 1.0
    theta, p_theta = srif.solve(noise)
    m = transition(st.last_tau, period_s)
    x = m @ theta
    if st.kind == GYRO and st.count >= 2:
        g = regressor(st.last_tau, period_s)
        m = m - np.outer(E3, g)
        x = m @ theta + E3 * st.last_z
    scale, ratio = low_frequency_scale(st, noise) if st.kind == GYRO else (1.0, None)
    return FilterResult(x=x, P=m @ p_theta @ m.T, tau=st.last_tau, samples=st.count,
                        noise=float(noise), noise_estimated=estimated, theta=theta,
                        rate_sigma_scale=scale, low_frequency_ratio=ratio)


def run(kind: str, tau: np.ndarray, z: np.ndarray, period_s: float,
        noise: Optional[float] = None, checkpoints: int = 0):
    """
    One filter over a whole record; returns (FilterResult, history).

    ``history`` (when ``checkpoints`` > 0) is a list of FilterResult at about that many evenly
    spaced samples, all with the final noise level, for convergence plots.
    """
    srif, st = Srif(), StreamState(kind, noise)
    if checkpoints <= 0:
        fold(srif, st, tau, z, period_s)
        return result(srif, st, period_s), []
    edges = np.unique(np.linspace(0, len(tau), checkpoints + 1).astype(int))
    partial = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        fold(srif, st, tau[lo:hi], z[lo:hi], period_s)
        partial.append((srif.r.copy(), srif.rows, StreamState(**vars(st))))
    final = result(srif, st, period_s)
    history = []
    for r, rows, snap in partial:
        s = Srif()
        s.r, s.rows = r, rows
        history.append(result(s, snap, period_s, noise_override=final.noise))
    return final, history
