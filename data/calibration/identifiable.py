"""What a calibration can identify on each scene: the parameters a rig's presses pin down, with
their physical ranges and units, and what the fit leaves out.

A parameter is named by its path in the scene's config: a scene attribute (`gel_thickness_mm`)
or an effect's parameter (`effects.contact.youngs_modulus_pa`); its unit is in its name. The
range is what the material or the read-out can physically be (a gel's modulus, an amplifier's
gain), wide enough to hold a rig that differs from the paper's sensor by tens of per cent;
`log` parameters span decades and are fitted on a log scale.

Declared per scene, beside the parameters:
- `unmodelled`: effects the fit model drops. They are either random per sensor or per press
  (noise, drift, a cell's fabrication gain), which no deterministic fit can match press by
  press, or quantisation, whose steps would make the fit's finite differences zero. The fitted
  scene keeps them as the default scene lists them; the fit's residuals hold what they add.
- `not_identifiable`: parameters left at their defaults and why (they cancel, or only their
  product with a declared one reaches the readings).
- `inputs` and `outputs`: the targets a press is simulated at (position, depth, force) and
  the targets the scene computes from them (rubber12's pressure from depth: its table values
  take part in the fit like readings, which is how the gel's modulus is identified).
"""
import inspect
from dataclasses import dataclass, field

import numpy as np

from common.errors import InputError


@dataclass(frozen=True)
class Parameter:
    path: str                 # scene attribute, or effects.<effect>.<parameter>
    low: float
    high: float
    log: bool
    what: str

    @property
    def unit(self) -> str:
        """The unit its name ends in (`_pa` -> Pa); unitless parameters say so."""
        suffix = self.path.rsplit("_", 1)[-1]
        return {"pa": "Pa", "mm": "mm", "um": "µm", "sq": "Ω/sq", "ohm": "Ω", "pf": "counts/pF"}.get(suffix, "1")


@dataclass(frozen=True)
class SceneCalibration:
    scene: str
    parameters: tuple[Parameter, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...] = ()
    unmodelled: tuple[str, ...] = ()
    not_identifiable: dict = field(default_factory=dict)
    noise_path: str | None = None   # the noise effect's level, set from the fit's residuals


