"""capacitive6x6's rows the paper cannot support (Egger et al. 2025, seed 001). Its other rows are
not registered yet: they keep the tolerances in runs/fidelity/capacitive6x6.py."""
from runs.fidelity.registered import register

register("capacitive6x6", "5", "sec. 3.5: \"Decision Tree Regression and GPR demonstrated fluctuating trends in "
         "predicted force values, resulting in irregular patterns ... step-like transitions, whereas GPR ... localized "
         "oscillations\"; Table 2: every model R² > 0.99",
         "rms departure from a cubic over a 300-press sweep, paper-configured models",
         "paper-configured: tree and GPR each > 2 x the rougher linear model, with test R² > 0.99",
         missing="the GPR's input (counts, scaled or normalised) and its kernel settings are not given, and the row "
                 "joins two claims (oscillating and R² > 0.99) that the paper's default GP meets only one at a time")
