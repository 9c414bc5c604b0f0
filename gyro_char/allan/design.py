"""
The fit's model: formula (4), with the sensor's filter in its white term and Markov terms added.

sigma^2(tau) = A(tau) z, z = [R^2, K^2, B^2, N^2, Q^2, q_1^2, q_2^2, ...] >= 0. The N column is
1 / tau (formula (4)) or, with a sensor filter, the exact Allan variance of unit-density white
noise through that filter and its decimation (``SensorFilter.white_avar``: N remains the
long-tau angle random walk). Each Markov column is IEEE 952 Annex C's exponentially
correlated term with its correlation time (``gyro_char.allan.expected.markov_avar``).
"""
from dataclasses import dataclass
from typing import Optional, Tuple

from gyro_char.allan.expected import markov_avar
from gyro_char.allan.model import design_matrix, TERMS
from gyro_char.allan.sensor_filter import SensorFilter
import numpy as np

N_INDEX = TERMS.index('N')


@dataclass(frozen=True)
class FitDesign:
    """Which columns the fit uses; ``dt`` (s) is needed only with a sensor filter."""

    dt: Optional[float] = None
    sensor_filter: Optional[SensorFilter] = None
    markov_tc: Tuple[float, ...] = ()

    @property
    def names(self) -> Tuple[str, ...]:
        """Return the column names: TERMS, then M1, M2, ... (one per Markov term)."""
        return TERMS + tuple(f'M{i + 1}' for i in range(len(self.markov_tc)))

    @property
    def markov_columns(self) -> Tuple[int, ...]:
        return tuple(range(len(TERMS), len(TERMS) + len(self.markov_tc)))

    def matrix(self, tau) -> np.ndarray:
        """Return A (len(tau), len(names)) with sigma^2 = A z."""
        tau = np.asarray(tau, dtype=np.float64)
        a_mat = design_matrix(tau)
        if self.sensor_filter is not None:
            if self.dt is None:
                raise ValueError('a sensor filter needs the sample interval dt')
            a_mat[:, N_INDEX] = self.sensor_filter.white_avar(tau, self.dt)
        if not self.markov_tc:
            return a_mat
        extra = np.stack([markov_avar(tau, tc) for tc in self.markov_tc], axis=-1)
        return np.concatenate([a_mat, extra], axis=-1)
