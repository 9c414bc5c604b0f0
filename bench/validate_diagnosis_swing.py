"""
Blind validation of ``gyro-char diagnose --kind swing`` (the swing part of validate_diagnosis).

Clean swing records come from the bench simulator (the paper's model, ADIS16405 preset, gyro
at 200 Hz, encoder at 1 kHz, 60 s); the effect is then added HERE, to the finished record, with
shapes that differ from the catalogue's (``gyro_char.sim.effects``), and the diagnosis is not told:

- time_delay: a sensor-internal group delay of a fractional number of samples, applied to the
  rate values by a 4-tap Lagrange interpolation FIR (catalogue: the stamps are shifted);
- g_sensitivity: g_y f_y + g_z (f_z - g) from the stand angle (catalogue searches g_y alone);
- scale_factor_nonlinearity: a soft saturation S tanh(ω / S) (catalogue: k2 ω² + k3 ω³);
- scale_factor_asymmetry: a ω tanh(ω / 0.05 rad/s), a smoothed |ω| (catalogue: a |ω|);
- timestamp_jitter: uniformly distributed encoder stamp errors (catalogue: Gaussian). IMU
  stamp errors are not used: the residual is blind to them to first order (the integrated
  angle and the encoder read at the same wrong stamp are off by the same rate x error);
- encoder_cyclic_error: a first + third harmonic error on 1000 lines per turn (catalogue:
  first + second harmonic on 2048 lines).

The true rate and angle for these shapes are the stand model's (amplitude, period, phase of the
preset).

Three modes:

- ``single``: one 60 s run at the preset's 5 s period per case (the look-alike pairs are
  ambiguous there: the diagnosis flags them and names the separating run);
- ``two``: each case is TWO runs of the same gyro and effect, at periods 5 s and 2.5 s (same
  20° amplitude), diagnosed together. Halving the period doubles the peak rate A ω and halves
  A / ω, which separates both look-alike pairs: the cos θ residual of a delay (-A ω d) doubles
  while that of g-sensitivity (-g_y g A / ω) halves (4x apart), and the 2f line of an
  asymmetry (∝ a A ω) doubles while that of a quadratic term (∝ k2 (A ω)²) quadruples. Half
  the amplitude at the same period would not separate delay from g-sensitivity (both ∝ A);
- ``pairs``: two-run cases with two effects at once (delay + saturation, g-sensitivity +
  asymmetry, jitter + cyclic error); success = both found among the selected effects.

Usage::

    python bench/validate_diagnosis_swing.py --repeats 8            # all modes (long)
    python bench/validate_diagnosis_swing.py --mode two --repeats 8  # two-run table only
    python bench/validate_diagnosis_swing.py --quick                # clean + delay + g, two-run
"""
import argparse
import sys
import time

from gyro_char.diagnosis import engine as diagnose, swing as diag_swing
from gyro_char.records import ENCODER_CHANNEL, Recording
from gyro_char.sim import simulator
from gyro_char.sim.config import BenchConfig
import numpy as np

RATE_HZ = 200.0
DURATION = 60.0
PERIOD = 5.0
G0 = 9.80665


def _stand(cfg, t):
    w = 2 * np.pi / cfg.stand.period_s
    arg = w * t + cfg.stand.phase
    return cfg.stand.amplitude * np.sin(arg), cfg.stand.amplitude * w * np.cos(arg)


def lagrange_delay(t, x, phi, rate, rng, samples):
    # 4-tap Lagrange fractional delay of D = 1 + frac samples, minus the whole sample, so that
    # the net delay is ``samples`` (any real value in [0, 1)).
    d = 1.0 + samples
    k = np.arange(4)
    h = np.array([np.prod([(d - m) / (j - m) for m in k if m != j]) for j in k])
    y = np.convolve(x, h)[:x.size]
    y = np.r_[y[1:], y[-1]]   # remove the whole-sample part of the delay
    y[:3] = x[:3]
    return t, y


