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
from ._fit import FitResult as FitResult
from ._fit import least_squares_fit as least_squares_fit
from ._friction import AbstractFrictionElement as AbstractFrictionElement
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
from ._reproduce import calibrate_table3 as calibrate_table3
from ._reproduce import equivalent_G as equivalent_G
from ._reproduce import reproduce_table3 as reproduce_table3
from ._reproduce import wang2022_table3_model as wang2022_table3_model
from ._slip import SlipSolution as SlipSolution
from ._slip import simulate_slip as simulate_slip
from ._slip import slip_phase_averages as slip_phase_averages
from ._surface import FractalSurface as FractalSurface
from ._surface import wang2022_surface as wang2022_surface

try:
    __version__ = version("tribojax")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0"
