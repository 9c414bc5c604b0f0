"""
Swing twins without simulating the whole record per candidate: noise part + effect part.

The observables are functions of the residual streams (``swing_obs.raw_parts``): linear ones
(the harmonic coefficients, the least-squares scale) and quadratic ones (Welch power, squared
line peaks, rate-bin mean squares, lagged increment sums). Every swing effect of the catalogue
is either DETERMINISTIC given the stand motion (time_delay, g_sensitivity, the scale-factor
nonlinearity and asymmetry, encoder_cyclic_error) or a noise independent of the baseline's
(timestamp_jitter; the scale-factor effects' rate noise, ``_rate_noise``). A candidate's
residual is then the baseline twin's noise residual N plus the effect's own residual D, and
for its observables:

- linear parts: exactly N's plus D's (the residual fit is a fixed projection);
- quadratic parts: the twin's residual is A + N with A the motion's own deterministic part
  (the gyro angle interpolated at the encoder stamps), so E|A + D + N|^2 = E|A + N|^2 +
  (|A + D|^2 - |A|^2): each pseudo-twin gets its baseline twin's parts plus that
  difference, taken from the noise-free runs (the cross term with N has zero mean; the one
  with A does not, and was 10 sigma in a 2.5 s-period record's line and rate-bin blocks).

N's parts come from full-length twins of the baseline, simulated once per seed (common random
numbers across candidates). D's come from a NOISE-FREE simulation of the baseline with and
without the effect, differenced sample by sample; the stand motion is periodic, so D is
computed on a whole number of swing periods (``SPAN_S``) instead of the whole record. For a
noise effect (jitter) the linear parts of D are dropped (zero mean) and its quadratic parts come
from runs on a grid of stamp errors (``EffectParts._jitter``); a correlated jitter
(``tau_s``) the same, its grid run at that correlation time. A noise part's squared line
peaks and band means are scaled from its run's span to the record's (a noise's line
amplitude falls as one over the root of the passes). A gyro lag (``time_delay``'s
``lag_s``) is linear too: its motion part is a deterministic D as above, and it also
colours the baseline's gyro noise, whose quadratic parts then change by those of R(H n) minus
those of R(n) (R: the residual, H: the lag, n: the twin's gyro noise, N B K, alone), from a
noise-only run on a grid of lags (``EffectParts._lag``). What this leaves out:
the cross terms' extra spread (the pseudo-twins' spread is the baseline's) and the effects'
interaction with quantization; ``--check`` simulates the selected model's twins in full.
"""
from typing import Callable, Dict, List, Sequence, Tuple

from gyro_char.diagnosis.swing_baseline import SwingBaseline
from gyro_char.diagnosis.swing_gains import (
    clean_config, lag_gain, limit_gain, limits_of, noise_config, span)
from gyro_char.diagnosis.swing_obs import raw_parts
from gyro_char.diagnosis.swing_rate_noise import (
    gate_grid, gate_weights, PLAIN_OFF, rate_noise_gain, split, unit_level)
from gyro_char.diagnosis.swing_residuals import common_samples, residuals
from gyro_char.records import ENCODER_CHANNEL
from gyro_char.sim import simulator
from gyro_char.sim.chain import JITTER_CLIP
import numpy as np

NOISE_EFFECTS = ('timestamp_jitter',)
LINEAR = ('harm', 'scale')
QUADRATIC = ('psd', 'line2', 'mean2', 'ms', 'msd', 'mp', 'acf', 'locked')
NOISE_SPAN_S = 240.0    # span of the jitter's runs (at most the record)
LIMIT_SPAN_S = np.inf  # a full-scale limit's noisy runs: the whole record (``_cut``)
JITTER_GRID = 8         # stamp errors run, log-spaced from 0.2 % to 45 % of the intervals
SMOOTH_GRID = (0.05, 20.0)  # a smooth stamp error's grid, in intervals (``_unit``)
LAG_GRID = (0.05, 20.0, 16)     # gyro lags run: from, to (gyro sample intervals), count
WHITE_GRID = (1.0 / 16.0, 0.25, 1.0)    # the gyro white power's scalings run (``_white_share``)


