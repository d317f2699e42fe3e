"""What each paper observed on its real sensor, measured on the scene that stands in for it.

One function per observation in ../shared/notes/seed-observations.md, registered with
`@observation(scene, number, statement, paper)` in the list of its scene (`CHECKS[scene]`).
A check gets a `SceneProbe` (the scene's composed parameters and helpers to simulate presses)
and returns a `Measured`: the scene's value in words, whether it holds (None = not measured by
this table, with the reason), the tolerance it was judged by, and the raw numbers the tests
assert with margin. bench/fidelity.py prints the table; tests/test_fidelity.py asserts every
row that holds. Fingertip (seed 003) rows go in `CHECKS["fingertip"]` the same way.

"Holds" follows the notes file's rule: the same measurement on simulated data agrees in
direction and, where the paper gives a number, in order of magnitude; each row states its
tolerance. Noise-free quantities (sensitivities, shapes) use the scene's field effects only
(its listed physics, no acquisition noise); noise quantities use every listed effect.
"""
from functools import cached_property

import numpy as np

from data.preprocessing.features import FEATURE_GROUPS, compute_features
from data.scenes.rubber12 import Rubber12Scene
from data.scenes.rubber12_effects import FIELD_EFFECTS
from runs.fidelity.observations import Measured, observation, probe


# -- rubber12 ------------------------------------------------------------------------------------
@probe("rubber12")
class SceneProbe:
    """Presses on one rubber12 configuration (`params`: the composed scene config as a dict).

    `repeats` sets the sample counts: the table uses the lab's sizes, tests smaller ones."""

    def __init__(self, params: dict, repeats: int = 20):
        self.params = {k: v for k, v in params.items() if k not in ("_target_", "_convert_")}
        self.params["progress"] = False
        self.repeats = repeats

    def scene(self, effects=None, **overrides) -> Rubber12Scene:
        params = {**self.params, **overrides}
        if effects is not None:
            params["effects"] = effects
        return Rubber12Scene(**params)

    @cached_property
    def field_effects(self) -> dict:
        """The listed physics without acquisition noise: the noise-free response."""
        return {k: v for k, v in self.params["effects"].items() if k in FIELD_EFFECTS}

    @cached_property
    def reading_effects_without_normalisation(self) -> dict:
        return {k: v for k, v in self.params["effects"].items() if k != "minmax_normalize"}

    @cached_property
    def points(self) -> np.ndarray:
        return self.scene().press_points()

    @cached_property
    def depths_mm(self) -> np.ndarray:
        low, high = self.params["depth_range_mm"]
        return np.linspace(low, high, self.params["n_depth_steps"])

    def field(self, x, y, depth):
        """Noise-free readings (ohms) and pressure (Pa) for presses."""
        table = self.scene(self.field_effects).simulate(x, y, depth)
        return table.channels, table.frame["pressure_pa"].to_numpy()

    @cached_property
    def rest_ohm(self) -> np.ndarray:
        return self.field([25.0], [25.0], [0.0])[0][0]

    @cached_property
    def curves(self):
        """Noise-free relative channel change (n_points, n_depths, n_channels) at P1-P9 over the
        lab's depths, and the pressure (n_points, n_depths)."""
        n_p, n_d = len(self.points), len(self.depths_mm)
        x = np.repeat(self.points[:, 0], n_d)
        y = np.repeat(self.points[:, 1], n_d)
        depth = np.tile(self.depths_mm, n_p)
        ohm, pressure = self.field(x, y, depth)
        relative = ohm / self.rest_ohm - 1.0
        return relative.reshape(n_p, n_d, -1), pressure.reshape(n_p, n_d)

    @cached_property
    def repeat_noise(self):
        """Readings of `repeats` identical presses at each P1-P9 at mid depth with every listed
        effect but normalisation: (n_points, repeats, n_channels) ohms, and the pressures."""
        depth = float(np.median(self.depths_mm))
        x = np.repeat(self.points[:, 0], self.repeats)
        y = np.repeat(self.points[:, 1], self.repeats)
        table = self.scene(self.reading_effects_without_normalisation).simulate(x, y, np.full(len(x), depth))
        shape = (len(self.points), self.repeats, -1)
        return table.channels.reshape(shape), table.frame["pressure_pa"].to_numpy().reshape(shape[:2])

    @cached_property
    def lab_table(self):
        """The lab protocol with every listed effect: 9 points x depths x 5 repeats."""
        n = len(self.points) * len(self.depths_mm) * 5
        return self.scene(n_samples=n, protocol="lab").generate()


