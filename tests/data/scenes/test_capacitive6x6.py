"""The capacitive skin scene (data/scenes/capacitive6x6.py): calibration against seed 001
(limit of detection ~0.1 N, ~150 counts at 3 N, nearly linear), the 12 x 21 grid, the effects
contract, the stream's ground truth, frames files (data/readers/contact_streams.py), bad input and
hard cases."""
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from omegaconf import OmegaConf

import data.scenes.capacitive6x6 as capacitive
from common.errors import InputError
from data.physics.hyperelastic_compression import gent_stretch, neo_hookean_stretch
from data.preprocessing.contact_windows import window_channel_names, window_indices, windows_around_peaks
from data.readers.contact_streams import TRUTH_COLUMNS, ContactStream, load_frames, save_frames_csv
from data.scenes.capacitive6x6 import Capacitive6x6Scene, channel_names
from data.scenes.capacitive6x6_effects import EFFECTS, FULL_SCALE_COUNTS
from data.scenes.capacitive6x6_sessions import SESSIONS

SCENES = Path(__file__).resolve().parents[3] / "configs" / "scene"
FULL_EFFECTS = OmegaConf.to_container(OmegaConf.load(SCENES / "capacitive6x6.yaml").effects)


def scene(effects=None, **kwargs):
    settings_ = {"n_repetitions": 3, "force_jitter": 0.0, "force_sensor_noise_n": 0.0, **kwargs}
    return Capacitive6x6Scene(effects=effects, **settings_)


def pressed_cell_change(table):
    """(force, change of the pressed cell) per press."""
    pitch = table.description["pitch_mm"]
    rows = (table.frame["y_mm"] / pitch - 0.5).round().astype(int)
    cols = (table.frame["x_mm"] / pitch - 0.5).round().astype(int)
    values = table.frame[table.channel_columns].to_numpy()
    index = rows.to_numpy() * table.description["grid"][1] + cols.to_numpy()
    return table.frame["force_n"].to_numpy(), values[np.arange(len(values)), index]


def short_stream(**kwargs):
    return Capacitive6x6Scene(protocol="stream", n_rest_frames=30, session_s=1.5, gap_s=0.2, **kwargs)


# -- calibration against seed 001 -----------------------------------------------------------
def level_means(table):
    """The force levels and the pressed cell's mean change at each."""
    force, change = pressed_cell_change(table)
    levels = np.unique(force)
    return levels, np.array([change[force == f].mean() for f in levels])


def line_r2(levels, means):
    slope, intercept = np.polyfit(levels, means, 1)
    return 1 - np.var(means - (slope * levels + intercept)) / np.var(means), slope


def test_ideal_chain_reads_about_150_counts_at_3_n_and_bends_as_the_papers_sensor():
    """The default spacer (Gent, J_m 0.2, 1150 counts/pF): a line through the ten levels' mean
    readings has R² 0.995-0.998 (seed 001's linear models, Table 2), 3 N reads ~140-150 counts
    (the paper: a peak of 150), the slope ~48 counts/N (its correlation factor 51.76), and the
    sensitivity falls with force."""
    levels, means = level_means(scene(press_cells=[[1, 1]]).generate())
    r2, slope = line_r2(levels, means)
    assert 0.995 < r2 < 0.998, r2
    assert 135 < means[-1] < 160 and 44 < slope < 52, (means[-1], slope)
    assert np.all(np.diff(means / levels) < 0)


def test_a_neo_hookean_spacer_reads_a_straight_line():
    """Without the limit (J_m null) the spacer's stiffening and the 1/d growth of C cancel to
    second order in the strain: the response is a line."""
    levels, means = level_means(scene(press_cells=[[1, 1]], spacer_limiting_i1=None, counts_per_pf=1000.0).generate())
    r2, slope = line_r2(levels, means)
    assert r2 > 0.999 and 140 < means[-1] < 160 and 45 < slope < 55, (r2, means[-1], slope)


def test_the_configured_sensor_is_the_scenes_default():
    """configs/scene/base/capacitive6x6.yaml and the class's keyword defaults are one sensor."""
    base = OmegaConf.load(SCENES / "base" / "capacitive6x6.yaml")
    defaults = Capacitive6x6Scene()
    for name in ("spacer_youngs_modulus_pa", "spacer_limiting_i1", "counts_per_pf", "spacer_thickness_mm",
                 "cover_thickness_mm", "sensing_area_mm2", "pitch_mm"):
        assert base[name] == getattr(defaults, name), name


