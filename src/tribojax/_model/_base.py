"""One model per record kind: the contract of a record model and of the effects it can carry.

A record model (`AbstractBaseline`) is an equinox Module holding one record's arrays; its
parameters θ are unconstrained, its physics knobs are the switches the effects move (null values:
the baseline physics). `fit` fits it alone, `discover` adds effects (`EffectDesign`), `predict`
evaluates it: the same model, residual, transforms, starts and solver (`fit_model`).
"""

from __future__ import annotations

import abc
import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import numpy as np

from .._fit._noise import ALPHA, noise_consistent, noise_estimate

N_WINDOWS = 32  # windows of the noise test
N_FOLD_BLOCKS = 16  # contiguous blocks of the default two-fold split, alternately assigned
K_MAX = 12
"""Most effect strengths in one model; fits are padded to this size so that one compiled solve
serves every combination of effects on a record shape."""


@dataclasses.dataclass(frozen=True)
class RecordData:
    """What a baseline compares with: observed samples and where they sit.

    y: observed samples (output units, e.g. m of slip or N of force), shape (n,).
    x: abscissa of each sample for regions and plots (e.g. time in s, displacement in m).
    segment: integer label per sample; windows never straddle a change of label (0 for one
        record; loop branches 0/1, ...). Sample order is the order of the record.
    noise_std: noise sd of y in output units from the sidecar, or None (estimated then).
    x_label, y_label: axis labels with units.
    segment_names: optional names of the labels (e.g. {0: "falling", 1: "rising"}).

    Every fit of a record model and `discover` read it (`AbstractBaseline.data`); earlier name
    `DiscoveryData` (`tribojax.discovery.DiscoveryData`, the same class).
    """

    y: np.ndarray
    x: np.ndarray
    segment: np.ndarray
    noise_std: float | None
    x_label: str
    y_label: str
    segment_names: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class EffectDesign:
    """One effect at one nuisance setting, in the affine form the engine fits.

    With strengths s (k,), the augmented model is
        y = baseline.predict(θ_b, knobs) + basis @ s,   knobs = knob_null ⊕ knob_set + knob_gain @ s
    so s = 0 is the null (an interior point: strengths are signed). An effect returns one design
    per point of its grid of nonlinear nuisance parameters (frequencies, velocity scales); the
    grid point only seeds them when the design makes them free: a strength that shifts a knob
    (e.g. log v_s), fitted jointly with the others in the refit (`free`).

    strength_names / strength_units: names and units of the physical strengths.
    strength_scale: physical strength per unit of s (k,), for reporting (s is O(1) in fits).
    knob_gain: (n_knobs, k) or None — how s moves the baseline's physics knobs.
    knob_set: {knob name: value} — nuisance knobs fixed while the effect is active.
    basis: (n, k) additive columns in output units per unit s, or None.
    nuisance: {name: value} reported with the result; n_nuisance counts the fixed ones in ΔBIC.
    free: ((strength index, nuisance name, physical strength → nuisance value), ...): strengths
        that are nuisance shifts (counted in k, reported under "nuisance", not as strengths).
    columns: (n, k) ∂y/∂s at s = 0 whatever the fit (additive effects whose knobs move a term
        outside the physics: the score test then needs no model solve), or None.
    starts: further strength vectors (k,) from which the refit starts (with the baseline at its
        current fit) while the Gauss–Newton and zero starts leave a misfit: seeds of an optimum
        far from the null along a valley that the local score cannot see.
    """

    strength_names: tuple[str, ...]
    strength_units: tuple[str, ...]
    strength_scale: np.ndarray
    knob_gain: np.ndarray | None = None
    knob_set: dict = dataclasses.field(default_factory=dict)
    basis: np.ndarray | None = None
    nuisance: dict = dataclasses.field(default_factory=dict)
    n_nuisance: int = 0
    free: tuple = ()
    columns: np.ndarray | None = None
    starts: tuple = ()

    @property
    def k(self) -> int:
        return len(self.strength_names)


