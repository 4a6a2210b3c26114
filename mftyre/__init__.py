"""mftyre: Magic Formula 6.1/6.2 tyre model driven by .tir property files (NumPy and CasADi).

    import mftyre
    model = mftyre.load_tir("tir_files/car_205_60R15_mf61.tir")
    out = model.evaluate(fz=4000.0, kappa=0.0, alpha=0.05)
    out.fy, out.mz, out.to_frame()

ISO-W (TYDEX W) axes, SI units.
"""
def _own_packages(names=("swift", "fmu")) -> None:
    """Our top-level packages ``swift`` and ``fmu`` (installed beside ``mftyre``) are imported from where they are
    installed, never from the user's working folder: under ``python -m mftyre``, a script or a notebook, the folder
    comes first on sys.path, and a ``swift.py`` or ``fmu/`` there was imported (and run) instead of ours. A finder
    ahead of the others gives our location for these two names; one of them already imported from elsewhere is
    dropped so the next import finds ours."""
    import importlib.util
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    own = {name: root / name / "__init__.py" for name in names if (root / name / "__init__.py").is_file()}

    class OwnPackages:
        @staticmethod
        def find_spec(name, path=None, target=None):
            init = own.get(name)
            if init is None:
                return None
            return importlib.util.spec_from_file_location(name, init, submodule_search_locations=[str(init.parent)])

    for name, init in own.items():
        module = sys.modules.get(name)
        if module is not None and Path(getattr(module, "__file__", "") or "").resolve() != init:
            for loaded in [m for m in sys.modules if m == name or m.startswith(name + ".")]:
                del sys.modules[loaded]
    if not any(type(f).__name__ == "OwnPackages" for f in sys.meta_path):
        sys.meta_path.insert(0, OwnPackages())


_own_packages()

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