def _aggregate(relative):
    """Aggregate change of a reading vector: the 2-norm of the channels' relative changes."""
    return np.linalg.norm(relative, axis=-1)


CORNERS, EDGE_MIDPOINTS, CENTRE = [0, 2, 6, 8], [1, 3, 5, 7], 4


@observation("rubber12", "1", "Repeated measurements at one position vary by a coefficient of variation "
             "below 2.3 % on every channel (§II-E)", "CV < 2.3 %")
def repeat_cv(probe: SceneProbe) -> Measured:
    readings, _ = probe.repeat_noise
    cv = readings.std(axis=1, ddof=1) / readings.mean(axis=1)
    worst = float(cv.max())
    return Measured(f"largest CV {100 * worst:.2f} % (P1-P9 at {np.median(probe.depths_mm):.2f} mm, "
                    f"{probe.repeats} repeats, every listed effect)", 0.0 < worst < 0.023,
                    "0 < CV < 2.3 %", {"max_cv": worst})


@observation("rubber12", "2", "Resistance changes nonlinearly with depth, consistent with percolation and "
             "tunnelling (§II-F, Fig. 4)")
def nonlinear_depth(probe: SceneProbe) -> Measured:
    relative, _ = probe.curves
    response = _aggregate(relative)                    # (points, depths)
    depth = probe.depths_mm
    deviation = []
    for curve in response:
        fit = np.polyval(np.polyfit(depth, curve, 1), depth)
        deviation.append(np.abs(curve - fit).max() / max(np.ptp(curve), 1e-300))
    median = float(np.median(deviation))
    return Measured(f"aggregate change departs from its best straight line by {100 * median:.1f} % of its "
                    f"span (median of P1-P9)", median >= 0.05, "departure >= 5 % of span",
                    {"median_departure": median})


@observation("rubber12", "3a", "Force at equal depth differs substantially from position to position "
             "(Fig. 4; 0.3, 0.9, 1.2, 3.0 mm)", "\"substantial\" (no number)")
def force_varies_with_position(probe: SceneProbe) -> Measured:
    depths = [0.3, 0.9, 1.2, 3.0]
    x = np.repeat(probe.points[:, 0], len(depths))
    y = np.repeat(probe.points[:, 1], len(depths))
    depth = np.tile(depths, len(probe.points))
    table = probe.scene(probe.reading_effects_without_normalisation).simulate(x, y, depth)
    pressure = table.frame["pressure_pa"].to_numpy().reshape(len(probe.points), len(depths))
    cv = pressure.std(axis=0, ddof=1) / pressure.mean(axis=0)
    smallest = float(cv.min())
    return Measured("CV of pressure over P1-P9: " + ", ".join(f"{d:g} mm {100 * c:.1f} %" for d, c in zip(depths, cv)),
                    smallest >= 0.10, "CV >= 10 % at every depth", {"min_cv": smallest})


@observation("rubber12", "3b", "The load cell measures force independently of depth (§II-E): pressure is "
             "a target of its own", "— (our criterion: corr(P, depth) < 0.99)")
