"""
Held-out swing set AI: written blind, without running the diagnosis.

Same interface as ``validate_diagnosis_swing_heldout_ah.py``: ``shapes(rate_hz)`` gives
``{name: (fn, [weak, strong, edge])}``, ``fn(imu_t, gyro, enc_t, enc_angle, stand, rng,
**params) -> (imu_t, gyro, enc_t, enc_angle)``, ``stand(t)`` the true (angle, rate). Each shape
is unlike the catalogue's, the development harness's and sets AG and AH, and the kinds of
departure differ from shape to shape:

- time_delay: counted stamps: the IMU runs on its own oscillator, fast by eps, and the driver
  stamps each sample by counting nominal steps from the last resync, a hardware capture that
  re-anchors it to the host clock; the resyncs come at gaps uniform in RESYNC_SPAN = 0.5-1.5
  of RESYNC_S = 20 s, drawn per gap, the first sample an anchor: the latency eps (t -
  t_anchor) (``counted_stamps``), a sawtooth that ramps up from zero and drops back at each
  resync (the stamps after a drop kept in order, a tenth of a step apart, until they catch
  up), the values untouched: a latency with memory and random resync instants, its mean eps
  E[g^2] / (2 E[g]) = 10.8 s eps (``counted_mean``, g a gap);
- g_sensitivity: a play in the potting: the g-sensitive stress reaches the sense element
  through potting that slips like dry friction, so the bias follows f_y = g sin(phi) through a
  play of half width PLAY = 1.5 m/s^2: g_y p, p_k = min(max(p_(k-1), f_k - PLAY), f_k + PLAY)
  (``play``): a hysteretic g-sensitivity, stuck for 2 PLAY of f_y after each turning point; at
  20 deg its fundamental 0.65 of the raw g_y f_y's and 29 deg behind it, its 3f 0.16 of that
  (odd lines only); a swing under 8.8 deg (g sin(phi) < PLAY) never moves it from where it
  sits (none at all from the level);
- scale_factor_nonlinearity: a segmented rebalance DAC: the closed-loop gyro's feedback DAC is
  sign-magnitude, its magnitude built of INL_SEGMENTS = 32 unary segments over 0-1.6 rad/s,
  each segment's current mismatched (one fixed device, seed INL_SEED): the rate response's INL
  is a random walk over the segments, endpoint-corrected and linear within each (``inl_table``,
  peak 1 at 0.8 rad/s): out = x + a sign(w) INL(|w|) (``inl_error``; the true rate, the
  read-out noise after it): an odd, memoryless, kinked error, a kink every 0.05 rad/s (8 under
  the 5 s swing's 0.44 rad/s peak, 17 under the 2.5 s swing's);
- scale_factor_asymmetry: a drooping bootstrap: the rebalance driver's positive half runs from
  a bootstrap capacitor that the positive force discharges (1 - D falls e-fold every DROOP_Q =
  0.4 rad of positive travel) and the negative half recharges (D falls e-fold every DROOP_TAU
  = 1 s; ``droop``): out = x - a D w while w > 0 (``droop_error``): positive rates read low by
  a deficit that grows through each positive half-swing and is only partly recovered over the
  negative one (D from 0.069 to 0.84 at the 5 s period, from 0.25 to 0.87 at 2.5 s): a
  direction-dependent gain with memory, set by the pace;
- timestamp_jitter: rotating sample-and-holds: the encoder's DAQ samples through four
  sample-and-hold units in turn, each converted in its own slot of the frame (slots
  SLOT_ORDER = 0, 2, 1, 3 for units 0-3, ``slot`` apart), and stamps the frame (the mean slot
  calibrated out); another acquisition steals a unit's turn in SLIP = 1 % of the frames, the
  rotation skipping on by one unit (``slot_errors``): stamp errors of 1.5, -0.5, 0.5 and -1.5
  slots in a rotation whose phase slips at random: spectral lines near 250 Hz (1.6 Hz half
  width) and at 500 Hz (3.2 Hz), 80 % of the variance in the latter (``slot_psd``), 1.12 slot
  rms (stamps in order);
- encoder_cyclic_error: a smudge on the grating: the 2500-line grating read by an optical head
  carries a contamination spot centred at SPOT_PHI = 9 deg, of Gaussian profile, sd SPOT_SD =
  2.5 deg, that unbalances the two tracks as the head passes it: a second-harmonic
  interpolation error a exp(-x^2 / 2) sin(2 SPOT_LINES phi + SPOT_PHASE), x = (phi -
  SPOT_PHI) / SPOT_SD (``spot_error``): a cyclic error confined to a stretch of the scale
  (under 0.2 % of a on the level and below, 0.01 % at the 20 deg turning point), at 312 Hz as
  the 5 s swing crosses it (623 Hz, aliased to 377 Hz, at 2.5 s).

Levels (``detectability``; 15 min, 1 kHz gyro and encoder, adis16405 preset: A = 20 deg, the
5 s period, N its gyro's ARW; s = N sqrt(2 / T) the sd of a fitted rate-residual sine):

- counted stamps: the matched detector on the noise-free angle residual of the mean latency d
  (``counted_mean``), rate(t - d) - rate(t) integrated, offset, bias ramp and scale factor
  fitted out, against the gyro angle noise N^2 / (2 pi f)^2, the encoder's white floor and the
  preset's stamp jitter (as sets AG and AH); the sawtooth about the mean, its random resyncs
  and the first gap's start not counted;
- play: the matched detector in the rate domain (AF's ``rate_z``, bias and scale factor
  fitted out);
- segmented DAC: the lines k = 2..60 of the error along the swing against s;
- bootstrap: the lines k = 2..60 of the settled period's error (the third of three) against s;
- sample-and-holds: the stamp error read through the swing's rate (``stamp_z``, as sets AG and
  AH), of the PSD ``slot_psd``;
- smudge: the matched detector on the noise-free angle residual, as the stamps'.
Edges solve z = 4 at the 5 s period, weak and strong z = 25 and 100 (``levels``, 3 digits; at
2.5 s the edges' z are: counted stamps 4.0x, bootstrap 2.0x, sample-and-holds 1.7x, DAC 1.1x,
play 1.0x, smudge 0.78x). Physical scale: oscillator errors eps of 17.4 (edge), 109 and 434 ppm
(mean latencies 0.188, 1.18 and 4.70 ms, at most 0.52, 3.3 and 13 ms before a resync); g_y of
5.33e-5, 3.33e-4 and 1.33e-3 rad/s/(m/s^2) (0.030, 0.19 and 0.75 deg/s/g); INL peaks a of
4.29e-4, 2.68e-3 and 0.0107 rad/s; bootstrap deficits a of 0.14 %, 0.86 % and 3.4 % (D a of
0.11 %, 0.72 % and 2.9 % at the end of a positive half-swing); slots of 0.845, 2.11 and 4.22 us
(0.94, 2.36 and 4.72 us rms, beside the preset's own 20 us white jitter); smudge errors a of
0.050, 0.31 and 1.25 arcsec on the 518 arcsec pitch.
"""
from functools import lru_cache