def test_stiffer_spacer_reads_less():
    _, soft = pressed_cell_change(scene(force_levels_n=[0.5]).generate())
    _, stiff = pressed_cell_change(scene(force_levels_n=[0.5], spacer_youngs_modulus_pa=6.6e5).generate())
    assert 0.45 < stiff.mean() / soft.mean() < 0.55   # half the compliance, half the closure (small strain)


def test_gent_spacer_is_neo_hookean_without_a_limit_and_stiffens_as_it_closes():
    stress = np.array([0.0, 1e3, 3e4, 1e5, 1e6])
    neo = neo_hookean_stretch(stress, 3.3e5)
    assert np.allclose(gent_stretch(stress, 3.3e5, 1e9), neo, atol=1e-8)
    gent = gent_stretch(stress, 3.3e5, 0.2)
    assert gent[0] == 1.0 and np.all(np.diff(gent) < 0)                  # closes further under more stress
    assert np.all(gent[1:] > neo[1:])                                     # but less than neo-Hookean
    assert abs(1 - gent[1] / neo[1]) < 1e-4                               # the same at small strain
    locking = gent[-1] ** 2 + 2 / gent[-1] - 3                            # I1 - 3 stays below J_m = 0.2
    assert 0.15 < locking < 0.2
    invariant = gent ** 2 + 2 / gent - 3                                  # and the stress is Gent's (Newton's check)
    assert np.allclose(3.3e5 / 3 * (gent ** -2 - gent) * 0.2 / (0.2 - invariant), stress, rtol=1e-9)


def limit_of_detection_n(noise_counts):
    """LOD = 3 sigma_blank / sensitivity (IUPAC; Long & Winefordner, Anal. Chem. 55, 1983):
    sigma of one rest frame over the slope (counts per newton) of the pressed cell's change."""
    s = scene({"baseline_noise": {"noise_counts": noise_counts}, "quantisation": {}},
              force_levels_n=[0.1, 0.2, 0.3, 0.5, 1.0], n_repetitions=10, moving_average_frames=1)
    force, change = pressed_cell_change(s.generate())
    sigma = s.stream().frames[:30].std(axis=0).mean()   # rest frames of the same scene, same noise
    return 3.0 * sigma / np.polyfit(force, change, 1)[0]


def test_limit_of_detection_is_about_0_1_n_and_grows_with_noise():
    assert 0.08 < limit_of_detection_n(1.6) < 0.12
    assert limit_of_detection_n(6.0) > 0.3


def test_the_pressed_cell_responds_most_and_the_neighbours_less():
    table = scene(force_levels_n=[2.0]).generate()
    values = table.frame[table.channel_columns].to_numpy().reshape(-1, 6, 6)
    first = values[0]   # a press at cell (1, 1)
    assert np.unravel_index(first.argmax(), first.shape) == (1, 1)
    assert 0 < first[1, 2] < first[1, 1] and first[1, 3] < first[1, 2]


# -- grid size ------------------------------------------------------------------------------
def test_the_muca_12_x_21_grid_works_in_both_protocols(compose_config):
    cfg = compose_config(["scene=capacitive6x6_muca", "scene.n_repetitions=2"]).scene
    s = capacitive6x6_from(cfg)
    table = s.generate()
    assert table.channel_columns == channel_names(12, 21) and len(table.channel_columns) == 252
    values = table.frame[table.channel_columns].to_numpy().reshape(-1, 12, 21)
    strongest = [np.unravel_index(v.argmax(), v.shape) for v in values[table.frame["force_n"] > 1.0]]
    pressed = {tuple(c) for c in table.description["press_cells"]}
    assert set(map(tuple, strongest)) <= pressed
    s.protocol, s.session_s, s.n_rest_frames = "stream", 1.0, 20
    stream = s.generate()
    assert stream.frames.shape[1:] == (12, 21) and np.isfinite(stream.frames).all()


def capacitive6x6_from(cfg):
    from hydra.utils import instantiate
    return instantiate(cfg)


