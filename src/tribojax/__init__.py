"""tribojax: rough-surface contact, friction and slip models in JAX.

Importing tribojax is cheap: a name is imported from its module when first used (PEP 562), so
the command line starts without JAX. The first use switches JAX to float64
(`jax_enable_x64`, `tribojax._precision`) and points JAX's persistent compilation cache at
tribojax's folder (`tribojax._cache`); `import tribojax` alone sets `JAX_ENABLE_X64=1` for a JAX
not yet imported, so that arrays made before the first use are float64 too.
"""

from __future__ import annotations

import importlib
import os
import sys
from importlib.metadata import PackageNotFoundError, version

if "jax" in sys.modules:  # already imported: switch it now (JAX reads the variable on import)
    sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    os.environ["JAX_ENABLE_X64"] = "1"

# public name -> (module, name in the module); one line per module
_EXPORTS: dict[str, tuple[str, str]] = {}


def _export(module: str, *names: str, **renamed: str) -> None:
    for name in names:
        _EXPORTS[name] = (module, name)
    for public, private in renamed.items():
        _EXPORTS[public] = (module, private)


_export("_contact._asperity", "REGIME_NAMES", "asperity_load", "asperity_regime", "critical_areas")
_export("_contact._contact", "ContactParameters", "FractalContact", "contact_parameters")
_export("_contact._materials", "ContactPair", "Material")
_export("_contact._surface", "FractalSurface")
_export("_decimate", "Decimation", "decimate_record")
_export("_dynamics._adjoint", "ForwardJacobianAdjoint")
_export("_dynamics._continuation", "FrequencyResponse", "frequency_response", "parameter_response")
_export(
    "_dynamics._design", "Peak", "PeakDesign", "amplitude_at", "frf_2dof_system", "minimise_peak",
    "peak_on_grid", "resonance_peak"
)
_export(
    "_dynamics._harmonic", "HarmonicCoefficients", "drive", "harmonic_balance",
    "harmonic_response"
)
_export("_dynamics._mhb", "FrictionSystem", "HBMSolution", "floquet_exponents", "solve_hbm")
_export(
    "_dynamics._profiles", "AbstractProfile", "DisplacementHistory", "MeasuredProfile",
    "PiecewiseLinearProfile", "TrapezoidProfile"
)
_export("_dynamics._rodas4", "Rodas4")
_export("_dynamics._slip", "SlipSolution", "simulate_slip", "slip_phase_averages")
_export(
    "_dynamics._structure", "AbstractContact", "DryFrictionContact2D", "Excitation",
    "FrictionContact", "Structure"
)
_export("_dynamics._transient", "integrate_steady")
_export("_fit._curve", "fit_steady_curve", "fit_transient", "transient_nrmse")
_export("_fit._engine", "FitError", "FitResult", "least_squares_fit")
_export("_fit._history", "BOUC_WEN_STARTS", "HistoryFit", "fit_history", "predict_history")
_export("_fit._surface", "fit_surface_from_runs")
_export("_friction._bouc_wen", "BoucWen")
_export("_friction._elastic2d", "ElasticDryFriction2D")
_export("_friction._element", "AbstractFrictionElement")
_export("_friction._lugre", "LuGre", "PreSlipLuGre")
_export(
    "_friction._rate_independent", "AbstractHysteresisElement", "IwanBank", "Jenkins", "Mindlin"
)
_export("_io._brfd", "read_brfd")
_export(
    "_io._curve", "FrictionCurve", "FrictionTransient", "effective_samples", "read_epos_steady",
    "read_epos_transient", "read_friction_curve", "write_friction_curve",
    "write_friction_transient"
)
_export("_io._files", "write_json_atomic")
_export("_io._loop", "HysteresisLoop", "read_loop", "synthetic_loop", "write_loop")
_export("_io._record", "AbstractRecord")
_export("_io._records", "detect_format", "read_record")
_export(
    "_io._slip_run", "SlipRun", "read_slip_run", "simulate_run", "synthetic_slip_run",
    "write_slip_run"
)
_export(
    "_model", "LoopAnalysis", "analyse_loop", "fit_loop", "fit_slip_run", "loop_residuals",
    "slip_run_start"
)
_export(
    "_presets", "CHAIN_DEFAULTS", "WANG2022_A_MAX", "WANG2022_CALIBRATED",
    "WANG2022_RETICLE_MASS_KG", "WANG2022_TANGENTIAL_LOAD_N",
)
_export(
    "_contact._presets", "vacuum_to_load", "wang2022_chuck", "wang2022_pair", "wang2022_reticle",
    "wang2022_surface", "wang2022_table3_model", "wu2015_eq5_stiffness",
)
_export(
    "_reproduce._chain_fit", "ChainFit", "ChainFitError", "chain_phase_slips",
    "fit_measured_slips", "rms_relative", "symmetric_bound", "wang2022_loads",
    CHAIN_DEFAULT_FREE="DEFAULT_FREE", CHAIN_PARAMETERS="PARAMETERS",
    wang2022_measured_slips="measured_slips", wang2022_theory_slips="paper_theory_slips"
)
_export("_reproduce._fit_figure", "plot_fit_measured")
_export("_reproduce._profile_likelihood", chain_profile_likelihood="profile_likelihood")
_export(
    "_reproduce._robust_fit", "RobustChainFit", "robust_fit_measured_slips",
    CHAIN_NOISE_MODELS="NOISE_MODELS"
)
_export("_reproduce._table3", "calibrate_table3", "equivalent_G", "reproduce_table3")
_export(
    "_reproduce._wu2015", "cbar_peak", "dimensionless_curves", "eq7_curves",
    "fractal_tangential_stiffness", "plot_wu2015", "wu2015_comparison", "wu2015_eq7"
)
_export("_results", "RESULTS")
_export(
    "_roughness._estimate", "RoughnessEstimate", "estimate_fractal", "psd_model",
    "structure_function_model"
)
_export("_roughness._synthesis", "direction_factor", "synthesize", "wm_profile", "yk_heights")
_export("_roughness._topography", "Topography", "read_topography")
_export(
    "_sensitivity", "Elasticities", "LoopChain", "ReticleChain", "elasticities",
    "hysteresis_sensitivities", "slip_sensitivities"
)
_export("_sweep", "product_grid", "sweep")
_export("_tables", "DataFileError", "read_table", "wang2022_table", "wu2015_table")
_SUBPACKAGES = ("discovery",)

__all__ = sorted(_EXPORTS) + list(_SUBPACKAGES) + ["__version__"]


def __getattr__(name: str):
    if name in _SUBPACKAGES:
        importlib.import_module(f"{__name__}._precision")
        return importlib.import_module(f"{__name__}.{name}")
    try:
        module, attr = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module 'tribojax' has no attribute {name!r}") from None
    importlib.import_module(f"{__name__}._precision")  # float64 and the cache before any use
    value = getattr(importlib.import_module(f"{__name__}.{module}"), attr)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


try:
    __version__ = version("tribojax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"
