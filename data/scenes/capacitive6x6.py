"""Scene `capacitive6x6`: a soft mutual-capacitance array of copper-yarn Tx/Rx crossings.

Sensor (seed 001, Egger et al., Sensors 25, 3011, 2025, sec. 2.2-2.3): a 6 x 6 grid of 0.2 mm
copper-yarn electrodes, Rx along the rows and Tx along the columns (the MUCA's 12 Rx x 21 Tx
read as 12 rows x 21 columns, as the public code's nrows=12, ncols=21), separated at each crossing
by a thin dielectric spacer ("a synthetic layer between them", sec. 2.1), under a 4 mm Dragon
Skin (Shore 2A) cover and on a 5 mm Ecoflex 00-30 layer; read by a MUCA board (FocalTech
FT5316, 21 Tx x 12 Rx, 1-4 pF, 16-bit raw values) at ~60 frames/s. Grid size is a parameter:
the MUCA's full 12 x 21 works the same way. Cell (r, c) sits at x = (c + 1/2) pitch,
y = (r + 1/2) pitch.

Ideal chain, per frame and crossing (what runs with no effect listed):
1. Loads on the surface (a probe or fingertips) spread through the cover: the vertical stress
   at the crossings' depth z = cover + spacer/2 is the Boussinesq solution sigma_zz =
   3 P z^3 / (2 pi R^5) (Johnson, *Contact Mechanics*, 1985, eq. 3.18f;
   data/physics/elastic_half_space.py), superposed over the contact disc (flat punch p ~
   1/sqrt(1 - r^2/a^2) for the robot's PLA probe, Johnson eq. 3.35; Hertz p ~ sqrt(1 - r^2/a^2)
   for fingertips, eq. 4.23) and averaged over the crossing's sensing disc (its fringing
   field, area `sensing_area_mm2`; tabulated in data/physics/buried_disc_stress.py). The cover
   is taken as a half-space (its 4 mm against loads of 2.5-5 mm radius); the soft Ecoflex below
   would spread the load a little more.
2. The spacer closes under that stress. Soft silicones at tens of percent strain need a
   hyperelastic law (physics notes; data/physics/hyperelastic_compression.py): incompressible
   neo-Hookean uniaxial compression, sigma = (E/3)(lambda^-2 - lambda), solved for the stretch
   lambda = d / d0; or, with
   `spacer_limiting_i1` set (the default, J_m = 0.2), Gent's law (the neo-Hookean stress times
   J_m / (J_m - (I1 - 3))), whose spacer stiffens as it closes, as a synthetic foam or fabric
   spacer does: the response bends below a line as seed 001's does (Table 2's linear R² 0.995-0.998).
3. Parallel-plate capacitance C = eps0 eps_r A / d (seed 001 eq. 1) with d = d0 lambda.
4. The board reports C as raw counts ("ratio of mutual capacitance", RMC) with a gain
   `counts_per_pf`; the defaults are calibrated to seed 001 sec. 3.4: limit of detection
   ~0.1 N (with baseline_noise), a change of ~150 counts at 3 N, nearly linear.
Effects (data/scenes/capacitive6x6_effects.py) add the non-ideal parts; nothing is on unless
listed.

Protocols:
- `characterisation` (sec. 3.4-3.5): the robot presses the PLA probe (5 mm diameter) at the
  centres of `press_cells` at each of `force_levels_n`, `n_repetitions` times. Every press is
  a short frame sequence (rest, ramp, hold, release) through the same chain. One row per
  press: channels `rmc_r{row}_c{col}` = the change of each cell's reading from the rest frames
  just before the press, after the paper's moving-average filter (a trailing mean of the last
  `moving_average_frames` hold frames, applied here on the host side as the paper's pipeline
  did, so a deployed model takes the averaged reading); targets force_n (the force sensor's
  reading over the same frames), x_mm, y_mm of the press; groups = the repetition, so a
  grouped 70/30 split keeps whole repetitions apart. With `characterisation_channels: window`
  the channels are the 3 x 3 cells around each press's largest change instead
  (data/preprocessing/contact_windows.py, the window the contact tracker reads a contact's force from) and
  the target is force_n alone.
- `stream` (sec. 3.3): `n_rest_frames` frames without contact (the tracker's calibration),
  then sessions of 1-5 contacts that tap, hold, glide, cross, merge and split
  (data/readers/contact_streams.py), each followed by a gap. `stream()` returns a ContactStream with
  the raw frames and the ground truth per frame and contact.
"""
import numpy as np
import pandas as pd

