"""The static twin the filter and read-out tests share: 100 Hz, an ADIS16405's step and noise."""
from gyro_char.diagnosis import static
import numpy as np

DT = 0.01
LSB = 0.05 * np.pi / 180.0               # output step, 0.05 deg/s
N_ARW = 2.4 * np.pi / 180.0 / 60.0       # white rate noise, 2.4 deg/sqrt(h)
BASE = static.StaticBaseline(N=N_ARW, bias=0.0, drift=0.0, lsb=LSB, dt=DT)
