# Blind validation, small version of bench/validate_diagnosis.py: effects generated with shapes
# the package catalogue does not have (Hann FIR, amplitude-modulated tone), not announced to the
# diagnosis; a clean baseline record must raise no effect.
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _harness():
    spec = importlib.util.spec_from_file_location(
        'validate_diagnosis', ROOT / 'bench' / 'validate_diagnosis.py')
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


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
