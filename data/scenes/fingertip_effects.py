"""Effects of the fingertip scene. A scene runs only those it lists.

Source effects act on the load, the skin's motion and the charge before the two channels are
synthesised (in this order: stick-slip moves the skin and modulates the load before the ridges
push on it); reading effects act on the synthesised channels (triboelectric current in nA,
piezoresistive amplifier output in V). Arrays are (n_recordings, n_timesteps); each function
draws from its own random stream `rng`.
"""
import numpy as np
from scipy.signal import lfilter

from common.errors import InputError
from data.physics.comb_electrodes import comb_differential
from data.physics.rough_contact import surface_profile
from data.physics.stick_slip import slip_length_mm, stick_slip_cycle
from data.scenes.fingertip_boards import ridge_profile


def _per_recording(state, key):
    materials, labels = state["materials"], state["labels"]
    return labels["material"].map(lambda m: materials[m][key]).to_numpy(dtype=np.float64)


# -- source effects -------------------------------------------------------------------------
def stick_slip(state, rng, finger_tangential_stiffness_n_per_mm=150.0, normal_coupling=0.2, bandwidth_hz=40.0):
    """Stick-slip of the skin on the board while sliding (data/physics/stick_slip.py): the board's
    friction pair against Kapton (fingertip_boards.MATERIALS) and the tangential spring (the pad in
    shear in series with the 3D-printed finger in bending, 3 E I / L^3: a PLA finger about 60 mm long
    of 15 mm square section gives ~150 N/mm, an estimate) set a sawtooth of
    the friction force, peak-to-peak 2 (mu_s - mu_k) N, at v k_t / (2 (mu_s - mu_k) N). The skin
    lags the drive during each stick (it stays put on the board, so the ridges and the roughness
    it slides over pause) and catches up at each slip. The finger is not perfectly normal to the
    board, so part of the friction change loads the film: N <- N + coupling (F_t - mu_k N)
    (`normal_coupling`, an estimate). Each pass starts at a random phase of the cycle.
    Light loads chatter at hundreds of hertz, beyond the 250 Hz sampling: the acquisition board
    filters its inputs in hardware (paper sec. 2.3), so the cycle reaches the channels attenuated as
    its fundamental f is by a first-order low-pass, 1 / sqrt(1 + (f / bandwidth)^2) (`bandwidth_hz`,
    an estimate), instead of aliasing into the record."""
    if finger_tangential_stiffness_n_per_mm <= 0:
        raise InputError(f"scene fingertip: stick_slip needs finger_tangential_stiffness_n_per_mm > 0, "
                         f"got {finger_tangential_stiffness_n_per_mm}")
    if bandwidth_hz <= 0:
        raise InputError(f"scene fingertip: stick_slip needs bandwidth_hz > 0, got {bandwidth_hz}")
    if not 0 <= normal_coupling < 1:
        raise InputError(f"scene fingertip: stick_slip needs 0 <= normal_coupling < 1, got {normal_coupling}")
    stiffness = 1.0 / (1.0 / state["tangential_stiffness_n_per_mm"] + 1.0 / finger_tangential_stiffness_n_per_mm)
    static, kinetic = _per_recording(state, "static_friction"), _per_recording(state, "kinetic_friction")
    level = state["force_n"].max(axis=1)
    slip = np.stack([slip_length_mm(n, s, k, stiffness) for n, s, k in zip(level, static, kinetic)])
    offset = rng.uniform(0, 1, size=len(level)) * slip
    phase, lag = stick_slip_cycle(state["travel_mm"] + offset[:, None], slip[:, None])
    frequency_hz = np.divide(state["slide_speed_mm_s"], slip, out=np.full_like(slip, np.inf), where=slip > 1e-6)
    passed = (1.0 / np.sqrt(1.0 + (frequency_hz / bandwidth_hz) ** 2))[:, None]
    sliding = state["sliding"]
    state["skin_position_mm"] = state["skin_position_mm"] - np.where(sliding, passed * lag, 0.0)
    friction_swing = ((static - kinetic) * level)[:, None] * passed * (2.0 * phase - 1.0)
    state["force_n"] = state["force_n"] + np.where(sliding, normal_coupling * friction_swing, 0.0)
    state["slip_length_mm"] = slip
    state["stick_slip_hz"] = frequency_hz


