"""TensorBoard logging of one run: per-epoch curves, final metrics, hyper-parameters, figures.

Writes real event files (torch's SummaryWriter) that `tensorboard --logdir <run>/tensorboard`
shows; hyper-parameters go to the `hparams` sub-run so the HPARAMS tab can compare runs.
"""
from torch.utils.tensorboard import SummaryWriter


def _scalar_hparams(flat: dict) -> dict:
    """add_hparams takes only int, float, str, bool: stringify the rest (lists, None)."""
    return {k: v if isinstance(v, (int, float, str, bool)) else str(v) for k, v in flat.items()}


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
        """Every number of an epoch record: train_loss -> loss/train, val_accuracy -> accuracy/val, lr -> lr."""
        step = record["epoch"]
        for key, value in record.items():
            if key == "epoch":
                continue
            split, _, metric = key.partition("_")
            self.writer_.add_scalar(f"{metric}/{split}" if split in ("train", "val") else key, value, step)

    def log_metrics(self, metrics: dict, prefix: str) -> None:
        for target, row in metrics.items():
            for name, value in row.items():
                self.writer_.add_scalar(f"{prefix}/{target}/{name}", value)

    def log_hparams(self, hparams: dict, final: dict) -> None:
        self.writer_.add_hparams(_scalar_hparams(hparams), final, run_name="hparams")

    def log_figure(self, tag: str, figure) -> None:
        self.writer_.add_figure(tag, figure, close=False)

    def flush(self) -> None:
        self.writer_.flush()