# -- the effects contract -------------------------------------------------------------------
def test_unlisted_effects_are_never_called(monkeypatch, counted_effects):
    spied, calls = counted_effects(EFFECTS)
    monkeypatch.setattr(capacitive, "EFFECTS", spied)
    monkeypatch.setattr(capacitive, "MATERIAL_EFFECTS", {n: spied[n] for n in capacitive.MATERIAL_EFFECTS})
    monkeypatch.setattr(capacitive, "READING_EFFECTS", {n: spied[n] for n in capacitive.READING_EFFECTS})
    scene({"hysteresis": {}, "baseline_noise": {}}).generate()
    assert {n for n, c in calls.items() if c} == {"hysteresis", "baseline_noise"}


def test_no_effects_means_an_ideal_noiseless_board():
    stream = short_stream().stream()
    rest = stream.frames[:stream.n_rest_frames]
    assert np.ptp(rest, axis=0).max() == 0.0    # zero-variance baseline: a hard case for the tracker


def test_an_effect_does_not_disturb_the_others_random_numbers():
    without = short_stream(effects={"baseline_noise": {}, "interference": {}}).stream().frames
    idle = short_stream(effects={"baseline_noise": {}, "drift": {"common_counts_per_min": 0.0, "cell_counts": 0.0},
                                 "interference": {}}).stream().frames
    assert np.array_equal(without, idle)


def test_same_scene_and_seed_give_identical_bytes_and_another_seed_differs():
    a = short_stream(effects=FULL_EFFECTS, seed=4).stream()
    b = short_stream(effects=FULL_EFFECTS, seed=4).stream()
    c = short_stream(effects=FULL_EFFECTS, seed=5).stream()
    assert a.frames.tobytes() == b.frames.tobytes() and a.truth.equals(b.truth)
    assert not np.array_equal(a.frames, c.frames)


def test_chunks_continue_one_recording(monkeypatch):
    """Frames simulated in small chunks equal frames simulated at once: the sensor's draws and
    the pending creep carry over, and every generator continues its sequence."""
    effects = {"hysteresis": {}, "fabrication_spread": {}, "crosstalk": {}, "drift": {}, "baseline_noise": {}}
    whole = short_stream(effects=effects).stream().frames
    monkeypatch.setattr(capacitive, "FRAMES_PER_CHUNK", 37)
    np.testing.assert_allclose(short_stream(effects=effects).stream().frames, whole, rtol=0, atol=1e-9)


def test_stream_is_what_generate_returns_for_the_stream_protocol():
    s = short_stream(effects={"baseline_noise": {}})
    assert np.array_equal(s.generate().frames, s.stream().frames) and s.load().truth.equals(s.stream().truth)


def test_effects_do_what_they_say():
    base = short_stream().stream()
    noisy = short_stream(effects={"baseline_noise": {"noise_counts": 2.0}}).stream()
    assert np.std(noisy.frames[:30] - base.frames[:30]) == pytest.approx(2.0, rel=0.1)
    quantised = short_stream(effects={"quantisation": {}}).stream().frames
    assert np.array_equal(quantised, np.rint(quantised)) and quantised.max() <= FULL_SCALE_COUNTS
    leaky = short_stream(effects={"crosstalk": {"rx_coupling": 0.1, "tx_coupling": 0.1}}).stream().frames
    rest = base.frames[0]
    assert (leaky - rest).sum() > (base.frames - rest).sum()
    drifting = short_stream(effects={"drift": {"common_counts_per_min": 0.0, "cell_counts": 20.0,
                                               "period_range_s": [10.0, 10.0]}}).stream().frames
    assert np.abs(drifting[:30] - base.frames[:30]).max() > 0.5      # the rest frames already wander
    spread = short_stream(effects={"fabrication_spread": {"gain_spread": 0.0, "offset_counts": 10.0}}).stream().frames
    assert np.std(spread[0] - rest) > 3.0


def test_hysteresis_lags_on_loading_and_lingers_on_unloading():
    s = scene({"hysteresis": {"creep_fraction": 0.3, "time_constant_s": 0.5}}, force_levels_n=[2.0],
              n_repetitions=1, press_cells=[[2, 2]])
    times = np.arange(40) / 60.0
    force = np.r_[np.linspace(0, 2, 20), np.linspace(2, 0, 20)]
    per_newton = s.stress_per_newton([15.0], [15.0], 2.5, "punch")[0]
    counts = s.read_frames(force[:, None, None] * per_newton, times)["counts"][:, 2, 2]
    ideal = Capacitive6x6Scene().read_frames(force[:, None, None] * per_newton, times)["counts"][:, 2, 2]
    up, down = 10, 29             # the same force (~1.05 N) on the way up and on the way down
    assert np.isclose(force[up], force[down], atol=0.06)
    assert counts[up] < ideal[up] and counts[down] > counts[up]


