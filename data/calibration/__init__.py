"""Calibration: which scene parameters a rig's presses identify, the fit, the presses' table, a rig stand-in."""