def pressure_is_not_depth(probe: SceneProbe) -> Measured:
    frame = probe.lab_table.frame
    corr = float(np.corrcoef(frame["pressure_pa"], frame["depth_mm"])[0, 1])
    return Measured(f"corr(pressure, depth) = {corr:.4f} on the lab protocol ({len(frame)} presses)",
                    corr < 0.99, "correlation < 0.99", {"corr": corr})


def _sensitivity_per_mm(probe):
    relative, _ = probe.curves
    response = _aggregate(relative)
    return (response[:, -1] - response[:, 0]) / np.ptp(probe.depths_mm)


@observation("rubber12", "4", "Corner positions (P1, P3, P7, P9) have lower piezoresistive sensitivity "
             "than central positions (§II-F)")
def corners_least_sensitive(probe: SceneProbe) -> Measured:
    s = _sensitivity_per_mm(probe)
    corners, centre, edges = s[CORNERS], s[CENTRE], s[EDGE_MIDPOINTS]
    holds = bool(corners.max() < centre)
    return Measured(f"aggregate |ΔR/R| per mm: corners {100 * corners.mean():.2f} %, edge midpoints "
                    f"{100 * edges.mean():.2f} %, centre {100 * centre:.2f} %", holds,
                    "every corner below P5", {"corner_max": float(corners.max()), "centre": float(centre),
                                              "edge_mean": float(edges.mean())})


@observation("rubber12", "5", "The centre (P5) has the widest dynamic range and the highest "
             "signal-to-noise ratio (§II-F)")
def centre_widest_range(probe: SceneProbe) -> Measured:
    relative, _ = probe.curves
    span = np.abs(relative[:, -1] - relative[:, 0]) * probe.rest_ohm        # ohms, (points, channels)
    best = span.argmax(axis=1)
    dynamic_range = span.max(axis=1) / probe.rest_ohm[best]
    readings, _ = probe.repeat_noise
    noise = readings.std(axis=1, ddof=1)                                     # (points, channels)
    snr = span[np.arange(len(span)), best] / noise[np.arange(len(span)), best]
    holds = bool(dynamic_range.argmax() == CENTRE and snr.argmax() == CENTRE)
    return Measured(f"largest single-channel span 0.3-3 mm: P5 {100 * dynamic_range[CENTRE]:.2f} %, best "
                    f"P{dynamic_range.argmax() + 1} {100 * dynamic_range.max():.2f} %; SNR P5 {snr[CENTRE]:.0f}, "
                    f"best P{snr.argmax() + 1} {snr.max():.0f}", holds, "P5 largest of P1-P9 in both",
                    {"range": dynamic_range.tolist(), "snr": snr.tolist()})


@observation("rubber12", "6", "Mirror-image positions give similar patterns; the ambiguity is worst near "
             "the midpoint of an edge (§III-A)")
def mirror_ambiguity_worst_at_edges(probe: SceneProbe) -> Measured:
    # A press 2.5 mm either side of a centreline, at the centre and at the four edge midpoints'
    # press rows (5 mm from the edge): the reading difference between the two, relative to the
    # press's own signal. Small = ambiguous. Field effects plus electrode contact (the asymmetry
    # the paper names).
    side, offset, depth = probe.params["side_mm"], 2.5, float(probe.depths_mm[-1])
    mid = side / 2
    effects = {**probe.field_effects, **{k: v for k, v in probe.params["effects"].items() if k == "electrode_contact"}}
    rows = {"centre": mid, "edge": 5.0}
    ratio = {}
    for name, across in rows.items():
        # mirror in x across x = mid at height `across`, and in y across y = mid at abscissa `across`
        x = np.array([mid - offset, mid + offset, across, across, mid])
        y = np.array([across, across, mid - offset, mid + offset, across])
        ohm = probe.scene(effects).simulate(x, y, np.full(5, depth)).channels
        rest = probe.scene(effects).simulate([mid], [mid], [0.0]).channels[0]
        signal = np.linalg.norm(ohm[4] / rest - 1)
        ratio[name] = 0.5 * (np.linalg.norm((ohm[0] - ohm[1]) / rest) + np.linalg.norm((ohm[2] - ohm[3]) / rest)) / signal
    holds = bool(ratio["edge"] < ratio["centre"])
    return Measured(f"difference of presses ±2.5 mm across a centreline / press signal: near an edge "
                    f"midpoint {ratio['edge']:.3f}, at the centre {ratio['centre']:.3f}", holds,
                    "smaller near the edge midpoint", {"edge": ratio["edge"], "centre": ratio["centre"]})