class AbstractBaseline(eqx.Module):
    """A baseline model of one record, with physics knobs that effects may move.

    Concrete baselines are equinox Modules holding the record's arrays (so one compiled fit
    serves every record of the same shape). θ is unconstrained (e.g. log of positive values).
    """

    kind: eqx.AbstractClassVar[str]  # "slip" or "loop"
    knob_names: eqx.AbstractClassVar[tuple[str, ...]]
    # False where the noise of the record cannot be told from its residual (a few summary
    # values, no sidecar): the baseline is then never declared consistent with the noise
    noise_gate: ClassVar[bool] = True

    @property
    @abc.abstractmethod
    def param_names(self) -> tuple[str, ...]:
        """Names of the physical parameters `physical(θ)` (a ClassVar or a property)."""

    @property
    @abc.abstractmethod
    def param_units(self) -> tuple[str, ...]:
        """Their units."""

    @abc.abstractmethod
    def knob_null(self) -> np.ndarray:
        """Knob values under which every effect vanishes (the baseline physics)."""

    def for_knobs(self, moved: tuple[bool, ...]) -> AbstractBaseline:
        """This model for a fit or an evaluation in which only the knobs flagged in `moved` (one
        bool per knob) may leave their null: a baseline may drop the physics that the others
        carry (the same values from a smaller program). Default: itself."""
        return self

    @abc.abstractmethod
    def start(self) -> np.ndarray:
        """Start θ for the baseline fit (unconstrained)."""

    def starts(self) -> list:
        """Start points of the baseline fit; the lowest converged cost is kept. Default
        `[self.start()]`."""
        return [self.start()]

    def restart(self, designs) -> np.ndarray | None:
        """A start θ (baseline, then the strengths of every design in `designs`) made afresh
        from the record with the designs in the model, for a refit whose starts from the current
        fit all stalled; None (the default) when the model has no such rule."""
        return None

    @abc.abstractmethod
    def physical(self, theta):
        """θ → physical parameters (JAX, differentiable)."""

    def theta_of(self, values) -> np.ndarray:
        """θ of physical parameter values (the order of `param_names`): the inverse of
        `physical`, used to evaluate a saved model on a record (`tribojax.predict`). A baseline
        that is to be saved and predicted with defines it."""
        raise NotImplementedError(
            f"{type(self).__name__} does not define theta_of: it cannot "
            "be rebuilt from saved parameters"
        )

    def param_ranges(self) -> tuple:
        """The open interval (lo, hi) of each physical parameter (the order of `param_names`):
        the domain of `physical`, e.g. (0, inf) for one it takes the log of. A saved model with a
        value outside is refused by name (`tribojax.load_model`, `tribojax.predict`). Default:
        every real number."""
        return ((-np.inf, np.inf),) * len(self.param_names)

    def options(self) -> dict:
        """How the model is built on a record beyond the record itself (saved with a fitted
        model, `tribojax.FittedModel.options`), e.g. a held bristle exponent; default none."""
        return {}

    @abc.abstractmethod
    def predict(self, theta, knobs):
        """Model samples (output units), shape (n,), at θ and knob vector `knobs` (JAX).

        Runs inside the compiled fit, forward-differentiated: it must not raise at a trial point
        (use `throw=False` in ODE solves) and must return non-finite samples where its solver
        failed (diffrax fills the times it did not reach with inf); non-finite samples reject
        that trial step, and at the optimum fail the fit (`model_failed`)."""

    @abc.abstractmethod
    def data(self) -> RecordData:
        """The observed record."""

    def value_and_jacobians(self, theta, knobs):
        """`predict` and its forward-mode Jacobians ∂/∂θ (n, p), ∂/∂knobs (n, n_knobs), in one
        pass (JAX); a baseline may split it (knobs that do not enter an ODE)."""

        def f(tb, kn):
            out = self.predict(tb, kn)
            return out, out

        (jb, jk), value = jax.jacfwd(f, argnums=(0, 1), has_aux=True)(theta, knobs)
        return value, jb, jk

    def value_and_jacobian(self, theta, null):
        """The model alone and ∂/∂θ (n, p) (JAX): the pass of a fit whose effects move no knob;
        `null` is `knob_null()` as an array (passed in: inside a fit the fields are traced).
        Default from `value_and_jacobians`; a baseline whose null physics is a smaller program
        (the paper's element without the knob states) overrides it and `predict_null`."""
        value, jb, _ = self.value_and_jacobians(theta, null)
        return value, jb

    def predict_null(self, theta, null):
        """`predict` with every knob at its null, `null` = `knob_null()` (JAX)."""
        return self.predict(theta, null)

    def noise_model(self, r) -> tuple[float, float]:
        """(σ̂, AR(1) ρ̂) of the noise in the baseline residual `r` (output units). Default:
        `noise_estimate` (first differences within segments); a baseline may override it with a
        record-specific estimator (e.g. differences between loop cycles)."""
        return noise_estimate(r, self.data().segment)

    def noise_test(self, r, n_params, *, alpha=ALPHA, n_windows=N_WINDOWS):
        """(consistent, p_value, sigma, rho): is the residual `r` (output units) of a fit with
        `n_params` parameters the record's noise? σ from the record (sidecar) or, when it has
        none, `noise_model(r)`; ρ from `noise_model(r)`; the test is `noise_consistent` (χ² of
        the whole record, windows, Fisher's g). This is the one verdict of `fit`
        (`FitResult.noise_consistent`, None where `noise_gate` is False) and of `discover`'s
        baseline."""
        d = self.data()
        sd, rho = self.noise_model(np.asarray(r, dtype=float))
        estimated = not d.noise_std
        sigma = sd if estimated else float(d.noise_std)
        ok, p, _ = noise_consistent(
            r,
            sigma,
            rho,
            d.segment,
            d.x,
            n_params,
            alpha=alpha,
            n_windows=n_windows,
            estimated=estimated,
        )
        return bool(ok), p, sigma, rho

    def folds(self) -> np.ndarray:
        """Two-fold split of the samples for held-out checks (0/1 per sample): each fold is
        fitted alone and scored on the other. Default: the record cut into `N_FOLD_BLOCKS`
        blocks of equal sample count, alternately labelled, so that both folds see every part
        of the drive (a slip run's rest, ramps and cruise). None: the model has no held-out
        check (discovery then judges on the whole record alone)."""
        n = self.data().y.shape[0]
        return (np.arange(n) * N_FOLD_BLOCKS // max(n, 1)) % 2

    def region_info(self, region: dict) -> dict:
        """Extra keys for a flagged region (e.g. a loop's branch and displacement range);
        default none."""
        return {}

    def unidentified(self, values: dict, std_errors: dict) -> dict:
        """Parameters the record does not determine, {name: {"lower_bound", "upper_bound",
        "unit"}}, from the fitted values and standard errors; default none."""
        return {}

    def more_steps(self, factor: int = 1):
        """This model with a larger step budget for its solver (a stalled fit's restart and, with
        `factor` times as many, a held-out check where a solve ran out use it); None when it has
        none (the default)."""
        return None

    def at_bound(self, theta) -> bool:
        """Whether θ sits at a bound of the model's parameters (a fit stopped there is held by
        the bound, not at a minimum of the cost); default never."""
        return False

    def signals(self) -> dict:
        """Measured signals (name → (n,) array) a remaining misfit is correlated with; default
        the abscissa."""
        d = self.data()
        return {d.x_label: np.asarray(d.x, dtype=float)}
