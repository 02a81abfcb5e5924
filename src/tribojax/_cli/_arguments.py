"""The arguments of every `tribojax` subcommand, declared without importing the library.

`tribojax --help`, a subcommand's `--help` and argument errors are answered from this module
alone (standard library, `tribojax._limits`/`_presets` constants and `_argument_types`), without
JAX; the subcommand's own module is imported only to run it.
"""

from __future__ import annotations

import math

from .. import _presets as P
from .._limits import (
    BOUC_WEN_STARTS,
    DECIMATION_MAX_SAMPLES,
    DEVICE_MODELS,
    ELEMENT_MODELS,
    MAX_STEPS,
    RECORD_FORMATS,
    ROUGHNESS_METHODS,
    TENSION_LAWS,
)
from ._argument_types import band_tension, positive_float, whole_number

CONTACT_DEFAULTS = dict(
    M=P.CALIBRATED_M,
    gamma=P.WANG2022_GAMMA,
    sigma_s=P.CALIBRATED_SIGMA_S,
    mu_t=P.CALIBRATED_MU_T,
    tangential_load=P.WANG2022_TANGENTIAL_LOAD_N,
    mass=P.WANG2022_RETICLE_MASS_KG,
)  # wang2022 pair, Table-3-calibrated constants (tribojax._presets)


def add_decimation_arguments(parser, max_samples: int = DECIMATION_MAX_SAMPLES) -> None:
    """`--decimate auto|off|N` and `--max-samples` of the commands that take a record."""
    parser.add_argument(
        "--decimate",
        default="auto",
        metavar="auto|off|N",
        help="long records: fit blocks of N samples reduced by local quadratics (noise "
        "scaled); auto (default) reduces a record to at most --max-samples samples; a "
        "history fit (--model an element or best) keeps every N-th sample (auto, off: all)",
    )
    parser.add_argument(
        "--max-samples",
        type=int,
        default=max_samples,
        help=f"the size 'auto' reduces to (default {max_samples})",
    )


def reproduce_arguments(parser) -> None:
    parser.add_argument(
        "--out", default="tribojax-out", help="output folder (default tribojax-out)"
    )


def contact_arguments(con) -> None:
    con.add_argument("--topography", help="profile/height map (.csv, .txt, .npy, instrument files)")
    con.add_argument("--unit", default="m", help="length unit of a plain file (m, mm, um, nm)")
    con.add_argument("--dx", type=float, help="sampling interval (in --unit) for .npy/matrices")
    con.add_argument("--method", default="psd", choices=ROUGHNESS_METHODS)
    con.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"), help="fit band, m")
    con.add_argument("--min-decades", type=float, default=1.0)
    con.add_argument("--D", type=float, help="surface fractal dimension (2, 3)")
    con.add_argument("--G", type=float, help="fractal roughness, m")
    con.add_argument("--load", type=float, nargs="+", required=True, help="normal load(s), N")
    for k, v in CONTACT_DEFAULTS.items():
        con.add_argument("--" + k.replace("_", "-"), dest=k, type=float, default=v)
    con.add_argument(
        "--json",
        help="write the results to this JSON file (never an existing "
        "file or the --topography input, unless --force for an existing result)",
    )
    con.add_argument("--force", action="store_true", help="replace an existing --json file")


def hysteresis_arguments(parser) -> None:
    parser.add_argument("--element", choices=("jenkins", "mindlin", "lugre"), default="mindlin")
    parser.add_argument("--mu", type=float, default=0.3, help="friction coefficient (default 0.3)")
    parser.add_argument("--N", type=float, default=2.94, help="normal load, N (default 2.94)")
    parser.add_argument(
        "--K-d",
        type=float,
        default=None,
        help="tangential contact stiffness, N/m (default: wu2015 Eq 5 at N, read as N/um)",
    )
    parser.add_argument(
        "--omega", type=float, default=2 * math.pi * 22, help="rad/s (default 2*pi*22)"
    )
    parser.add_argument(
        "--C-tau",
        type=float,
        default=0.0,
        help="lugre only: bristle damping C_tau, N s/m (default 0); F_s = mu*N, K_tau = K_d",
    )
    rng = parser.add_mutually_exclusive_group()
    rng.add_argument("--abar", type=float, nargs=2, metavar=("MIN", "MAX"), default=None)
    rng.add_argument("--A", type=float, nargs=2, metavar=("MIN_m", "MAX_m"), default=None)
    parser.add_argument("--n", type=int, default=100, help="number of amplitudes (default 100)")
    parser.add_argument("--loop", default=None, help="CSV (t_s, u_m, f_N) to analyse and fit")
    parser.add_argument(
        "--fit-model",
        choices=("steady", "history"),
        default="steady",
        help="fit the steady loop (default) or drive the element through the measured history",
    )
    parser.add_argument("--out", default="tribojax-out/hysteresis", help="output folder")
    parser.add_argument(
        "--force",
        action="store_true",
        help="replace an earlier result in --out (its files from an earlier run "
        "that this run does not write are removed)",
    )