def force_ripple(state, rng, amplitude=0.08):
    """Texture-induced force modulation while sliding: ridges passing under the cushion push it
    up and down, F <- F (1 + amplitude (2 c(x / period) - 1)), at v / period. Flat boards: none."""
    profile, period = state["profile"], state["period_mm"]
    ridged = period > 0
    if not ridged.any():
        return
    c = np.zeros_like(state["force_n"])
    for name in np.unique(profile[ridged]):
        rows = profile == name
        c[rows] = ridge_profile(name, state["skin_position_mm"][rows] / period[rows, None])
    sliding = state["sliding"]
    state["force_n"] = state["force_n"] * np.where(ridged[:, None] & sliding, 1.0 + amplitude * (2 * c - 1), 1.0)
    state["ridge_contact"] = c        # the scene's ridge charge reads the same contact share


def roughness(state, rng, efficiency=0.1, step_mm=0.05):
    """The board's waviness read by the comb electrodes while sliding. Each board is one line scan
    with its material's roughness spectrum (Hurst exponent, roll-off; data/physics/rough_contact.py),
    unit rms, drawn once per board. Where the board rises the local pressure rises by a share
    `efficiency` of the nominal one (an estimate), the contact share (and so the charge) follows
    with Persson's slope p0 da/dp0, and the combs read that charge pattern through their period
    selectivity (data/physics/comb_electrodes.py). Each pass reads the filtered scan at the skin's
    position, so the current carries a random, narrow band around v / grating period whose strength
    is the board's roughness spectrum near the grating's wavelength (none on a fully touching board).
    The scene multiplies the pattern by sigma A0 and the slope at the momentary load."""
    if efficiency < 0 or step_mm <= 0:
        raise InputError(f"scene fingertip: roughness needs efficiency >= 0 and step_mm > 0, got {efficiency}, {step_mm}")
    labels, materials = state["labels"], state["materials"]
    position = state["skin_position_mm"]
    pad_mm = state["fingertip_length_mm"]
    length_mm = float(position.max()) + pad_mm + 4 * step_mm
    boards = labels["board"].to_numpy()
    names = list(dict.fromkeys(boards))
    scans = []
    for board in names:
        p = materials[board.split("/")[0]]
        scan = surface_profile(rng, length_mm, step_mm, p["hurst_exponent"], p["roll_off_mm"],
                               state["roughness_cutoff_mm"])
        scans.append(comb_differential(scan, step_mm, state["grating_period_mm"], pad_mm))
    scans = np.stack(scans)
    index_of = {board: i for i, board in enumerate(names)}
    row = np.array([index_of[board] for board in boards])
    index = np.clip((position / step_mm).astype(np.int64), 0, scans.shape[1] - 1)
    state["roughness_pattern"] = scans[row[:, None], index]
    state["roughness_scale_mm2"] = efficiency * state["nominal_area_mm2"]


def humidity(state, rng, relative_humidity_pct=45.0, drift_pct=3.0, correlation_passes=300.0, reference_pct=30.0,
             decay_pct=50.0):
    """Surface charge falls as humidity rises (a water film bleeds charge away; physics notes):
    sigma <- sigma exp(-(RH - RH_ref) / decay). The room's humidity drifts slowly over the session
    (passes in recording order, board by board): an Ornstein-Uhlenbeck process (Uhlenbeck &
    Ornstein, Phys. Rev. 36 (1930) 823) with mean `relative_humidity_pct`, stationary spread
    `drift_pct` and a correlation of `correlation_passes` passes, sampled once per pass."""
    if drift_pct < 0 or correlation_passes <= 0:
        raise InputError(f"scene fingertip: humidity needs drift_pct >= 0 and correlation_passes > 0, "
                         f"got {drift_pct}, {correlation_passes}")
    n = len(state["sigma_uc_m2"])
    keep = np.exp(-1.0 / correlation_passes)
    shocks = rng.standard_normal(n) * drift_pct * np.sqrt(1 - keep ** 2)
    shocks[0] = rng.standard_normal() * drift_pct              # start in the stationary distribution
    rh = relative_humidity_pct + lfilter([1.0], [1.0, -keep], shocks)
    rh = np.clip(rh, 0.0, 100.0)
    state["relative_humidity_pct"] = rh
    state["sigma_uc_m2"] = state["sigma_uc_m2"] * np.exp(-(rh - reference_pct) / decay_pct)


