"""The fits' settings that the command line shows: defaults and allowed values.

One light module (no numpy), so that ``uvsim --help`` and every command's parser read them
without importing the fitting machinery; the modules that use them import them from here.
"""

# ----------------------------------------------------------------------------- calibration
#: Window lengths of the joint stage's continuation: 2 s windows, held nearly continuous by
#: DEFAULT_CONTINUITY.  ``(2.0, None)`` adds a whole-run stage with each channel scaled by its own
#: RMS error (:func:`uvsim.fitting.evaluate.judged_scales`), the least-squares form of the
#: verdict's score; measured on the structural benchmark it called fewer fits better (44 of 50
#: against 46) and took 1.7 times as long, so it is an option, not the default
#: (docs/calibration_method.md, "A whole-run stage on the verdict's measure").
DEFAULT_HORIZONS = (2.0,)
#: Continuity factors of the joint stage's last horizon (:func:`uvsim.fitting.fit`): the
#: continuity defects' sd is DEFECT_SIGMA x 0.05 (0.25 mm, 0.5 mrad/s ...), so that what the
#: fit improves is close to the free simulation the result check compares (docs/calibration.md,
#: "Continuity"; the soft default of diagnosis let a fit trade open-loop depth for windowed cost).
DEFAULT_CONTINUITY = (0.05,)
#: How samples of channels logged at different rates count (:func:`uvsim.measurements.measurements_for`):
#: per second of log, so that a 10 Hz depth is not outweighed tenfold by a 100 Hz IMU whose
#: model errors are as correlated (docs/calibration_sensors.md, "Sample weighting").
DEFAULT_SAMPLE_WEIGHTING = "per_second"
#: How the samples of channels logged at different rates are weighted
#: (:func:`uvsim.measurements.measurements_for`).
SAMPLE_WEIGHTINGS = ("per_sample", "per_second")
#: Loss functions of the measurement residuals (``loss=``, as scipy.optimize.least_squares
#: names them): "linear" (least squares) or "huber".
LOSSES = ("linear", "huber")

# ----------------------------------------------------------------------------- diagnosis
#: Window length (s) of a diagnosis' prediction-error fits (``uvsim diagnose --horizon``).
DEFAULT_HORIZON = 3.0