def _band_tension_argument(parser) -> None:
    parser.add_argument(
        "--band-tension",
        type=band_tension,
        default=None,
        metavar="T",
        help="loops and histories of a band brake: the band's set tension, N (or "
        "'30lb'); default: from a brfd file name (<f>Hz<T>lbtension... or "
        "earthquake_<name>_<T>lb)",
    )


def fit_arguments(parser, batch: bool = False) -> None:
    _record_argument(
        parser,
        batch,
        nargs="+",
        help="CSV: a slip run (time_s,stage_accel_m_s2,slip_m) or a loop "
        "(time_s,displacement_m,force_N), each with its <stem>.json sidecar; a brfd JSON; an "
        "EPOS export or a folder of EPOS steady-state exports (one friction curve); several "
        "loops or histories: one parameter set fitted to all (--model an element or best)",
    )
    if not batch:
        parser.add_argument(
            "--out", default=None, help="output folder (default tribojax-out/fit-STEM)"
        )
    parser.add_argument(
        "--alpha",
        default=None,
        help="slip runs: the bristle exponent α held at this value (default 1, the paper's law "
        "and discover's baseline) or 'free' to fit it",
    )
    parser.add_argument(
        "--start",
        nargs="+",
        default=None,
        metavar="NAME=VALUE",
        help="start values, SI units: slip runs F_s, K_tau, C_tau, alpha; loops mu_N, K_d",
    )
    parser.add_argument(
        "--element",
        choices=("jenkins", "mindlin"),
        default="jenkins",
        help="loops: the hysteresis element (default jenkins)",
    )
    parser.add_argument(
        "--model",
        choices=("record", "steady", "history", *ELEMENT_MODELS, *DEVICE_MODELS, "best"),
        default=None,
        help="loops: 'history' (default for a periodic loop: the loop model that discover also "
        "fits) or 'steady' (wu2015's steady-loop formula) fit --element; "
        "jenkins|mindlin|lugre|bouc_wen|band_brake drive that element (+ force offset) through "
        "the measured history, best: the first four, and band_brake on a band brake's records "
        "(band tension known), lowest BIC over the records together (default for a "
        "non-periodic history); friction curves: record (Coulomb + viscous, the model "
        "discover starts from; default) or lugre (the steady law with a direction "
        "asymmetry; best: the same)",
    )
    parser.add_argument(
        "--n-starts",
        type=positive_float("--n-starts"),
        nargs="+",
        default=None,
        metavar="N",
        help="--model bouc_wen or best: starts of the Bouc–Wen sharpness n, the lowest "
        "residual kept (default one start, n = 2; a thorough fit: "
        + " ".join(f"{v:g}" for v in BOUC_WEN_STARTS)
        + ")",
    )
    parser.add_argument(
        "--tension-law",
        choices=("auto", *TENSION_LAWS),
        default="auto",
        help="history fits of a band brake's records: how the slip forces follow the band "
        "tension (default auto: in proportion at one tension, with a residual tension from "
        "two, and a wrap growing with the tension from three)",
    )
    parser.add_argument(
        "--mixed-scales",
        action="store_true",
        help="several records: fit them together even when their force scales "
        "differ by more than 100x (refused otherwise)",
    )
    parser.add_argument(
        "--from",
        dest="from_model",
        default=None,
        metavar="MODEL.json",
        help="fit the model saved in a fit.json or discovery.json (with the "
        "effects discovery added) to this record, from its saved "
        "values",
    )
    parser.add_argument(
        "--free",
        nargs="+",
        default=None,
        metavar="NAME",
        help="with --from a history model (a fit.json of --model ELEMENT): the parameters "
        "refitted, the rest held at the saved values (a new campaign calibrated by one or two "
        "tests; default: the element's and f0)",
    )
    parser.add_argument(
        "--format",
        choices=RECORD_FORMATS,
        default=None,
        help="the record's format (default: detected)",
    )
    parser.add_argument(
        "--max-steps",
        type=int,
        default=None,
        help=f"LM step budget (default {MAX_STEPS} for slip runs and loops; "
        "friction curves: the steady-law fit's own budget)",
    )
    if not batch:
        parser.add_argument("--force", action="store_true", help="replace an existing DIR/fit.json")
    _band_tension_argument(parser)
    add_decimation_arguments(parser)


