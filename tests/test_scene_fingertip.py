"""Physics checks on the fingertip scene."""
from pathlib import Path

import numpy as np
import pytest
from omegaconf import OmegaConf

from data.scenes.fingertip_boards import TEXTURES
from data.errors import InputError
from data.scenes.fingertip import FingertipScene

FULL = OmegaConf.to_container(OmegaConf.load(Path(__file__).resolve().parents[1] / "configs/scene/fingertip.yaml").effects)


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
    band = freqs > 0.5
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


def test_charge_grows_with_force_so_force_confounds_material():
    recordings = scene(["acrylic/flat"], {}, force_levels_n=[1, 25])
    mean_abs = np.abs(recordings.channel("triboelectric_na")).mean(axis=1)
    assert mean_abs[recordings.labels.force_level_n == 25].min() > 3 * mean_abs[recordings.labels.force_level_n == 1].max()


def test_protocol_labels_and_shapes():
    recordings = scene("combined18", {})
    assert len(recordings) == 18 * 6 * 2 and recordings.signals.shape[1] == 2
    assert recordings.labels["board"].nunique() == 18
    assert set(recordings.labels["force_level_n"]) == {1, 5, 10, 15, 20, 25}
    assert recordings.signals.dtype == np.float32 and np.isfinite(recordings.signals).all()
    assert recordings.signals.shape[2] > 1400  # longer than the paper's 1,400-step window


def test_humidity_lowers_the_current_and_effects_are_seeded():
    dry = scene(["glass/circular_5mm"], {"humidity": {"relative_humidity_pct": 20, "spread_pct": 0}})
    wet = scene(["glass/circular_5mm"], {"humidity": {"relative_humidity_pct": 80, "spread_pct": 0}})
    assert np.abs(wet.signals[:, 0]).mean() < 0.5 * np.abs(dry.signals[:, 0]).mean()
    a, b = scene(["glass/flat"], FULL, seed=3), scene(["glass/flat"], FULL, seed=3)
    assert a.signals.tobytes() == b.signals.tobytes()


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
])
def test_bad_settings_are_one_line_errors(kwargs, message):
    with pytest.raises(InputError, match=message):
        FingertipScene(**{"boards": ["glass/flat"], **kwargs}).generate()
