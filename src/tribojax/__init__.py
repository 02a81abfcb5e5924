"""tribojax: rough-surface contact, friction and slip models in JAX.

Importing tribojax is cheap: a public name is imported from its module when first used (PEP 562
`__getattr__`), so the command line starts without JAX. The names and their homes are the
imports of the `TYPE_CHECKING` block below (read by type checkers, the API docs and, parsed once,
by `__getattr__`). `import tribojax` switches JAX to float64 (`jax_enable_x64`): an imported JAX
at once, a JAX imported later through `JAX_ENABLE_X64=1`, so that arrays made before the first
use are float64 too. The first use also points JAX's persistent compilation cache at tribojax's
folder (`tribojax._cache`).
"""

from __future__ import annotations

import ast
import importlib
import os
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING

from ._limits import XLA_HOIST_OPTION as _XLA_HOIST_OPTION

if "jax" in sys.modules:  # already imported: switch it now (JAX reads the variable on import)
    sys.modules["jax"].config.update("jax_enable_x64", True)
else:
    os.environ["JAX_ENABLE_X64"] = "1"

# One kernel per slip solve, unless TRIBOJAX_XLA_HOIST=off: XLA:CPU compiles every while loop free
# of library calls into one kernel (its size limit raised from 1 kB) and Rodas4 factorises small
# systems without LAPACK (docs/performance.md, "One kernel per solve"). XLA reads the flag when
# JAX's first backend starts: not set once one runs, nor beside a user's own extra options.
_HOIST_FLAG = f"--xla_backend_extra_options={_XLA_HOIST_OPTION}=1000000000"


def _backend_started() -> bool:
    bridge = getattr(getattr(sys.modules.get("jax"), "_src", None), "xla_bridge", None)
    return bool(bridge is not None and bridge.backends_are_initialized())


_hoist = os.environ.get("TRIBOJAX_XLA_HOIST", "on").strip().lower() or "on"
if _hoist not in ("on", "off", "1", "0", "yes", "no", "true", "false"):
    raise ValueError(f"TRIBOJAX_XLA_HOIST = {_hoist!r}: allowed 'on' (the default) or 'off'")
if _hoist in ("on", "1", "yes", "true") and not _backend_started() \
        and "xla_backend_extra_options" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {_HOIST_FLAG}".strip()

