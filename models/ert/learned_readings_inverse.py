"""A learned ERT inverse on the readings: a linear map to the load on each fabric patch, then a
small MLP on the window of patches around the most loaded one.

Why this shape: a press changes the conductance of whole 20 mm patches, so where inside a patch
it sits is only in how the neoprene shares its load with the neighbouring patches. Step one is a
GREIT-like linear map (Adler et al. 2009, eq. 8 and 10) from the 276 reduced readings
u = K^T v (data/ert/readings.py) to the 10 x 10 patch loads, trained on simulated presses whose desired
image is the true patch loads (data/ert/patch_loads.py `patch_loads_n`, the scene's own footprint and
foam spread), with a noise term lambda K^T K. Step two reads the press from the
(2h + 1)^2 patches around the patch whose 3 x 3 neighbourhood carries most load (relative loads,
the log of the largest, and where the window sits on the sheet): an MLP predicts the offset
from that patch's centre and the force. The window moves with the press, so every training
press teaches the same local map (an MLP on all 276 readings needed far more presses and did
worse); its place lets the MLP learn what differs near edges and electrodes.

Training presses come from `n_training_sensors` simulated sensors (seeds `training_seed` + k,
never the sensor under test: runs/studies/ert_tests.py refuses a collision) through
GreitReconstruction.training_frames, the one simulator of other sensors' presses, reduced to u
sensor by sensor. The amount matters most: 40 sensors x 1,000 presses instead of 20 x 500 took
one boundary sensor from 3.35 to 2.79 mm at 10 N, 80 instead of 40 another 3 % (docs/ert.md);
a wider net (256) trained longer (60 epochs) did worse (3.00 mm). `fit(X, y)`
receives validation presses of the sensor under test (a calibration recording): only the noise
weight lambda is chosen there, by one net per weight; the networks never see them. At that
weight `n_members` nets (their own initialisation and batch order) are averaged: five, chosen on
validation sensors that are neither training nor test sensors (bench/ert_learned_validation.py,
seeds 30,000-30,002, boundary at 1 mV): the mean of k nets falls with k on every sensor, 3 -> 5
nets by 0.024 mm at 10 N and 0.034 mm at 4 N, 5 -> 7 by 0.016 and 0.016 more at two more nets'
cost (docs/ert.md).

The whole map is one torch module (`module_`): the voltages -> patch loads matrix (K times the
patch map, folded), the window gather and the members' MLPs (MeanOfNets), so `predict` and its ONNX graph
(export/torch_graphs.py `to_onnx`) are the same computation.
"""
import json
from functools import lru_cache

import numpy as np
import torch
from sklearn.utils.validation import check_is_fitted
from torch import nn

from common.errors import InputError
from data.ert.patch_loads import patch_loads_n
from data.ert.readings import transfer_basis
from models.ert.greit import GreitReconstruction
from models.ert.reconstruction import ERTReconstruction, localisation_mm
from models.ert.validation import checked_presses, checked_voltages, required_geometry

OFFSET_SCALE_MM = 10.0        # half a patch: the MLP's offsets are of order one
FORCE_CENTRE_N, FORCE_SCALE_N = 8.0, 4.0


class MeanOfNets(nn.Module):
    """The mean output of several networks on the same input: an ensemble that stays one module,
    so `predict` and its ONNX graph remain the same computation."""

    def __init__(self, nets):
        super().__init__()
        self.nets = nn.ModuleList(nets)

    def forward(self, x):
        return torch.stack([net(x) for net in self.nets]).mean(dim=0)


