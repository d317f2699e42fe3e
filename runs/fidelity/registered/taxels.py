"""taxels' rows (Effects of the elastic cover on tactile sensor arrays, seed 004,
../shared/seeds/004_*.txt), registered from the paper's own words.

Registered 2026-12-06 for issue 42, after the rows had been measured under the same tolerances in
runs/fidelity/taxels.py (their verdicts were known). The paper states no bound around any of its
figures: every numeric threshold is ours (an earlier issue's goals), the directions are the paper's.
"""
from runs.fidelity.registered import register

S = "taxels"

register(S, "1", "§5: \"In the measurement shown in Fig. 2(a) |ε_zmax/ε_zmin| ≈ 19, which indicates a much stronger "
         "lateral-inhibition effect than it is predicted\" (eq. 3: 5^{5/2} ≈ 56)",
         "|ε_z,max / ε_z,min| of a 10 mN needle scan at 180 µm, mechanics and read back over 20 noise seeds",
         "13.3-24.7 (± 30 % of 19)")   # our threshold
register(S, "2", "§5: \"The measured W curve is linear, but its slope, 1.14 is different from the predicted 2.82 ... "
         "according to the measurements the ε_z curves are narrower than the prediction\"",
         "slope of W over 150-1000 µm (mechanics)",
         "between the measured 1.14 and the theory's 2.83")
         # the paper's direction (narrower than the theory) bounded below by its own figure; the band is ours
register(S, "3", "§5: \"the A curve can be fitted better with a 1/z^{1.45} function instead of the theoretical "
         "1/z^2\"", "exponent of A over 150-1000 µm (mechanics)", "−1.45 ± 0.25")   # our threshold
register(S, "4", "§7: \"From Fig. 2 it is clear that the shear sensitivity of our sensors is less than the prediction "
         "(the ratio of the maximum values of ε_z and γ_x is high). Shear sensitivity can be increased efficiently by "
         "attaching a rigid load-transmitting rod to the middle of the sensor membrane\"",
         "max |γ_x| / max |ε_z| of a normal needle scan (theory 0.75 · 0.8^2.5 = 0.429); a moving load's peak "
         "|γ_x| / |ε_z| with and without the rod", "< 0.429; hair > flat")   # the paper's two directions
register(S, "5", "§8: \"results in Fig. 9 clearly prove that sensors with elastic bumps on top have increased "
         "lateral sensitivity, they react more vigorously to arbitrary forces\"",
         "mean |γ_x| per unit shear under a 3 mm probe, bumps / flat, 3 sets of 200 probe positions",
         "> 1 in every set (the paper's direction)")
register(S, "6", "§8: \"The bump (Fig. 10(b)) and the ridge (Fig. 10(d)) integrate the load from their entire surface "
         "and respond to the amplitude of the load and the shear force direction ... The flat surface (Fig. 10(a)) and "
         "the ridge parallel to indentation–motion direction (Fig. 10(c)) represent the complicated strain "
         "distribution\"; \"we could demonstrate the direction selectivity of the fingerprint-like ridges\"",
         "peak shear moved across / along the ridge (flat cover: 1); correlation of ε_z along the ridge with the "
         "flat cover's", "across/along > 1, flat 1; along-ridge shape correlation > 0.9")
         # the directions are the paper's; the 0.9 correlation is ours
