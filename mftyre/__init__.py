"""mftyre: Magic Formula 6.1/6.2 tyre model driven by .tir property files (NumPy and CasADi).

    import mftyre
    model = mftyre.load_tir("tir_files/car_205_60R15_mf61.tir")
    out = model.evaluate(fz=4000.0, kappa=0.0, alpha=0.05)
    out.fy, out.mz, out.to_frame()

ISO-W (TYDEX W) axes, SI units.
"""
from .errors import DataError, InputClippedWarning, MFTyreError, ModelInputError, TirError
from .model import MFModel, MFOutputs, load_tir

__version__ = "0.1.0"
__all__ = ["load_tir", "MFModel", "MFOutputs", "MFTyreError", "TirError", "DataError", "ModelInputError",
           "InputClippedWarning"]