from heldout_detect import encoder_floor, matched_z, print_levels, solved_levels
from heldout_detect import stamp_z, step_of, swing_scales

import numpy as np

from validate_diagnosis_swing_heldout_af import increasing, rate_z

from validate_diagnosis_swing_heldout_m import fitted_residual

from validate_diagnosis_swing_heldout_n import angle_residual

G0 = 9.80665
RESYNC_S, RESYNC_SPAN = 20.0, (0.5, 1.5)   # s: mean resync interval; its gaps' span (x RESYNC_S)
PLAY = 1.5                              # m/s^2: the potting's play (half width) in f_y
INL_SEGMENTS, INL_FULL, INL_SEED = 32, 1.6, 2024   # DAC segments over 0..INL_FULL rad/s; device
DROOP_Q, DROOP_TAU = 0.4, 1.0           # rad of positive travel an e-fold; s: the recharge
SLOT_ORDER, SLIP = (0, 2, 1, 3), 0.01   # the units' slots in the frame; share of stolen slots
SPOT_LINES, SPOT_PHASE = 2500, 0.6      # the grating's lines a turn; the error's phase
SPOT_PHI, SPOT_SD = np.deg2rad(9.0), np.deg2rad(2.5)   # rad: the smudge's centre and width (sd)
KEY = {'time_delay': 'eps', 'g_sensitivity': 'gy', 'scale_factor_nonlinearity': 'a',
       'scale_factor_asymmetry': 'a', 'timestamp_jitter': 'slot', 'encoder_cyclic_error': 'a'}