if TYPE_CHECKING:
    from ._chain import mu_min as chain_mu_min  # noqa: F401
    from ._chain import to_physical as chain_physical  # noqa: F401
    from ._chain import to_theta as chain_theta  # noqa: F401
    from ._contact._asperity import REGIME_NAMES as REGIME_NAMES
    from ._contact._asperity import asperity_load as asperity_load
    from ._contact._asperity import asperity_regime as asperity_regime
    from ._contact._asperity import critical_areas as critical_areas
    from ._contact._contact import ContactParameters as ContactParameters
    from ._contact._contact import FractalContact as FractalContact
    from ._contact._contact import contact_parameters as contact_parameters
    from ._contact._materials import ContactPair as ContactPair
    from ._contact._materials import Material as Material
    from ._contact._presets import vacuum_to_load as vacuum_to_load
    from ._contact._presets import wang2022_chuck as wang2022_chuck
    from ._contact._presets import wang2022_pair as wang2022_pair
    from ._contact._presets import wang2022_reticle as wang2022_reticle
    from ._contact._presets import wang2022_surface as wang2022_surface
    from ._contact._presets import wang2022_table3_model as wang2022_table3_model
    from ._contact._presets import wu2015_eq5_stiffness as wu2015_eq5_stiffness
    from ._contact._surface import FractalSurface as FractalSurface
    from ._decimate import Decimation as Decimation
    from ._decimate import decimate_record as decimate_record
    from ._dynamics._adjoint import ForwardJacobianAdjoint as ForwardJacobianAdjoint
    from ._dynamics._continuation import FrequencyResponse as FrequencyResponse
    from ._dynamics._continuation import frequency_response as frequency_response
    from ._dynamics._continuation import parameter_response as parameter_response
    from ._dynamics._design import Peak as Peak
    from ._dynamics._design import PeakDesign as PeakDesign
    from ._dynamics._design import amplitude_at as amplitude_at
    from ._dynamics._design import frf_2dof_system as frf_2dof_system
    from ._dynamics._design import minimise_peak as minimise_peak
    from ._dynamics._design import peak_on_grid as peak_on_grid
    from ._dynamics._design import resonance_peak as resonance_peak
    from ._dynamics._harmonic import HarmonicCoefficients as HarmonicCoefficients
    from ._dynamics._harmonic import drive as drive
    from ._dynamics._harmonic import harmonic_balance as harmonic_balance
    from ._dynamics._harmonic import harmonic_response as harmonic_response
    from ._dynamics._mhb import FrictionSystem as FrictionSystem
    from ._dynamics._mhb import HBMSolution as HBMSolution
    from ._dynamics._mhb import floquet_exponents as floquet_exponents
    from ._dynamics._mhb import solve_hbm as solve_hbm
    from ._dynamics._profiles import AbstractProfile as AbstractProfile
    from ._dynamics._profiles import DisplacementHistory as DisplacementHistory
    from ._dynamics._profiles import MeasuredProfile as MeasuredProfile
    from ._dynamics._profiles import PiecewiseLinearProfile as PiecewiseLinearProfile
    from ._dynamics._profiles import TrapezoidProfile as TrapezoidProfile
    from ._dynamics._rodas4 import Rodas4 as Rodas4
    from ._dynamics._slip import SlipSolution as SlipSolution
    from ._dynamics._slip import simulate_slip as simulate_slip
    from ._dynamics._slip import slip_phase_averages as slip_phase_averages
    from ._dynamics._structure import AbstractContact as AbstractContact
    from ._dynamics._structure import DryFrictionContact2D as DryFrictionContact2D
    from ._dynamics._structure import Excitation as Excitation
    from ._dynamics._structure import FrictionContact as FrictionContact
    from ._dynamics._structure import Structure as Structure
    from ._dynamics._transient import integrate_steady as integrate_steady
    from ._fit._curve import fit_steady_curve as fit_steady_curve
    from ._fit._curve import fit_transient as fit_transient
    from ._fit._curve import transient_nrmse as transient_nrmse
    from ._fit._engine import FitError as FitError
    from ._fit._engine import FitResult as FitResult
    from ._fit._engine import least_squares_fit as least_squares_fit
    from ._fit._history import BOUC_WEN_STARTS as BOUC_WEN_STARTS
    from ._fit._history import HistoryFit as HistoryFit
    from ._fit._history import fit_history as fit_history
    from ._fit._history import predict_history as predict_history
    from ._fit._surface import fit_surface_from_runs as fit_surface_from_runs
    from ._friction._band_brake import BandBrake as BandBrake
    from ._friction._bouc_wen import BoucWen as BoucWen
    from ._friction._elastic2d import ElasticDryFriction2D as ElasticDryFriction2D
    from ._friction._element import AbstractFrictionElement as AbstractFrictionElement
    from ._friction._lugre import LuGre as LuGre
    from ._friction._lugre import PreSlipLuGre as PreSlipLuGre
    from ._friction._rate_independent import AbstractHysteresisElement as AbstractHysteresisElement
    from ._friction._rate_independent import IwanBank as IwanBank
    from ._friction._rate_independent import Jenkins as Jenkins
    from ._friction._rate_independent import Mindlin as Mindlin
    from ._io._brfd import brfd_band_tension as brfd_band_tension
    from ._io._brfd import brfd_test as brfd_test
    from ._io._brfd import read_brfd as read_brfd
    from ._io._curve import FrictionCurve as FrictionCurve
    from ._io._curve import FrictionTransient as FrictionTransient
    from ._io._curve import effective_samples as effective_samples
    from ._io._curve import read_epos_steady as read_epos_steady
    from ._io._curve import read_epos_transient as read_epos_transient
    from ._io._curve import read_friction_curve as read_friction_curve
    from ._io._curve import write_friction_curve as write_friction_curve
    from ._io._curve import write_friction_transient as write_friction_transient
    from ._io._files import write_json_atomic as write_json_atomic
    from ._io._loop import HysteresisLoop as HysteresisLoop
    from ._io._loop import read_loop as read_loop
    from ._io._loop import synthetic_loop as synthetic_loop
    from ._io._loop import write_loop as write_loop
    from ._io._record import AbstractRecord as AbstractRecord
    from ._io._records import detect_format as detect_format
    from ._io._records import read_record as read_record
    from ._io._slip_run import SlipRun as SlipRun
    from ._io._slip_run import read_slip_run as read_slip_run
    from ._io._slip_run import simulate_run as simulate_run
    from ._io._slip_run import synthetic_slip_run as synthetic_slip_run
    from ._io._slip_run import write_slip_run as write_slip_run
    from ._limits import DISCOVER_MAX_SAMPLES as DISCOVER_MAX_SAMPLES
    from ._model import FittedModel as FittedModel
    from ._model import LoopAnalysis as LoopAnalysis
    from ._model import SavedEffect as SavedEffect
    from ._model import analyse_loop as analyse_loop
    from ._model import fit_loop as fit_loop
    from ._model import fit_slip_run as fit_slip_run
    from ._model import loop_residuals as loop_residuals
    from ._model import slip_run_start as slip_run_start
    from ._predict import Prediction as Prediction
    from ._predict import fitted_model as fitted_model
    from ._predict import load_model as load_model
    from ._predict import predict as predict
    from ._predict import refit as refit
    from ._presets import CHAIN_DEFAULTS as CHAIN_DEFAULTS
    from ._presets import FRF_2DOF as FRF_2DOF
    from ._presets import WANG2022_A_MAX as WANG2022_A_MAX
    from ._presets import WANG2022_CALIBRATED as WANG2022_CALIBRATED
    from ._presets import WANG2022_RETICLE_MASS_KG as WANG2022_RETICLE_MASS_KG
    from ._presets import WANG2022_TANGENTIAL_LOAD_N as WANG2022_TANGENTIAL_LOAD_N
    from ._reproduce._chain_fit import DEFAULT_FREE as CHAIN_DEFAULT_FREE  # noqa: F401
    from ._reproduce._chain_fit import PARAMETERS as CHAIN_PARAMETERS  # noqa: F401
    from ._reproduce._chain_fit import ChainFit as ChainFit
    from ._reproduce._chain_fit import ChainFitError as ChainFitError
    from ._reproduce._chain_fit import chain_phase_slips as chain_phase_slips
    from ._reproduce._chain_fit import fit_measured_slips as fit_measured_slips
    from ._reproduce._chain_fit import measured_slips as wang2022_measured_slips  # noqa: F401
    from ._reproduce._chain_fit import paper_theory_slips as wang2022_theory_slips  # noqa: F401
    from ._reproduce._chain_fit import rms_relative as rms_relative
    from ._reproduce._chain_fit import symmetric_bound as symmetric_bound
    from ._reproduce._chain_fit import wang2022_loads as wang2022_loads
    from ._reproduce._fit_figure import plot_fit_measured as plot_fit_measured
    from ._reproduce._profile_likelihood import profile_likelihood as chain_profile_likelihood  # noqa: F401
    from ._reproduce._robust_fit import NOISE_MODELS as CHAIN_NOISE_MODELS  # noqa: F401
    from ._reproduce._robust_fit import RobustChainFit as RobustChainFit
    from ._reproduce._robust_fit import robust_fit_measured_slips as robust_fit_measured_slips
    from ._reproduce._table3 import calibrate_table3 as calibrate_table3
    from ._reproduce._table3 import equivalent_G as equivalent_G
    from ._reproduce._table3 import reproduce_table3 as reproduce_table3
    from ._reproduce._wu2015 import cbar_peak as cbar_peak
    from ._reproduce._wu2015 import dimensionless_curves as dimensionless_curves
    from ._reproduce._wu2015 import eq7_curves as eq7_curves
    from ._reproduce._wu2015 import fractal_tangential_stiffness as fractal_tangential_stiffness
    from ._reproduce._wu2015 import plot_wu2015 as plot_wu2015
    from ._reproduce._wu2015 import wu2015_comparison as wu2015_comparison
    from ._reproduce._wu2015 import wu2015_eq7 as wu2015_eq7
    from ._results import RESULTS as RESULTS
    from ._roughness._estimate import RoughnessEstimate as RoughnessEstimate
    from ._roughness._estimate import estimate_fractal as estimate_fractal
    from ._roughness._estimate import psd_model as psd_model
    from ._roughness._estimate import structure_function_model as structure_function_model
    from ._roughness._synthesis import direction_factor as direction_factor
    from ._roughness._synthesis import synthesize as synthesize
    from ._roughness._synthesis import wm_profile as wm_profile
    from ._roughness._synthesis import yk_heights as yk_heights
    from ._roughness._topography import Topography as Topography
    from ._roughness._topography import read_topography as read_topography
    from ._sensitivity import Elasticities as Elasticities
    from ._sensitivity import LoopChain as LoopChain
    from ._sensitivity import ReticleChain as ReticleChain
    from ._sensitivity import elasticities as elasticities
    from ._sensitivity import hysteresis_sensitivities as hysteresis_sensitivities
    from ._sensitivity import slip_sensitivities as slip_sensitivities
    from ._sweep import product_grid as product_grid
    from ._sweep import sweep as sweep
    from ._tables import DataFileError as DataFileError
    from ._tables import DataFileWarning as DataFileWarning
    from ._tables import read_table as read_table
    from ._tables import wang2022_table as wang2022_table
    from ._tables import wu2015_table as wu2015_table


def _exports() -> dict[str, tuple[str, str]]:
    """public name -> (home module, name there): the imports of the TYPE_CHECKING block."""
    out = {}
    for node in ast.parse(Path(__file__).read_text(encoding="utf-8")).body:
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            for imp in node.body:
                for alias in imp.names:
                    out[alias.asname or alias.name] = (imp.module, alias.name)
    return out


_EXPORTS = _exports()
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
    importlib.import_module(f"{__name__}._precision")  # the compilation cache before any use
    value = getattr(importlib.import_module(f"{__name__}.{module}"), attr)
    globals()[name] = value  # later lookups skip __getattr__
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


try:
    __version__ = version("tribojax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"
