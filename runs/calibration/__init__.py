"""experiment=calibrate: a scene fitted to a rig's presses, pretraining on it, the choice on validation."""
