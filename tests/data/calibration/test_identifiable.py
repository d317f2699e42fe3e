"""Each calibratable scene declares parameters that exist on its default config, inside their
physical ranges, with a unit; values are read and set by path; the optimiser's [0, 1] coordinate
maps back to the value; a scene without declarations is a one-line error."""
import sys

import pytest
from hydra.utils import instantiate

from common.errors import InputError
from data.calibration.identifiable import (CALIBRATIONS, calibration_for, from_unit_interval, get_value,
                                           set_value, to_unit_interval)


@pytest.mark.parametrize("name", sorted(CALIBRATIONS))
def test_declared_parameters_sit_inside_their_ranges_on_the_default_scene(compose_config, name):
    scene = instantiate(compose_config([f"scene={name}"]).scene)
    calibration = calibration_for(scene)
    assert calibration.scene == name and calibration.parameters and calibration.not_identifiable
    for p in calibration.parameters:
        assert p.low < get_value(scene, p.path) < p.high, p.path
        assert p.unit and p.what
    assert set(calibration.unmodelled) <= set(sys.modules[type(scene).__module__].EFFECTS)


def test_values_are_read_and_set_by_path_without_touching_the_config_dicts(compose_config):
    scene = instantiate(compose_config(["scene=rubber12"]).scene)
    effects = scene.effects
    set_value(scene, "effects.contact.youngs_modulus_pa", 2.0e5)
    set_value(scene, "sheet_resistance_ohm_per_sq", 5.0e3)
    assert get_value(scene, "effects.contact.youngs_modulus_pa") == 2.0e5 and scene.sheet_resistance_ohm_per_sq == 5e3
    assert effects["contact"]["youngs_modulus_pa"] == 1.0e5   # a copy was changed, not the original mapping


def test_an_unset_effect_parameter_reads_its_functions_default(compose_config):
    scene = instantiate(compose_config(["scene=taxels"]).scene)
    scene.effects = {**scene.effects, "amplifier": {}}
    assert get_value(scene, "effects.amplifier.gain") == 55.0


@pytest.mark.parametrize("name", sorted(CALIBRATIONS))
def test_the_unit_interval_maps_back(name):
    for p in CALIBRATIONS[name].parameters:
        for value in (p.low, (p.low + p.high) / 2, p.high):
            assert from_unit_interval(p, to_unit_interval(p, value)) == pytest.approx(value, rel=1e-9)
        assert to_unit_interval(p, p.low) == pytest.approx(0.0, abs=1e-12)
        assert to_unit_interval(p, p.high) == pytest.approx(1.0)


def test_a_scene_without_declarations_is_refused():
    with pytest.raises(InputError, match="scene fingertip declares no calibration parameters; experiment=calibrate"):
        calibration_for("fingertip")
