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
from .core import BOUNDS, COMPARED_STAGES, FitResult, StageResult, fit_tir, load_data
from .metrics import normalised_rms
from .stages import STAGE_NAMES, STAGES
from .start import start_parameters
from .verify import verify_tir

__all__ = ["fit_tir", "FitResult", "StageResult", "normalised_rms", "start_parameters", "STAGES", "STAGE_NAMES",
           "BOUNDS", "COMPARED_STAGES", "load_data", "verify_tir"]
