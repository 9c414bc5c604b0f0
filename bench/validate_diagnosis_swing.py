"""
Blind validation of ``gyro-char diagnose --kind swing`` (the swing part of validate_diagnosis).

Clean swing records come from the bench simulator (the paper's model, ADIS16405 preset, gyro
at 200 Hz, encoder at 1 kHz, 60 s); the effect is then added HERE, to the finished record, with
shapes that differ from the catalogue's (``gyro_char.effects_*``), and the diagnosis is not told:

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
preset). Usage::

    python bench/validate_diagnosis_swing.py            # full table (a few minutes)
    python bench/validate_diagnosis_swing.py --quick    # clean + delay + saturation
"""
import argparse
import sys
import time

from gyro_char import bench_sim, diag_swing, diagnose
from gyro_char.recordings import ENCODER_CHANNEL, Recording
from gyro_char.sim_config import BenchConfig
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


def make_record(name, level, seed):
    cfg = BenchConfig.from_preset('adis16405', {'gyro': {'rate_hz': RATE_HZ}})
    run = bench_sim.simulate_swing(cfg, duration=DURATION, seed=seed, channels=('gyro_x',))
    imu, enc = run.imu, run.encoder
    if name is None:
        return imu, enc
    rng = np.random.default_rng(seed + 99)
    fn, levels = SHAPES[name]
    if name == 'encoder_cyclic_error':
        p = levels[level]
        phi = enc.channels[ENCODER_CHANNEL]
        e = phi + p['a1'] * np.sin(1000 * phi + 0.4) + p['a3'] * np.sin(3000 * phi + 1.1)
        return imu, Recording(enc.t, {ENCODER_CHANNEL: e}, enc.source)
    if name == 'timestamp_jitter':
        w = levels[level]['half_width']
        return imu, Recording(enc.t + rng.uniform(-w, w, enc.t.size),
                              dict(enc.channels), enc.source)
    phi, rate = _stand(cfg, imu.t)
    t, x = fn(imu.t, imu.channels['gyro_x'], phi, rate, rng, **levels[level])
    return Recording(t, {'gyro_x': x}, imu.source), enc


def run_case(name, level, seed, repeats):
    imu, enc = make_record(name, level, seed)
    return diagnose.run(diag_swing.swing_problem(imu, enc, PERIOD), repeats=repeats,
                        seed=seed + 17)


def cases(quick, seeds):
    if quick:
        yield None, None, seeds[0]
        yield 'time_delay', 1, seeds[0]
        yield 'scale_factor_nonlinearity', 1, seeds[0]
        return
    for s in seeds:
        yield None, None, s
    for name in SHAPES:
        for level in (0, 1):
            for s in seeds:
                yield name, level, s


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--quick', action='store_true')
    ap.add_argument('--repeats', type=int, default=5)
    ap.add_argument('--seeds', type=int, nargs='+', default=[11, 12])
    args = ap.parse_args(argv)
    rows, t0 = [], time.time()
    for name, level, seed in cases(args.quick, args.seeds):
        d = run_case(name, level, seed, args.repeats)
        amb = d.ambiguous[0]['effects'] if d.ambiguous else []
        rows.append({'truth': name, 'level': level, 'seed': seed,
                     'detected': d.baseline_gap > d.null_gap['q95'],
                     'selected': d.selected_effects, 'top1': d.ranking[0]['effect'],
                     'ambiguous': amb, 'shrink': 1.0 - d.final_gap / d.baseline_gap})
        print(f'{str(name):28s} level {level} seed {seed} gap {d.baseline_gap:6.2f} -> '
              f'{d.final_gap:5.2f} (null q95 {d.null_gap["q95"]:.2f}) top-1 '
              f'{rows[-1]["top1"]} selected {d.selected_effects} ambiguous {amb} '
              f'[{time.time() - t0:.0f} s]', flush=True)
    report(rows)
    return 0


def report(rows):
    eff = [r for r in rows if r['truth']]
    det = [r for r in eff if r['detected']]
    ok = [r for r in det if r['selected'][:1] == [r['truth']]]
    flagged = [r for r in det if r not in ok and r['truth'] in r['ambiguous']]
    print(f'\ndetected {len(det)}/{len(eff)}; top-1 (first selected == truth) among detected '
          f'{len(ok)}/{len(det)} = {100.0 * len(ok) / max(len(det), 1):.0f} %; wrong top-1 '
          f'but flagged ambiguous with the truth: {len(flagged)}')
    for name in SHAPES:
        rs = [r for r in eff if r['truth'] == name]
        print(f'  {name:28s} detected {sum(r["detected"] for r in rs)}/{len(rs)} first '
              f'selected {[(r["selected"] or ["none"])[0] for r in rs]}')
    if det:
        print(f'median gap shrink over detected cases: '
              f'{100.0 * float(np.median([r["shrink"] for r in det])):.0f} %')
    clean = [r for r in rows if not r['truth']]
    fa = [r for r in clean if r['selected']]
    print(f'false alarms on clean records: {len(fa)}/{len(clean)}')


if __name__ == '__main__':
    sys.exit(main())