def discover_arguments(parser, batch: bool = False) -> None:
    _record_argument(
        parser,
        batch,
        help="record (slip run or loop CSV, brfd JSON, friction curve or a "
        "folder of EPOS steady-state exports); several loops or histories at two or more "
        "band tensions: which parts of the tension law they demand",
        nargs="+",
    )
    if not batch:
        parser.add_argument(
            "--model",
            choices=(*ELEMENT_MODELS, *DEVICE_MODELS),
            default=None,
            help="several records: the history element fitted to them (default band_brake)",
        )
    if not batch:
        parser.add_argument(
            "--out", default="discovery-out", help="output folder (default discovery-out)"
        )
        parser.add_argument(
            "--force", action="store_true", help="replace an existing discovery.json"
        )
    parser.add_argument(
        "--format",
        choices=RECORD_FORMATS,
        default=None,
        help="the record's format (default: detected)",
    )
    parser.add_argument("--max-effects", type=int, default=3, help="greedy rounds (default 3)")
    parser.add_argument(
        "--from",
        dest="from_model",
        default=None,
        metavar="MODEL.json",
        help="start from the model saved in a discovery.json or fit.json (its "
        "effects refitted on this record), and look for more",
    )
    add_decimation_arguments(parser)
    _band_tension_argument(parser)  # a band brake's record: its effects become candidates
    parser.add_argument(
        "--initial",
        choices=("rest", "measured"),
        default=None,
        help="loops and histories: the element starts at rest (default) or in "
        "the state that carries the record's first measured force (a history "
        "that begins under load)",
    )


def predict_arguments(parser, batch: bool = False) -> None:
    model_help = "fit.json or discovery.json (its fitted_model), or a saved model"
    if batch:
        parser.add_argument("--model", required=True, metavar="MODEL.json", help=model_help)
    else:
        parser.add_argument("model", help=model_help)
    _record_argument(parser, batch, help="the record to predict (any format `fit` reads)")
    if not batch:
        parser.add_argument(
            "--out", default=None, help="output folder (default tribojax-out/predict-STEM)"
        )
    parser.add_argument(
        "--format",
        choices=RECORD_FORMATS,
        default=None,
        help="the record's format (default: detected)",
    )
    if not batch:
        parser.add_argument(
            "--force", action="store_true", help="replace an existing DIR/prediction.json"
        )
    parser.add_argument(
        "--initial",
        choices=("rest", "measured"),
        default=None,
        help="loop and history models: start from rest or in the state that "
        "carries the record's first measured force (history models: jenkins, "
        "band_brake); default: as the model was fitted (rest)",
    )
    _band_tension_argument(parser)


def _record_argument(parser, batch: bool, help: str, nargs=None) -> None:
    """The record positional: the single command's `file`, or batch's `records` (several)."""
    if batch:
        parser.add_argument(
            "records",
            nargs="+",
            metavar="RECORD",
            help="records: files, folders (their records, a folder of EPOS steady-state "
            "exports as one) or quoted globs ('runs/*.csv')",
        )
    else:
        parser.add_argument("file", nargs=nargs, help=help)


# the subcommands `tribojax batch` runs on each record (their arguments, in batch form)
BATCH_COMMANDS = {
    "fit": fit_arguments,
    "discover": discover_arguments,
    "predict": predict_arguments,
}


def batch_arguments(parser) -> None:
    sub = parser.add_subparsers(dest="batch_command", required=True, metavar="COMMAND")
    for name, add_arguments in BATCH_COMMANDS.items():
        cmd = sub.add_parser(name, help=f"`tribojax {name}` on each record")
        add_arguments(cmd, batch=True)
        cmd.add_argument(
            "--out",
            required=True,
            help="output folder: DIR/<record stem>/ as the single command writes it, "
            "DIR/batch.csv and DIR/batch.json",
        )
        where = cmd.add_mutually_exclusive_group()
        where.add_argument(
            "--workers",
            type=whole_number("--workers"),
            default=None,
            help="worker processes of the local cluster (default: one per core, "
            "at most one per 2 GiB of memory)",
        )
        where.add_argument(
            "--scheduler",
            default=None,
            metavar="ADDRESS",
            help="an existing Dask scheduler (tcp://HOST:PORT)",
        )
        where.add_argument(
            "--scheduler-file",
            default=None,
            metavar="FILE",
            help="an existing Dask scheduler's file (`dask scheduler --scheduler-file FILE`)",
        )
        cmd.add_argument(
            "--force",
            action="store_true",
            help="run every record again (default: a record whose outputs are complete "
            "from an earlier run with the same options is not run again)",
        )
        cmd.add_argument(
            "--quiet",
            action="store_true",
            help="no progress display (it is shown only on a terminal)",
        )


def frf_arguments(parser) -> None:
    parser.add_argument("config", help="TOML file: structure, contacts, excitation, harmonics")
    parser.add_argument("--out", default="tribojax-out/frf", help="output folder")
