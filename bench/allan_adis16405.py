"""
N and B of the real ADIS16405 static records, per axis, against the paper and the datasheet.

Reads the ADIS16405 ``*.csv.gz`` in shared/data beside the clone (never copied in) and prints, per
record and gyro axis: the lag-1 autocorrelation of the samples, sigma(1 s) (the usual
read-off of N), the flat floor min sigma / 0.664 (the read-off of B), and the fitted N, B of
formula (4) (``--fit``, default the paper's L1 objective) over all taus and over tau >= 1 s
(clear of the sensor's internal averaging filter), their ratio, the largest deviation of the
fitted model from the curve below 0.1 s, sigma(0.01 s) x sqrt(0.01 s) (the N one would read off
inside the filtered region) and the strongest spectral line above 5 Hz. ``--sensor-filter`` and
``--markov`` are those of ``gyro-char allan``; with ``--out`` each record's allan.png (and the
other files) is written there.

    python bench/allan_adis16405.py [--boot 50] [--fit l1w]
    python bench/allan_adis16405.py --sensor-filter auto --markov 2 --out /tmp/adis
"""
import argparse
from pathlib import Path

from gyro_char.allan.compute import compute
from gyro_char.allan.fit import fit_result
from gyro_char.io import read_imu
from gyro_char.records import GYRO_CHANNELS
from gyro_char.report.allan_outputs import write_outputs
from gyro_char.units import to_human
import numpy as np

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'adis16405'
PAPER = {'gyro_x': (1.890, 36.950), 'gyro_y': (1.648, 31.058), 'gyro_z': (1.463, 30.724)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    ap.add_argument('--boot', type=int, default=50)
    ap.add_argument('--fit', choices=('l1', 'l1w', 'weighted'), default='l1')
    ap.add_argument('--sensor-filter', default='none')
    ap.add_argument('--markov', type=int, default=0)
    ap.add_argument('--out', default=None, help='write the files of each record in OUT/<record>')
    args = ap.parse_args()
    print('N in deg/sqrt(h), B in deg/h. Paper (Table 2) X/Y/Z: N 1.890/1.648/1.463, '
          'B 36.95/31.06/30.72; datasheet N 2.0, B 25.2/0.664 = 38.0')
    print(f'{"record":6s} {"axis":6s} {"acf1":>6s} {"s(1s)":>7s} {"floor/.664":>10s} '
          f'{"N fit":>7s} {"B fit":>7s} {"N t>=1s":>8s} {"B t>=1s":>8s} {"ratio":>6s} '
          f'{"dev<.1s":>7s} {"s(.01s)":>8s} {"line Hz":>8s}  filter / Markov T_c (s)')
    for path in sorted(DATA.glob('adis16405_static_*.csv.gz')):
        rec = read_imu(str(path), quiet=True)
        res = compute(rec, channels=list(GYRO_CHANNELS), sensor_filter=args.sensor_filter)
        fits = fit_result(res, method=args.fit, n_boot=args.boot, markov=args.markov)
        fits_1s = fit_result(res, method=args.fit, n_boot=args.boot, tau_min=1.0,
                             markov=args.markov)
        if args.out:
            write_outputs(str(Path(args.out) / path.name.split('.')[0]), res, fits, '/imu',
                          title=f'{path.name}: --sensor-filter {args.sensor_filter} '
                                f'--markov {args.markov}')
        dt = res.dt
        for c, name in enumerate(res.channels):
            y = rec.channels[name] - rec.channels[name].mean()
            acf1 = float(np.dot(y[1:], y[:-1]) / np.dot(y, y))
            k1 = int(np.argmin(np.abs(res.tau - 1.0)))
            n_read = res.adev[k1, c] * np.sqrt(res.tau[k1])
            b_read = res.adev[:, c].min() / 0.664
            spec = np.abs(np.fft.rfft(y[:2 ** 20] if y.size >= 2 ** 20 else y)) ** 2
            freq = np.fft.rfftfreq(min(y.size, 2 ** 20), dt)
            band = freq > 5.0
            line = freq[band][np.argmax(spec[band])]
            peak = spec[band].max() / np.median(spec[band])
            vals = [to_human('N', 'gyro', n_read), to_human('B', 'gyro', b_read),
                    to_human('N', 'gyro', fits[name].terms['N'].value),
                    to_human('B', 'gyro', fits[name].terms['B'].value),
                    to_human('N', 'gyro', fits_1s[name].terms['N'].value),
                    to_human('B', 'gyro', fits_1s[name].terms['B'].value),
                    to_human('N', 'gyro', res.adev[0, c] * np.sqrt(res.tau[0]))]
            short = res.tau < 0.1
            dev = np.max(np.abs(np.sqrt(fits[name].model_avar(res.tau[short])
                                        / res.avar[short, c]) - 1.0))
            filt = fits[name].extra_json()['sensor_filter']
            label = (filt['kind'] if filt['kind'] == 'none'
                     else f'{filt["kind"]}:{filt["taps"]}@{filt["internal_rate_x"]}x')
            markov = ','.join(f'{m.tau_c:.0f}' for m in fits[name].markov) or '-'
            print(f'{path.name[-8:-7]:>6s} {name:6s} {acf1:6.3f} {vals[0]:7.3f} {vals[1]:10.2f} '
                  f'{vals[2]:7.3f} {vals[3]:7.2f} {vals[4]:8.3f} {vals[5]:8.2f} '
                  f'{vals[2] / vals[4] - 1:+6.1%} {dev:7.1%} {vals[6]:8.3f} '
                  f'{line:6.2f}{"*" if peak > 30 else " "}  {label} / {markov}')
    print('line Hz: strongest spectral line above 5 Hz ("*": > 30x the median level)')


if __name__ == '__main__':
    main()
