"""Signal-level estimation shared by simulation, calibration and diagnosis.

* :mod:`~uvsim.estimation.derivatives` - Savitzky-Golay velocities and accelerations
  from logged positions and attitudes;
* :mod:`~uvsim.estimation.noise` - measurement-noise levels per channel, with detection
  of held (repeated) and interpolated samples so that a slow sensor logged on a fast grid
  is judged at its native rate.

These helpers sit below :mod:`uvsim.fitting`, :mod:`uvsim.calibration` and
:mod:`uvsim.diagnosis` in the import order (they need only numpy, scipy and the run
reader).
"""
