"""Fitting Magic Formula parameters to tyre measurements (lmfit, staged as on the test bench).

    from mftyre.data import read_tydex
    from mftyre.fit import fit_tir
    result = fit_tir(read_tydex("trailer.tdx"))          # generic start; or start="start.tir"
    result.write_tir("fitted.tir"); result.save_report("report/report.md")
    result.model, result.stages["pure_fy"].values, result.comparison

Stages (:data:`STAGE_NAMES`, see :mod:`mftyre.fit.stages` for the parameters of each): pure_fx, pure_fy,
mz, combined_fx, combined_fy, mz_combined, mx, my, vertical, rolling_radius. Fit error: the normalised RMS
of Schmeitz et al. (2005), eq. (4) (:func:`normalised_rms`); the report's pressure comparison follows that
paper's Table 2. Before fitting, the test programme is recognised (:mod:`mftyre.programme`) and a time series
reduced per sweep (:mod:`mftyre.timeseries`); every stage result must pass :func:`verify_tir` (also the gap
finder's check before it writes an improved .tir).
Command line: ``mftyre fit DATA -o out.tir [--start FILE.tir] [--report report.md]``.
"""

from ..lazy import export_lazily

__all__ = ["fit_tir", "FitResult", "StageResult", "normalised_rms", "start_parameters", "STAGES", "STAGE_NAMES",
           "BOUNDS", "COMPARED_STAGES", "load_data", "verify_tir"]
#: the names above, each imported from its submodule when first used: `mftyre fit --help` imports no lmfit
export_lazily(__name__, {
    "BOUNDS": "core", "COMPARED_STAGES": "core", "FitResult": "core", "StageResult": "core", "fit_tir": "core",
    "load_data": "core", "normalised_rms": "metrics", "STAGE_NAMES": "stages", "STAGES": "stages",
    "start_parameters": "start", "verify_tir": "verify"})
