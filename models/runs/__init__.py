"""The runs train.py starts: seed, datamodule, then the regression or classification run."""
