"""Stage acceleration profiles a(t) that drive the reticle slip model.

A profile gives the stage acceleration (m/s²) at time t (s) and the times where a(t) is not
smooth; the slip simulation stops its steps there (diffrax `jump_ts`), since an implicit solver
loses its order across a kink. All three profiles are piecewise linear between nodes and constant
outside them (a(t) = first / last node value).
"""

from __future__ import annotations

import abc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike

from .._checks import as_f64, check_range, fail_if
from .._tables import read_table


class AbstractProfile(eqx.Module):
    """A prescribed stage acceleration a(t) (m/s²)."""

    @abc.abstractmethod
    def acceleration(self, t: ArrayLike) -> Array:
        """Stage acceleration at time `t` (s), m/s²."""

    @abc.abstractmethod
    def kinks(self) -> Array | None:
        """Times (s) where a(t) or its slope jumps (for diffrax `jump_ts`), or None."""


def _validated_nodes(times, values, what: str, quantity: str = "accelerations"):
    times = as_f64(times, f"{what} times")
    values = as_f64(values, f"{what} {quantity}")
    if times.ndim != 1 or values.shape != times.shape or times.shape[0] < 2:
        raise ValueError(
            f"{what}: times and {quantity} must be 1-D of equal length >= 2, got shapes "
            f"{times.shape} and {values.shape}"
        )
    xp = jnp if isinstance(times, jax.core.Tracer) or isinstance(values, jax.core.Tracer) else np
    # (NumPy on concrete nodes: no JAX program compiled and dispatched per eager check)
    times = fail_if(times, ~xp.all(xp.isfinite(times)), f"{what}: a time is NaN or infinite")
    values = fail_if(
        values, ~xp.all(xp.isfinite(values)), f"{what}: an entry of {quantity} is NaN or infinite"
    )
    bad = ~xp.all(xp.diff(times) > 0)
    times = fail_if(times, bad, f"{what}: times must be strictly increasing")
    return times, values


class PiecewiseLinearProfile(AbstractProfile):
    """Any piecewise-linear acceleration through the nodes (times in s, accelerations in m/s²)."""

    times: Array  # s, strictly increasing
    accelerations: Array  # m/s², finite

    def __init__(self, times, accelerations):
        self.times, self.accelerations = _validated_nodes(times, accelerations, "profile")

    def acceleration(self, t):
        return jnp.interp(t, self.times, self.accelerations)

    def kinks(self):
        return self.times


class MeasuredProfile(AbstractProfile):
    """An acceleration interpolated linearly from a measured column (e.g. an accelerometer log).

    Validated on construction: times strictly increasing, no NaN/inf. `stops` (s) are the times
    where the solver stops a step (diffrax `jump_ts`); None leaves every kink to the step
    controller (measured data kink at every sample). `stop_at_samples=True` stops at every
    sample (short, coarse logs). `from_samples` chooses the stops of a record's drive.
    """

    times: Array  # s, strictly increasing
    accelerations: Array  # m/s²
    stops: Array | None  # s, or None
    stop_at_samples: bool = eqx.field(static=True, default=False)

    def __init__(self, times, accelerations, *, stop_at_samples: bool = False, stops=None):
        self.times, self.accelerations = _validated_nodes(times, accelerations, "measured profile")
        self.stop_at_samples = bool(stop_at_samples)
        if stop_at_samples:
            stops = self.times
        self.stops = None if stops is None else as_f64(stops, "measured profile stops")

    @classmethod
    def from_samples(cls, times, accelerations, *, max_stops: int = 64):
        """The drive of a sampled record: linear between all samples, stopped at its kinks.

        The solver stops at the ends and the samples where the slope changes by more than 1e-9
        of max|a|/duration (a sampled trapezoid: its 8 corners) when there are at most
        `max_stops` of them; otherwise (noisy measured data, a kink at every sample) it stops
        nowhere and the step controller handles the kinks.
        """
        t = np.asarray(times, np.float64)
        a = np.asarray(accelerations, np.float64)
        kinks = np.ones(t.size, bool)
        if t.size > 2:
            slope = np.diff(a) / np.diff(t)
            scale = max(float(np.max(np.abs(a))), 1e-300) / float(t[-1] - t[0])
            kinks = np.concatenate([[True], np.abs(np.diff(slope)) > 1e-9 * scale, [True]])
        return cls(t, a, stops=t[kinks] if np.count_nonzero(kinks) <= max_stops else None)

    @classmethod
    def from_file(cls, path, time_column="time_s", acceleration_column="acceleration_m_per_s2"):
        """Read a CSV (tribojax.read_table format); a malformed file raises DataFileError."""
        table = read_table(path, columns=(time_column, acceleration_column))
        t, a = table[time_column], table[acceleration_column]
        bad = np.flatnonzero(np.diff(t) <= 0)
        if bad.size:
            raise ValueError(
                f"{path}: column {time_column!r} is not strictly increasing at data row "
                f"{bad[0] + 2} (t = {t[bad[0] + 1]:g} after {t[bad[0]]:g})"
            )
        return cls(t, a)

    def acceleration(self, t):
        return jnp.interp(t, self.times, self.accelerations)

    def kinks(self):
        return self.stops


