"""TensorBoard logging of one run: per-epoch curves, final metrics, hyper-parameters, figures.

Each run writes its event files into `<run dir>/tensorboard/<name>`, the name saying what ran
(`run_name`): `tensorboard --logdir outputs` lists `<date>/<time>_<pid>/tensorboard/rubber12·blend·seed0`,
and `--logdir_spec outputs:outputs,multirun:multirun` also every sweep job, as
`multirun/…/<job>/tensorboard/rubber12·extra_trees·seed1·trial3`. One entry per run: the hyper-parameters
go into the run's own event file (the HPARAMS tab's session start and end), flattened to numbers
and short strings. No experiment summary is written: TensorBoard would take the first run's as
the whole comparison's, hiding the hyper-parameters of runs of another model; without one it
builds the columns from every run's own.

A blend's members report their epochs under the blend's run, each curve labelled with its member
(models/epoch_callback.py): `members/resmlp/fold0/loss/train`.
"""
from hydra.core.hydra_config import HydraConfig
from hydra.types import RunMode
from omegaconf import OmegaConf
from torch.utils.tensorboard import SummaryWriter
from torch.utils.tensorboard.summary import hparams as hparams_summaries

SEPARATOR = "·"
TEXT_LIMIT = 60   # characters of a string hyper-parameter: the HPARAMS table's column stays readable


def run_name(cfg) -> str:
    """What ran, in a few words: the experiment (and any experiment/<group> choice; else the scene,
    else the data source), the model (not for a study, which its experiment names), the seed, and
    in a sweep the trial (Hydra's job number): rubber12·blend·seed0, accuracy_vs_time·dt·decision_tree·seed0·trial4.
    Outside Hydra (a composed config in tests) the model is named by its class."""
    choices, trial = {}, None
    if HydraConfig.initialized():
        hydra = HydraConfig.get()
        choices = {k: v for k, v in hydra.runtime.choices.items() if v is not None}
        trial = OmegaConf.select(hydra, "job.num", default=None) if hydra.mode == RunMode.MULTIRUN else None
    parts = [choices[k] for k in sorted(choices) if k == "experiment" or k.startswith("experiment/")]
    if not parts:
        uses_scene = "source" in cfg.data and OmegaConf.is_interpolation(cfg.data, "source")  # source: ${scene}
        parts = [choices.get("scene" if uses_scene else "data", "")]
    if cfg.get("study") is None:
        parts.append(choices.get("model") or cfg.model._target_.rsplit(".", 1)[-1])
    parts.append(f"seed{cfg.seed}")
    if trial is not None:
        parts.append(f"trial{trial}")
    return SEPARATOR.join(str(p).replace("/", "-") for p in parts if p != "")


def _short(value) -> str:
    """A value's text, cut to TEXT_LIMIT characters; a cut list says how many items it has."""
    text = str(value)
    if len(text) <= TEXT_LIMIT:
        return text
    end = f"… ({len(value)} items)" if isinstance(value, (list, tuple)) else "…"
    return text[:TEXT_LIMIT - len(end)] + end


def flat_hparams(values: dict, prefix: str = "") -> dict:
    """Nested settings -> {dotted key: number or short string}, as TensorBoard's HPARAMS tab
    takes them: dicts become dotted keys, a `_target_` its class name; None, a bool (which torch's
    summary would turn into 0 or 1), a list or a string its text, cut to TEXT_LIMIT characters;
    Hydra's other keys (_convert_, ...) are dropped."""
    flat = {}
    for key, value in values.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flat_hparams(value, f"{name}."))
        elif key == "_target_":
            flat[name] = str(value).rsplit(".", 1)[-1]
        elif str(key).startswith("_"):
            continue
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            flat[name] = value
        else:
            flat[name] = _short(value)
    return flat


class TensorBoardLogger:
    def __init__(self, log_dir: str):
        self.log_dir = log_dir

    def __enter__(self):
        self._writer = None
        return self

    @property
    def writer_(self) -> SummaryWriter:
        """Opened on first use: a run that fails before logging anything leaves no event file."""
        if self._writer is None:
            self._writer = SummaryWriter(log_dir=self.log_dir)
        return self._writer

    def __exit__(self, *exc):
        if self._writer is not None:
            self._writer.close()

    def log_epoch(self, record: dict) -> None:
        """Every number of an epoch record: train_loss -> loss/train, val_accuracy -> accuracy/val,
        lr -> lr; a blend member's record (its `member` says which, e.g. resmlp/fold0) under
        members/<member>/."""
        step = record["epoch"]
        prefix = f"members/{record['member']}/" if record.get("member") else ""
        for key, value in record.items():
            if key in ("epoch", "member"):
                continue
            split, _, metric = key.partition("_")
            self.writer_.add_scalar(prefix + (f"{metric}/{split}" if split in ("train", "val") else key), value, step)

    def log_metrics(self, metrics: dict, prefix: str) -> None:
        for target, row in metrics.items():
            for name, value in row.items():
                if value is not None:   # not defined (R² of one row, MAPE of all-zero targets): no point
                    self.writer_.add_scalar(f"{prefix}/{target}/{name}", value)

    def log_hparams(self, hparams: dict, final: dict) -> None:
        """The run's hyper-parameters (flattened) and its final scores, in the run's own event file."""
        _, session_start, session_end = hparams_summaries(flat_hparams(hparams), final)
        self.writer_.file_writer.add_summary(session_start)
        self.writer_.file_writer.add_summary(session_end)
        for tag, value in final.items():
            self.writer_.add_scalar(tag, value)

    def log_text(self, tag: str, text: str) -> None:
        self.writer_.add_text(tag, text)

    def log_figure(self, tag: str, figure) -> None:
        self.writer_.add_figure(tag, figure, close=False)

    def flush(self) -> None:
        self.writer_.flush()