class PatchWindowNet(nn.Module):
    """voltages (n, n_channels) float32 -> (n, 3) x_mm, y_mm, force_n."""

    def __init__(self, load_map, n_side, patch_mm, half_width, width, n_layers=2):
        super().__init__()
        self.n_side, self.half_width, self.patch_mm = int(n_side), int(half_width), float(patch_mm)
        self.register_buffer("load_map", torch.as_tensor(load_map, dtype=torch.float32))    # (n_channels, n_patches)
        span = 2 * self.half_width + 1
        offsets = torch.arange(span)
        padded_side = self.n_side + 2 * self.half_width
        self.register_buffer("window_index", (offsets[:, None] * padded_side + offsets[None, :]).reshape(-1))
        n_features = span * span + 3
        self.register_buffer("feature_mean", torch.zeros(n_features))
        self.register_buffer("feature_scale", torch.ones(n_features))
        layers, size = [], n_features
        for _ in range(n_layers):
            layers += [nn.Linear(size, width), nn.GELU()]
            size = width
        self.mlp = nn.Sequential(*layers, nn.Linear(size, 3))

    def features(self, voltages):
        """(patch-centre xy of the window's middle patch (n, 2), window features (n, n_features))."""
        return self.load_features(voltages @ self.load_map)

    def load_features(self, loads):
        """`features` from the patch loads (n, n_patches)."""
        n, h = self.n_side, self.half_width
        # the window sits on the patch whose 3 x 3 neighbourhood carries most load: the single
        # largest patch of a weak press is at times a distant noise peak, the neighbourhood rarely
        neighbourhood = nn.functional.avg_pool2d(loads.reshape(-1, 1, n, n), 3, stride=1, padding=1)
        peak = neighbourhood.reshape(loads.shape[0], -1).argmax(dim=1)
        iy, ix = torch.div(peak, n, rounding_mode="floor"), torch.remainder(peak, n)
        padded = nn.functional.pad(loads.reshape(-1, n, n), (h, h, h, h)).reshape(loads.shape[0], -1)
        window = torch.gather(padded, 1, (iy * (n + 2 * h) + ix)[:, None] + self.window_index[None, :])
        top = window.max(dim=1, keepdim=True).values.clamp_min(1e-6)
        centre = torch.stack([ix, iy], dim=1).to(loads.dtype) * self.patch_mm + 0.5 * self.patch_mm
        # where the window sits (-1 to 1 across the sheet): near an edge or an electrode the same
        # window means a different offset, and what cannot be told apart is best guessed per place
        place = centre / (n * self.patch_mm) * 2.0 - 1.0
        return centre, torch.cat([window / top, torch.log(top), place], dim=1)

    def forward(self, voltages):
        return self.head(*self.features(voltages))

    def head(self, centre, features):
        """The MLP on `features`' output: training runs it on features computed once."""
        out = self.mlp((features - self.feature_mean) / self.feature_scale)
        return torch.cat([centre + OFFSET_SCALE_MM * out[:, :2], FORCE_CENTRE_N + FORCE_SCALE_N * out[:, 2:]], dim=1)


@lru_cache(maxsize=2)
def _reduced_presses(simulator_json: str) -> tuple[np.ndarray, np.ndarray]:
    """(u = K^T v, targets) of GreitReconstruction(**params)'s training presses, simulated one
    sensor at a time and reduced at once: 40,000 full frames of 6,624 channels would hold 2 GB,
    their reduced readings 90 MB. Kept per process: every sensor under test reuses them."""
    params = json.loads(simulator_json)
    basis = transfer_basis(params["geometry"])
    readings, targets = [], []
    for seed in GreitReconstruction(**params).training_sensor_seeds():
        voltages, part = GreitReconstruction(**{**params, "n_training_sensors": 1, "training_seed": seed}).training_frames()
        readings.append(np.asarray(basis.T @ voltages.T).T)
        targets.append(part)
    return np.vstack(readings), np.vstack(targets)