class EffectParts:
    """
    The effect part D of a candidate on each record, cached by the candidate's effects.

    ``config(base)`` is the twin's simulator config (``swing_twin.twin_config``), ``scale`` the
    least-squares scale of a run (``swing_twin.record_scale``).
    """

    def __init__(self, bases: Sequence[SwingBaseline], ranges: Sequence[dict],
                 config: Callable, scale: Callable):
        self.bases, self.ranges = list(bases), list(ranges)
        self.config, self.scale = config, scale
        self.cache: Dict[Tuple[int, str], dict] = {}
        self.clean: Dict[int, tuple] = {}

    def _run(self, i: int, effects: list, span_s: float = 0.0, noisy: bool = False,
             full: bool = False, gain: float = 1.0):
        b = self.bases[i]
        cfg = (self.config(b) if full else
               (noise_config if noisy else clean_config)(self.config(b)))
        cfg.noise[f'gyro_{b.axis}']['N'] *= np.sqrt(gain)
        run = simulator.simulate_swing(cfg, seed=0,
                                       duration=min(span_s, b.duration) or span(b),
                                       effects=effects, channels=(f'gyro_{b.axis}',),
                                       stamp_latency=b.stall_trace)
        res = residuals(run.imu.t, run.imu.channels[f'gyro_{b.axis}'], run.encoder.t,
                        run.encoder.channels[ENCODER_CHANNEL], b.period_s)
        return res, self.scale(run.imu, run.encoder, b.axis)

    def _single(self, i: int, effects: list, noise: bool, span_s: float = 0.0,
                full: bool = False, gain: float = 1.0) -> dict:
        # ``full``: both runs with the twin's noise (one realisation, common to both), so
        # that the part keeps the effect's interaction with that noise; ``gain``: the run
        # with the effect at that much more gyro noise power (``limit_gain``).
        key = (i, repr(effects) + f' {span_s} {gain}' + (' full' if full else ''))
        if key not in self.cache:
            if len(self.cache) > 4096:
                self.cache = {k: v for k, v in self.cache.items() if 'unit' in k[1]}
            res0, s0 = self._clean(i, span_s, full)
            res, s = self._run(i, effects, span_s, full=full, gain=gain)
            part = self._difference(i, res0, res, cross=full or not noise)
            part['scale'] = s - s0
            if noise:
                part = self._as_noise(i, part, span_s)
            self.cache[key] = part
        return self.cache[key]

    def _clean(self, i: int, span_s: float, full: bool = False):
        """Return the run of record ``i`` without effects over ``span_s`` (cached), its scale."""
        if (i, span_s, full) not in self.clean:
            self.clean[(i, span_s, full)] = self._run(i, [], span_s, full=full)
        return self.clean[(i, span_s, full)]

    def _difference(self, i: int, res0, res, cross: bool = False) -> dict:
        # Sample by sample: the same sample numbers of both runs (a stamp shift may drop
        # an edge sample from one of them). ``cross``: the parts are those of the run with
        # the effect minus those without, so the quadratic ones keep the cross term of D
        # with the motion's own deterministic residual A (interpolation of the gyro angle at
        # the encoder stamps), which every twin shares: E|A + D + N|^2 - E|A + N|^2 (the
        # linear ones are D's either way: the residual fit is a fixed projection). The parts
        # without the effect are kept on ``res0`` (a cached clean run) when all its samples
        # are used.
        ig0, ig = common_samples(res0.idx_g, res.idx_g)
        ie0, ie = common_samples(res0.idx_e, res.idx_e)
        whole = ig0.size == res0.r.size and ie0.size == res0.r_e.size
        geo = res0 if whole else res0.take(ig0, ie0)
        if not cross:
            return raw_parts(geo, self.ranges[i], res.r[ig] - geo.r, res.r_e[ie] - geo.r_e)
        with_fx = raw_parts(geo, self.ranges[i], res.r[ig], res.r_e[ie])
        without = geo.geometry('own_parts', lambda: raw_parts(geo, self.ranges[i]))
        return {**with_fx, **{q: with_fx[q] - without[q] for q in LINEAR + QUADRATIC
                              if q in with_fx}}

    def _as_noise(self, i: int, part: dict, span_s: float) -> dict:
        # Zero-mean linear parts; a noise's squared line amplitudes, and what it leaves in the
        # phase-locked waveform, scale as 1 / length.
        b = self.bases[i]
        ratio = min(span_s or span(b), b.duration) / b.duration
        return {**part, 'harm': np.zeros_like(part['harm']), 'scale': 0.0, 'noise': True,
                'line2': part['line2'] * ratio, 'mean2': part['mean2'] * ratio,
                'locked': part['locked'] * ratio}

    def _lag_grid(self, i: int) -> np.ndarray:
        lo, hi, n = LAG_GRID
        return np.geomspace(lo * self.bases[i].dt, hi * self.bases[i].dt, n)

    def _noise_alone(self, i: int, fx: list, full: bool = False, gain: float = 1.0,
                     span_s: float = NOISE_SPAN_S) -> dict:
        # Raw parts of the gyro noise's residual alone under ``fx``: noisy minus clean run
        # (``full``: every noise of the twin, the quantizations and the encoder's included;
        # ``gain``: the gyro noise's power that much higher), over ``span_s``.
        key = (i, f'unit noise {fx!r} {gain} {span_s}' + (' full' if full else ''))
        if key not in self.cache:
            runs = [self._run(i, fx, span_s, False)[0],
                    self._run(i, fx, span_s, True, full, gain)[0]]
            self.cache[key] = self._difference(i, *runs)
        return self.cache[key]

    def _stall(self, i: int, stalls: list) -> List[dict]:
        """
        Return a host stall's parts: its motion part and what it does to the gyro noise.

        Both over the whole record (the latency follows the record's trace, not the swing's
        period). The stamps' gap after a stall integrates one noisy sample over the whole
        stall, so the stall adds noise of its own (on a 120 s run of 100 ms stalls it raised
        the residual PSD's top bins 1.8 times, as much as its motion part did): the noise's
        parts under the stall less its parts without (one realisation, as ``_bend``).
        """
        key = (i, 'unit stall ' + repr(stalls))
        if key not in self.cache:
            # The motion part on each run's own stamps: read on the plain run's (as
            # ``_difference`` does, right for a latency that only shifts them) the stall's
            # residual came out 3 times its power.
            res0, s0 = self._clean(i, LIMIT_SPAN_S)
            res, s = self._run(i, stalls, LIMIT_SPAN_S)
            own = raw_parts(res, self.ranges[i])
            base = res0.geometry('own_parts', lambda: raw_parts(res0, self.ranges[i]))
            motion = {**own, **{q: own[q] - base[q] for q in LINEAR + QUADRATIC if q in own},
                      'scale': s - s0}
            stalled = self._noise_alone(i, stalls, span_s=LIMIT_SPAN_S)
            plain = self._noise_alone(i, [], span_s=LIMIT_SPAN_S)
            noise = {**plain, **{q: stalled[q] - plain[q] for q in QUADRATIC}}
            self.cache[key] = [motion, self._as_noise(i, noise, LIMIT_SPAN_S)]
        return self.cache[key]

    def _colour(self, i: int, k: int) -> dict:
        """Return g parts(R(H n)) minus parts(R(n)) at grid lag k (``lag_gain``)."""
        key = (i, f'unit lag {k}')
        if key not in self.cache:
            lag, b = float(self._lag_grid(i)[k]), self.bases[i]
            g = lag_gain(lag, b.dt, b.period_s)
            out = [self._noise_alone(i, []), self._noise_alone(i, [{
                'name': 'time_delay', 'params': {'delay_s': lag, 'lag_s': lag}}])]
            part = {q: g * out[1][q] - out[0][q] for q in QUADRATIC}
            floor = {q: np.minimum(g * out[1][q] / np.maximum(out[0][q], 1e-300), 1.0)
                     for q in ('psd', 'mean2', 'ms')}
            self.cache[key] = {**self._as_noise(i, {**out[0], **part}, NOISE_SPAN_S),
                               'floor': floor}
        return self.cache[key]

    def _lag(self, i: int, lag: float) -> dict:
        """Return the lag's noise colouring: grid parts interpolated in log lag, ∝ lag² below."""
        grid = self._lag_grid(i)
        if lag <= grid[0]:
            lo, s = self._colour(i, 0), (lag / grid[0]) ** 2
            out = {q: (v * s if q in QUADRATIC else v) for q, v in lo.items()}
            out['floor'] = {q: 1.0 - s * (1.0 - r) for q, r in lo['floor'].items()}
            return out
        x = np.log(min(lag, grid[-1]))
        k = int(np.clip(np.searchsorted(np.log(grid), x) - 1, 0, grid.size - 2))
        f = (x - np.log(grid[k])) / (np.log(grid[k + 1]) - np.log(grid[k]))
        lo, hi = self._colour(i, k), self._colour(i, k + 1)
        out = {q: ((1 - f) * lo[q] + f * hi[q] if q in QUADRATIC else v)
               for q, v in lo.items()}
        out['floor'] = {q: (1 - f) * lo['floor'][q] + f * hi['floor'][q] for q in lo['floor']}
        return out

    def _grid(self, i: int, stream: float, order: float = 1.0) -> np.ndarray:
        b = self.bases[i]
        dts = [b.dt, b.encoder_dt] if stream == 2.0 else [b.dt if stream == 0.0 else
                                                          b.encoder_dt]
        if order == 2.0:
            return np.geomspace(SMOOTH_GRID[0] * min(dts), SMOOTH_GRID[1] * max(dts),
                                JITTER_GRID)
        return np.geomspace(0.002 * min(dts), JITTER_CLIP * max(dts), JITTER_GRID)

    def _unit(self, i: int, stream: float, k: int, shape: dict) -> dict:
        # The jitter at grid point k over NOISE_SPAN_S, per unit stamp variance; ``shape``:
        # its correlation (tau_s and order, or a resonance's freq_hz and q). A smooth error
        # (order 2) is run with the twin's noise: it moves the gyro stamps' phase in the
        # encoder interval by whole intervals, and with it how the interpolation passes the
        # encoder's noise on (the residual's increment correlation), which a noise-free run
        # cannot show.
        order = shape.get('order', 1.0)
        sigma = float(self._grid(i, stream, order)[k])
        part = self._single(i, [{'name': 'timestamp_jitter', 'params': {
            'sigma_s': sigma, 'stream': stream, **shape}}], True, span_s=NOISE_SPAN_S,
            full=order == 2.0)
        return {q: v / sigma ** 2 if q in QUADRATIC else v for q, v in part.items()}

    def _jitter(self, i: int, params: dict) -> dict:
        """
        Return the jitter's part: quadratic parts per unit variance, interpolated in log σ.

        Not simply proportional to sigma^2: where the gyro stamps fall next to encoder
        samples, the interpolated encoder error depends on whether the error moved the stamp
        across them (measured: 18 % less per unit variance at 10 % than at 0.4 % of the
        encoder interval, 120 s at 200 Hz), and the stamp error is clipped at 0.45 interval.
        """
        sigma, stream = float(params['sigma_s']), float(params.get('stream', 2.0))
        shape = jitter_shape(params)
        grid = self._grid(i, stream, shape.get('order', 1.0))
        x = float(np.clip(np.log(max(sigma, 1e-30)), np.log(grid[0]), np.log(grid[-1])))
        k = int(np.clip(np.searchsorted(np.log(grid), x) - 1, 0, grid.size - 2))
        f = (x - np.log(grid[k])) / (np.log(grid[k + 1]) - np.log(grid[k]))
        lo, hi = self._unit(i, stream, k, shape), self._unit(i, stream, k + 1, shape)
        return {q: (sigma ** 2 * ((1 - f) * lo[q] + f * hi[q]) if q in QUADRATIC else lo[q])
                for q in lo}

    def _bend(self, i: int, fx: dict) -> dict:
        """
        Return how a table on the sensed value changes the gyro noise's quadratic parts.

        The table bends noise and signal alike (``on_output``): the noise comes out scaled by
        the table's slope along the swing. Its parts under the table minus its parts without
        (``_noise_alone``: the same realisation), as a noise part.
        """
        key = (i, 'unit bend ' + repr(fx))
        if key not in self.cache:
            bent, plain = self._noise_alone(i, [fx]), self._noise_alone(i, [])
            part = {**plain, **{q: bent[q] - plain[q] for q in QUADRATIC}}
            self.cache[key] = self._as_noise(i, part, NOISE_SPAN_S)
        return self.cache[key]

    def _limit_gain(self, i: int, limits: list) -> float:
        key = (i, 'unit gain ' + repr(limits))
        if key not in self.cache:
            b = self.bases[i]
            self.cache[key] = limit_gain(self.config(b), limits, b.axis, span(b))
        return self.cache[key]

    def _cut(self, i: int, limits: list) -> dict:
        """
        Return the share of the gyro noise's power a limit leaves, per quadratic element.

        Where the output sits at the limit its noise is gone: the limit scales the noise's
        power down (the twin's noise first restored by ``limit_gain``). Its part, one
        realisation with the limit less the same without, can take off more than a twin of
        another realisation holds (a band's largest line, weighted by the fast passages the
        limit flattens: log10 of a negative power, z of 3 000 on a 15 minute run); a twin
        keeps at least this share of its band means and rate-bin mean squares (``combine``'s
        floor), at most the gain (the phase-locked power is left out: the noise-alone runs
        carry there the limit's own change with the noise, E clip(w + n) - clip(w)).
        """
        key = (i, 'unit cut ' + repr(limits))
        if key not in self.cache:
            gain = self._limit_gain(i, limits)
            cut, plain = self._noise_alone(i, limits, True, gain), self._noise_alone(i, [], True)
            share = {q: np.clip(cut[q] / np.maximum(plain[q], 1e-300), 0.0, gain)
                     for q in ('mean2', 'ms')}
            self.cache[key] = {**share, 'line2': share['mean2']}
        return self.cache[key]

    def _rate_unit(self, i: int, name: str, level: dict) -> dict:
        # A rate noise alone at unit level (``unit_level``) over NOISE_SPAN_S, as a noise part.
        fx = {'name': name, 'params': {**PLAIN_OFF[name], **level}}
        return self._single(i, [fx], True, span_s=NOISE_SPAN_S)

    def _white_share(self, i: int, gain: float) -> tuple:
        """
        Return (the gyro noise's parts, their change when N² is scaled by ``gain``).

        The parts of R(sqrt(g) w + c) (w: the white noise, c: the correlated B and K, one
        realisation) are a + b g + c' sqrt(g) in g, so three runs (g = 1/16, 1/4, 1: at
        g = 0 the simulator would draw c from other numbers) give the change at any g, the
        correlated terms' own parts untouched.
        """
        grid = np.array(WHITE_GRID)
        runs = [self._as_noise(i, self._noise_alone(i, [], gain=g), NOISE_SPAN_S)
                for g in WHITE_GRID]
        inv = np.linalg.inv(np.column_stack([np.ones(3), grid, np.sqrt(grid)]))
        out = {}
        for q in QUADRATIC:
            coef = np.tensordot(inv, np.stack([np.asarray(r[q], float) for r in runs]), 1)
            out[q] = coef[1] * (gain - 1.0) + coef[2] * (np.sqrt(gain) - 1.0)
        p1 = runs[-1]
        return p1, out

    def _rate_noise(self, i: int, noises: list) -> dict:
        """
        Return the rate-dependent noises' part (``swing_rate_noise``), N's share included.

        Linear in the noise's power: a white scale-factor noise's quadratic parts are its
        unit run's times (sf_noise / unit)², a gated one's interpolated between unit runs on
        a grid of gates (one realisation, common to all). The twin's own gyro white noise
        gives up the mean power added (``rate_noise_gain``): its noise-alone parts times the
        gain less one, and no twin keeps less than that share of its power (``floor``).
        """
        b = self.bases[i]
        gain = rate_noise_gain(noises, b)
        plain, acc = self._white_share(i, gain)
        for fx in noises:
            name, p = fx['name'], fx['params']
            sf, gate = float(p.get('sf_noise', 0.0)), float(p.get('gate_noise', 0.0))
            terms = []
            if sf:
                unit = unit_level(name, b, False)
                terms.append(((sf / unit['sf_noise']) ** 2, self._rate_unit(i, name, unit)))
            where = gate_weights(float(p.get('noise_gate_rads', 0.0)), gate_grid(b))
            if gate and where is not None:
                k, f = where
                unit = unit_level(name, b, True)
                for j, w in ((k, 1.0 - f), (k + 1, f)):
                    run = self._rate_unit(i, name, {**unit,
                                                    'noise_gate_rads': gate_grid(b)[j]})
                    terms.append((w * (gate / unit['gate_noise']) ** 2, run))
            for w, run in terms:
                acc = {q: acc[q] + w * run[q] for q in QUADRATIC}
        return {**plain, **acc, 'floor': dict.fromkeys(('psd', 'mean2', 'ms', 'locked'), gain)}

    def part(self, i: int, effects: list) -> List[dict]:
        """Return D's raw parts on record ``i``: the deterministic effects', then noises'."""
        pairs = [split(fx) for fx in effects if fx['name'] not in NOISE_EFFECTS]
        det = [d for d, _ in pairs if d is not None]
        noises = [n for _, n in pairs if n is not None]
        # A full-scale limit acts on the noise too (it cuts what reaches past it, on one side
        # only: E clip(w + n) is not clip(w), the whole effect of a limit just below the peak
        # rate, and it smooths the clipped corners): its part is run with the twin's noise
        # over the whole record (the noise's share of a line peak falls with the length),
        # apart from the others (a gyro lag would colour that noise twice: ``_lag``), and
        # takes from a twin no more of its noise than the limit does (``_cut``).
        limits = limits_of(det)
        # A host stall (``_stall``): its motion part noise-free (with the twin's noise, one
        # realisation's cross term of the large stall residual with it went into every
        # pseudo-twin: the residual PSD's top bin 87 sigma off on a 120 s run).
        stalls = [fx for fx in det if fx['name'] == 'time_delay'
                  and fx['params'].get('stall_gain', 0)]
        det = [fx for fx in det if fx not in limits and fx not in stalls]
        out = [self._single(i, det, False)] if det else []
        if limits:
            gain = self._limit_gain(i, limits)
            out.append({**self._single(i, limits, False, span_s=LIMIT_SPAN_S, full=True,
                                       gain=gain), 'floor': self._cut(i, limits)})
        if stalls:
            out += self._stall(i, stalls)
        out += [self._lag(i, float(fx['params']['lag_s'])) for fx in det
                if fx['name'] == 'time_delay' and fx['params'].get('lag_s', 0)]
        out += [self._bend(i, fx) for fx in det if fx['params'].get('on_output', 0)]
        out += [self._rate_noise(i, noises)] if noises else []
        return out + [self._jitter(i, fx['params']) for fx in effects
                      if fx['name'] == 'timestamp_jitter' and fx['params'].get('sigma_s', 0)]


def jitter_shape(params: dict) -> dict:
    """Return a stamp error's correlation parameters: a resonance's, tau_s (order 2), or none."""
    if float(params.get('freq_hz', 0.0)):
        return {'freq_hz': float(params['freq_hz']), 'q': float(params.get('q', 2.0))}
    tau = float(params.get('tau_s', 0.0))
    if not tau:
        return {}
    return {'tau_s': tau, **({'order': 2.0} if float(params.get('order', 1.0)) == 2.0 else {})}
