"""Seed 001's observations (Egger et al. 2025, the capacitive elastomer array), measured on the
`capacitive6x6` scene. One check per observation of ../shared/notes/seed-observations.md (seed 001
section), registered in `CHECKS["capacitive6x6"]`; printed by

    .venv/bin/python bench/fidelity.py --scene capacitive6x6   # 9 min at load average 16 on 2 cores (GP, SVR)

Every measurement runs over `seeds` (0-2: the scene's seed, the split's seed and the models'
seed together) and reports mean ± sd.

The models of rows 3-5 are the project's own configs (`model=linear_regression, svr,
decision_tree, gaussian_process`: seed 001's four), fitted on the characterisation presses (four
cells x ten force levels x `n_repetitions`, every listed effect) from the 36 cells' RMC changes,
standardised on the training rows as the datamodule does, to force_n. Two protocols:
- `paper`: a random 70/30 split of the presses (seed 001 sec. 3.5);
- `by repetition`: 70/30 with whole repetitions kept apart (Touchstone's `split: grouped` in
  configs/experiment/capacitive_force.yaml), so no test press shares a repetition, and its
  slice of drift, with a training press.
Both see every force level in training: on this protocol the levels are discrete and repeated.

Beside them, rows 4a and 5 fit the four models as the paper configured them (`PAPER_CONFIGURED`):
the paper names scikit-learn (1.2.2, sec. 2.3) and of the settings only the SVR's linear kernel,
so every other setting is the library's default, and it reports each sensor apart from that
sensor's own reading (Table 2's rows, Fig. 18's force-RMC axes), so each pressed cell gets its
own four models with its RMC change as the one feature, on the same train and test presses.
"""
import os
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np
from hydra import compose, initialize_config_dir
from hydra.utils import instantiate
from omegaconf import OmegaConf
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel
from sklearn.linear_model import LinearRegression
from sklearn.metrics import r2_score
from sklearn.svm import SVR
from sklearn.tree import DecisionTreeRegressor

from common.spread import format_mean_sd
from common.standardise import mean_and_scale
from data.scenes.capacitive6x6 import (Capacitive6x6Scene, correlation_factor_rmc_per_n, pressed_cell,
                                       pressed_cell_rmc)
from data.splits.indices import holdout
from models.contact_tracking.timing import latency_summary, timed_updates
from runs.fidelity.observations import Measured, observation, probe
from runs.report.tracking_metrics import evaluate_tracking
from runs.studies.capacitive_tracking import make_tracker, track

ROOT = Path(__file__).resolve().parents[2]
MODELS = ("linear_regression", "svr", "decision_tree", "gaussian_process")
PROTOCOLS = ("paper", "by repetition")
TEST_FRACTION = 0.30
SWEEP_PRESSES = 300
CONFIGURATIONS = ("project", "paper-configured")
# seed 001's four models with the defaults of the paper's scikit-learn 1.2.2 but the one setting
# the paper names (the SVR's linear kernel). Its GP default kernel was 1.0 * RBF(1.0) with both
# hyper-parameters fixed (not fitted) and no noise term (alpha 1e-10); scikit-learn fits the
# default kernel's hyper-parameters since its pull request #32964 (2026), so it is spelled out.
PAPER_CONFIGURED = {"linear_regression": lambda seed: LinearRegression(),
                    "svr": lambda seed: SVR(kernel="linear"),
                    "decision_tree": lambda seed: DecisionTreeRegressor(random_state=seed),
                    "gaussian_process": lambda seed: GaussianProcessRegressor(
                        ConstantKernel(1.0, "fixed") * RBF(1.0, "fixed"), random_state=seed)}