class LearnedReadingsInverse(ERTReconstruction):
    """ERT voltages (changes from the unloaded frame) -> (x_mm, y_mm, force_n)."""

    def __init__(self, geometry=None, training_scene=None, patch_mm=20.0, foam_spread_sd_mm=None,
                 n_training_sensors=80, presses_per_sensor=1000, training_force_range_n=(1.0, 15.0),
                 training_seed=20_000, noise_weights=(1e-6, 1e-5, 1e-4), half_width_patches=2, width=128,
                 epochs=30, batch_size=256, learning_rate=3e-3, n_members=5, quantification_limit_n=2.0, seed=0):
        self.geometry = geometry
        self.training_scene = training_scene
        self.patch_mm = patch_mm
        self.foam_spread_sd_mm = foam_spread_sd_mm
        self.n_training_sensors = n_training_sensors
        self.presses_per_sensor = presses_per_sensor
        self.training_force_range_n = training_force_range_n
        self.training_seed = training_seed
        self.noise_weights = noise_weights
        self.half_width_patches = half_width_patches
        self.width = width
        self.epochs = epochs
        self.batch_size = batch_size
        self.learning_rate = learning_rate
        self.n_members = n_members
        self.quantification_limit_n = quantification_limit_n
        self.seed = seed

    def _simulator(self) -> GreitReconstruction:
        side = self.geometry["side_mm"]
        return GreitReconstruction(geometry=self.geometry, training_scene=self.training_scene,
                                   n_training_sensors=self.n_training_sensors,
                                   presses_per_sensor=self.presses_per_sensor,
                                   training_force_range_n=tuple(self.training_force_range_n),
                                   training_position_range_mm=(0.0, side), training_seed=self.training_seed)

    def training_sensor_seeds(self) -> list[int]:
        return self._simulator().training_sensor_seeds()

    def chosen_hyperparameters(self) -> dict:
        return {"noise_weight": self.noise_weight_}

    def _training_readings(self) -> tuple[np.ndarray, np.ndarray]:
        """(u = K^T v, targets) of the training presses."""
        simulator = self._simulator().get_params()
        return _reduced_presses(json.dumps({**simulator, "training_force_range_n": list(simulator["training_force_range_n"]),
                                            "training_position_range_mm": list(simulator["training_position_range_mm"])},
                                           sort_keys=True))

    def _spread_sd_mm(self) -> float:
        """The foam spread the training scene simulates (its `foam_spread` effect), unless given."""
        if self.foam_spread_sd_mm is not None:
            return float(self.foam_spread_sd_mm)
        effect = (self.training_scene.get("effects") or {}).get("foam_spread")
        if effect is None:
            return 0.0
        return float((effect or {}).get("spread_per_thickness", 1.0)) * float(self.training_scene.get("foam_thickness_mm", 4.0))


    def fit(self, X, y):
        """X, y: validation presses of the sensor under test (the noise weight is chosen there)."""
        required_geometry(self.geometry)
        if int(self.half_width_patches) < 0 or min(int(self.width), int(self.epochs), int(self.n_members)) < 1:
            raise InputError(f"model.half_width_patches must be >= 0, width, epochs and n_members >= 1; got "
                             f"{self.half_width_patches}, {self.width}, {self.epochs}, {self.n_members}")
        weights = np.atleast_1d(np.asarray(self.noise_weights, dtype=float))
        if weights.size == 0 or not (weights > 0).all():
            raise InputError(f"model.noise_weights must be positive, got {weights.tolist()}")
        basis = transfer_basis(self.geometry)
        X, y = checked_presses(X, y, basis.shape[0], self.quantification_limit_n)
        side = float(self.geometry["side_mm"])
        n_side = int(round(side / float(self.patch_mm)))
        u, targets = self._training_readings()
        loads = patch_loads_n(targets[:, None, :3], side, float(self.patch_mm),
                              self.geometry["indenter_diameter_mm"] / 2.0, self._spread_sd_mm())
        noise = np.asarray((basis.T @ basis).todense())
        signal = u.T @ u
        scale = np.trace(signal) / np.trace(noise)
        validation = torch.as_tensor(X, dtype=torch.float32)

        def validation_mm(module):
            with torch.no_grad():
                return localisation_mm(module(validation).numpy()[:, :2], y)

        best, scores = None, []
        for weight in weights:       # one net per noise weight chooses the weight
            patch_map = np.linalg.solve(signal + weight * scale * noise, u.T @ loads)        # (n_z, n_patches)
            module = self._train(np.asarray(basis @ patch_map), u @ patch_map, targets, n_side, member=0)
            scores.append({"noise_weight": float(weight), "localisation_mm": validation_mm(module)})
            if best is None or scores[-1]["localisation_mm"] < best[0]:
                best = (scores[-1]["localisation_mm"], float(weight), module, patch_map)
        _, self.noise_weight_, module, patch_map = best
        # then n_members - 1 more nets at that weight (other initialisations and batch orders),
        # averaged: their errors are partly independent, the mean's smaller (docs/ert.md)
        members = [module] + [self._train(np.asarray(basis @ patch_map), u @ patch_map, targets, n_side, member=k)
                              for k in range(1, int(self.n_members))]
        module.mlp = MeanOfNets([member.mlp for member in members])
        self.module_ = module
        self.validation_scores_ = scores
        self.ensemble_localisation_mm_ = validation_mm(module)
        self.n_features_in_ = basis.shape[0]
        return self

    def _train(self, load_map, loads, targets, n_side, member) -> PatchWindowNet:
        # every (sensor seed, member) pair its own stream: member k of one sensor is never member 0 of another
        member_seed = int(np.random.SeedSequence([int(self.seed), int(member)]).generate_state(1)[0])
        generator = torch.Generator().manual_seed(member_seed)
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(member_seed)
            module = PatchWindowNet(load_map, n_side, self.patch_mm, int(self.half_width_patches), int(self.width))
        with torch.no_grad():     # the patch map is fixed: its features once, not per step
            centre, features = module.load_features(torch.as_tensor(loads, dtype=torch.float32))
            module.feature_mean.copy_(features.mean(dim=0))
            module.feature_scale.copy_(features.std(dim=0) + 1e-6)
        goal = torch.as_tensor(targets[:, :3], dtype=torch.float32)
        batch = int(self.batch_size)
        steps_per_epoch = max(1, len(features) // batch)
        optimiser = torch.optim.AdamW(module.mlp.parameters(), lr=float(self.learning_rate) / 3, weight_decay=1e-4)
        schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, float(self.learning_rate),
                                                       total_steps=int(self.epochs) * steps_per_epoch)
        scale = torch.tensor([OFFSET_SCALE_MM, OFFSET_SCALE_MM, FORCE_SCALE_N])
        module.train()
        for _ in range(int(self.epochs)):
            order = torch.randperm(len(features), generator=generator)
            for step in range(steps_per_epoch):
                rows = order[step * batch:(step + 1) * batch]
                loss = nn.functional.smooth_l1_loss(module.head(centre[rows], features[rows]) / scale, goal[rows] / scale,
                                                    beta=0.1)
                optimiser.zero_grad()
                loss.backward()
                optimiser.step()
                schedule.step()
        return module.eval()

    def predict(self, X) -> np.ndarray:
        check_is_fitted(self, "module_")
        X = checked_voltages(X, self.n_features_in_)
        with torch.no_grad():
            return self.module_(torch.from_numpy(np.array(X, dtype=np.float32))).numpy().astype(float)
