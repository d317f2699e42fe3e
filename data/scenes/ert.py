"""Scenes `ert_boundary` and `ert_internal`: the ERT textile skin of seed 002.

Sensor (seed 002 §3): a 200 x 200 mm high-resistance knitted fabric (20 kOhm/sq) with 24 point
electrodes, under a 10 x 10 array of 20 x 20 mm low-resistance fabric patches (20 Ohm/sq) glued to
4 mm neoprene foam. A press pushes patches into the base fabric; the contact resistance falls
and the sheet's local conductance rises (data/scenes/ert_effects.py `contact_resistance`). The
electrode layout is config (`electrodes_mm`, 1-based numbering = list order): ert_boundary puts
all 24 on the edges, ert_internal 20 on the edges and 4 inside (the paper's pattern study, §4.2);
any other layout is a list away.

Readings (seed 002 §3.4, eq. 2): one current source drives `current_a` between an injection
pair (a, b) (all N(N-1)/2 = 276 pairs, or a listed subset) and the voltage is read between
successive electrodes (c, c+1), all from one transfer-resistance matrix per press. The
patterns, the forward solve, the readings and the Jacobian are the ERT package's (data/ert/);
this module runs the protocols through the effects. Channels are the change from the unloaded frame taken
before the first press, `dv_a01_b02_m01_v` (time-difference imaging, as ERT systems record).

Protocols: `single_point` (an 18 x 18 grid = the paper's 324 points, at `n_force_levels`
forces), `calibration` (the same presses, a different recording: its own noise), `two_point`
(two indenters `distances_mm` apart at three `two_point_locations_mm`, `n_repeats` each),
`random` (one contact, or two with `two_contact_probability`, anywhere; for learning), `blank`
(`n_samples` frames with nothing pressed: the limit of quantification's blank readings).
`recording_presses` (null = one recording) splits a protocol into recordings that each take
their own unloaded frame, so baseline drift restarts: training data for a learned inverse then
holds several independent drift walks, like the separate test recording it is scored on.
Targets: x_mm, y_mm (the contact, or the mid-point of two), force_n (total); extra columns
give the second contact, the mean pressure and the recording. One group per press, or per
recording when `recording_presses` is set.
`session` (0 = the first) numbers repeated sessions of the same protocol on the same sensor:
each session draws its own noise, hysteresis, drift (and random presses), so session 1 of
`calibration` is a recording independent of session 0, which the Tikhonov reconstruction is
fitted on. Session 0 keeps the streams' plain names.
"""
import numpy as np
import pandas as pd
import scipy.sparse as sp

from common.errors import InputError
from data.ert.cells import patch_weights
from data.ert.forward import sheet_solver
from data.ert.jacobian import cell_jacobian, channel_jacobian
from data.ert.patch_loads import patch_loads_n
from data.ert.protocol import channel_names, injection_pairs, measurement_pairs
from data.ert.readings import four_terminal_voltage_v
from data.physics.press_update import PatchUpdateSolver
from data.scenes.contract import random_generator_for, resolve_effects
from data.scenes.ert_effects import (
    EFFECTS,
    PRESS_EFFECTS,
    READING_EFFECTS,
    SENSOR_EFFECTS,
)
from data.sensor_table import SensorTable

TARGETS = ["x_mm", "y_mm", "force_n"]
PROTOCOLS = ("single_point", "calibration", "two_point", "random", "blank")