TARGETS = (25.0, 100.0, 4.0)            # z of the weak, strong and edge levels
GUESS = {'time_delay': 1e-4, 'g_sensitivity': 1e-4, 'scale_factor_nonlinearity': 1e-3,
         'scale_factor_asymmetry': 1e-3, 'timestamp_jitter': 3e-6, 'encoder_cyclic_error': 1e-6}
SLOPE = {'timestamp_jitter': 2.0}       # first guess of d ln z / d ln x (else 1)


def resync_anchors(t, rng) -> np.ndarray:
    """
    Return each sample's anchor index: the last resync at or before it.

    The first sample is an anchor; the gaps between resyncs are uniform in RESYNC_SPAN times
    RESYNC_S, each capturing the first sample at or after its instant.
    """
    t = np.asarray(t, float)
    lo = RESYNC_SPAN[0] * RESYNC_S
    gaps = rng.uniform(*RESYNC_SPAN, int((t[-1] - t[0]) / lo) + 2) * RESYNC_S
    idx = np.searchsorted(t, t[0] + np.r_[0.0, np.cumsum(gaps)])
    mark = np.zeros(t.size, int)
    mark[idx[idx < t.size]] = 1
    return np.maximum.accumulate(np.where(mark == 1, np.arange(t.size), 0))


def counted_stamps(t, eps: float, rng) -> np.ndarray:
    """Return the stamps t + eps (t - t_anchor) (``resync_anchors``), kept in order."""
    t = np.asarray(t, float)
    if not eps:
        return t.copy()
    return increasing(t + eps * (t - t[resync_anchors(t, rng)]), step_of(t))


def counted_mean(eps: float) -> float:
    """Return the mean latency eps E[g^2] / (2 E[g]) of the counted stamps (g: a resync gap)."""
    lo, hi = RESYNC_SPAN
    return eps * RESYNC_S * (lo * lo + lo * hi + hi * hi) / (3.0 * (lo + hi))


def play(f, h: float) -> np.ndarray:
    """Return the play p_k = min(max(p_(k-1), f_k - h), f_k + h), p_(-1) = 0, along ``f``."""
    f = np.asarray(f, float)
    out = np.empty(f.size)
    if not f.size:
        return out
    out[0] = min(max(0.0, f[0] - h), f[0] + h)
    d = np.sign(np.diff(f))
    if not np.any(d):
        out[1:] = out[0]
        return out
    nz = np.flatnonzero(d)                                 # flat steps join the run before
    d = d[nz[np.maximum(np.searchsorted(nz, np.arange(d.size), side='right') - 1, 0)]]
    cuts = np.r_[0, np.flatnonzero(np.diff(d)) + 1, d.size]
    last = out[0]
    for s, e in zip(cuts[:-1], cuts[1:]):                  # a monotone run f[s + 1..e]
        seg = f[s + 1:e + 1]
        out[s + 1:e + 1] = np.maximum(last, seg - h) if d[s] > 0 else np.minimum(last, seg + h)
        last = out[e]
    return out


@lru_cache(maxsize=1)
def inl_table() -> tuple:
    """Return the DAC's INL at its INL_SEGMENTS + 1 knots: endpoint-corrected, peak 1."""
    mismatch = np.random.default_rng(INL_SEED).standard_normal(INL_SEGMENTS)
    c = np.r_[0.0, np.cumsum(mismatch)]
    inl = c - np.arange(INL_SEGMENTS + 1) / INL_SEGMENTS * c[-1]
    return tuple((inl / np.abs(inl).max()).tolist())


def inl_error(w, a: float) -> np.ndarray:
    """Return a sign(w) INL(|w|), the INL linear between knots j INL_FULL / INL_SEGMENTS."""
    w = np.asarray(w, float)
    knots = np.linspace(0.0, INL_FULL, INL_SEGMENTS + 1)
    return a * np.sign(w) * np.interp(np.abs(w), knots, inl_table())