def split(table, protocol: str, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Train and test rows of a characterisation table under one of `PROTOCOLS`: the datamodule's
    own hold-out (data/splits/indices.py), random or grouped by repetition."""
    train, test = holdout(np.arange(len(table.frame)), table.groups, TEST_FRACTION,
                          "random" if protocol == "paper" else "grouped", seed)
    return np.sort(train), np.sort(test)


def per_cell_fit(table, train, test, sweep, make_model, reading=lambda rmc: rmc):
    """One `make_model()` per pressed cell, fitted on that cell's training presses from its own
    RMC change (as `reading` gives it: the change itself by default) to force_n: the test
    presses' predictions (each by its own cell's model) and the predictions on `sweep` (of the
    sweep's cell's model)."""
    y, rmc, cell = table.frame["force_n"].to_numpy(), reading(_pressed_cell_rmc(table)), _pressed_cell_index(table)
    predicted, swept = np.empty(len(test)), None
    for which in np.unique(cell):
        model = make_model().fit(rmc[train][cell[train] == which, None], y[train][cell[train] == which])
        here = cell[test] == which
        predicted[here] = model.predict(rmc[test][here, None])
        if which == _pressed_cell_index(sweep)[0]:
            swept = model.predict(reading(_pressed_cell_rmc(sweep))[:, None])
    return predicted, swept


@probe("capacitive6x6")
class CapacitiveProbe:
    """The capacitive scene over `seeds`: its characterisation tables, the four models fitted
    under both protocols, its streams. `repeats` is unused (the repetitions are the scene's
    `n_repetitions`: override scene.n_repetitions for a smaller table)."""

    def __init__(self, params: dict, repeats: int = 20, seeds=(0, 1, 2)):
        self.params = {k: v for k, v in params.items() if k not in ("_target_", "_convert_")}
        self.seeds = tuple(seeds)
        self._fits = {}

    def scene(self, seed: int, **overrides) -> Capacitive6x6Scene:
        return Capacitive6x6Scene(**{**self.params, "seed": seed, **overrides})

    @cached_property
    def tables(self) -> dict:
        return {seed: self.scene(seed, protocol="characterisation").generate() for seed in self.seeds}

    @cached_property
    def model_configs(self) -> dict:
        with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
            return {name: compose("config", overrides=[f"model={name}"]).model for name in MODELS}

    def fit(self, protocol: str, seed: int, name: str, configuration: str = "project") -> dict:
        """Model `name` in `configuration` fitted under `protocol` on seed `seed`'s table (once;
        kept): its test R², RMSE (N) and correlation factor (counts/N), and its predictions on the
        force sweep."""
        key = (configuration, protocol, seed, name)
        if key not in self._fits:
            table = self.tables[seed]
            y = table.frame["force_n"].to_numpy()
            train, test = split(table, protocol, seed)
            fitted = self._project_fit if configuration == "project" else self._paper_configured_fit
            predicted, sweep = fitted(table, train, test, seed, name)
            self._fits[key] = {"r2": float(r2_score(y[test], predicted)),
                               "rmse": float(np.sqrt(np.mean((predicted - y[test]) ** 2))),
                               "slope": correlation_factor_rmc_per_n(_pressed_cell_rmc(table)[test], predicted),
                               "sweep": sweep}
        return self._fits[key]

    def _project_fit(self, table, train, test, seed, name):
        """The project's model config on the 36 cells, standardised on the training rows: test
        and sweep predictions."""
        X, y = table.channels, table.frame["force_n"].to_numpy()
        mean, scale = mean_and_scale(X[train])
        model = instantiate(self.model_configs[name], seed=seed)
        model.fit((X[train] - mean) / scale, y[train])
        return model.predict((X[test] - mean) / scale), model.predict((self.sweep(seed).channels - mean) / scale)

    def _paper_configured_fit(self, table, train, test, seed, name):
        """`PAPER_CONFIGURED[name]` per pressed cell, from that cell's RMC change alone."""
        return per_cell_fit(table, train, test, self.sweep(seed), lambda: PAPER_CONFIGURED[name](seed))

    @lru_cache(maxsize=None)
    def sweep(self, seed: int):
        """`SWEEP_PRESSES` presses at the first pressed cell, forces evenly over the levels' range
        (not only the levels), every listed effect: what a model does between the levels."""
        levels = self.params["force_levels_n"]
        force = np.linspace(min(levels), max(levels), SWEEP_PRESSES)
        cell = np.asarray(self.params["press_cells"][0])[None]
        scene = self.scene(seed, protocol="characterisation")
        return scene.simulate(np.zeros(SWEEP_PRESSES, dtype=int), np.repeat(cell, SWEEP_PRESSES, axis=0), force)

    def per_model(self, protocol: str, key: str, models=MODELS, configuration: str = "project") -> dict:
        """model -> its `key` over the seeds."""
        return {name: np.array([self.fit(protocol, seed, name, configuration)[key] for seed in self.seeds])
                for name in models}

    @cached_property
    def tracking_study(self) -> dict:
        """configs/experiment/capacitive_tracking.yaml's study settings."""
        with initialize_config_dir(config_dir=str(ROOT / "configs"), version_base="1.3"):
            cfg = compose("config", overrides=["experiment=capacitive_tracking"])
        return OmegaConf.to_container(cfg.study, resolve=True)

    @cached_property
    def tracking(self) -> dict:
        """seed -> the stream's tracking metrics (ours, no force, as the capacitive_tracking study
        evaluates them) and the p50 time per frame (us) of the live frames and of the rest frames
        (no contact: the tracker fitted on them, then updated with them again), and the noise of
        one frame at rest (median cell, counts)."""
        out = {}
        for seed in self.seeds:
            stream = self.scene(seed, protocol="stream").stream()
            params = self.tracking_study["trackers"]["ours"]
            table, timing, _ = track(stream, params, None, keep_images=False)
            metrics = evaluate_tracking(stream.truth, table, stream.n_frames, stream.pitch_mm,
                                        self.tracking_study["min_force_n"])
            tracker = make_tracker(stream.rows, stream.cols, stream.pitch_mm, params, None)
            rest = stream.frames[:stream.n_rest_frames]
            tracker.fit(rest)
            _, empty_us = timed_updates(tracker, rest)
            out[seed] = {"metrics": metrics["overall"], "live_us": timing["p50_us"],
                         "rest_sd_counts": float(np.median(rest.std(axis=0, ddof=1))),
                         "empty_us": latency_summary(empty_us)["p50_us"],
                         "contacts_per_frame": len(table) / (stream.n_frames - stream.n_rest_frames)}
        return out


