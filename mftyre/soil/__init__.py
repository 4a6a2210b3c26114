"""A tyre on soft soil beside the Magic Formula on hard ground.

* :mod:`~mftyre.soil.soils`: soil property sets (Bekker n, k_c, k_phi; Mohr-Coulomb c, phi; Janosi-Hanamoto K)
  as data, built-in (``soils.csv``, with sources) or from a user CSV file;
* :mod:`~mftyre.soil.equations`: the semi-empirical tyre-on-soil model (Bekker, Janosi-Hanamoto, Wong),
  backend-neutral, sharing the .tir's vertical relation and contact patch;
* :class:`SoftSoilTyre`: NumPy evaluation, the towed wheel (zero-torque slip solved), the slip-sinkage and
  bulldozing options, a CasADi function;
* :class:`ConeIndexTyre`: the cone-index route (Brixius's mobility number), a simpler model behind the same
  interface (``evaluate``, ``towed``, the same outputs);
* :class:`Ground`: one interface for a vehicle model: hard ground (Magic Formula), soft soil, or a blend.
"""
from ..lazy import export_lazily

__all__ = ["Soil", "builtin_soils", "read_soils", "soil", "SoftSoilTyre", "SoilOutputs", "SinkageError", "OUTPUTS",
           "Ground", "GroundForces", "ConeIndexTyre"]
#: the names above, each imported from its submodule when first used (`mftyre --help` registers `mftyre soil`)
export_lazily(__name__, {
    "Soil": "soils", "builtin_soils": "soils", "read_soils": "soils", "soil": "soils",
    "SinkageError": "model", "SoftSoilTyre": "model", "SoilOutputs": "model", "OUTPUTS": "equations",
    "ConeIndexTyre": "cone_index", "Ground": "ground", "GroundForces": "ground"})
