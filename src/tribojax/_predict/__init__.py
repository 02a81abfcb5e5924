"""Fitted models as values: saved by `fit` and `discover`, loaded and evaluated on records they
never saw (`tribojax predict`)."""

from .._model import RECORD_KINDS as RECORD_KINDS
from ._fit_report import FitReport as FitReport
from ._fit_report import saved_if_converged as saved_if_converged
from ._prediction import SAVED_KEY as SAVED_KEY
from ._prediction import ExtrapolationWarning as ExtrapolationWarning
from ._prediction import Prediction as Prediction
from ._prediction import fitted_model as fitted_model
from ._prediction import load_model as load_model
from ._prediction import predict as predict
from ._prediction import refit as refit
