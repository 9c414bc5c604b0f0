"""A weak mode's search starts where the PSD's gap lies (``static_bands.with_gap_band``)."""
from gyro_char.diagnosis import observables as obs
from gyro_char.diagnosis import static, static_expect
from gyro_char.diagnosis.engine import run
from gyro_char.diagnosis.static_bands import resonance_space, with_gap_band
import numpy as np
import pytest

DT = 0.01
LSB = 0.05 * np.pi / 180.0
BASE = static.StaticBaseline(N=7e-4, bias=0.0, drift=0.0, lsb=LSB, dt=DT)
SPAN = (0.1, 50.0)


def band(lo, hi, excess=4.0, observable='psd'):
    return {'observable': observable, 'range': [lo, hi], 'range_unit': 'Hz',
            'excess': excess}


def centres(space):
    """Return the freq_hz ranges of a resonance search and its alternatives."""
    return [next((p.lo, p.hi) for p in s.params if p.name == 'freq_hz')
            for s in (space,) + tuple(space.alternatives)]


def test_a_mid_spectrum_band_adds_one_start_there_and_only_once():
    spaces = [resonance_space(0.01, 5.0, DT, None)]
    where = [band(0.1, 0.3, excess=-6.0), band(19.6, 26.8), band(30.0, 36.0, excess=3.5)]
    out = with_gap_band(spaces, where, 0.01, DT, SPAN)
    ranges = centres(out[0])
    assert len(ranges) == 2 and ranges[0] == pytest.approx((4.25, 5.75))
    lo, hi = ranges[1]
    assert lo <= 19.6 and hi >= 26.8 and hi < 0.45 / DT
    q = next(p for p in out[0].alternatives[0].params if p.name == 'q')
    assert q.init == pytest.approx(np.sqrt(19.6 * 26.8) / 7.2)
    # The spaces given are not changed, and a second call adds nothing more.
    assert len(centres(spaces[0])) == 1
    assert len(centres(with_gap_band(out, where, 0.01, DT, SPAN)[0])) == 2


@pytest.mark.parametrize('where', [
    [band(0.1, 1.6)],                  # a rise from the lowest bin: a slow process
    [band(19.6, 50.0)],                # a rise to the highest: white angle noise
    [band(2.0, 12.0)],                 # six times wider than it is low: not one mode
    [band(19.6, 26.8, excess=-5.0)],   # a dip: a filter's
    [band(19.6, 26.8, observable='adev')],
    [band(4.5, 5.5)],                  # where the search starts already
])
def test_no_start_from_a_band_that_is_not_a_modes(where):
    spaces = [resonance_space(0.01, 5.0, DT, None)]
    assert len(centres(with_gap_band(spaces, where, 0.01, DT, SPAN)[0])) == 1


def test_a_weak_mode_without_a_peak_or_bump_is_named_at_its_frequency():
    # A mode too weak for a bump in the raw PSD, whose strongest narrow bin the noise put at
    # 16.7 Hz: the main start (+-15 % about that bin) cannot reach 23 Hz; the gap's band can.
    n = 2 ** 17
    x = static.simulate_twin(BASE, n, [('resonance', {'sigma': 1e-3, 'freq_hz': 23.0,
                                                      'q': 8.0})], 2)
    psd = obs.welch_psd(x, DT)
    tone = obs.detected_tones(x, DT, min_prominence=0.0, max_tones=1, psd=psd)[0]
    assert abs(tone - 23.0) > 0.15 * tone and obs.broad_peak(psd) is None
    problem = static_expect.closed_form_problem([x], DT, twins=8, seed=3)
    d = run(problem, repeats=8, seed=3)
    assert d.selected_effects == ['resonance']
    assert dict(d.model)['resonance']['freq_hz'] == pytest.approx(23.0, rel=0.05)
    assert d.baseline_gap > 1.5 * d.null_gap['q95'] and d.final_gap < d.null_gap['q95']
