"""Names and budgets shared by the library and the command line's argument parser.

This module imports nothing, so `tribojax --help` and argument errors are answered without
importing JAX; each name's one home is here, and the modules that use it import it from here.
"""

INTERRUPTED = 130
"""The command line's exit status after Ctrl-C or SIGTERM (128 + SIGINT)."""

RECORD_FORMATS = ("slip", "loop", "brfd", "epos_steady", "epos", "curve")
"""The record formats `tribojax.read_record` reads (`format=`; detected when None)."""

ROUGHNESS_METHODS = ("structure", "psd", "rms")
"""Estimators of D and G from a topography (`tribojax.estimate_fractal`)."""

ELEMENT_MODELS = ("jenkins", "mindlin", "lugre", "bouc_wen")
"""Friction elements a displacement history is fitted with (`tribojax.fit_history`); `best`
chooses among these."""
DEVICE_MODELS = ("band_brake",)
TENSION_LAWS = {"proportional": 1, "residual": 2, "growing": 3}
"""A history fit's band-tension laws and the distinct tensions each needs (`law_spec`): T/T_ref;
with a residual tension T_res; with T_res and a wrap that grows with the tension (γ)."""
"""Device models a history is also fitted with when named (`--model band_brake`)."""

STEADY_STARTS = tuple((b, f) for b in (2.0, 0.5, 8.0) for f in (1.0, 0.3, 3.0))
"""Starts of the LuGre steady-law fit (`tribojax.fit_steady_curve`): (β, factor on the data's
v_s estimate). The law has separate optima (a Stribeck step, β → ∞, beside a smooth rise or dip:
driveNo2's curve converges to either from nearby starts), so one start can stop in the worse;
the lowest misfit of the converged fits is kept."""
BOUC_WEN_STARTS = (0.5, 2.0, 10.0)
"""Starts of the Bouc–Wen sharpness n for a thorough history fit (`fit_history(n_starts=)`,
`tribojax fit --n-starts`): its optima fall in separate families (n < 1, soft; n of tens, close
to Jenkins), so one start can miss the better one; the lowest residual is kept."""

MAX_STEPS = 128
"""Step budget of every record-model fit (accepted and rejected steps; one compile)."""

DECIMATION_MAX_SAMPLES = 5_000
"""Samples a long record is reduced to before it is fitted or searched (`decimate_record`'s
default, `--max-samples` of `tribojax fit` and `discover`: one budget, so both fit the same
samples). Discovery's time and memory grow with the record (20,000 slip samples: 86 s, 4.1 GiB
on 10^6 samples); a slip fit on 5,000 recovers the truth as on 20,000 (docs/performance.md)."""
DISCOVER_MAX_SAMPLES = DECIMATION_MAX_SAMPLES
"""The same budget under its earlier name (`tribojax.DISCOVER_MAX_SAMPLES`)."""

# Plausible magnitudes of a record's samples, SI units: far beyond any rig (a displacement of 1 km,
# a force of 1 GN, a slip of 1 m, a stage acceleration of 10^4 m/s²) and far below where a fit's
# sums of squares overflow float64. A sample beyond them is a unit or export error (a value typed
# in mm into a metre column is not caught; one scaled by 1e300 is), refused naming where it is.
SAMPLE_LIMITS = {"u": (1e3, "m"), "f": (1e9, "N"), "slip": (1.0, "m"), "accel": (1e4, "m/s²")}
# ... and the smallest largest-magnitude a record may have: a record whose every sample is below
# these (a femtometre, a piconewton) is no measurement but a unit error (×1e-300), which would
# otherwise reach the solvers as underflow.
SAMPLE_FLOORS = {"u": 1e-15, "f": 1e-12, "slip": 1e-15, "accel": 1e-12}


# The largest magnitude of a saved model's value (a parameter or an effect's strength, in the units
# the model file states): far beyond any contact (a stiffness of 10^20 N/m, a force of 10^20 N)
# and far below where a prediction overflows float64. A value beyond it is refused by name.
PARAMETER_LIMIT = 1e20

# The largest ratio of two records' force scales (sd of the force, at one band tension) that a
# joint fit takes without being asked: beyond it the small record weighs nothing in the fit (two
# orders of magnitude: a unit error, or records of another device).
JOINT_SCALE_RATIO = 100.0
