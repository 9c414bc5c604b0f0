# Blind validation, small version of bench/validate_diagnosis.py: effects generated with shapes
# the package catalogue does not have (Hann FIR, amplitude-modulated tone, white angle error),
# not announced to the diagnosis; a clean baseline record must raise no effect.
import bench_script
import numpy as np


def _harness():
    return bench_script.load('validate_diagnosis')


def test_blind_diagnosis_names_unannounced_effects_and_stays_quiet_on_clean_data():
    h = _harness()
    n, repeats = 8192, 5
    clean = h.run_case([], n, seed=31, repeats=repeats)
    assert clean.selected_effects == []
    tone = h.run_case([('vibration', 1)], n, seed=32, repeats=repeats)
    assert tone.selected_effects[:1] == ['vibration']
    assert abs(tone.steps[0]['params']['freq_hz'] - 31.7) < 0.5
    smooth = h.run_case([('internal_lowpass', 1)], n, seed=33, repeats=repeats)
    assert smooth.selected_effects[:1] == ['internal_lowpass']
    assert smooth.final_gap < 0.3 * smooth.baseline_gap


def test_white_angle_error_is_read_as_dithered_quantization_of_the_same_power():
    # White angle error uniform on one step (variance step^2 / 12); the catalogue's dithered
    # quantizer has mean error variance step_c^2 / 6, so the same power is step_c = step / sqrt 2.
    h = _harness()
    d = h.run_case([('quantization', 1)], 8192, seed=34, repeats=5)
    assert d.selected_effects == ['quantization']      # no second effect to mop up the shape
    params = d.steps[0]['params']
    step = h.SHAPES['quantization'][1][1]['step']
    assert params['dither'] == 1.0
    assert abs(params['step_rad'] / (step / np.sqrt(2.0)) - 1.0) < 0.1
    assert d.final_excess < 0.1 * d.baseline_excess
