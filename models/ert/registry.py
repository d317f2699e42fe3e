"""The ERT reconstructions by name: what a study's `reconstruction.kind` and the benches' method
names choose from. A new reconstruction is one module in this package and one line here."""
from common.errors import InputError
from models.ert.gauss_newton import GaussNewtonReconstruction
from models.ert.greit import GreitReconstruction
from models.ert.learned_inverse import GreitLearnedInverse
from models.ert.learned_readings_inverse import LearnedReadingsInverse
from models.ert.reconstruction import ERTReconstruction
from models.ert.tikhonov import TikhonovReconstruction

RECONSTRUCTIONS: dict[str, type[ERTReconstruction]] = {
    "tikhonov": TikhonovReconstruction,
    "gauss_newton": GaussNewtonReconstruction,
    "greit": GreitReconstruction,
    "greit_learned": GreitLearnedInverse,
    "learned_mlp": LearnedReadingsInverse,
}


def reconstruction_class(name: str) -> type[ERTReconstruction]:
    """The class registered as `name`; an unknown name is refused naming the registry and its entries."""
    try:
        return RECONSTRUCTIONS[name]
    except (KeyError, TypeError):
        raise InputError(f"reconstruction kind '{name}' is not in the ERT reconstruction registry "
                         f"(models/ert/registry.py RECONSTRUCTIONS): expected one of "
                         f"{', '.join(RECONSTRUCTIONS)}") from None