# -- the stream -----------------------------------------------------------------------------
def test_stream_truth_covers_every_session_with_unique_ids():
    stream = Capacitive6x6Scene(protocol="stream", seed=1).stream()
    truth = stream.truth
    assert list(truth.columns) == TRUTH_COLUMNS
    assert set(truth["session"]) == set(SESSIONS)
    assert truth["frame"].min() >= stream.n_rest_frames and truth["frame"].max() < stream.n_frames
    assert not truth.duplicated(["frame", "contact_id"]).any()
    per_frame = truth.groupby("frame").size()
    assert per_frame.max() <= 5 and (per_frame >= 1).all()
    assert (truth["force_n"] > 0).all() and (truth["radius_mm"] > 0).all()
    side = 6 * stream.pitch_mm
    assert truth["x_mm"].between(0, side).all() and truth["y_mm"].between(0, side).all()
    # a merge ends the younger contact; a split gives the parent's id to the larger child
    merge = truth[truth["session"] == "merge"]
    older, younger = sorted(merge["contact_id"].unique())
    assert merge.loc[merge["contact_id"] == older, "frame"].max() > merge.loc[merge["contact_id"] == younger, "frame"].max()
    split = truth[truth["session"] == "split"]
    parent, child = sorted(split["contact_id"].unique())
    first_child = split.loc[split["contact_id"] == child, "frame"].min()
    at = split[split["frame"] == first_child + 5].set_index("contact_id")["force_n"]
    assert at[parent] > at[child]


def test_stream_frames_light_up_under_single_contacts():
    stream = Capacitive6x6Scene(protocol="stream", seed=2, sessions=["hold", "glide"]).stream()
    truth = stream.truth
    rest = stream.frames[0]
    single = truth[truth.groupby("frame")["contact_id"].transform("size") == 1]
    single = single[single["force_n"] > 0.5]
    x_cells, y_cells = stream.cell_centres_mm()
    errors = []
    for _, row in single.iterrows():
        change = stream.frames[int(row["frame"])] - rest
        r, c = np.unravel_index(change.argmax(), change.shape)
        errors.append(np.hypot(x_cells[r, c] - row["x_mm"], y_cells[r, c] - row["y_mm"]))
    assert len(errors) > 50 and np.max(errors) <= stream.pitch_mm * np.sqrt(0.5) + 1e-9
    quiet = np.setdiff1d(np.arange(stream.n_rest_frames, stream.n_frames), truth["frame"])
    assert np.abs(stream.frames[quiet] - rest).max() < 1e-9


def test_contacts_add_up_linearly_while_the_strain_is_small():
    s = Capacitive6x6Scene()
    per_newton = s.stress_per_newton([9.0, 27.0], [9.0, 27.0], 4.0, "hertz")
    one = s.ideal_change_counts(0.1 * per_newton[0])
    two = s.ideal_change_counts(0.1 * per_newton.sum(axis=0))
    other = s.ideal_change_counts(0.1 * per_newton[1])
    np.testing.assert_allclose(two, one + other, rtol=1e-3, atol=1e-6)


# -- frames files ---------------------------------------------------------------------------
def test_frames_round_trip_through_csv_and_npy(tmp_path):
    stream = short_stream(effects={"baseline_noise": {}, "quantisation": {}}).stream()
    csv = save_frames_csv(stream, tmp_path / "frames.csv")
    assert csv.read_text().splitlines()[0].count(",") == 35
    back = load_frames(csv, 6, 6, n_rest_frames=30)
    assert isinstance(back, ContactStream) and back.truth is None
    assert np.array_equal(back.frames, stream.frames)
    np.save(tmp_path / "frames.npy", stream.frames)
    assert np.array_equal(load_frames(tmp_path / "frames.npy", 6, 6, n_rest_frames=30).frames, stream.frames)


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


REST = "\n".join([",".join(["1200"] * 4)] * 12) + "\n"