from common.errors import InputError
from data.physics.buried_disc_stress import PROFILES, kernel_lookup, stress_kernel
from data.physics.hyperelastic_compression import gent_stretch, neo_hookean_stretch
from data.preprocessing.contact_windows import window_channel_names, windows_around_peaks
from data.readers.contact_streams import ContactStream, check_grid
from data.scenes.capacitive6x6_effects import EFFECTS, MATERIAL_EFFECTS, READING_EFFECTS
from data.scenes.capacitive6x6_sessions import SESSIONS, Choreography, choreograph
from data.scenes.contract import random_generator_for, resolve_effects
from data.sensor_table import SensorTable

EPSILON_0_F_PER_M = 8.8541878128e-12
TARGETS = ["force_n", "x_mm", "y_mm"]
CHARACTERISATION_CHANNELS = ("cells", "window")
PRESSES_PER_CHUNK = 256      # characterisation presses simulated together (memory, not results)
FRAMES_PER_CHUNK = 2048      # stream frames simulated together


def channel_names(rows: int, cols: int) -> list[str]:
    """Row-major cell names, the order the firmware streams them (seed 001 eq. 2)."""
    return [f"rmc_r{r}_c{c}" for r in range(rows) for c in range(cols)]


def pressed_cell(frame: pd.DataFrame, rows: int, cols: int, pitch_mm: float) -> np.ndarray:
    """Each press's cell, as its row-major channel index row * cols + col (from the press's x_mm, y_mm)."""
    row = np.clip(np.rint(frame["y_mm"].to_numpy() / pitch_mm - 0.5).astype(np.int64), 0, rows - 1)
    col = np.clip(np.rint(frame["x_mm"].to_numpy() / pitch_mm - 0.5).astype(np.int64), 0, cols - 1)
    return row * cols + col


def pressed_cell_rmc(frame: pd.DataFrame, rows: int, cols: int, pitch_mm: float) -> np.ndarray:
    """Each press's reading at the cell it was pressed on."""
    values = frame[channel_names(rows, cols)].to_numpy(dtype=np.float64)
    return values[np.arange(len(values)), pressed_cell(frame, rows, cols, pitch_mm)]


def correlation_factor_rmc_per_n(rmc: np.ndarray, force_n: np.ndarray) -> float:
    """Seed 001's "correlation factor" (sec. 3.5: "the average slope obtained from the Decision
    Tree model was 51.76"): the least-squares slope, with an intercept, of the pressed cell's RMC
    change against force, in counts per newton. Given a model's predicted force it is that
    model's slope; given the force sensor's reading, the sensor's sensitivity. Its inverse
    (newtons per count) turns a reading into force. The paper's value, ~150 counts at 3 N, is
    consistent with counts per newton, not newtons per count."""
    rmc, force_n = np.asarray(rmc, dtype=float), np.asarray(force_n, dtype=float)
    if len(rmc) < 2 or np.ptp(force_n) == 0:
        return float("nan")
    return float(np.polyfit(force_n, rmc, 1)[0])