def g_both(t, x, phi, rate, rng, gy, gz):
    return t, x + gy * G0 * np.sin(phi) + gz * G0 * (np.cos(phi) - 1.0)


def saturation(t, x, phi, rate, rng, s):
    return t, x + s * np.tanh(rate / s) - rate


def smooth_asym(t, x, phi, rate, rng, a):
    return t, x + a * rate * np.tanh(rate / 0.05)


SHAPES = {
    'time_delay': (lagrange_delay, [{'samples': 0.23}, {'samples': 0.61}]),
    'g_sensitivity': (g_both, [{'gy': 2e-4, 'gz': 5e-5}, {'gy': 5e-4, 'gz': 1e-4}]),
    'scale_factor_nonlinearity': (saturation, [{'s': 1.3}, {'s': 0.9}]),
    'scale_factor_asymmetry': (smooth_asym, [{'a': 3e-3}, {'a': 8e-3}]),
    'timestamp_jitter': (None, [{'half_width': 1e-4}, {'half_width': 3e-4}]),
    'encoder_cyclic_error': (None, [{'a1': 5e-5, 'a3': 2e-5}, {'a1': 2e-4, 'a3': 5e-5}]),
}


PAIRS = [(('time_delay', 1), ('scale_factor_nonlinearity', 1)),
         (('g_sensitivity', 1), ('scale_factor_asymmetry', 1)),
         (('timestamp_jitter', 1), ('encoder_cyclic_error', 1))]
TWO_PERIODS = (PERIOD, PERIOD / 2)


def make_record(truth, seed, period=PERIOD):
    """IMU and encoder of one run with the harness-shaped effects ``[(name, level), ...]``."""
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': RATE_HZ},
                                                'stand': {'period_s': period}})
    run = simulator.simulate_swing(cfg, duration=DURATION, seed=seed, channels=('gyro_x',))
    imu, enc = run.imu, run.encoder
    rng = np.random.default_rng(seed + 99)
    for name, level in truth:
        fn, levels = SHAPES[name]
        p = levels[level]
        if name == 'encoder_cyclic_error':
            phi = enc.channels[ENCODER_CHANNEL]
            e = phi + p['a1'] * np.sin(1000 * phi + 0.4) + p['a3'] * np.sin(3000 * phi + 1.1)
            enc = Recording(enc.t, {ENCODER_CHANNEL: e}, enc.source)
        elif name == 'timestamp_jitter':
            w = p['half_width']
            enc = Recording(enc.t + rng.uniform(-w, w, enc.t.size), dict(enc.channels),
                            enc.source)
        else:
            phi, rate = _stand(cfg, imu.t)
            t, x = fn(imu.t, imu.channels['gyro_x'], phi, rate, rng, **p)
            imu = Recording(t, {'gyro_x': x}, imu.source)
    return imu, enc


def run_case(truth, seed, repeats, periods):
    # Runs of one case differ in period and noise realisation (seed), not in the effect.
    records = [(*make_record(truth, seed + 100 * k, per), per) for k, per in enumerate(periods)]
    return diagnose.run(diag_swing.swing_records_problem(records), repeats=repeats,
                        seed=seed + 17)


