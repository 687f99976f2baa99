"""soilcal.rsm: response-surface regression, ANOVA, fit statistics and screening analysis
with Design-Expert semantics (see :mod:`soilcal.rsm.model`, :mod:`soilcal.rsm.screening`,
:mod:`soilcal.rsm.transforms`, :mod:`soilcal.rsm.printed`)."""

from soilcal.rsm.model import (
    RSMFit,
    apply_transform,
    backward_eliminate,
    drop_terms,
    fit_response_surface,
    full_quadratic_terms,
    inverse_transform,
    parse_term,
    term_name,
)
from soilcal.rsm.printed import compare_printed, parse_printed
from soilcal.rsm.screening import screening_effects
from soilcal.rsm.transforms import STANDARD_LAMBDAS, boxcox, transform_suggestion

__all__ = [
    "RSMFit",
    "STANDARD_LAMBDAS",
    "apply_transform",
    "backward_eliminate",
    "boxcox",
    "compare_printed",
    "drop_terms",
    "fit_response_surface",
    "full_quadratic_terms",
    "inverse_transform",
    "parse_printed",
    "parse_term",
    "screening_effects",
    "term_name",
    "transform_suggestion",
]