class Capacitive6x6Scene:
    """Simulated capacitive skin: `generate()` (characterisation) -> SensorTable; `stream()` -> ContactStream."""

    name = "capacitive6x6"

    def __init__(self, rows=6, cols=6, pitch_mm=6.0, protocol="characterisation", seed=0, effects=None,
                 cover_thickness_mm=4.0, spacer_thickness_mm=0.5, spacer_permittivity=2.8,
                 spacer_youngs_modulus_pa=3.3e5, spacer_limiting_i1=0.2, sensing_area_mm2=25.0, counts_per_pf=1150.0,
                 frame_rate_hz=60.0,
                 probe_radius_mm=2.5, probe_profile="punch",
                 force_levels_n=(0.1, 0.2, 0.3, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0), n_repetitions=100,
                 press_cells=((1, 1), (1, 4), (4, 1), (4, 4)), force_jitter=0.02, force_sensor_noise_n=0.005,
                 rest_frames_per_press=30, ramp_frames=4, hold_frames=20, moving_average_frames=5,
                 characterisation_channels="cells", press_offset_mm=0.0, n_rest_frames=120, sessions=SESSIONS, session_s=3.0, gap_s=0.5, max_contacts=5,
                 contact_force_range_n=(0.3, 3.0), contact_radius_range_mm=(3.0, 5.0),
                 contact_speed_range_mm_s=(15.0, 40.0), contact_profile="hertz", progress=False):
        self.rows = rows
        self.cols = cols
        self.pitch_mm = pitch_mm
        self.protocol = protocol
        self.seed = seed
        self.effects = effects
        self.cover_thickness_mm = cover_thickness_mm
        self.spacer_thickness_mm = spacer_thickness_mm
        self.spacer_permittivity = spacer_permittivity
        self.spacer_youngs_modulus_pa = spacer_youngs_modulus_pa
        self.spacer_limiting_i1 = spacer_limiting_i1
        self.sensing_area_mm2 = sensing_area_mm2
        self.counts_per_pf = counts_per_pf
        self.frame_rate_hz = frame_rate_hz
        self.probe_radius_mm = probe_radius_mm
        self.probe_profile = probe_profile
        self.force_levels_n = force_levels_n
        self.n_repetitions = n_repetitions
        self.press_cells = press_cells
        self.force_jitter = force_jitter
        self.force_sensor_noise_n = force_sensor_noise_n
        self.rest_frames_per_press = rest_frames_per_press
        self.ramp_frames = ramp_frames
        self.hold_frames = hold_frames
        self.moving_average_frames = moving_average_frames
        self.characterisation_channels = characterisation_channels
        self.press_offset_mm = press_offset_mm
        self.n_rest_frames = n_rest_frames
        self.sessions = sessions
        self.session_s = session_s
        self.gap_s = gap_s
        self.max_contacts = max_contacts
        self.contact_force_range_n = contact_force_range_n
        self.contact_radius_range_mm = contact_radius_range_mm
        self.contact_speed_range_mm_s = contact_speed_range_mm_s
        self.contact_profile = contact_profile
        self.progress = progress

    # -- checks -----------------------------------------------------------------------------
    def _check(self):
        def fail(message):
            raise InputError(f"scene {self.name}: {message}")

        check_grid(self.rows, self.cols, self.pitch_mm, self.frame_rate_hz, f"scene {self.name}")
        if self.protocol not in ("characterisation", "stream"):
            fail(f"protocol must be 'characterisation' or 'stream', got '{self.protocol}'")
        for name in ("cover_thickness_mm", "spacer_thickness_mm", "spacer_youngs_modulus_pa",
                     "sensing_area_mm2", "counts_per_pf"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
                fail(f"{name} must be a positive number, got {value!r}")
        if self.spacer_limiting_i1 is not None and not (isinstance(self.spacer_limiting_i1, (int, float))
                                                        and np.isfinite(self.spacer_limiting_i1)
                                                        and self.spacer_limiting_i1 > 0):
            fail(f"spacer_limiting_i1 must be a positive number or null (neo-Hookean), got {self.spacer_limiting_i1!r}")
        if not (np.isfinite(self.spacer_permittivity) and self.spacer_permittivity >= 1.0):
            fail(f"spacer_permittivity (relative) must be >= 1, got {self.spacer_permittivity!r}")
        if self.probe_profile not in PROFILES or self.contact_profile not in PROFILES:
            fail(f"probe_profile and contact_profile must be one of {', '.join(PROFILES)}, "
                 f"got '{self.probe_profile}' and '{self.contact_profile}'")
        if not 0.0 <= self.probe_radius_mm <= 15.0:
            fail(f"probe_radius_mm must be in [0, 15], got {self.probe_radius_mm!r}")
        if self.protocol == "characterisation":
            if not (isinstance(self.press_offset_mm, (int, float)) and 0.0 <= self.press_offset_mm <= self.pitch_mm / 2):
                fail(f"press_offset_mm must be in [0, pitch_mm / 2 = {self.pitch_mm / 2}], got {self.press_offset_mm!r}")
            if self.characterisation_channels not in CHARACTERISATION_CHANNELS:
                fail(f"characterisation_channels must be one of {', '.join(CHARACTERISATION_CHANNELS)}, "
                     f"got '{self.characterisation_channels}'")
            levels = np.asarray(self.force_levels_n, dtype=float)
            if levels.ndim != 1 or len(levels) == 0 or not np.all(np.isfinite(levels)) or np.any(levels <= 0):
                fail(f"force_levels_n must be a list of positive forces, got {self.force_levels_n!r}")
            if not isinstance(self.n_repetitions, int) or self.n_repetitions < 1:
                fail(f"n_repetitions must be a positive integer, got {self.n_repetitions!r}")
            for name in ("rest_frames_per_press", "ramp_frames", "hold_frames", "moving_average_frames"):
                if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                    fail(f"{name} must be a positive integer, got {getattr(self, name)!r}")
            if self.moving_average_frames > self.hold_frames:
                fail(f"moving_average_frames ({self.moving_average_frames}) cannot exceed hold_frames "
                     f"({self.hold_frames})")
            if not (0 <= self.force_jitter < 1 and self.force_sensor_noise_n >= 0):
                fail(f"force_jitter must be in [0, 1) and force_sensor_noise_n >= 0, got "
                     f"{self.force_jitter}, {self.force_sensor_noise_n}")
            self._cells()
        else:
            if not isinstance(self.n_rest_frames, int) or self.n_rest_frames < 10:
                fail(f"n_rest_frames must be an integer >= 10 (the tracker's baseline), got {self.n_rest_frames!r}")
            if not isinstance(self.max_contacts, int) or not 1 <= self.max_contacts <= 10:
                fail(f"max_contacts must be an integer in 1..10, got {self.max_contacts!r}")
            low, high = self.contact_force_range_n
            if not 0 < low <= high:
                fail(f"contact_force_range_n must satisfy 0 < low <= high, got {list(self.contact_force_range_n)}")
            low, high = self.contact_radius_range_mm
            if not 0 <= low <= high <= 15.0:
                fail(f"contact_radius_range_mm must satisfy 0 <= low <= high <= 15, "
                     f"got {list(self.contact_radius_range_mm)}")
            low, high = self.contact_speed_range_mm_s
            if not 0 < low <= high:
                fail(f"contact_speed_range_mm_s must satisfy 0 < low <= high, got {list(self.contact_speed_range_mm_s)}")
            if not (self.session_s > 0 and self.gap_s >= 0):
                fail(f"session_s must be > 0 and gap_s >= 0, got {self.session_s}, {self.gap_s}")

    def _cells(self) -> np.ndarray:
        """The pressed cells as [[row, col], ...]; `all` presses every cell."""
        if isinstance(self.press_cells, str):
            if self.press_cells != "all":
                raise InputError(f"scene {self.name}: press_cells must be 'all' or a list of [row, col], "
                                 f"got '{self.press_cells}'")
            return np.array([(r, c) for r in range(self.rows) for c in range(self.cols)])
        cells = np.asarray(list(map(list, self.press_cells)), dtype=np.int64)
        if cells.ndim != 2 or cells.shape[1] != 2 or len(cells) == 0 or cells.min() < 0 \
                or (cells[:, 0] >= self.rows).any() or (cells[:, 1] >= self.cols).any():
            raise InputError(f"scene {self.name}: press_cells must be [row, col] pairs inside the "
                             f"{self.rows} x {self.cols} grid, got {cells.tolist()}")
        return cells

    # -- the sensor's physics ---------------------------------------------------------------
    @property
    def crossing_depth_mm(self) -> float:
        return self.cover_thickness_mm + self.spacer_thickness_mm / 2.0

    @property
    def rest_capacitance_pf(self) -> float:
        """C0 = eps0 eps_r A / d0 of one crossing (seed 001 eq. 1), in pF."""
        return 1e12 * EPSILON_0_F_PER_M * self.spacer_permittivity * self.sensing_area_mm2 * 1e-6 \
            / (self.spacer_thickness_mm * 1e-3)

    def cell_centres_mm(self) -> tuple[np.ndarray, np.ndarray]:
        y, x = np.meshgrid((np.arange(self.rows) + 0.5) * self.pitch_mm,
                           (np.arange(self.cols) + 0.5) * self.pitch_mm, indexing="ij")
        return x, y

    def _kernel(self, profile):
        return stress_kernel(float(self.crossing_depth_mm), float(np.sqrt(self.sensing_area_mm2 / np.pi)), profile)

    def stress_per_newton(self, x_mm, y_mm, radius_mm, profile) -> np.ndarray:
        """[n_loads, rows, cols] mean vertical stress (Pa) per newton at every crossing for loads
        centred at (x_mm, y_mm) with contact radius radius_mm."""
        x_cells, y_cells = self.cell_centres_mm()
        x_mm, y_mm, radius_mm = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (x_mm, y_mm, radius_mm))
        distance = np.hypot(x_cells[None] - x_mm[:, None, None], y_cells[None] - y_mm[:, None, None])
        return kernel_lookup(self._kernel(profile), distance, np.broadcast_to(radius_mm[:, None, None], distance.shape))

    def spacer_stretch(self, stress_pa: np.ndarray) -> np.ndarray:
        """d / d0 of the spacer under a vertical stress: neo-Hookean, or Gent's law when
        `spacer_limiting_i1` is set."""
        if self.spacer_limiting_i1 is None:
            return neo_hookean_stretch(stress_pa, self.spacer_youngs_modulus_pa)
        return gent_stretch(stress_pa, self.spacer_youngs_modulus_pa, float(self.spacer_limiting_i1))

    def ideal_change_counts(self, stress_pa: np.ndarray) -> np.ndarray:
        """Change in counts from rest of an ideal crossing under a vertical stress (no effects)."""
        stretch = self.spacer_stretch(stress_pa)
        return self.counts_per_pf * self.rest_capacitance_pf * (1.0 / stretch - 1.0)

    def read_frames(self, stress_pa: np.ndarray, time_s: np.ndarray, device: dict | None = None) -> dict:
        """Frames [n_frames, rows, cols] of stress (Pa) -> the board's readings through the
        listed effects. Returns the chain's state: `counts` (as reported), `rest_counts`
        (the ideal reading at rest per cell, after any fabrication offset) and more.

        A long recording goes through in consecutive chunks that share one `device` dict: the
        sensor's own draws (gains, phases, pending creep) and each effect's generator live
        there, so chunk after chunk continues one recording."""
        device = {} if device is None else device
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        generators = device.setdefault("generators", {})
        state = {"closure": 1.0 - self.spacer_stretch(stress_pa),
                 "time_s": np.asarray(time_s, dtype=float), "frame_rate_hz": float(self.frame_rate_hz),
                 "device": device}
        for _, fn, params in (e for e in effects if e[0] in MATERIAL_EFFECTS):
            fn(state, **params)
        rest = self.counts_per_pf * self.rest_capacitance_pf
        state["rest_counts"] = np.full((self.rows, self.cols), rest)
        # C = eps0 eps_r A / (d0 (1 - closure)): the closure is capped short of touching plates
        state["counts"] = rest / (1.0 - np.clip(state["closure"], None, 0.99))
        for name, fn, params in (e for e in effects if e[0] in READING_EFFECTS):
            if name not in generators:
                generators[name] = random_generator_for(self.seed, name)
            fn(state, generators[name], **params)
        state["effects"] = [name for name, _, _ in effects]
        return state

    # -- protocol: characterisation ---------------------------------------------------------
    def _press_schedule(self):
        """One row per press, in the robot's order: repetition, then cell, then force level."""
        cells = self._cells()
        levels = np.asarray(self.force_levels_n, dtype=float)
        rep, cell, level = np.meshgrid(np.arange(self.n_repetitions), np.arange(len(cells)),
                                       np.arange(len(levels)), indexing="ij")
        rep, cell, level = rep.ravel(), cell.ravel(), level.ravel()
        rng = random_generator_for(self.seed, "protocol")
        force = levels[level] * (1.0 + self.force_jitter * rng.standard_normal(len(rep)))
        offsets = rng.uniform(-1.0, 1.0, (len(rep), 2)) * self.press_offset_mm if self.press_offset_mm else None
        return rep, cells[cell], np.maximum(force, 0.0), rng, offsets

    def generate(self) -> SensorTable | ContactStream:
        """The protocol's data: a SensorTable of presses (characterisation) or a ContactStream."""
        self._check()
        if self.protocol == "stream":
            return self.stream()
        rep, cells, force, rng, offsets = self._press_schedule()
        return self.simulate(rep, cells, force, rng, offsets)

    def simulate(self, repetition, cells, force_n, rng=None, offsets_mm=None) -> SensorTable:
        """Presses of the probe at cell centres (cells [n, 2] as row, col), moved by offsets_mm
        ([n, 2] as x, y; None: at the centres), with the given forces through the listed
        effects; one SensorTable row per press."""
        cells = np.asarray(cells, dtype=np.int64).reshape(-1, 2)
        force_n = np.asarray(force_n, dtype=float)
        rng = rng if rng is not None else random_generator_for(self.seed, "protocol")
        n_presses = len(force_n)
        rest, ramp, hold = self.rest_frames_per_press, self.ramp_frames, self.hold_frames
        # Force profile of one press, as a share of its level: rest, ramp up, hold, ramp down.
        profile = np.r_[np.zeros(rest), np.arange(1, ramp + 1) / ramp, np.ones(hold), np.arange(ramp - 1, -1, -1) / ramp]
        per_press = len(profile)
        x_cells, y_cells = self.cell_centres_mm()
        x_mm, y_mm = x_cells[cells[:, 0], cells[:, 1]], y_cells[cells[:, 0], cells[:, 1]]
        if offsets_mm is not None:
            x_mm, y_mm = x_mm + offsets_mm[:, 0], y_mm + offsets_mm[:, 1]
        unique, which = np.unique(np.column_stack([x_mm, y_mm]), axis=0, return_inverse=True)
        pattern = self.stress_per_newton(unique[:, 0], unique[:, 1],
                                         self.probe_radius_mm, self.probe_profile)       # [positions, rows, cols]
        applied = force_n[:, None] * profile[None, :]                                    # [presses, frames]
        # The paper's moving average (sec. 2.6): a trailing mean over the last frames of the hold,
        # taken against the mean of the rest frames just before the press.
        end = rest + ramp + hold
        window = slice(end - self.moving_average_frames, end)
        reading = np.empty((n_presses, self.rows * self.cols))
        device, effects = {}, []
        for start in range(0, n_presses, PRESSES_PER_CHUNK):  # chunks keep memory flat in n_presses
            part = slice(start, min(start + PRESSES_PER_CHUNK, n_presses))
            stress = applied[part, :, None, None] * pattern[which.ravel()[part]][:, None]   # [presses, frames, r, c]
            first = start * per_press
            time_s = (first + np.arange(stress.shape[0] * per_press)) / self.frame_rate_hz
            state = self.read_frames(stress.reshape(-1, self.rows, self.cols), time_s, device)
            counts = state["counts"].reshape(-1, per_press, self.rows * self.cols)
            reading[part] = counts[:, window].mean(axis=1) - counts[:, :rest].mean(axis=1)
            effects = state["effects"]
        sensed_force = applied[:, window].mean(axis=1) \
            + self.force_sensor_noise_n * rng.standard_normal(n_presses) / np.sqrt(self.moving_average_frames)
        targets = list(TARGETS)
        if self.characterisation_channels == "window":  # what the tracker reads around a contact's peak
            channels, reading, targets = window_channel_names(), windows_around_peaks(reading, self.rows, self.cols), ["force_n"]
        else:
            channels = channel_names(self.rows, self.cols)
        frame = pd.DataFrame(reading, columns=channels)
        frame["force_n"], frame["x_mm"], frame["y_mm"] = sensed_force, x_mm, y_mm
        description = {"source": "scene", "scene": self.name, "protocol": self.protocol,
                       "effects": effects, "n_samples": n_presses, "grid": [self.rows, self.cols],
                       "pitch_mm": float(self.pitch_mm), "press_cells": np.unique(cells, axis=0).tolist(),
                       "press_offset_mm": float(self.press_offset_mm),
                       "reading": "change of RMC counts from the rest frames before each press, "
                                  f"moving average of {self.moving_average_frames} frames",
                       "channels": self.characterisation_channels}
        return SensorTable(frame, channels, targets, np.asarray(repetition), description)

    # -- protocol: stream -------------------------------------------------------------------
    def choreography(self) -> Choreography:
        return Choreography(width_mm=self.cols * self.pitch_mm, height_mm=self.rows * self.pitch_mm,
                            margin_mm=self.pitch_mm / 2, frame_rate_hz=float(self.frame_rate_hz),
                            max_contacts=self.max_contacts, force_range_n=tuple(self.contact_force_range_n),
                            radius_range_mm=tuple(self.contact_radius_range_mm),
                            speed_range_mm_s=tuple(self.contact_speed_range_mm_s),
                            min_separation_mm=2.0 * self.pitch_mm)

    def frames_for(self, truth: pd.DataFrame, n_frames: int) -> dict:
        """The board's frames for a ground truth (one row per frame and contact): the chain's
        state with `counts` [n_frames, rows, cols]."""
        frames = truth["frame"].to_numpy() if len(truth) else np.zeros(0, dtype=np.int64)
        per_newton = self.stress_per_newton(truth["x_mm"].to_numpy(), truth["y_mm"].to_numpy(),
                                            truth["radius_mm"].to_numpy(), self.contact_profile) if len(truth) else None
        counts, device, state = np.empty((n_frames, self.rows, self.cols)), {}, {}
        for start in range(0, n_frames, FRAMES_PER_CHUNK):
            stop = min(start + FRAMES_PER_CHUNK, n_frames)
            stress = np.zeros((stop - start, self.rows, self.cols))
            rows = np.flatnonzero((frames >= start) & (frames < stop))
            if len(rows):
                # linear elasticity: the stresses of simultaneous contacts add
                np.add.at(stress, frames[rows] - start,
                          truth["force_n"].to_numpy()[rows, None, None] * per_newton[rows])
            state = self.read_frames(stress, np.arange(start, stop) / self.frame_rate_hz, device)
            counts[start:stop] = state["counts"]
        state["counts"] = counts
        return state

    def stream(self) -> ContactStream:
        """Rest frames, then the sessions; raw frames with their ground truth."""
        protocol = self.protocol
        try:
            self.protocol = "stream"
            self._check()
        finally:
            self.protocol = protocol
        sessions = [self.sessions] if isinstance(self.sessions, str) else list(self.sessions)
        truth, n_frames = choreograph(sessions, random_generator_for(self.seed, "protocol"), self.choreography(),
                                      self.n_rest_frames, self.session_s, self.gap_s)
        state = self.frames_for(truth, n_frames)
        description = {"source": "scene", "scene": self.name, "protocol": "stream", "effects": state["effects"],
                       "sessions": sessions, "grid": [self.rows, self.cols], "seed": self.seed,
                       "rest_counts": float(self.counts_per_pf * self.rest_capacitance_pf)}
        return ContactStream(state["counts"], float(self.frame_rate_hz), float(self.pitch_mm),
                             int(self.n_rest_frames), truth, description)

    def load(self) -> SensorTable | ContactStream:
        """Datamodule entry point: scenes and user tables both `load()`."""
        return self.generate()
