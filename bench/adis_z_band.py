"""
What the real ADIS16405 Z axis's 20 Hz band is: its wander in time and its fourth moment.

Reads the ADIS16405 ``*.csv.gz`` in shared/data beside the clone (never copied in). Per record:
the peak frequency in 12-40 Hz of 20.48 s windows (how far the band's centre wanders), the
band's power over the white floor's share of it (how steady it is), the share of the band's
power within 0.5 Hz of each window's peak (how narrow it is at any moment), and the excess
kurtosis per 5 Hz band (``gyro_char.diagnosis.band_kurtosis``): a Gaussian mode, wandering or
not, has an excess kurtosis of 0 or more; a line of steady amplitude has less.

    python bench/adis_z_band.py
"""
from pathlib import Path

from gyro_char.diagnosis import band_kurtosis as bk
from gyro_char.diagnosis import observables as obs
from gyro_char.io import read_imu
import numpy as np
from scipy import signal

DATA = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'adis16405'


def main() -> int:
    for path in sorted(DATA.glob('adis16405_static_*.csv.gz')):
        rec = read_imu(str(path), quiet=True)
        x = rec.channels['gyro_z']
        dt = float(np.median(np.diff(rec.t)))
        f, _, s = signal.spectrogram(x - x.mean(), fs=1.0 / dt, nperseg=2048, noverlap=0)
        band = (f >= 12.0) & (f <= 40.0)
        df = f[1] - f[0]
        peak = f[band][np.argmax(s[band], axis=0)]
        power = s[band].sum(axis=0) * df
        white = np.median(s[(f > 40.0) & (f < 48.0)]) * band.sum() * df
        near = np.array([s[band][np.abs(f[band] - p) <= 0.5, i].sum() / s[band][:, i].sum()
                         for i, p in enumerate(peak)])
        ranges = bk.band_ranges(x.size, dt)
        kurt = bk.record_kurtosis(obs.detrend(x), dt, ranges)
        print(f'{path.name}: {peak.size} windows of {2048 * dt:.2f} s')
        print('  peak frequency (Hz), 5/25/50/75/95 %:',
              np.round(np.percentile(peak, [5, 25, 50, 75, 95]), 2),
              '; first five windows:', np.round(peak[:5], 1))
        print('  band power / white floor, 5/50/95 %:',
              np.round(np.percentile(power / white, [5, 50, 95]), 2))
        print('  share within 0.5 Hz of the peak, 5/50/95 %:',
              np.round(np.percentile(near, [5, 50, 95]), 2))
        print('  excess kurtosis per band:', ', '.join(
            f'{lo:g}-{hi:g} Hz {k:+.2f}' for (lo, hi), k in zip(ranges, kurt)))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