def droop(w, step: float) -> np.ndarray:
    """
    Return the bootstrap's droop D_k along the rates ``w``, D_(-1) = 0.

    While w_k > 0: 1 - D_k = (1 - D_(k-1)) exp(-w_k step / DROOP_Q) (discharged by the positive
    travel); else D_k = D_(k-1) exp(-step / DROOP_TAU) (recharged).
    """
    w = np.asarray(w, float)
    pos = w > 0
    cuts = np.r_[0, np.flatnonzero(np.diff(pos)) + 1, w.size]
    out, last = np.empty(w.size), 0.0
    for s, e in zip(cuts[:-1], cuts[1:]):
        if pos[s]:
            out[s:e] = 1.0 - (1.0 - last) * np.exp(-np.cumsum(w[s:e]) * (step / DROOP_Q))
        else:
            out[s:e] = last * np.exp(-np.arange(1, e - s + 1) * (step / DROOP_TAU))
        last = out[e - 1]
    return out


def droop_error(w, step: float, a: float) -> np.ndarray:
    """Return the rate error -a D_k w_k while w_k > 0 (``droop``), else 0."""
    w = np.asarray(w, float)
    return np.where(w > 0, -a * droop(w, step) * w, 0.0)


def slot_offsets() -> np.ndarray:
    """Return the stamp error of each unit in slots: its slot's lead on the frame's mean slot."""
    order = np.asarray(SLOT_ORDER, float)
    return order.mean() - order


def slot_errors(n: int, slot: float, rng) -> np.ndarray:
    """
    Return n stamp errors slot ``slot_offsets()[c_k]`` of the rotating sample-and-hold units.

    c_0 uniform; c_k = c_(k-1) + 1 + B_k modulo the units, B_k Bernoulli(SLIP) (a stolen slot).
    """
    units = len(SLOT_ORDER)
    skip = rng.random(n) < SLIP
    skip[0] = False
    c = (rng.integers(units) + np.arange(n) + np.cumsum(skip)) % units
    return slot * slot_offsets()[c]


def slot_stamps(t, slot: float, rng) -> np.ndarray:
    """Return the stamps t + ``slot_errors`` (kept in order)."""
    t = np.asarray(t, float)
    if not slot:
        return t.copy()
    return increasing(t + slot_errors(t.size, slot, rng), step_of(t))


def slot_psd(f, slot: float, fs: float) -> np.ndarray:
    """
    Return the two-sided PSD (s^2/Hz) of ``slot_errors`` at ``f``.

    sum_q |a_q|^2 (1 - |l_q|^2) / |1 - l_q exp(-i W)|^2 slot^2 / fs, W = 2 pi f / fs, a_q the
    units' Fourier coefficients, l_q = z^q (1 - SLIP + SLIP z^q), z = exp(-2 pi i / units).
    """
    v = slot_offsets()
    units = v.size
    a = np.fft.fft(v) / units
    x = np.exp(-2j * np.pi * np.asarray(f, float) / fs)
    out = np.zeros(np.shape(f))
    for q in range(1, units):
        zq = np.exp(-2j * np.pi * q / units)
        lam = zq * (1.0 - SLIP + SLIP * zq)
        out += abs(a[q]) ** 2 * (1.0 - abs(lam) ** 2) / np.abs(1.0 - lam * x) ** 2
    return slot * slot * out / fs


def spot_error(phi, a: float) -> np.ndarray:
    """
    Return the smudge's error a exp(-x^2 / 2) sin(2 SPOT_LINES phi + SPOT_PHASE) at ``phi``.

    x = (phi - SPOT_PHI) / SPOT_SD: the spot's profile along the scale.
    """
    phi = np.asarray(phi, float)
    x = (phi - SPOT_PHI) / SPOT_SD
    return a * np.exp(-0.5 * x * x) * np.sin(2 * SPOT_LINES * phi + SPOT_PHASE)