@pytest.mark.parametrize("text, rows, cols, message", [
    (REST + "1200,1200,1200\n", 2, 2, "rows differ in their number of cells|frame 12 has 1 missing cell"),
    (REST, 3, 3, "4 cells per frame, expected rows x cols = 9"),
    (REST + "1200,nan,1200,1200\n", 2, 2, "frame 12, cell 1 is not a finite number"),
    (REST + "1200,abc,1200,1200\n", 2, 2, r"frame 12, cell 1 is not a finite number: 'abc'"),
    ("", 2, 2, "file is empty"),
    (",".join(["1200"] * 4) + "\n", 2, 2, "1 frames, fewer than the 10 rest frames"),
])
def test_bad_frames_files_are_one_line_errors(tmp_path, text, rows, cols, message):
    with pytest.raises(InputError, match=message) as error:
        load_frames(write(tmp_path, "frames.csv", text), rows, cols, n_rest_frames=10)
    assert "\n" not in str(error.value)


def test_bad_npy_and_paths_are_one_line_errors(tmp_path):
    np.save(tmp_path / "grid.npy", np.zeros((20, 6, 6)))
    with pytest.raises(InputError, match="frames of 6 x 6 cells do not match the grid 12 x 21"):
        load_frames(tmp_path / "grid.npy", 12, 21)
    np.save(tmp_path / "nan.npy", np.full((20, 4), np.nan))
    with pytest.raises(InputError, match="frame 0, cell 0 is not a finite number"):
        load_frames(tmp_path / "nan.npy", 2, 2, n_rest_frames=10)
    with pytest.raises(InputError, match="no such file"):
        load_frames(tmp_path / "missing.csv", 6, 6)
    with pytest.raises(InputError, match="unsupported file type '.txt'"):
        load_frames(write(tmp_path, "frames.txt", REST), 2, 2)
    with pytest.raises(InputError, match="rows and cols must be positive integers"):
        load_frames(write(tmp_path, "frames.csv", REST), 0, 4)


@pytest.mark.parametrize("kwargs, message", [
    ({"cover_thickness_mm": -4.0}, "cover_thickness_mm must be a positive number"),
    ({"spacer_permittivity": 0.5}, "spacer_permittivity"),
    ({"spacer_limiting_i1": 0.0}, "spacer_limiting_i1 must be a positive number or null"),
    ({"protocol": "random"}, "protocol must be 'characterisation' or 'stream'"),
    ({"press_cells": [[6, 0]]}, r"press_cells must be \[row, col\] pairs inside the 6 x 6 grid"),
    ({"force_levels_n": [0.1, -1.0]}, "force_levels_n must be a list of positive forces"),
    ({"moving_average_frames": 40}, "moving_average_frames \\(40\\) cannot exceed hold_frames"),
    ({"rows": 0}, "rows and cols must be positive integers"),
    ({"effects": {"humidity": {}}}, "unknown effect 'humidity'; valid effects: baseline_noise"),
    ({"effects": {"baseline_noise": {"sigma": 1}}}, "effect 'baseline_noise' has no parameter 'sigma'"),
    ({"effects": {"baseline_noise": {"noise_counts": -1}}}, "noise_counts >= 0"),
    ({"protocol": "stream", "sessions": ["wave"]}, "unknown session 'wave'"),
    ({"protocol": "stream", "n_rest_frames": 3}, "n_rest_frames must be an integer >= 10"),
])
def test_impossible_scene_parameters_are_one_line_errors(kwargs, message):
    with pytest.raises(InputError, match=message) as error:
        Capacitive6x6Scene(**{"n_repetitions": 1, **kwargs}).generate()
    assert "\n" not in str(error.value)


# -- hard cases -----------------------------------------------------------------------------
contact = st.tuples(st.floats(-20, 80), st.floats(-20, 80), st.floats(0.0, 60.0), st.floats(0.0, 15.0))


@settings(max_examples=40)
@given(st.lists(contact, min_size=1, max_size=6), st.sampled_from([{}, {"quantisation": {}}, FULL_EFFECTS]))
def test_any_contacts_give_finite_frames_in_the_16_bit_range(contacts, effects):
    s = Capacitive6x6Scene(effects=effects)
    truth = pd.DataFrame([{"frame": 1, "contact_id": k, "x_mm": x, "y_mm": y, "force_n": f, "radius_mm": r,
                           "session": "hold"} for k, (x, y, f, r) in enumerate(contacts)])
    counts = s.frames_for(truth, 3)["counts"]
    assert np.isfinite(counts).all()
    if "quantisation" in effects:
        assert counts.min() >= 0 and counts.max() <= FULL_SCALE_COUNTS


