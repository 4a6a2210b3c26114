"""mftyre: Magic Formula 6.1/6.2 tyre model driven by .tir property files (NumPy and CasADi).

    import mftyre
    model = mftyre.load_tir("tir_files/car_205_60R15_mf61.tir")
    out = model.evaluate(fz=4000.0, kappa=0.0, alpha=0.05)
    out.fy, out.mz, out.to_frame()

ISO-W (TYDEX W) axes, SI units.
"""
from .errors import DataError, InputClippedWarning, LoadFactorWarning, MFTyreError, ModelInputError, \
    PressureFactorWarning, ReferenceValueWarning, TirError, TurnSlipWarning

__version__ = "0.1.0"
__all__ = ["load_tir", "MFModel", "MFOutputs", "MFTyreError", "TirError", "DataError", "ModelInputError",
           "InputClippedWarning", "LoadFactorWarning", "PressureFactorWarning", "ReferenceValueWarning",
           "TurnSlipWarning", "read_tir", "write_tir", "sample_tir", "read_data"]

#: Imported when first used, so ``import mftyre`` stays light (no NumPy): name -> (module, attribute).
_LAZY = {"load_tir": ("model", "load_tir"), "MFModel": ("model", "MFModel"), "MFOutputs": ("model", "MFOutputs"),
         "read_tir": ("tir", "read_tir"), "write_tir": ("tir", "write_tir"), "sample_tir": ("files", "sample_tir"),
         "read_data": ("data", "read_data")}
_SUBMODULES = ("files", "data", "tir", "params", "fit", "gaps", "programme", "rig", "compiled", "transient", "soil",
               "compat", "cli", "model", "backend", "formula", "inputs", "variables", "vehicle")


def __getattr__(name):  # PEP 562: mftyre.files.sample_tir(...) and mftyre.write_tir(...) after `import mftyre`
    import importlib

    if name in _LAZY:
        module, attribute = _LAZY[name]
        return getattr(importlib.import_module(f".{module}", __name__), attribute)
    if name in _SUBMODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'mftyre' has no attribute {name!r}")
