"""Scene `taxels`: an n x n array of silicon 3-axis force taxels under an elastic cover (seed 004).

Sensor (seed 004 sec. 2-4, Table 1): taxels on a square grid of pitch `pitch_mm` (2 x 2, 1.5 mm),
centred on the origin; taxel k = row * n + col, row 0 at the bottom (most negative y), col 0 at
the left. Each taxel is a plate on four bridges (left, right, down, up), each a piezoresistor.
The cover (Elastosil, E = 2.4 MPa, nu = 0.5) is `cover_thickness_um` thick. The bridges read the
strain at the taxel, inverted from seed eq. (2):
    gamma_x = a_s (dV_left - dV_right), gamma_y = a_s (dV_down - dV_up), eps_z = (a_n / 2) sum dV,
taking the fourth (saddle) mode dV_left + dV_right - dV_down - dV_up as zero, i.e.
    dV_left/right = eps_z / (2 a_n) +/- gamma_x / (2 a_s), dV_down/up = eps_z / (2 a_n) +/- gamma_y / (2 a_s).
The constants follow the bare die's sensitivity k (mV/mN/V) and supply V_s: the plate of side
`plate_side_um` carries the force its area sees at that strain, F_z = E eps_z A (normal) and
F_t = 2 G gamma A (shear), and sum dV = k V_s F_z, dV_left - dV_right = k V_s F_x. So a_n =
2 / (k V_s E A), a_s = 1 / (k V_s 2 G A). Channels: v_t<k>_<bridge>_mv (before the `amplifier`
effect: the bare bridge change; after it, the amplified output).

Protocols (positions in mm, forces in mN in the config, N in the table):
  needle_scan       a needle moved along x at y = the bottom taxel row, constant normal force
                    (seed 004 Fig. 2: 100 um needle, 10 mN, 180 um cover), one sample per scan at 30 Hz;
  thickness_series  the needle scan repeated for each cover thickness in `thickness_series_um` (Fig. 3-4);
  moving_loads      point loads moved across the array through the bottom-left taxel, one straight
                    pass per direction in `directions_deg`, with friction shear mu F along the motion (Fig. 10);
  random_loads      position, normal and shear (inside the friction cone) drawn uniformly, for learning.
Targets: x_mm, y_mm, normal_n, shear_x_n, shear_y_n. Groups: one per load (random_loads), one per
pass (moving_loads), one per thickness (thickness_series), one per position (needle_scan).
Extra columns: thickness_um, time_s, and the noise-free strain at each taxel (gamma_x_t<k>,
gamma_y_t<k>, eps_z_t<k>), which studies compare with eq. (1).
"""
import numpy as np
import pandas as pd

from common.errors import InputError
from data.scenes.contract import random_generator_for, resolve_effects
from data.scenes.taxels_effects import COVER_EFFECTS, EFFECTS, LOAD_EFFECTS, READING_EFFECTS
from data.sensor_table import SensorTable

TARGETS = ["x_mm", "y_mm", "normal_n", "shear_x_n", "shear_y_n"]
BRIDGES = ("left", "right", "down", "up")
PROTOCOLS = ("needle_scan", "thickness_series", "moving_loads", "random_loads")
SCAN_RATE_HZ = 30.0


