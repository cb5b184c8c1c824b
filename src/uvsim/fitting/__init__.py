"""The fitting machinery shared by calibration and diagnosis.

* :mod:`~uvsim.fitting.parameters` - which parameters are free, their bounds, the
  physical-by-construction map (:class:`ParameterSpace`);
* :mod:`~uvsim.fitting.nodes` - window-start states estimated from the log;
* :mod:`~uvsim.fitting.windows` - runs cut into windows, whole runs simulated in one
  batch, the tangent coordinates of a state;
* :mod:`~uvsim.fitting.objective` - the windowed (multiple-shooting) prediction-error
  residual of a set of runs, through :mod:`uvsim.measurements`;
* :mod:`~uvsim.fitting.linearization` - one linearization of a windowed problem
  (forward-difference Jacobians, each run's normal-equation pieces);
* :mod:`~uvsim.fitting.evaluators` - linearizing the problems in this process, in a pool
  of processes, or with a prior;
* :mod:`~uvsim.fitting.solver` - Levenberg-Marquardt with the per-run nuisance
  eliminated, robust uncertainty;
* :mod:`~uvsim.fitting.fitter` - :func:`fit`: continuation over window lengths, results;
* :mod:`~uvsim.fitting.equation_error` - the inverse-dynamics (equation-error) fit that
  seeds the candidates of a diagnosis;
* :mod:`~uvsim.fitting.compare` - block-bootstrap comparison of models on validation runs.
"""
from uvsim.lazy_imports import lazy_getattr

#: The package's names, imported when first used (PEP 562), so that importing one light
#: submodule (``uvsim.fitting.parameters``, ``uvsim.fitting.verdict``) does not import the
#: whole machinery: it kept every ``uvsim`` command's start at 1.6 s.
_LAZY = {"FitResult": "uvsim.fitting.fitter", "fit": "uvsim.fitting.fitter", "identifiability": "uvsim.fitting.fitter",
         "FreeParameter": "uvsim.fitting.parameters", "ParameterSpace": "uvsim.fitting.parameters",
         "make_space": "uvsim.fitting.parameters"}
__all__ = list(_LAZY)

__getattr__ = lazy_getattr(__name__, _LAZY)