def test_saturation_and_every_cell_above_threshold():
    s = Capacitive6x6Scene(effects={"quantisation": {}}, counts_per_pf=50_000.0)
    truth = pd.DataFrame([{"frame": 1, "contact_id": 0, "x_mm": 18.0, "y_mm": 18.0, "force_n": 200.0,
                           "radius_mm": 15.0, "session": "hold"}])
    counts = s.frames_for(truth, 2)["counts"]
    assert (counts[1] > counts[0]).all()                 # every cell above its rest value
    assert counts.max() == FULL_SCALE_COUNTS              # 16-bit saturation, not overflow or NaN


def test_a_run_with_an_impossible_scene_stops_before_writing_anything(compose_config, tmp_path):
    from runs.run import run
    cfg = compose_config(["experiment=capacitive_force", "model=linear_regression", "scene.spacer_thickness_mm=0"])
    with pytest.raises(InputError, match="spacer_thickness_mm must be a positive number") as error:
        run(cfg, tmp_path)
    assert "\n" not in str(error.value) and not any(tmp_path.iterdir())


@pytest.mark.slow   # ~10-30 s: a whole train.py process
def test_train_cli_refuses_an_impossible_scene_in_one_line_and_writes_nothing(tmp_path):
    import subprocess
    import sys
    root = Path(__file__).resolve().parents[3]
    out = tmp_path / "run"
    result = subprocess.run([sys.executable, str(root / "train.py"), "experiment=capacitive_force", "hydra.mode=RUN",
                             "model=linear_regression", "scene.cover_thickness_mm=-4", f"hydra.run.dir={out}"],
                            capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode == 2, result.stderr[-2000:]
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "cover_thickness_mm must be a positive number" in lines[0]
    assert not (out / "metrics.json").exists() and not (out / "model.onnx").exists()


def test_window_characterisation_reads_the_cells_around_each_press_as_the_tracker_does():
    cells = scene(n_repetitions=2).generate()
    window = scene(n_repetitions=2, characterisation_channels="window").generate()
    assert window.channel_columns == window_channel_names() and window.target_columns == ["force_n"]
    assert np.array_equal(window.channels[:, 4], cells.channels.max(axis=1))        # the centre: the largest cell
    np.testing.assert_array_equal(window.channels, windows_around_peaks(cells.channels, 6, 6))
    with pytest.raises(InputError, match="characterisation_channels"):
        scene(characterisation_channels="ring").generate()


@settings(max_examples=60)
@given(rows=st.integers(1, 7), cols=st.integers(1, 7), seed=st.integers(0, 2**16))
def test_windows_hold_the_peak_at_the_centre_and_zero_outside_the_grid(rows, cols, seed):
    loads = np.random.default_rng(seed).normal(size=(3, rows * cols))
    windows = windows_around_peaks(loads, rows, cols)
    assert np.array_equal(windows[:, 4], loads.max(axis=1))
    indices = window_indices(rows, cols)
    outside = indices == rows * cols
    assert outside.sum() == 9 * rows * cols - sum(                       # cells inside each 3 x 3 window
        (min(r + 1, rows - 1) - max(r - 1, 0) + 1) * (min(c + 1, cols - 1) - max(c - 1, 0) + 1)
        for r in range(rows) for c in range(cols))
    peak = loads.argmax(axis=1)
    assert np.all(windows[outside[peak]] == 0.0)


def test_press_offsets_move_the_presses_within_their_cells():
    centred = scene(n_repetitions=2).generate()
    moved = scene(n_repetitions=2, press_offset_mm=3.0).generate()
    shift = np.abs(moved.frame[["x_mm", "y_mm"]].to_numpy() - centred.frame[["x_mm", "y_mm"]].to_numpy())
    assert shift.max() <= 3.0 and shift.max() > 1.0
    assert not np.allclose(moved.channels, centred.channels)
    with pytest.raises(InputError, match="press_offset_mm"):
        scene(press_offset_mm=4.0).generate()        # beyond half the 6 mm pitch