class ERTScene:
    """Simulated presses on the ERT skin; `generate()` returns a SensorTable."""

    def __init__(self, name="ert_boundary", electrodes_mm=None, protocol="single_point", seed=0, effects=None,
                 side_mm=200.0, grid_nodes=41, patch_mm=20.0, foam_thickness_mm=4.0,
                 sheet_resistance_ohm_per_sq=2.0e4, electrode_width_mm=0.0, current_a=1.0e-4,
                 injection="all", measurement="successive", indenter_diameter_mm=10.0,
                 force_range_n=(2.0, 15.0), n_force_levels=3, grid_points_per_side=18,
                 two_point_locations_mm=((50.0, 100.0), (100.0, 30.0), (100.0, 100.0)),
                 distances_mm=(20, 25, 30, 35, 40, 45, 50, 55, 60), two_point_force_n=8.0, n_repeats=10,
                 n_samples=2000, position_range_mm=(10.0, 190.0), two_contact_probability=0.0,
                 recording_presses=None, session=0):
        self.name = name
        self.electrodes_mm = electrodes_mm
        self.protocol = protocol
        self.seed = seed
        self.effects = effects
        self.side_mm = side_mm
        self.grid_nodes = grid_nodes
        self.patch_mm = patch_mm
        self.foam_thickness_mm = foam_thickness_mm
        self.sheet_resistance_ohm_per_sq = sheet_resistance_ohm_per_sq
        self.electrode_width_mm = electrode_width_mm
        self.current_a = current_a
        self.injection = injection
        self.measurement = measurement
        self.indenter_diameter_mm = indenter_diameter_mm
        self.force_range_n = force_range_n
        self.n_force_levels = n_force_levels
        self.grid_points_per_side = grid_points_per_side
        self.two_point_locations_mm = two_point_locations_mm
        self.distances_mm = distances_mm
        self.two_point_force_n = two_point_force_n
        self.n_repeats = n_repeats
        self.n_samples = n_samples
        self.position_range_mm = position_range_mm
        self.two_contact_probability = two_contact_probability
        self.recording_presses = recording_presses
        self.session = session

    # -- geometry ---------------------------------------------------------------------------------
    def _check(self):
        if self.protocol not in PROTOCOLS:
            raise InputError(f"scene.protocol must be one of {', '.join(PROTOCOLS)}, got '{self.protocol}'")
        if not self.side_mm > 0 or self.sheet_resistance_ohm_per_sq <= 0 or not self.current_a > 0:
            raise InputError(f"scene ert: side_mm, sheet_resistance_ohm_per_sq and current_a must be > 0, got "
                             f"{self.side_mm}, {self.sheet_resistance_ohm_per_sq}, {self.current_a}")
        n_patch = self.side_mm / self.patch_mm
        if self.patch_mm <= 0 or abs(n_patch - round(n_patch)) > 1e-9:
            raise InputError(f"scene ert: patch_mm must divide side_mm, got {self.patch_mm} and {self.side_mm}")
        if self.grid_nodes < 5:
            raise InputError(f"scene ert: grid_nodes must be >= 5, got {self.grid_nodes}")
        low, high = self.force_range_n
        if not 0.0 <= low <= high or self.indenter_diameter_mm <= 0 or self.foam_thickness_mm < 0:
            raise InputError(f"scene ert: need 0 <= force_range_n low <= high, indenter_diameter_mm > 0, "
                             f"foam_thickness_mm >= 0; got {list(self.force_range_n)}, "
                             f"{self.indenter_diameter_mm}, {self.foam_thickness_mm}")
        if int(self.session) < 0:
            raise InputError(f"scene ert: session must be >= 0, got {self.session}")
        if self.recording_presses is not None and int(self.recording_presses) < 1:
            raise InputError(f"scene ert: recording_presses must be >= 1 or null, got {self.recording_presses}")
        if self.electrodes_mm is None or np.asarray(self.electrodes_mm).ndim != 2 or np.asarray(self.electrodes_mm).shape[1] != 2:
            raise InputError("scene ert: electrodes_mm must be a list of [x, y] electrode positions in mm")

    def _stream(self, name: str):
        """The generator of one per-recording random source: its name carries the protocol and,
        past session 0, the session, so repeated recordings draw independently."""
        session = f"session{int(self.session)}/" if int(self.session) else ""
        return random_generator_for(self.seed, f"{session}{name}")

    @property
    def n_electrodes(self) -> int:
        return len(self.electrodes_mm)

    def patterns(self) -> tuple[np.ndarray, np.ndarray]:
        """(injection pairs, measurement pairs), 0-based."""
        return injection_pairs(self.injection, self.n_electrodes), measurement_pairs(self.measurement, self.n_electrodes)

    def channel_names(self) -> list[str]:
        return channel_names(*self.patterns())

    def sensor(self) -> dict:
        """The simulated sensor: nominal geometry through the listed sensor effects."""
        n_side = int(round(self.side_mm / self.patch_mm))
        state = {"electrodes_mm": np.asarray(self.electrodes_mm, dtype=float), "side_mm": float(self.side_mm),
                 "n_patches": n_side * n_side, "patch_base_resistance_scale": np.ones(n_side * n_side),
                 "patch_sensitivity_scale": np.ones(n_side * n_side), "anisotropy_ratio": 1.0}
        for name, fn, params in resolve_effects(self.name, self.effects, EFFECTS):
            if name in SENSOR_EFFECTS:
                fn(state, random_generator_for(self.seed, name), **params)
        return state

    def _solver(self, sensor) -> PatchUpdateSolver:
        return sheet_solver(float(self.side_mm), int(self.grid_nodes), float(self.electrode_width_mm),
                            tuple(map(tuple, np.round(sensor["electrodes_mm"], 9))), float(self.patch_mm),
                            float(self.sheet_resistance_ohm_per_sq),
                            tuple(np.round(sensor["patch_base_resistance_scale"], 12)), float(sensor["anisotropy_ratio"]))

    # -- protocols --------------------------------------------------------------------------------
    def grid_points_mm(self, per_side=None) -> np.ndarray:
        """Centres of an n x n grid of cells over the sheet (18 x 18 = the paper's 324 points)."""
        n = per_side or self.grid_points_per_side
        axis = (np.arange(n) + 0.5) * self.side_mm / n
        return np.array([(x, y) for y in axis for x in axis])

    def _contacts(self):
        """(n_presses, n_contacts, 3) [x_mm, y_mm, force_n] and extra per-press columns."""
        low, high = self.force_range_n
        if self.protocol in ("single_point", "calibration"):
            points = self.grid_points_mm()
            forces = np.linspace(low, high, self.n_force_levels)
            xy = np.repeat(points, len(forces), axis=0)
            force = np.tile(forces, len(points))
            return np.column_stack([xy, force])[:, None, :], {}
        if self.protocol == "two_point":
            rows, extra = [], {"location": [], "distance_mm": []}
            for k, centre in enumerate(np.asarray(self.two_point_locations_mm, dtype=float)):
                for distance in self.distances_mm:
                    for _ in range(self.n_repeats):
                        half = distance / 2.0
                        rows.append([[centre[0] - half, centre[1], self.two_point_force_n],
                                     [centre[0] + half, centre[1], self.two_point_force_n]])
                        extra["location"].append(k + 1)
                        extra["distance_mm"].append(float(distance))
            contacts = np.array(rows)
            if (contacts[..., :2] < 0).any() or (contacts[..., :2] > self.side_mm).any():
                raise InputError("scene ert: a two_point indenter falls off the sheet; move the location or "
                                 "shorten the distances")
            return contacts, {k: np.asarray(v) for k, v in extra.items()}
        if self.protocol == "blank":
            return np.column_stack([np.full((self.n_samples, 2), self.side_mm / 2), np.zeros(self.n_samples)])[:, None, :], {}
        rng = self._stream("protocol")
        lo, hi = self.position_range_mm
        n = self.n_samples
        contacts = np.zeros((n, 2, 3))
        contacts[:, :, :2] = rng.uniform(lo, hi, size=(n, 2, 2))
        contacts[:, :, 2] = rng.uniform(low, high, size=(n, 2))
        contacts[rng.random(n) >= self.two_contact_probability, 1, 2] = 0.0
        return contacts, {}

    def generate(self) -> SensorTable:
        """Run the protocol through the listed effects."""
        self._check()
        contacts, extra = self._contacts()
        return self.simulate(contacts, extra)

    def load(self) -> SensorTable:
        return self.generate()

    # -- simulation -------------------------------------------------------------------------------
    def transfer_resistance(self, contacts: np.ndarray, sensor=None) -> np.ndarray:
        """(n_presses, n_electrodes, n_electrodes) transfer resistances for (n, n_contacts, 3)
        contacts through the listed press effects (no reading effects)."""
        sensor = self.sensor() if sensor is None else sensor
        return self._solver(sensor).transfer_resistance(self.node_conductance_s(contacts, sensor), chunk=64)

    def node_conductance_s(self, contacts: np.ndarray, sensor) -> np.ndarray:
        """(n_presses, n_nodes) sheet conductance of every grid node (siemens per square) under
        (n, n_contacts, 3) contacts, through the listed press effects."""
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        solver = self._solver(sensor)
        node_patch = patch_weights(solver.solver.grid.node_xy_mm, self.side_mm, self.patch_mm)
        base_nodes = solver._base_nodes
        press = {"geometry": {"foam_thickness_mm": self.foam_thickness_mm}, "spread_sd_mm": 0.0,
                 "patch_sensitivity_scale": sensor["patch_sensitivity_scale"], "local": False}
        for name, fn, params in effects:
            if name in ("foam_spread", "local_contact"):
                fn(press, **params)
        radius = self.indenter_diameter_mm / 2.0
        if press["local"]:
            # Loads on the grid nodes' cells, scaled to the force that loads a whole patch to the
            # same pressure; each node takes its patch's sensitivity.
            spacing = solver.solver.grid.spacing_mm
            cell = np.asarray(contacts, dtype=float).copy()
            cell[..., :2] += spacing / 2.0
            press["patch_force_n"] = patch_loads_n(cell, self.side_mm + spacing, spacing, radius,
                                                   press["spread_sd_mm"]) * (self.patch_mm / spacing) ** 2
            press["patch_sensitivity_scale"] = node_patch @ sensor["patch_sensitivity_scale"]
        else:
            press["patch_force_n"] = patch_loads_n(contacts, self.side_mm, self.patch_mm, radius, press["spread_sd_mm"])
        press["patch_conductance_factor"] = np.ones_like(press["patch_force_n"])
        for name, fn, params in effects:
            if name in PRESS_EFFECTS and name not in ("foam_spread", "local_contact"):
                if name in ("hysteresis", "viscoelastic_hysteresis"):
                    fn(press, self._stream(f"{self.protocol}/{name}"), **params)
                else:
                    fn(press, **params)
        factor = press["patch_conductance_factor"]
        if not press["local"]:      # each node takes its patches' factors (at most four, hence sparse)
            factor = (sp.csr_matrix(node_patch) @ factor.T).T
        return base_nodes[None, :] * factor

    def transfer_jacobian(self, sensor) -> np.ndarray:
        """(n_patches, n_electrodes, n_electrodes) dZ / d (relative patch conductance) of the sensor unloaded."""
        solver = self._solver(sensor)
        return cell_jacobian(solver.solver, solver.base_conductance_s, self.side_mm, self.patch_mm)

    def patch_jacobian(self, sensor) -> np.ndarray:
        """(n_channels, n_patches) d voltage / d (relative patch conductance) of the sensor unloaded."""
        return channel_jacobian(self.transfer_jacobian(sensor), *self.patterns(), self.current_a)

    def simulate(self, contacts: np.ndarray, extra=None) -> SensorTable:
        """Readings for arbitrary presses: (n, n_contacts, 3) [x_mm, y_mm, force_n]."""
        self._check()
        contacts = np.asarray(contacts, dtype=float)
        if contacts.ndim == 2:
            contacts = contacts[:, None, :]
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        injections, measurements = self.patterns()
        sensor = self.sensor()
        z = self.transfer_resistance(contacts, sensor)
        z0 = self.transfer_resistance(np.zeros((1, 1, 3)), sensor)
        n = len(contacts)
        # Recordings: the unloaded frame is re-taken every `recording_presses` presses (null = one
        # recording), so baseline noise and drift restart; each recording is one group.
        recording = np.arange(n) // int(self.recording_presses) if self.recording_presses else np.zeros(n, dtype=int)
        n_recordings = int(recording.max()) + 1 if n else 1
        baseline = four_terminal_voltage_v(z0, injections, measurements, self.current_a).reshape(1, -1)
        reading = {"voltage_v": four_terminal_voltage_v(z, injections, measurements, self.current_a).reshape(n, -1),
                   "baseline_v": np.repeat(baseline, n_recordings, axis=0), "recording": recording,
                   "patch_jacobian": lambda: self.patch_jacobian(sensor), "patterns": (injections, measurements),
                   "current_a": float(self.current_a)}
        for name, fn, params in effects:
            if name in READING_EFFECTS:
                fn(reading, self._stream(f"{self.protocol}/{name}"), **params)

        channels = channel_names(injections, measurements)
        # the change from each recording's unloaded frame, in place (13 M numbers at 2000 presses)
        change = reading["voltage_v"]
        change -= reading["baseline_v"][recording] if n_recordings > 1 else reading["baseline_v"][0]
        frame = pd.DataFrame(change, columns=channels, copy=False)
        force = contacts[:, :, 2]
        total = force.sum(axis=1)
        active = force > 0
        n_active = np.maximum(active.sum(axis=1), 1)
        centre = (contacts[:, :, :2] * active[..., None]).sum(axis=1) / n_active[:, None]
        centre[~active.any(axis=1)] = contacts[~active.any(axis=1), 0, :2]
        targets = pd.DataFrame({"x_mm": centre[:, 0], "y_mm": centre[:, 1], "force_n": total})
        area_mm2 = np.pi * (self.indenter_diameter_mm / 2.0) ** 2
        more = {"pressure_kpa": contacts[:, 0, 2] / area_mm2 * 1e3, "recording": recording}
        if contacts.shape[1] > 1:
            more.update({"x1_mm": contacts[:, 0, 0], "y1_mm": contacts[:, 0, 1],
                         "x2_mm": contacts[:, 1, 0], "y2_mm": contacts[:, 1, 1], "force2_n": contacts[:, 1, 2]})
        more.update(extra or {})
        frame = pd.concat([frame, targets, pd.DataFrame(more)], axis=1)
        description = {"source": "scene", "scene": self.name, "protocol": self.protocol,
                       "effects": [name for name, _, _ in effects], "n_samples": n,
                       "n_injections": len(injections), "n_measurements": len(measurements)}
        groups = recording if self.recording_presses else np.arange(n)   # whole recordings held out together
        return SensorTable(frame, channels, list(TARGETS), groups, description)

    def geometry(self) -> dict:
        """The nominal geometry a reconstruction is built from (what the designer drew, not what
        the sensor effects made of it)."""
        return {"side_mm": float(self.side_mm), "grid_nodes": int(self.grid_nodes),
                "electrode_width_mm": float(self.electrode_width_mm),
                "electrodes_mm": np.asarray(self.electrodes_mm, dtype=float).tolist(),
                "sheet_resistance_ohm_per_sq": float(self.sheet_resistance_ohm_per_sq),
                "current_a": float(self.current_a), "injection": self.injection, "measurement": self.measurement,
                "indenter_diameter_mm": float(self.indenter_diameter_mm)}
