"""Physics checks on the fingertip scene."""
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from common.errors import InputError
from data.scenes.fingertip import FingertipScene
from data.scenes.fingertip_boards import TEXTURES

FULL = OmegaConf.to_container(OmegaConf.load(Path(__file__).resolve().parents[3] / "configs/scene/fingertip.yaml").effects)


def scene(boards, effects=None, **kwargs):
    return FingertipScene(boards=boards, effects=effects or {}, **{"passes_per_level": 2, **kwargs}).generate()


@pytest.mark.parametrize("texture", TEXTURES[1:])
def test_triboelectric_fundamental_is_speed_over_period(texture):
    recordings = scene([f"resin/{texture}"], FULL, force_levels_n=[10], passes_per_level=1)
    period_mm = float(texture.split("_")[1][:-2])
    speed = 15.0
    current = recordings.channel("triboelectric_na")[0]
    t = recordings.time_s
    # the sliding segment: after the cushion is loaded, before it unloads (with a margin)
    sliding = (t > 1.5) & (t < 6.5)
    segment = current[sliding] - current[sliding].mean()
    spectrum = np.abs(np.fft.rfft(segment * np.hanning(segment.size), n=16 * segment.size))
    freqs = np.fft.rfftfreq(16 * segment.size, 1 / recordings.sample_rate_hz)
    band = (freqs > 0.5) & (freqs < 40.0)    # below the mains hum
    dominant = freqs[band][np.argmax(spectrum[band])]
    assert dominant == pytest.approx(speed / period_mm, rel=0.05)


def test_piezoresistive_channel_is_monotone_in_force():
    recordings = scene(["acrylic/flat"], FULL)
    plateau = recordings.channel("piezoresistive_v")[:, 400:1500].mean(axis=1)
    by_level = recordings.labels.assign(v=plateau).groupby("force_level_n")["v"].mean()
    assert by_level.is_monotonic_increasing and by_level.diff().dropna().gt(0).all()
    assert 0.0 < by_level.iloc[0] and by_level.iloc[-1] < 3.3
    # saturation: the step from 20 to 25 N is smaller than from 1 to 5 N
    assert by_level[25.0] - by_level[20.0] < by_level[5.0] - by_level[1.0]


def test_higher_charge_material_gives_larger_current_at_equal_force():
    recordings = scene(["glass/flat", "acrylic/flat", "carbon_fibre/flat"], {}, force_levels_n=[15])
    mean_abs = recordings.labels.assign(i=np.abs(recordings.channel("triboelectric_na")).mean(axis=1)) \
        .groupby("material")["i"].mean()
    assert mean_abs["glass"] > mean_abs["acrylic"] > mean_abs["carbon_fibre"]


def test_materials_differ_in_how_charge_grows_with_force():
    """Persson's real contact area: smooth glass is in full contact from the lightest level, rough
    leather's contact (and so its charge) keeps growing, marble saturates between the two."""
    ft = FingertipScene(boards=["glass/flat"])
    glass = ft.real_contact_fraction([1.0, 25.0], "glass")
    leather = ft.real_contact_fraction([1.0, 25.0], "leather")
    assert glass[0] > 0.99
    assert leather[1] > 10 * leather[0] and leather[1] < 0.5
    marble = ft.real_contact_fraction([1.0, 5.0], "marble")
    assert marble[0] < 0.9 < marble[1]
    recordings = scene(["leather/flat", "glass/flat"], {}, force_levels_n=[1, 25])
    peak = np.abs(recordings.channel("triboelectric_na")).max(axis=1)
    labels = recordings.labels.assign(peak=peak).groupby(["material", "force_level_n"])["peak"].mean()
    assert labels["leather", 25.0] > 5 * labels["leather", 1.0]
    assert labels["glass", 25.0] < 1.15 * labels["glass", 1.0]


def test_cushion_compression_is_a_small_share_of_its_thickness():
    ft = FingertipScene()
    assert ft.cushion_compression_mm(25.0) < 0.05 * ft.cushion_thickness_mm
    assert 5.0 < ft.normal_stiffness_n_per_mm < ft.finger_stiffness_n_per_mm


def test_flat_boards_carry_no_grating_carrier():
    """A uniform surface has nothing for the 2 mm electrode grating to modulate: no line at
    v / 2 mm = 7.5 Hz on a flat board (without noise), one at v / period on a ridged board."""
    recordings = scene(["acrylic/flat", "acrylic/circular_5mm"], {}, force_levels_n=[10], passes_per_level=1)
    t = recordings.time_s
    sliding = (t > 1.5) & (t < 6.5)
    current = recordings.channel("triboelectric_na")[:, sliding]
    spectrum = np.abs(np.fft.rfft(current - current.mean(axis=1, keepdims=True), axis=1))
    freqs = np.fft.rfftfreq(current.shape[1], 1 / recordings.sample_rate_hz)
    line = np.abs(freqs - 7.5) < 0.3
    assert spectrum[0, line].max() < 1e-3 * spectrum[1].max()


