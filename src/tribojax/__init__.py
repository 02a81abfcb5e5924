"""tribojax: rough-surface contact, friction and slip models in JAX.

Importing tribojax switches JAX to float64 (`jax_enable_x64`); see `tribojax._precision`.
"""

from importlib.metadata import PackageNotFoundError, version

from . import _precision as _precision  # noqa: F401  (float64 switch; must come first)
from ._asperity import (
    REGIME_NAMES as REGIME_NAMES,
)
from ._asperity import (
    asperity_load as asperity_load,
)
from ._asperity import (
    asperity_regime as asperity_regime,
)
from ._asperity import (
    critical_areas as critical_areas,
)
from ._contact import (
    ContactParameters as ContactParameters,
)
from ._contact import (
    FractalContact as FractalContact,
)
from ._contact import (
    contact_parameters as contact_parameters,
)
from ._data import DataFileError as DataFileError
from ._data import read_table as read_table
from ._data import wang2022_table as wang2022_table
from ._data import wu2015_table as wu2015_table
from ._fit import FitResult as FitResult
from ._fit import least_squares_fit as least_squares_fit
from ._fit_chain import ChainFit as ChainFit
from ._fit_chain import chain_phase_slips as chain_phase_slips
from ._fit_chain import fit_measured_slips as fit_measured_slips
from ._fit_user import fit_slip_run as fit_slip_run
from ._fit_user import fit_surface_from_runs as fit_surface_from_runs
from ._fit_user import slip_run_start as slip_run_start
from ._friction import AbstractFrictionElement as AbstractFrictionElement
from ._hysteresis import HarmonicCoefficients as HarmonicCoefficients
from ._hysteresis import drive as drive
from ._hysteresis import harmonic_balance as harmonic_balance
from ._hysteresis import harmonic_response as harmonic_response
from ._hysteresis_elements import AbstractHysteresisElement as AbstractHysteresisElement
from ._hysteresis_elements import Jenkins as Jenkins
from ._hysteresis_elements import Mindlin as Mindlin
from ._loops import HysteresisLoop as HysteresisLoop
from ._loops import LoopAnalysis as LoopAnalysis
from ._loops import analyse_loop as analyse_loop
from ._loops import fit_loop as fit_loop
from ._loops import read_loop as read_loop
from ._loops import synthetic_loop as synthetic_loop
from ._loops import write_loop as write_loop
from ._lugre import LuGre as LuGre
from ._lugre import PreSlipLuGre as PreSlipLuGre
from ._materials import (
    ContactPair as ContactPair,
)
from ._materials import (
    Material as Material,
)
from ._materials import (
    vacuum_to_load as vacuum_to_load,
)
from ._materials import (
    wang2022_chuck as wang2022_chuck,
)
from ._materials import (
    wang2022_pair as wang2022_pair,
)
from ._materials import (
    wang2022_reticle as wang2022_reticle,
)
from ._profiles import AbstractProfile as AbstractProfile
from ._profiles import MeasuredProfile as MeasuredProfile
from ._profiles import PiecewiseLinearProfile as PiecewiseLinearProfile
from ._profiles import TrapezoidProfile as TrapezoidProfile
from ._records import SlipRun as SlipRun
from ._records import read_record as read_record
from ._records import read_slip_run as read_slip_run
from ._records import simulate_run as simulate_run
from ._records import synthetic_slip_run as synthetic_slip_run
from ._records import write_slip_run as write_slip_run
from ._reproduce import calibrate_table3 as calibrate_table3
from ._reproduce import equivalent_G as equivalent_G
from ._reproduce import reproduce_table3 as reproduce_table3
from ._reproduce import wang2022_table3_model as wang2022_table3_model
from ._rosenbrock import Rodas4 as Rodas4
from ._roughness import RoughnessEstimate as RoughnessEstimate
from ._roughness import estimate_fractal as estimate_fractal
from ._roughness import psd_model as psd_model
from ._roughness import structure_function_model as structure_function_model
from ._sensitivity import Elasticities as Elasticities
from ._sensitivity import LoopChain as LoopChain
from ._sensitivity import ReticleChain as ReticleChain
from ._sensitivity import elasticities as elasticities
from ._sensitivity import hysteresis_sensitivities as hysteresis_sensitivities
from ._sensitivity import slip_sensitivities as slip_sensitivities
from ._slip import SlipSolution as SlipSolution
from ._slip import simulate_slip as simulate_slip
from ._slip import slip_phase_averages as slip_phase_averages
from ._surface import FractalSurface as FractalSurface
from ._surface import wang2022_surface as wang2022_surface
from ._sweep import product_grid as product_grid
from ._sweep import sweep as sweep
from ._synthesis import direction_factor as direction_factor
from ._synthesis import synthesize as synthesize
from ._synthesis import wm_profile as wm_profile
from ._synthesis import yk_heights as yk_heights
from ._topography import Topography as Topography
from ._topography import read_topography as read_topography
from ._wu2015 import cbar_peak as cbar_peak
from ._wu2015 import dimensionless_curves as dimensionless_curves
from ._wu2015 import eq7_curves as eq7_curves
from ._wu2015 import fractal_tangential_stiffness as fractal_tangential_stiffness
from ._wu2015 import plot_wu2015 as plot_wu2015
from ._wu2015 import wu2015_comparison as wu2015_comparison
from ._wu2015 import wu2015_eq5_stiffness as wu2015_eq5_stiffness
from ._wu2015 import wu2015_eq7 as wu2015_eq7

try:
    __version__ = version("tribojax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"