class DisplacementHistory(eqx.Module):
    """A prescribed displacement u(t) (m), linear between samples: a measured loop's drive.

    `displacements` at `times` (s, strictly increasing) is what `tribojax.drive` takes
    (`drive(element, history.displacements, history.times)`); `velocity` is the slope of the
    sample interval (m/s), constant within it.
    """

    times: Array  # s, strictly increasing
    displacements: Array  # m

    def __init__(self, times, displacements):
        nodes = _validated_nodes(times, displacements, "displacement history", "displacements")
        self.times, self.displacements = nodes

    def displacement(self, t: ArrayLike) -> Array:
        """u(t), m (the end values outside the record)."""
        return jnp.interp(t, self.times, self.displacements)

    def velocity(self, t: ArrayLike) -> Array:
        """du/dt of the sample interval holding `t`, m/s (the end intervals outside the record)."""
        i = jnp.clip(jnp.searchsorted(self.times, t, side="right") - 1, 0, self.times.size - 2)
        du = self.displacements[i + 1] - self.displacements[i]
        return du / (self.times[i + 1] - self.times[i])


class TrapezoidProfile(AbstractProfile):
    """wang2022's stage cycle: accelerate, cruise, decelerate, with linear ramps (Figure 9).

    a(t) is 0 until `t_start`, ramps to `a_max` over `ramp`, holds for `hold`, ramps back to 0,
    stays at 0 for `cruise`, then mirrors the same to −a_max and back. The peak velocity is
    v_max = a_max·(ramp + hold). Defaults give docs/reproduction.md's profile (a_max = 1 m/s²,
    v_max = 0.5 m/s, ramps 0.10–0.25, 0.60–0.75, 1.50–1.65, 2.00–2.15 s).
    """

    a_max: Array  # m/s², > 0
    ramp: Array  # s, > 0
    hold: Array  # s, >= 0
    cruise: Array  # s, >= 0
    t_start: Array  # s, >= 0

    def __init__(self, a_max=1.0, ramp=0.15, hold=0.35, cruise=0.75, t_start=0.1):
        self.a_max = check_range(a_max, "a_max", 0.0, unit="m/s^2")
        self.ramp = check_range(ramp, "ramp", 0.0, unit="s")
        self.hold = check_range(hold, "hold", 0.0, lo_open=False, unit="s")
        self.cruise = check_range(cruise, "cruise", 0.0, lo_open=False, unit="s")
        self.t_start = check_range(t_start, "t_start", 0.0, lo_open=False, unit="s")

    @classmethod
    def from_v_max(cls, a_max=1.0, v_max=0.5, ramp=0.15, cruise=0.75, t_start=0.1):
        """The profile reaching `v_max` (m/s): hold = v_max/a_max − ramp must be >= 0."""
        hold = check_range(v_max, "v_max", 0.0, unit="m/s") / a_max - ramp
        return cls(
            a_max,
            ramp,
            fail_if(hold, hold < 0, "v_max < a_max*ramp: no hold phase"),
            cruise,
            t_start,
        )

    @property
    def v_max(self) -> Array:
        """Peak stage velocity a_max·(ramp + hold), m/s."""
        return self.a_max * (self.ramp + self.hold)

    def kinks(self):
        r, h, c = self.ramp, self.hold, self.cruise
        return jnp.cumsum(jnp.stack([self.t_start, r, h, r, c, r, h, r]))

    def acceleration(self, t):
        levels = self.a_max * jnp.array([0.0, 1.0, 1.0, 0.0, 0.0, -1.0, -1.0, 0.0])
        return jnp.interp(t, self.kinks(), levels)

    def windows(self):
        """wang2022's averaging windows (s): steady acceleration, cruise, steady deceleration.

        For the default profile [0.25, 0.60], [0.73, 1.50], [1.65, 2.00] (Tables 4–7); the cruise
        window starts 0.02 s after the ramp ends, as in the paper.
        """
        k = self.kinks()
        return jnp.array([[k[1], k[2]], [k[3] - 0.02, k[4]], [k[5], k[6]]])