def cases(mode, quick, seeds):
    """(mode, truth, level label) per case; truth = [(effect, level), ...]."""
    if quick:
        yield 'two', [], seeds[0]
        yield 'two', [('time_delay', 1)], seeds[0]
        yield 'two', [('g_sensitivity', 1)], seeds[0]
        return
    for m in (('single', 'two', 'pairs') if mode == 'all' else (mode,)):
        if m == 'pairs':
            for pair in PAIRS:
                for s in seeds:
                    yield m, list(pair), s
            continue
        for s in seeds:
            yield m, [], s
        for name in SHAPES:
            for level in (0, 1):
                for s in seeds:
                    yield m, [(name, level)], s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--quick', action='store_true')
    ap.add_argument('--mode', choices=('single', 'two', 'pairs', 'all'), default='all')
    ap.add_argument('--repeats', type=int, default=5)
    ap.add_argument('--seeds', type=int, nargs='+', default=[11, 12])
    args = ap.parse_args(argv)
    rows, t0 = [], time.time()
    for mode, truth, seed in cases(args.mode, args.quick, args.seeds):
        d = run_case(truth, seed, args.repeats, (PERIOD,) if mode == 'single' else TWO_PERIODS)
        amb = sorted({n for a in d.ambiguous for n in a['effects']})
        rows.append({'mode': mode, 'truth': [n for n, _ in truth],
                     'label': '+'.join(f'{n}/{lv}' for n, lv in truth) or 'clean',
                     'seed': seed, 'detected': d.baseline_gap > d.null_gap['q95'],
                     'selected': d.selected_effects, 'ambiguous': amb,
                     'shrink': 1.0 - d.final_gap / d.baseline_gap,
                     'shrink_excess': 1.0 - d.final_excess / max(d.baseline_excess, 1e-12)})
        print(f'{mode:6s} {rows[-1]["label"]:52s} seed {seed} gap {d.baseline_gap:6.2f} -> '
              f'{d.final_gap:5.2f} (null q95 {d.null_gap["q95"]:.2f}) selected '
              f'{d.selected_effects} ambiguous {amb} [{time.time() - t0:.0f} s]', flush=True)
    for mode in ('single', 'two', 'pairs'):
        if any(r['mode'] == mode for r in rows):
            report(mode, [r for r in rows if r['mode'] == mode])
    return 0


def _pct(k, n):
    return f'{k}/{n} = {100.0 * k / max(n, 1):.0f} %'


def report(mode, rows):
    print(f'\n=== {mode} ===')
    eff = [r for r in rows if r['truth']]
    det = [r for r in eff if r['detected']]
    if mode == 'pairs':
        both = [r for r in det if set(r['truth']) <= set(r['selected'])]
        first = [r for r in det if r['selected'][:1] and r['selected'][0] in r['truth']]
        print(f'detected {len(det)}/{len(eff)}; both effects selected {_pct(len(both), len(det))}'
              f'; first selected is one of the pair {_pct(len(first), len(det))}')
        for r in eff:
            print(f'  {r["label"]:52s} seed {r["seed"]}: selected {r["selected"]}')
    else:
        ok = [r for r in det if r['selected'][:1] == r['truth']]
        flagged = [r for r in det if r not in ok and r['truth'][0] in r['ambiguous']]
        print(f'detected {len(det)}/{len(eff)}; top-1 (first selected == truth) among '
              f'detected {_pct(len(ok), len(det))}; wrong top-1 but flagged ambiguous with '
              f'the truth: {len(flagged)}')
        confusion(det)
    if det:
        print(f'median gap shrink over detected cases: 1 - final/baseline '
              f'{100.0 * float(np.median([r["shrink"] for r in det])):.0f} %, excess form '
              f'{100.0 * float(np.median([r["shrink_excess"] for r in det])):.0f} %')
    clean = [r for r in rows if not r['truth']]
    fa = [r for r in clean if r['selected']]
    print(f'false alarms on clean records: {len(fa)}/{len(clean)}')


def confusion(det):
    """Truth (rows) against the first selected effect (columns), detected cases."""
    cols = list(SHAPES) + ['none']
    short = {c: ''.join(w[0] for w in c.split('_')) for c in cols}
    print('  truth \\ first selected    ' + ' '.join(f'{short[c]:>5s}' for c in cols))
    for name in SHAPES:
        rs = [r for r in det if r['truth'] == [name]]
        counts = [sum((r['selected'] or ['none'])[0] == c for r in rs) for c in cols]
        print(f'  {name:28s}' + ' '.join(f'{k:5d}' for k in counts))
    print('  (' + ', '.join(f'{short[c]} = {c}' for c in cols) + ')')


if __name__ == '__main__':
    sys.exit(main())