@observation("rubber12", "7", "Depth is less observable than x, y, especially at small depths (§III-B)")
def depth_weak_at_small_depths(probe: SceneProbe) -> Measured:
    relative, _ = probe.curves
    response = _aggregate(relative)
    slope = np.diff(response, axis=1) / np.diff(probe.depths_mm)
    shallow = float((slope[:, 0] / slope.mean(axis=1)).mean())
    return Measured(f"slope of the aggregate change at 0.3-0.6 mm = {shallow:.2f} x its mean over "
                    f"0.3-3.0 mm (mean of P1-P9)", shallow < 1.0, "ratio < 1", {"shallow_ratio": shallow})


@observation("rubber12", "8", "Pressure shows as an aggregate change over many channels, not in one "
             "channel (§III-B)")
def pressure_is_aggregate(probe: SceneProbe) -> Measured:
    relative, _ = probe.curves
    change = np.abs(relative[:, -1])                                      # (points, channels) at 3 mm
    effective = (change.sum(axis=1) ** 2 / (change ** 2).sum(axis=1))
    mean = float(effective.mean())
    return Measured(f"effective number of channels carrying the change at 3 mm: {mean:.1f} of "
                    f"{change.shape[1]} (mean of P1-P9)", mean >= 3.0, ">= 3 channels",
                    {"effective_channels": mean})


@observation("rubber12", "9", "At high force, nonlinearity and partial saturation reduce incremental "
             "sensitivity (§III-B)")
def saturation_at_high_force(probe: SceneProbe) -> Measured:
    relative, pressure = probe.curves
    response = _aggregate(relative)
    per_pa = np.diff(response, axis=1) / np.diff(pressure, axis=1)
    middle = per_pa.shape[1] // 2
    ratio = float((per_pa[:, -1] / per_pa[:, middle]).mean())
    return Measured(f"d(aggregate change)/d(pressure) at the deepest step = {ratio:.2f} x that at mid "
                    f"depth (mean of P1-P9)", ratio < 1.0, "ratio < 1", {"ratio": ratio})


SPLITS = (0, 1, 2)   # rows 10 and 11: the random hold-out's and the forest's seeds


def _mean_sd(values, digits=2) -> str:
    values = np.asarray(values, dtype=float)
    return f"{values.mean():.{digits}f} ± {values.std(ddof=1):.{digits}f}"


@observation("rubber12", "10", "Uncertainty is highest near the boundaries, at shallow depths and at high "
             "pressure; lowest in the centre and at intermediate depths (§III-C)")
