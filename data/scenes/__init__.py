"""Simulated sensors: one module per sensor with its effects module beside it, and the scene contract (contract.py)."""
