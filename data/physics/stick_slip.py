"""Stick-slip of a compliant slider driven at constant speed: the spring-block model.

A pad pressed with normal force N and dragged through a tangential spring of stiffness k_t at
speed v sticks until the spring's force reaches the static friction mu_s N, then slips; with a
kinetic friction mu_k < mu_s the slip overshoots symmetrically about mu_k N and the spring force
drops to (2 mu_k - mu_s) N (Rabinowicz, *Friction and Wear of Materials*, 2nd ed. 1995, ch. 4.8;
Persson, *Sliding Friction*, 2nd ed. 2000, ch. 12; Baumberger & Caroli, Adv. Phys. 55 (2006) 279).
Each cycle the drive advances by the slip length

    Delta = 2 (mu_s - mu_k) N / k_t,        period T = Delta / v,

so the tangential force is a sawtooth of peak-to-peak 2 (mu_s - mu_k) N whose frequency
v k_t / (2 (mu_s - mu_k) N) falls as the load rises: a friction pair sets both how strongly and
how fast the contact chatters, and both change with force. During a stick phase the skin does
not move over the board; during the (short) slip it catches up with the drive. mu_s = mu_k:
steady sliding, no stick-slip.
"""
import numpy as np

from common.errors import InputError

MIN_SLIP_MM = 1e-6


def check_friction(static, kinetic, name="friction pair"):
    if not (np.isfinite(static) and np.isfinite(kinetic)) or kinetic < 0 or static < 0:
        raise InputError(f"{name}: friction coefficients must be >= 0, got static {static}, kinetic {kinetic}")
    if static < kinetic:
        raise InputError(f"{name}: static friction ({static}) below kinetic friction ({kinetic})")


def slip_length_mm(normal_force_n, static, kinetic, tangential_stiffness_n_per_mm):
    """Drive advance per stick-slip cycle, Delta = 2 (mu_s - mu_k) N / k_t."""
    check_friction(static, kinetic)
    if not tangential_stiffness_n_per_mm > 0:
        raise InputError(f"tangential stiffness must be positive, got {tangential_stiffness_n_per_mm} N/mm")
    return 2.0 * (static - kinetic) * np.maximum(np.asarray(normal_force_n, dtype=np.float64), 0.0) \
        / tangential_stiffness_n_per_mm


def stick_slip_cycle(drive_mm, slip_mm):
    """Phase of the stick-slip cycle (0..1, rising through the stick, back to 0 at each slip) and
    the skin's lag behind the drive (mm) for a drive position `drive_mm` (the slider's travel
    since sliding began). Where there is no stick-slip (slip_mm = 0) the phase is 0 and the lag 0."""
    slip = np.asarray(slip_mm, dtype=np.float64)
    chatters = slip > MIN_SLIP_MM             # below a nanometre the cycle is no stick-slip (and 1/slip overflows)
    safe = np.where(chatters, slip, 1.0)
    cycles = drive_mm / safe
    phase = np.where(chatters, cycles - np.floor(cycles), 0.0)    # mod 1, without np.mod's cost
    return phase, phase * np.where(chatters, slip, 0.0)