CALIBRATIONS = {
    "rubber12": SceneCalibration(
        scene="rubber12",
        parameters=(
            Parameter("sheet_resistance_ohm_per_sq", 2.0e3, 5.0e4, True, "the film's sheet resistance: every reading's scale"),
            Parameter("effects.electrode_contact.resistance_ohm", 10.0, 2.0e3, True,
                      "contact resistance of each electrode: an offset on every channel"),
            Parameter("effects.contact.youngs_modulus_pa", 2.0e4, 5.0e5, True,
                      "the gel's modulus: pressure per depth (from the table's pressure column)"),
            Parameter("effects.percolation.junction_loss_per_strain", 0.1, 10.0, True,
                      "how fast stretched film loses conduction paths: the response's size"),
        ),
        inputs=("x_mm", "y_mm", "depth_mm"), outputs=("pressure_pa",),
        unmodelled=("specimen", "temperature_drift", "adc", "outlier_rejection", "load_cell"),
        not_identifiable={
            "percolation.exponent, filler_fraction, percolation_threshold":
                "trade off against junction_loss_per_strain (one response size)",
            "tunneling.gap_nm, barrier_height_ev": "trade off against junction_loss_per_strain",
            "contact.film_modulus_pa": "moves the readings under the probe by < 1 % over its range",
            "gel_thickness_mm": "trades off against junction_loss_per_strain and the specimen's own thickness "
                                "map (fitted together on stand-in rigs it landed far outside its own interval)",
            "probe_radius_mm, side_mm": "the rig's geometry: give them, they are not fitted",
        }),
    "taxels": SceneCalibration(
        scene="taxels",
        parameters=(
            Parameter("cover_thickness_um", 100.0, 1500.0, True, "the cover's thickness: how wide a press spreads"),
            Parameter("effects.amplifier.gain", 10.0, 300.0, True,
                      "the amplifier's gain (times the die's sensitivity and supply): every reading's scale"),
            Parameter("effects.plate_averaging.side_um", 150.0, 600.0, False,
                      "the membrane the bridges integrate over: shear against normal response"),
        ),
        inputs=("x_mm", "y_mm", "normal_n", "shear_x_n", "shear_y_n"),
        unmodelled=("noise", "adc"), noise_path="effects.noise.rms_mv",
        not_identifiable={
            "youngs_modulus_pa": "cancels: the bridge constants derive from the same modulus as the strain",
            "sensitivity_mv_per_mn_per_v, supply_v": "only their product with the amplifier's gain reaches a reading",
            "pitch_mm, n_taxels_side": "the rig's geometry: give them, they are not fitted",
        }),
    "capacitive6x6": SceneCalibration(
        scene="capacitive6x6",
        parameters=(
            Parameter("counts_per_pf", 200.0, 5.0e3, True, "the board's gain: every reading's scale"),
            Parameter("spacer_limiting_i1", 0.05, 2.0, True, "Gent's J_m: how the response bends at high force"),
            Parameter("cover_thickness_mm", 1.5, 8.0, False, "the cover's thickness: what neighbouring cells see"),
        ),
        inputs=("force_n", "x_mm", "y_mm"),
        unmodelled=("fabrication_spread", "drift", "interference", "baseline_noise", "quantisation"),
        not_identifiable={
            "spacer_youngs_modulus_pa": "trades off against counts_per_pf (change per newton is their ratio; "
                                        "fitted together, each one's sd exceeded its value)",
            "spacer_permittivity, sensing_area_mm2, spacer_thickness_mm":
                "only their product with counts_per_pf reaches a reading (C0 = eps A / d0)",
            "crosstalk couplings": "trade off against the cover's spread on neighbouring cells",
            "rows, cols, pitch_mm": "the rig's geometry: give them, they are not fitted",
        }),
}


def calibration_for(scene) -> SceneCalibration:
    """The declarations of a scene object (or its name); a scene without any is a one-line error."""
    name = scene if isinstance(scene, str) else getattr(scene, "name", type(scene).__name__)
    if name not in CALIBRATIONS:
        raise InputError(f"scene {name} declares no calibration parameters; experiment=calibrate fits "
                         f"{', '.join(CALIBRATIONS)}")
    return CALIBRATIONS[name]


def get_value(scene, path: str) -> float:
    """A parameter's value on a scene object: an attribute, or an effect's parameter (a listed
    effect that does not set it takes its function's default, which the scene module declares)."""
    if not path.startswith("effects."):
        return float(getattr(scene, path))
    _, effect, name = path.split(".")
    params = (scene.effects or {}).get(effect)
    if params is None:
        raise InputError(f"scene {scene.name}: calibration needs the '{effect}' effect listed (its {name})")
    if name in params:
        return float(params[name])
    # the effect's own default (amplifier gain 55), from the scene module's registry
    registry = inspect.getmodule(type(scene)).EFFECTS
    return float(inspect.signature(registry[effect]).parameters[name].default)


def set_value(scene, path: str, value: float) -> None:
    if not path.startswith("effects."):
        setattr(scene, path, float(value))
        return
    _, effect, name = path.split(".")
    scene.effects = {**scene.effects, effect: {**(scene.effects[effect] or {}), name: float(value)}}


def to_unit_interval(parameter: Parameter, value: float) -> float:
    """The optimiser's coordinate: 0 at the low bound, 1 at the high one (log scale when declared)."""
    transform = np.log if parameter.log else (lambda v: v)
    return float((transform(value) - transform(parameter.low)) / (transform(parameter.high) - transform(parameter.low)))


def from_unit_interval(parameter: Parameter, u: float) -> float:
    if parameter.log:
        return float(np.exp(np.log(parameter.low) + u * (np.log(parameter.high) - np.log(parameter.low))))
    return float(parameter.low + u * (parameter.high - parameter.low))