class TaxelsScene:
    """Simulated loads on the taxel array; `generate()` returns a SensorTable."""

    name = "taxels"

    def __init__(self, n_samples=2000, protocol="random_loads", seed=0, effects=None,
                 n_taxels_side=2, pitch_mm=1.5, plate_side_um=100.0, cover_thickness_um=580.0,
                 youngs_modulus_pa=2.4e6, poisson_ratio=0.5, sensitivity_mv_per_mn_per_v=5.0, supply_v=5.0,
                 needle_force_mn=10.0, scan_range_mm=(-2.25, 0.75),
                 thickness_series_um=(150.0, 300.0, 580.0, 850.0, 1000.0),
                 directions_deg=(0.0, 90.0), friction_coefficient=0.3,
                 position_margin_mm=0.5, normal_range_mn=(1.0, 10.0), progress=False):
        self.n_samples = n_samples
        self.protocol = protocol
        self.seed = seed
        self.effects = effects
        self.n_taxels_side = n_taxels_side
        self.pitch_mm = pitch_mm
        self.plate_side_um = plate_side_um
        self.cover_thickness_um = cover_thickness_um
        self.youngs_modulus_pa = youngs_modulus_pa
        self.poisson_ratio = poisson_ratio
        self.sensitivity_mv_per_mn_per_v = sensitivity_mv_per_mn_per_v
        self.supply_v = supply_v
        self.needle_force_mn = needle_force_mn
        self.scan_range_mm = scan_range_mm
        self.thickness_series_um = thickness_series_um
        self.directions_deg = directions_deg
        self.friction_coefficient = friction_coefficient
        self.position_margin_mm = position_margin_mm
        self.normal_range_mn = normal_range_mn
        self.progress = progress

    # -- geometry -----------------------------------------------------------------------------
    def _check(self):
        if not isinstance(self.n_samples, int) or self.n_samples < 1:
            raise InputError(f"scene.n_samples must be a positive integer, got {self.n_samples!r}")
        if self.protocol not in PROTOCOLS:
            raise InputError(f"scene.protocol must be one of {', '.join(PROTOCOLS)}, got '{self.protocol}'")
        if not isinstance(self.n_taxels_side, int) or self.n_taxels_side < 1:
            raise InputError(f"scene.n_taxels_side must be a positive integer, got {self.n_taxels_side!r}")
        for name in ("pitch_mm", "plate_side_um", "youngs_modulus_pa", "sensitivity_mv_per_mn_per_v", "supply_v"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"scene.{name} must be > 0, got {value}")
        thickness = [self.cover_thickness_um] + list(self.thickness_series_um)
        if not all(np.isfinite(t) and t > 0 for t in thickness):
            raise InputError(f"scene: cover thickness must be > 0 um, got {thickness}")
        if not 0.0 < self.poisson_ratio <= 0.5:
            raise InputError(f"scene.poisson_ratio must be in (0, 0.5], got {self.poisson_ratio}")
        low, high = self.normal_range_mn
        if not 0.0 <= low <= high or self.friction_coefficient < 0:
            raise InputError(f"scene: normal_range_mn must be 0 <= low <= high and friction_coefficient >= 0, "
                             f"got {list(self.normal_range_mn)} and {self.friction_coefficient}")

    def taxel_xy_mm(self) -> np.ndarray:
        """Taxel centres (T, 2) in mm, row-major from the bottom-left."""
        n = self.n_taxels_side
        offsets = (np.arange(n) - (n - 1) / 2.0) * self.pitch_mm
        gx, gy = np.meshgrid(offsets, offsets)
        return np.column_stack([gx.ravel(), gy.ravel()])

    def channel_names(self) -> list[str]:
        return [f"v_t{k}_{b}_mv" for k in range(self.n_taxels_side**2) for b in BRIDGES]

    # -- protocols ----------------------------------------------------------------------------
    def _scan(self, n):
        start, stop = self.scan_range_mm
        x = np.linspace(start, stop, n)
        y = np.full(n, self.taxel_xy_mm()[0, 1])
        return x, y

    def loads(self):
        """x_mm, y_mm, normal_mn, shear_x_mn, shear_y_mn, thickness_um, groups, time_s per sample."""
        n = self.n_samples
        zeros = np.zeros(n)
        thickness = np.full(n, float(self.cover_thickness_um))
        time_s = np.arange(n) / SCAN_RATE_HZ
        if self.protocol == "needle_scan":
            x, y = self._scan(n)
            return x, y, np.full(n, self.needle_force_mn), zeros, zeros, thickness, np.arange(n), time_s
        if self.protocol == "thickness_series":
            series = np.asarray(self.thickness_series_um, dtype=float)
            per = max(1, n // len(series))
            which = np.minimum(np.arange(n) // per, len(series) - 1)
            position = np.arange(n) - which * per
            count = np.where(which == len(series) - 1, n - (len(series) - 1) * per, per)
            start, stop = self.scan_range_mm
            x = start + (stop - start) * position / np.maximum(count - 1, 1)
            y = np.full(n, self.taxel_xy_mm()[0, 1])
            return x, y, np.full(n, self.needle_force_mn), zeros, zeros, series[which], which, time_s
        if self.protocol == "moving_loads":
            directions = np.deg2rad(np.asarray(self.directions_deg, dtype=float))
            per = max(1, n // len(directions))
            which = np.minimum(np.arange(n) // per, len(directions) - 1)
            count = np.where(which == len(directions) - 1, n - (len(directions) - 1) * per, per)
            along = (np.arange(n) - which * per) / np.maximum(count - 1, 1)   # 0 .. 1
            half_span = self.pitch_mm * (self.n_taxels_side - 1) / 2.0 + self.pitch_mm
            s = (2.0 * along - 1.0) * half_span
            through = self.taxel_xy_mm()[0]
            ux, uy = np.cos(directions[which]), np.sin(directions[which])
            force = np.full(n, self.needle_force_mn)
            friction = self.friction_coefficient * force
            return (through[0] + s * ux, through[1] + s * uy, force, friction * ux, friction * uy,
                    thickness, which, time_s)
        rng = random_generator_for(self.seed, "protocol")
        half = self.pitch_mm * (self.n_taxels_side - 1) / 2.0 + self.position_margin_mm
        x, y = rng.uniform(-half, half, size=(2, n))
        normal = rng.uniform(*self.normal_range_mn, size=n)
        magnitude = self.friction_coefficient * normal * np.sqrt(rng.uniform(size=n))   # uniform in the cone's disc
        angle = rng.uniform(0.0, 2.0 * np.pi, size=n)
        return (x, y, normal, magnitude * np.cos(angle), magnitude * np.sin(angle), thickness,
                np.arange(n), time_s)

    # -- simulation ---------------------------------------------------------------------------
    def geometry(self) -> dict:
        return {"pitch_mm": float(self.pitch_mm), "plate_side_um": float(self.plate_side_um),
                "youngs_modulus_pa": float(self.youngs_modulus_pa), "poisson_ratio": float(self.poisson_ratio)}

    def bridge_constants(self):
        """(a_n, a_s): strain per mV of bridge change, from the die's sensitivity (module docstring)."""
        volts_per_newton = self.sensitivity_mv_per_mn_per_v * self.supply_v   # mV/mN = V/N
        area = (self.plate_side_um * 1e-6) ** 2
        shear_modulus = self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))
        mv_per_newton = 1e3 * volts_per_newton
        return 2.0 / (mv_per_newton * self.youngs_modulus_pa * area), 1.0 / (mv_per_newton * 2 * shear_modulus * area)

    def bridges_mv(self, strain) -> np.ndarray:
        """(n, T, 3) strains (gamma_x, gamma_y, eps_z) -> (n, 4 T) bridge changes, inverse of eq. (2)."""
        alpha_n, alpha_s = self.bridge_constants()
        common = strain[..., 2] / (2.0 * alpha_n)
        dx, dy = strain[..., 0] / (2.0 * alpha_s), strain[..., 1] / (2.0 * alpha_s)
        out = np.stack([common + dx, common - dx, common + dy, common - dy], axis=-1)
        return out.reshape(strain.shape[0], -1)

    def strain_from_bridges(self, bridges_mv) -> np.ndarray:
        """Seed eq. (2) itself: (n, 4 T) bridge changes -> (n, T, 3) (gamma_x, gamma_y, eps_z)."""
        alpha_n, alpha_s = self.bridge_constants()
        v = np.asarray(bridges_mv, dtype=float).reshape(len(bridges_mv), -1, 4)
        return np.stack([alpha_s * (v[..., 0] - v[..., 1]), alpha_s * (v[..., 2] - v[..., 3]),
                         0.5 * alpha_n * v.sum(axis=-1)], axis=-1)

    def simulate(self, x_mm, y_mm, normal_mn, shear_x_mn=0.0, shear_y_mn=0.0, thickness_um=None,
                 groups=None, time_s=None, chunk: int = 256) -> SensorTable:
        """Readings for arbitrary point loads (mm, mN), through the listed effects."""
        x = np.atleast_1d(np.asarray(x_mm, dtype=float))
        n = len(x)
        y, normal, shear_x, shear_y = (np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy()
                                       for v in (y_mm, normal_mn, shear_x_mn, shear_y_mn))
        thickness = np.broadcast_to(np.asarray(self.cover_thickness_um if thickness_um is None else thickness_um,
                                               dtype=float), (n,)).copy()
        if not np.all(np.isfinite(np.c_[x, y, normal, shear_x, shear_y])):
            raise InputError("scene taxels: load positions and forces must be finite")
        if np.any(thickness <= 0) or not np.all(np.isfinite(thickness)):
            raise InputError(f"scene taxels: cover thickness must be > 0 um, got {thickness.min()}")
        groups = np.arange(n) if groups is None else np.asarray(groups)
        time_s = np.arange(n) / SCAN_RATE_HZ if time_s is None else np.asarray(time_s)
        effects = resolve_effects(self.name, self.effects, EFFECTS)
        field_effects = [e for e in effects if e[0] in LOAD_EFFECTS or e[0] in COVER_EFFECTS]
        reading_effects = [e for e in effects if e[0] in READING_EFFECTS]
        taxels = self.taxel_xy_mm() * 1e-3
        geometry = self.geometry()

        strain = np.zeros((n, len(taxels), 3))
        for start in range(0, n, chunk):
            part = slice(start, min(start + chunk, n))
            state = {"load_x_m": x[part, None] * 1e-3, "load_y_m": y[part, None] * 1e-3,
                     "normal_n": normal[part, None] * 1e-3, "shear_x_n": shear_x[part, None] * 1e-3,
                     "shear_y_n": shear_y[part, None] * 1e-3, "thickness_m": thickness[part] * 1e-6,
                     "taxel_xy_m": taxels, "geometry": geometry}
            for _, fn, params in field_effects:
                fn(state, **params)
            strain[part] = state.get("strain", 0.0) + state.get("direct_strain", 0.0)

        state = {"bridges_mv": self.bridges_mv(strain)}
        for name, fn, params in reading_effects:
            fn(state, random_generator_for(self.seed, name), **params)

        channels = self.channel_names()
        frame = pd.DataFrame(state["bridges_mv"], columns=channels)
        for column, values in zip(TARGETS, (x, y, normal * 1e-3, shear_x * 1e-3, shear_y * 1e-3)):
            frame[column] = values
        frame["thickness_um"] = thickness
        frame["time_s"] = time_s
        for k in range(len(taxels)):
            for j, component in enumerate(("gamma_x", "gamma_y", "eps_z")):
                frame[f"{component}_t{k}"] = strain[:, k, j]
        description = {"source": "scene", "scene": self.name, "protocol": self.protocol,
                       "effects": [name for name, _, _ in effects], "n_samples": n}
        return SensorTable(frame, channels, list(TARGETS), groups, description)

    def generate(self) -> SensorTable:
        """Run the protocol: `n_samples` loads through the listed effects."""
        self._check()
        x, y, normal, shear_x, shear_y, thickness, groups, time_s = self.loads()
        return self.simulate(x, y, normal, shear_x, shear_y, thickness, groups, time_s)

    def load(self) -> SensorTable:
        """Datamodule entry point: scenes and user tables both `load()` a SensorTable."""
        return self.generate()
