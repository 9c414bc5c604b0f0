"""
Swing-stand calibration: the paper's 5-state Kalman filter on encoder and integrated gyro angle.

``model`` (states, transition, estimates (1)-(3)), ``batch`` (the exact square-root information
filter over a whole run), ``align`` (encoder and gyro streams onto one time base), ``filter``
(``estimate_swing``: the offline entry point).
"""
from gyro_char.swing.filter import estimate_swing
from gyro_char.swing.model import SwingEstimates, SwingNoise

__all__ = ['estimate_swing', 'SwingEstimates', 'SwingNoise']