@observation("capacitive6x6", "1", "Detection and localisation run within 1 ms per frame: ≈ 404.7 µs without "
             "contacts, ≈ 627.2 µs with clustered contacts (the authors' machine, their Python code)",
             "404.7 / 627.2 µs")
def tracking_within_a_millisecond(probe: CapacitiveProbe) -> Measured:
    runs = probe.tracking.values()
    live, empty = [r["live_us"] for r in runs], [r["empty_us"] for r in runs]
    contacts = np.mean([r["contacts_per_frame"] for r in runs])
    holds = bool(np.mean(live) < 1000 and np.mean(empty) < 1000)
    return Measured(f"p50 per frame, our tracker (no force, one thread, load average {os.getloadavg()[0]:.1f}): "
                    f"{format_mean_sd(empty, '.1f')} µs without contacts, {format_mean_sd(live, '.1f')} µs on the "
                    f"sessions' frames "
                    f"({contacts:.1f} contacts per frame; seeds {_seeds(probe)})", holds,
                    "both below 1,000 µs (timings: not asserted by the tests)",
                    {"live_us": live, "empty_us": empty})


def _seeds(probe) -> str:
    return f"{probe.seeds[0]}-{probe.seeds[-1]}" if len(probe.seeds) > 1 else str(probe.seeds[0])


def _pressed_cell_rmc(table) -> np.ndarray:
    rows, cols = table.description["grid"]
    return pressed_cell_rmc(table.frame, rows, cols, table.description["pitch_mm"])


def _pressed_cell_index(table) -> np.ndarray:
    rows, cols = table.description["grid"]
    return pressed_cell(table.frame, rows, cols, table.description["pitch_mm"])


@observation("capacitive6x6", "2", "Limit of detection ≈ 0.1 N; the response is nearly linear over 0.1-3 N, "
             "RMC peak ≈ 150 at 3 N (sec. 3.4)", "0.1 N; ≈ 150 at 3 N")