def uncertainty_pattern(probe: SceneProbe) -> Measured:
    # The paper's uncertainty is the spread of K-fold candidate models plus residual variance;
    # here: the spread across the trees of an extra-trees forest, out of fold (5 random folds,
    # the paper's random hold-out), each target scaled by its standard deviation, averaged;
    # once per seed of the folds and the forest (SPLITS).
    from sklearn.ensemble import ExtraTreesRegressor
    from sklearn.model_selection import KFold

    table = probe.lab_table
    features = compute_features(table.channels, FEATURE_GROUPS)
    targets = table.frame[table.target_columns].to_numpy()
    scaled = targets / targets.std(axis=0)
    frame = table.frame
    centre = np.isclose(frame["x_mm"], probe.params["side_mm"] / 2) & np.isclose(frame["y_mm"], probe.params["side_mm"] / 2)
    depth = frame["depth_mm"].to_numpy()
    shallow, middle = depth <= np.quantile(depth, 0.2), (depth > np.quantile(depth, 0.4)) & (depth < np.quantile(depth, 0.6))
    pressure = frame["pressure_pa"].to_numpy()
    high, mid_p = pressure >= np.quantile(pressure, 0.8), (pressure > np.quantile(pressure, 0.4)) & (pressure < np.quantile(pressure, 0.6))
    ratios = {"boundary / centre": [], "shallow / intermediate depth": [], "high / intermediate pressure": []}
    for seed in SPLITS:
        spread = np.zeros(len(targets))
        for train, test in KFold(5, shuffle=True, random_state=seed).split(features):
            forest = ExtraTreesRegressor(n_estimators=50, random_state=seed, n_jobs=1).fit(features[train], scaled[train])
            per_tree = np.stack([tree.predict(features[test]) for tree in forest.estimators_])
            spread[test] = per_tree.std(axis=0).mean(axis=1)
        for name, (a, b) in {"boundary / centre": (~centre, centre), "shallow / intermediate depth": (shallow, middle),
                             "high / intermediate pressure": (high, mid_p)}.items():
            ratios[name].append(float(spread[a].mean() / spread[b].mean()))
    return Measured(f"tree spread out of fold (seeds {SPLITS[0]}-{SPLITS[-1]}, mean ± sd): " +
                    ", ".join(f"{n} {_mean_sd(r)}" for n, r in ratios.items()),
                    all(np.mean(r) > 1.0 for r in ratios.values()), "every ratio > 1",
                    {name: float(np.mean(r)) for name, r in ratios.items()})


@observation("rubber12", "11", "Test R² of extra trees on a random 15 % hold-out; x notably less accurate "
             "than y (Table II)", "x 0.947, y 0.976, z 0.852, P 0.867")
def extra_trees_r2(probe: SceneProbe) -> Measured:
    from sklearn.ensemble import ExtraTreesRegressor
    from sklearn.metrics import r2_score

    table = probe.lab_table
    features = compute_features(table.channels, FEATURE_GROUPS)
    targets = table.frame[table.target_columns].to_numpy()
    scores = []
    for seed in SPLITS:
        test = np.random.default_rng(seed).permutation(len(targets))[: round(0.15 * len(targets))]
        train = np.setdiff1d(np.arange(len(targets)), test)
        forest = ExtraTreesRegressor(n_estimators=100, random_state=seed, n_jobs=1).fit(features[train], targets[train])
        scores.append(r2_score(targets[test], forest.predict(features[test]), multioutput="raw_values"))
    r2 = np.mean(scores, axis=0)
    paper = np.array([0.9466, 0.9762, 0.8516, 0.8670])
    holds = bool(np.all(np.abs(r2 - paper) <= 0.1))
    return Measured("R² " + ", ".join(f"{n} {_mean_sd(v, 3)}" for n, v in
                                      zip(("x", "y", "z", "P"), np.array(scores).T)) +
                    f" ({len(targets)} lab presses, 100 trees, physics features, {len(SPLITS)} random hold-outs)",
                    holds, "every target's mean within ±0.10 of the paper",
                    {"r2": r2.tolist(), "r2_sd": np.std(scores, axis=0, ddof=1).tolist()})


@observation("rubber12", "12", "Extra trees beat the residual network and random forest on validation "
             "(weights 0, 0, 1) (§IV-E, §V-D)")
def extra_trees_selected(probe: SceneProbe) -> Measured:
    return Measured("not measured here: a model comparison (bench/blend_weights.py)", None)


@observation("rubber12", "13", "K-fold blending reduced the network's prediction variance (§IV-D)", "8.3 %")
def kfold_variance(probe: SceneProbe) -> Measured:
    return Measured("not measured here: a model comparison (bench/kfold_variance.py)", None)