def shapes(rate_hz: float) -> dict:
    """Return ``{name: (fn, [weak, strong, edge])}`` for a gyro sampled at ``rate_hz``."""
    def counted(imu_t, gyro, enc_t, enc, stand, rng, eps):
        return counted_stamps(imu_t, eps, rng), gyro, enc_t, enc

    def played(imu_t, gyro, enc_t, enc, stand, rng, gy):
        return imu_t, gyro + gy * play(G0 * np.sin(stand(imu_t)[0]), PLAY), enc_t, enc

    def segmented(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + inl_error(stand(imu_t)[1], a), enc_t, enc

    def drooping(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro + droop_error(stand(imu_t)[1], step_of(imu_t), a), enc_t, enc

    def slotted(imu_t, gyro, enc_t, enc, stand, rng, slot):
        return imu_t, gyro, slot_stamps(enc_t, slot, rng), enc

    def smudged(imu_t, gyro, enc_t, enc, stand, rng, a):
        return imu_t, gyro, enc_t, enc + spot_error(stand(enc_t)[0], a)

    return {
        'time_delay': (counted, [{'eps': 1.09e-4}, {'eps': 4.34e-4}, {'eps': 1.74e-5}]),
        'g_sensitivity': (played, [{'gy': 3.33e-4}, {'gy': 1.33e-3}, {'gy': 5.33e-5}]),
        'scale_factor_nonlinearity': (segmented, [{'a': 2.68e-3}, {'a': 0.0107},
                                                  {'a': 4.29e-4}]),
        'scale_factor_asymmetry': (drooping, [{'a': 8.58e-3}, {'a': 0.0343}, {'a': 1.37e-3}]),
        'timestamp_jitter': (slotted, [{'slot': 2.11e-6}, {'slot': 4.22e-6},
                                       {'slot': 8.45e-7}]),
        'encoder_cyclic_error': (smudged, [{'a': 1.51e-6}, {'a': 6.04e-6}, {'a': 2.42e-7}]),
    }


def settled_lines(err, per: int) -> float:
    """Return the norm of lines k = 2..60 of the last ``per`` samples of ``err``."""
    return float(2 * np.linalg.norm((np.fft.rfft(err[-per:]) / per)[2:61]))


def detectability(name: str, params: dict, period_s: float = 5.0, duration: float = 900.0,
                  rate_hz: float = 1000.0) -> float:
    """Analytic z of one level on one run (module docstring), preset adis16405 numbers."""
    n_arw, amp, enc, w, s = swing_scales(period_s, duration)
    p = params
    per = int(round(period_s * rate_hz))                     # samples a period
    if name in ('scale_factor_nonlinearity', 'scale_factor_asymmetry'):
        rate = amp * w * np.cos(w * np.arange(3 * per) / rate_hz)
        if name == 'scale_factor_nonlinearity':
            return settled_lines(inl_error(rate, p['a']), per) / s
        return settled_lines(droop_error(rate, 1.0 / rate_hz, p['a']), per) / s
    floor = encoder_floor(enc, rate_hz, amp * w)
    if name == 'timestamp_jitter':
        return stamp_z(lambda f: slot_psd(f, p['slot'], rate_hz), amp * w, w / (2 * np.pi),
                       n_arw, floor, duration, rate_hz, 400001)
    t = np.arange(int(duration * rate_hz)) / rate_hz
    phi, rate = amp * np.sin(w * t), amp * w * np.cos(w * t)
    if name == 'encoder_cyclic_error':
        return matched_z(angle_residual(spot_error(phi, p['a']), t, phi), rate_hz, n_arw, floor)
    if name == 'g_sensitivity':
        return rate_z(p['gy'] * play(G0 * np.sin(phi), PLAY), rate, n_arw, rate_hz)
    err = amp * w * np.cos(w * (t - counted_mean(p['eps']))) - rate
    return matched_z(fitted_residual(err, t, phi, rate_hz), rate_hz, n_arw, floor)


def levels(names=None, digits: int = 3) -> dict:
    """Return ``{name: [weak, strong, edge]}`` solved for z = TARGETS, to ``digits`` digits."""
    return solved_levels(detectability, KEY, GUESS, TARGETS, names, slope=SLOPE,
                         digits=digits)


if __name__ == '__main__':
    print_levels(levels(), detectability)