def test_stick_slip_frequency_falls_with_load_and_shows_in_the_force():
    effects = {"stick_slip": {"finger_tangential_stiffness_n_per_mm": 5.0}}   # a soft finger: slow enough to sample
    recordings = scene(["resin/flat"], effects, force_levels_n=[10, 25], passes_per_level=1)
    t = recordings.time_s
    sliding = (t > 1.5) & (t < 6.5)
    volts = recordings.channel("piezoresistive_v")[:, sliding]
    spectrum = np.abs(np.fft.rfft(volts - volts.mean(axis=1, keepdims=True), axis=1))
    freqs = np.fft.rfftfreq(volts.shape[1], 1 / recordings.sample_rate_hz)
    ft = FingertipScene()
    k_t = 1 / (1 / ft.cushion_shear_stiffness_n_per_mm + 1 / 5.0)
    resin = ft.material_properties()["resin"]
    expected = [15.0 * k_t / (2 * (resin["static_friction"] - resin["kinetic_friction"]) * f) for f in (10, 25)]
    dominant = freqs[np.argmax(spectrum[:, 1:], axis=1) + 1]
    np.testing.assert_allclose(dominant, expected, rtol=0.05)
    assert dominant[1] < dominant[0]


def test_protocol_labels_and_shapes():
    recordings = scene("combined18", {})
    assert len(recordings) == 18 * 6 * 2 and recordings.signals.shape[1] == 2
    assert recordings.labels["board"].nunique() == 18
    paper = {f"{m}/{t}" for m in ("silk", "paper") for t in ("flat", "circular_4mm", "circular_6mm",
                                                               "triangular_4mm", "triangular_6mm")} \
        | {f"{m}/flat" for m in ("acrylic", "bakelite", "marble", "leather", "nylon", "glass", "resin", "wood")}
    assert set(recordings.labels["board"]) == paper          # the paper's sec. 4.2.3
    assert set(recordings.labels["force_level_n"]) == {1, 5, 10, 15, 20, 25}
    assert recordings.signals.dtype == np.float32 and np.isfinite(recordings.signals).all()
    assert recordings.signals.shape[2] > 1400  # longer than the paper's 1,400-step window


def test_humidity_lowers_the_current_and_drifts_slowly_over_the_session():
    dry = scene(["glass/circular_5mm"], {"humidity": {"relative_humidity_pct": 20, "drift_pct": 0}})
    wet = scene(["glass/circular_5mm"], {"humidity": {"relative_humidity_pct": 80, "drift_pct": 0}})
    assert np.abs(wet.signals[:, 0]).mean() < 0.5 * np.abs(dry.signals[:, 0]).mean()
    session = scene("materials10", {"humidity": {}}, passes_per_level=15, force_levels_n=[1, 5, 10, 15, 20, 25])
    rh = session.labels["relative_humidity_pct"].to_numpy()
    step = np.abs(np.diff(rh))
    assert step.std() < 0.4 and step.max() < 1.5 and 1.0 < rh.max() - rh.min() < 15   # ~0.25 % RH a pass, a few % a session


def test_effects_are_seeded_and_each_draws_from_its_own_stream():
    a, b = scene(["glass/flat"], FULL, seed=3), scene(["glass/flat"], FULL, seed=3)
    assert a.signals.tobytes() == b.signals.tobytes()
    base = {"stick_slip": {}, "roughness": {}, "electrostatic_noise": {}}
    # humidity held at its reference leaves sigma unchanged: listing it must not move the others' draws
    neutral = {**base, "humidity": {"relative_humidity_pct": 30.0, "reference_pct": 30.0, "drift_pct": 0.0}}
    x, y = scene(["leather/flat"], base), scene(["leather/flat"], neutral)
    np.testing.assert_array_equal(x.signals, y.signals)


def test_touch_down_does_not_clip_the_adc_at_25_n():
    recordings = scene(["glass/flat", "nylon/flat", "silk/triangular_4mm"], FULL, force_levels_n=[25])
    current = recordings.channel("triboelectric_na")
    assert np.abs(current).max() < 0.8 * 3.3 / 2 / 0.005
    assert recordings.channel("piezoresistive_v").max() < 3.2


def test_adc_quantises_and_clips():
    recordings = scene(["glass/flat"], {"adc": {"bits": 4}}, force_levels_n=[25])
    volts = recordings.channel("piezoresistive_v")
    assert np.unique(volts).size <= 16
    current = recordings.channel("triboelectric_na")
    assert np.abs(current).max() <= 3.3 / 2 / 0.005 + 1e-3


@pytest.mark.parametrize("kwargs, message", [
    ({"boards": "materials11"}, "unknown board set 'materials11'"),
    ({"boards": ["gold/flat"]}, "unknown material 'gold'"),
    ({"boards": ["glass/wavy_3mm"]}, "unknown texture 'wavy_3mm'"),
    ({"effects": {"percolation": {}}}, "scene fingertip: unknown effect 'percolation'; valid effects: adc"),
    ({"force_levels_n": [0, 5]}, "force_levels_n"),
    ({"materials": {"glass": {"youngs_modulus_mpa": -5.0}}}, "youngs_modulus_mpa must be positive"),
    ({"materials": {"glass": {"kinetic_friction": -0.1}}}, "friction must satisfy"),
    ({"materials": {"glass": {"static_friction": 0.1}}}, "friction must satisfy"),
    ({"materials": {"glass": {"hurst_exponent": 1.5}}}, "hurst_exponent"),
    ({"materials": {"glass": {"colour": 3}}}, "unknown property 'colour'"),
    ({"materials": {"gold": {"static_friction": 0.3}}}, "a new material needs every property"),
    ({"cushion_modulus_mpa": -1.0}, "cushion_modulus_mpa must be positive"),
    ({"reference_v": 5.0}, "reference_v"),
    ({"effects": {"stick_slip": {"normal_coupling": 2.0}}}, "normal_coupling"),
])
def test_bad_settings_are_one_line_errors(kwargs, message):
    with pytest.raises(InputError, match=message):
        FingertipScene(**{"boards": ["glass/flat"], **kwargs}).generate()
