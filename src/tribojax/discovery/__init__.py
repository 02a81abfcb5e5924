"""Discovery: find where a model and its data disagree, name the missing effect, add it.

The workflow is `discover`'s docstring (and docs/discovery.md); `DiscoveryReport.as_dict()` is
discovery.json.

How to plug in (the contract; a loop or user module needs nothing else)
-----------------------------------------------------------------------
A **baseline** is a concrete `AbstractBaseline` (an equinox Module holding the record's arrays):

    class MyBaseline(AbstractBaseline):
        kind = "loop"                                   # ClassVar: effects of this kind apply
        param_names = ("mu_N", "K_d"); param_units = ("N", "N/m")
        knob_names = ("microslip", "load_slope")        # physics knobs effects may move
        ...fields: the record's arrays (jnp), e.g. u, f, t ...
        def knob_null(self): return np.array([0.0, 0.0])   # knobs under which effects vanish
        def start(self): return np.log([...])           # unconstrained θ0 (np array)
        def physical(self, theta): return jnp.exp(theta)  # θ → physical values (JAX)
        def predict(self, theta, knobs): ...            # (n,) model samples (JAX, jacfwd-able)
        def data(self): return RecordData(y=f, x=u, segment=branch, noise_std=None or sd,
                                             x_label="u (m)", y_label="force (N)",
                                             segment_names={0: "falling", 1: "rising"})

`predict` must be jit/jacfwd-able in (theta, knobs); the record arrays are fields, so one compiled
fit serves all records of the same shape. Knobs are always present (their null values give the
baseline), so every augmented model whose effects move a knob shares one compiled function; the
model alone and its additive effects share a second (`value_and_jacobian`, the null physics
differentiated over θ only: a smaller program, e.g. the slip model without its knob states).

An **effect** is a concrete `AbstractEffect` with ClassVars `name`, `kind` and a method
`designs(baseline) -> list[EffectDesign]`, one design per point of its nuisance grid. A design is
the affine form the engine fits, with signed strengths s (null s = 0, an interior point, so the
score test is valid):

    y = baseline.predict(θ, knobs) + basis @ s,   knobs = knob_null ⊕ knob_set + knob_gain @ s

- a physics effect sets `knob_gain` (n_knobs × k) and possibly `knob_set` (nuisance knobs);
- an additive (measurement) effect sets `basis` (n × k, output units per unit s);
- `strength_names`, `strength_units`, `strength_scale` (physical value per unit s; pick the unit
  so that s is O(1)), `nuisance` (reported), `n_nuisance` (counted in ΔBIC).
An effect may also override `refine(baseline, design, score) -> EffectDesign` to polish its
nuisance values around the best grid point (`score(design)` is the Rao statistic at the current
fit; `vibration` refines its frequency and damping this way).
Add it to `default_effects(kind)` with `@register_effect` (the built-in effects are a fixed
table, `tribojax._model._default_effects`), or pass it explicitly:
`discover(baseline, effects=[*default_effects("slip"), MyEffect()])`. At most `K_MAX` = 12
strengths in one model.

Fitting: `tribojax.least_squares_fit` (optimistix Levenberg–Marquardt) on one residual function
whose effect strengths are padded to `K_MAX` (inactive ones masked and held at 0), so one compiled
solve serves every combination of effects on a record shape; its Jacobian comes from one
forward-mode pass of `predict` over θ and the knobs. `predict` must not raise inside that solve:
a trial point where it is not finite is rejected as a rise of the cost.

Slip side (`slip_baseline`, effects `sensor_drift`, `position_error`, `vibration`,
`load_coupling`, `stribeck`, `viscous_friction`): see `tribojax._model._slip` and
`tribojax._model._effects_slip`.

Loop side (`loop_baseline`: Jenkins, wu2015 Eq 1, driven by the measured displacement; effects
`microslip`, `viscous_damping`, `normal_load_variation`, `backlash`, `force_offset`;
`discover_loop`, `plot_loop_discovery`; hidden-effect loops `hidden_effect_loop` and wu2015 Eq 7
stand-ins `eq7_standin_loop`): see `tribojax._model._effects_loop`. Optional baseline hooks:
`AbstractBaseline.noise_model`, `region_info`.

Curve side (`curve_baseline`: Coulomb + linear viscous friction of a steady `FrictionCurve`, both
directions, each point weighted by its standard error; effects `stribeck` (LuGre steady law),
`asymmetry` (a direction-dependent level) and `viscous` (a power-law viscous term);
`discover_curve`, `plot_curve_discovery`): see `tribojax._model._effects_curve`.
"""

from .._fit._noise import find_regions as find_regions
from .._fit._noise import noise_estimate as noise_estimate
from .._model import ALPHA as ALPHA
from .._model import GAP_GRID as GAP_GRID
from .._model import K_MAX as K_MAX
from .._model import AbstractBaseline as AbstractBaseline
from .._model import AbstractEffect as AbstractEffect
from .._model import AugmentedPreSlip as AugmentedPreSlip
from .._model import CurveBaseline as CurveBaseline
from .._model import EffectDesign as EffectDesign
from .._model import LoopBaseline as LoopBaseline
from .._model import RecordData as DiscoveryData  # noqa: F401  (its earlier name, the same class)
from .._model import RecordData as RecordData
from .._model import SlipBaseline as SlipBaseline
from .._model import curve_baseline as curve_baseline
from .._model import default_effects as default_effects
from .._model import loop_baseline as loop_baseline
from .._model import register_effect as register_effect
from .._model import slip_baseline as slip_baseline
from .._model import slip_start as slip_start
from .._model import stage_travel as stage_travel
from ._discover import DELTA_BIC_THRESHOLD as DELTA_BIC_THRESHOLD
from ._discover import DiscoveryReport as DiscoveryReport
from ._discover import discover as discover
from ._discover_campaign import CAMPAIGN_EFFECTS as CAMPAIGN_EFFECTS
from ._discover_campaign import CampaignDiscovery as CampaignDiscovery
from ._discover_campaign import discover_campaigns as discover_campaigns
from ._discover_curve import discover_curve as discover_curve
from ._discover_curve import plot_curve_discovery as plot_curve_discovery
from ._discover_loop import discover_loop as discover_loop
from ._discover_loop import plot_loop_discovery as plot_loop_discovery
from ._discover_tension import TensionDiscovery as TensionDiscovery
from ._discover_tension import discover_tension as discover_tension
from ._loop_synthetic import eq7_standin_loop as eq7_standin_loop
from ._loop_synthetic import eq7_standin_shape as eq7_standin_shape
from ._loop_synthetic import hidden_effect_loop as hidden_effect_loop
from ._plot import plot_correction as plot_correction
from ._plot import plot_discovery as plot_discovery
from ._tables import wang2022_table_baseline as wang2022_table_baseline
from ._tables import wang2022_table_effects as wang2022_table_effects