def detection_limit_and_linearity(probe: CapacitiveProbe) -> Measured:
    lod, peak, line_r2 = [], [], []
    for seed, table in probe.tables.items():
        rmc, force = _pressed_cell_rmc(table), table.frame["force_n"].to_numpy()
        levels = np.asarray(probe.params["force_levels_n"])
        level = np.abs(force[:, None] - levels[None]).argmin(axis=1)
        means = np.array([rmc[level == k].mean() for k in range(len(levels))])
        slope, intercept = np.polyfit(levels, means, 1)
        line_r2.append(1 - np.var(means - (slope * levels + intercept)) / np.var(means))
        peak.append(means[-1])
        lod.append(3 * probe.tracking[seed]["rest_sd_counts"] / slope)
    holds = bool(0.05 <= np.mean(lod) <= 0.2 and 100 <= np.mean(peak) <= 225 and np.mean(line_r2) > 0.99)
    return Measured(f"limit of detection (3σ of one rest frame, median cell / slope) {format_mean_sd(lod, '.3f')} N; "
                    f"pressed cell's change at 3 N {format_mean_sd(peak, '.1f')} counts; R² of a line through the ten "
                    f"levels' means "
                    f"{format_mean_sd(line_r2, '.5f')} (seeds {_seeds(probe)}, every listed effect)", holds,
                    "LOD 0.05-0.2 N, 3 N change 100-225 counts, line R² > 0.99",
                    {"lod_n": lod, "peak_counts": peak, "line_r2": line_r2})


def _ranking_text(probe, protocol, configuration="project") -> str:
    r2, rmse = (probe.per_model(protocol, key, configuration=configuration) for key in ("r2", "rmse"))
    order = sorted(MODELS, key=lambda m: rmse[m].mean())
    return (f"{protocol}: " + ", ".join(f"{m} R² {format_mean_sd(r2[m], '.4f')} "
                                        f"RMSE {format_mean_sd(rmse[m], '.4f')} N" for m in order))


@observation("capacitive6x6", "3", "Every model (linear regression, linear SVR, decision tree, GPR) reaches "
             "R² > 0.99 (linear models > 0.995) on every sensor (Table 2)", "R² > 0.99; linear > 0.995")
def every_model_above_0_99(probe: CapacitiveProbe) -> Measured:
    worst = {}
    for protocol in PROTOCOLS:
        r2 = probe.per_model(protocol, "r2")
        worst[protocol] = {"all": float(min(v.min() for v in r2.values())),
                           "linear": float(min(r2["linear_regression"].min(), r2["svr"].min()))}
    holds = all(w["all"] > 0.99 and w["linear"] > 0.995 for w in worst.values())
    return Measured("lowest test R² of any seed, any model / of the linear two: " + "; ".join(
        f"{p} split {w['all']:.4f} / {w['linear']:.4f}" for p, w in worst.items()) +
        f" (seeds {_seeds(probe)}, force_n)", holds, "every model > 0.99 and the linear two > 0.995 under both "
        "splits", {"worst": worst})


@observation("capacitive6x6", "4a", "The decision tree is the best of the four models (Table 2)",
             "tree RMSE 0.0446-0.0585 N vs linear 0.10-0.15 N")
def decision_tree_is_best(probe: CapacitiveProbe) -> Measured:
    """Judged on the paper's configuration under the paper's split (the tree's RMSE below every
    other model's on every seed); the project's models under both splits are reported beside it."""
    best, tree_wins = {}, {}
    for configuration in CONFIGURATIONS:
        for protocol in PROTOCOLS:
            rmse = probe.per_model(protocol, "rmse", configuration=configuration)
            best[configuration, protocol] = min(MODELS, key=lambda m: rmse[m].mean())
            tree_wins[configuration, protocol] = bool(all(np.all(rmse["decision_tree"] < rmse[m])
                                                          for m in MODELS if m != "decision_tree"))
    text = "; ".join(f"{configuration}, {_ranking_text(probe, p, configuration)}"
                     for configuration in CONFIGURATIONS for p in PROTOCOLS)
    return Measured(text + f" (best first; seeds {_seeds(probe)}; judged on the paper-configured models, one "
                    "per sensor from its own reading with scikit-learn 1.2.2's defaults)",
                    tree_wins["paper-configured", "paper"],
                    "paper-configured, paper's split: the tree's RMSE below every other model's on every seed",
                    {"best": {" / ".join(k): v for k, v in best.items()},
                     "tree_wins": {" / ".join(k): v for k, v in tree_wins.items()}})


@observation("capacitive6x6", "4b", "The decision tree's own accuracy: RMSE 0.0446-0.0585 N, mean R² 0.9996, "
             "correlation factor (slope) 51.76 (sec. 3.5)", "0.0446-0.0585 N; 0.9996; 51.76")