def charge_memory(state, rng, transfer_per_contact=0.5, pass_interval_s=15.0):
    """Charge builds up over repeated contacts and decays between them (the familiar rise of a
    triboelectric output over its first cycles; decay by surface conduction, Lowell & Rose-Innes,
    Adv. Phys. 29 (1980) 947): each contact closes `transfer_per_contact` of the gap to the
    saturated charge, b' = b + beta (1 - b); between passes it decays, b <- b' exp(-dt / tau), tau
    the board's `charge_decay_s`. Run over each board's passes in recording order from an
    uncharged board; sigma <- sigma b' of each pass. beta and the interval are estimates."""
    if not 0 < transfer_per_contact <= 1 or pass_interval_s < 0:
        raise InputError(f"scene fingertip: charge_memory needs 0 < transfer_per_contact <= 1 and "
                         f"pass_interval_s >= 0, got {transfer_per_contact}, {pass_interval_s}")
    boards = state["labels"]["board"].to_numpy()
    keep = np.exp(-pass_interval_s / _per_recording(state, "charge_decay_s"))
    level = np.empty(len(boards))
    charged = {}
    for i, board in enumerate(boards):          # recording order = session order
        b = charged.get(board, 0.0)
        level[i] = b + transfer_per_contact * (1.0 - b)
        charged[board] = level[i] * keep[i]
    state["charge_level"] = level
    state["sigma_uc_m2"] = state["sigma_uc_m2"] * level


# -- reading effects ------------------------------------------------------------------------
def electrostatic_noise(state, rng, mains_hz=50.0, hum_na=2.0, broadband_na=1.0, piezo_noise_v=0.002):
    """Pick-up on the high-impedance triboelectric line: mains hum at a random phase per
    recording plus white noise; a little white noise on the amplifier's output too."""
    current = state["triboelectric_na"]
    omega_t = 2 * np.pi * mains_hz * state["time_s"]
    phase = rng.uniform(0, 2 * np.pi, size=(len(current), 1))
    # sin(wt + phase) = sin(wt) cos(phase) + cos(wt) sin(phase): two outer products, no per-sample sine
    hum = hum_na * (np.cos(phase) * np.sin(omega_t)[None, :] + np.sin(phase) * np.cos(omega_t)[None, :])
    state["triboelectric_na"] = current + hum + broadband_na * rng.standard_normal(current.shape, dtype=np.float32)
    state["piezoresistive_v"] = state["piezoresistive_v"] \
        + piezo_noise_v * rng.standard_normal(current.shape, dtype=np.float32)


def adc(state, rng, bits=12, supply_v=3.3, transimpedance_v_per_na=0.005):
    """Both channels through an N-bit ADC over 0..supply (the ESP32's 12-bit ADC, paper sec. 2.3):
    the current via a transimpedance stage centred at mid-rail (+/- 330 nA at the default gain), the
    amplifier's output directly. Values outside the range clip, as a real ADC does."""
    if bits < 1:
        raise InputError(f"scene fingertip: adc needs bits >= 1, got {bits}")
    lsb = supply_v / (2**bits - 1)

    def quantise(volts):
        return np.clip(np.rint(volts / lsb), 0, 2**bits - 1) * lsb

    mid = supply_v / 2
    state["triboelectric_na"] = (quantise(mid + transimpedance_v_per_na * state["triboelectric_na"]) - mid) \
        / transimpedance_v_per_na
    state["piezoresistive_v"] = quantise(state["piezoresistive_v"])


SOURCE_EFFECTS = {"stick_slip": stick_slip, "force_ripple": force_ripple, "roughness": roughness,
                  "humidity": humidity, "charge_memory": charge_memory}
READING_EFFECTS = {"electrostatic_noise": electrostatic_noise, "adc": adc}
EFFECTS = {**SOURCE_EFFECTS, **READING_EFFECTS}