def decision_tree_accuracy(probe: CapacitiveProbe) -> Measured:
    rmse, r2, slope = (probe.per_model("paper", key, ["decision_tree"])["decision_tree"] for key in ("rmse", "r2", "slope"))
    holds = bool(0.0446 / 2 <= rmse.mean() <= 2 * 0.0585 and r2.mean() > 0.99 and abs(slope.mean() / 51.76 - 1) <= 0.2)
    return Measured(f"paper's split: RMSE {format_mean_sd(rmse, '.4f')} N, R² {format_mean_sd(r2, '.4f')}, "
                    f"slope {format_mean_sd(slope, '.2f')} counts/N (seeds {_seeds(probe)})", holds, "RMSE within a factor 2 of 0.0446-0.0585 N, R² > 0.99, "
                    "slope within ±20 %", {"rmse": rmse.tolist(), "r2": r2.tolist(), "slope": slope.tolist()})


def roughness(force: np.ndarray, predicted: np.ndarray) -> float:
    """How far a model's predictions over a force sweep depart from a smooth curve: the rms of
    the residual from a cubic in the true force, in newtons (steps and oscillations leave a
    residual; a smooth response leaves only the readings' noise)."""
    return float(np.sqrt(np.mean((predicted - np.polyval(np.polyfit(force, predicted, 3), force)) ** 2)))


@observation("capacitive6x6", "5", "Decision tree and GPR predictions fluctuate (step-like / oscillating) where "
             "the linear models are smooth (sec. 3.5, Fig. 18)")
def tree_and_gpr_fluctuate(probe: CapacitiveProbe) -> Measured:
    """Judged on the paper-configured models under the paper's split: the tree and the GPR each
    more than twice as rough as the rougher linear model while still accurate (test R² > 0.99,
    as every model of the paper's Table 2 is); the project's models are reported beside them."""
    ratio, accurate, parts = {}, {}, []
    for configuration in CONFIGURATIONS:
        rough = {name: np.array([roughness(probe.sweep(seed).frame["force_n"].to_numpy(),
                                           probe.fit("paper", seed, name, configuration)["sweep"])
                                 for seed in probe.seeds]) for name in MODELS}
        r2 = probe.per_model("paper", "r2", configuration=configuration)
        smooth = max(rough["linear_regression"].mean(), rough["svr"].mean())
        ratio[configuration] = {n: float(rough[n].mean() / smooth) for n in ("decision_tree", "gaussian_process")}
        accurate[configuration] = {n: bool(r2[n].mean() > 0.99) for n in ("decision_tree", "gaussian_process")}
        parts.append(f"{configuration}: " + ", ".join(f"{n} {format_mean_sd(v, '.4f')} N" for n, v in rough.items()) +
                     f"; tree / linear {ratio[configuration]['decision_tree']:.1f}, GPR / linear "
                     f"{ratio[configuration]['gaussian_process']:.1f} (GPR test R² "
                     f"{format_mean_sd(r2['gaussian_process'], '.4f')})")
    holds = all(ratio["paper-configured"][n] > 2.0 and accurate["paper-configured"][n]
                for n in ("decision_tree", "gaussian_process"))
    return Measured(f"rms departure from a cubic over a {SWEEP_PRESSES}-press sweep 0.1-3 N (paper's split, seeds "
                    f"{_seeds(probe)}): " + "; ".join(parts) + " (judged on the paper-configured models)", holds,
                    "paper-configured: tree and GPR each > 2 x the rougher linear model, with test R² > 0.99",
                    {"ratio": ratio, "accurate": accurate})


@observation("capacitive6x6", "6", "Jaccard cluster tracking keeps labels consistent over time while contacts "
             "move and change intensity (sec. 2.5.2, 3.3)")
def labels_stay_consistent(probe: CapacitiveProbe) -> Measured:
    runs = [r["metrics"] for r in probe.tracking.values()]
    idf1, switches = [m["idf1"] for m in runs], [m["id_switches"] for m in runs]
    holds = bool(np.mean(idf1) >= 0.9)
    return Measured(f"sessions stream (tap, hold, glide, cross, merge, split), our tracker: IDF1 "
                    f"{format_mean_sd(idf1, '.3f')}, identity switches {format_mean_sd(switches, '.1f')} per stream "
                    f"(seeds {_seeds(probe)})", holds,
                    "IDF1 >= 0.9", {"idf1": idf1, "id_switches": switches})
