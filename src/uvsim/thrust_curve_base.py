"""The thrust-curve interface: :class:`ThrustCurve`, what every curve of uvsim implements.

A thrust curve maps one ESC's PWM command (microseconds) to thrust (N) and back, vectorized
over any array shape.  :class:`ThrustCurve` holds what all curves share: the public
``thrust``/``pwm`` methods with their range checks (out-of-range or non-finite values raise
:class:`uvsim.errors.SimulationError` naming the value and the valid range; nothing is
clipped), the largest forward and reverse thrust, and equality and hashing by a curve's
parameters.  Subclasses evaluate already-validated arrays: the fixed curves in
:mod:`uvsim.thrust_curves` (tabulated, linear) and the battery-aware one in
:mod:`uvsim.voltage_curves`.  This module imports no other uvsim curve module.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import SimulationError


# --------------------------------------------------------------------------- base class
class ThrustCurve:
    """Strategy interface: PWM (us) <-> thrust (N), vectorized over any shape.

    Subclasses set ``pwm_min``, ``pwm_max`` (valid command range, us), ``deadband``
    (``(lo, hi)``, us), ``neutral`` (us) and ``name``, and implement :meth:`_thrust`
    and :meth:`_pwm` on already-validated float arrays.
    """

    pwm_min: float
    pwm_max: float
    deadband: tuple[float, float]
    neutral: float
    name: str
    #: True for curves whose thrust depends on the supply voltage
    #: (:class:`uvsim.voltage_curves.VoltageThrustCurve`); fixed curves ignore it.
    voltage_dependent: bool = False

    # -- public API ------------------------------------------------------------------
    def thrust(self, pwm: np.ndarray) -> np.ndarray:
        """Thrust for ESC commands.

        Parameters
        ----------
        pwm : array_like, any shape
            ESC pulse widths, microseconds.

        Returns
        -------
        ndarray, same shape as ``pwm``
            Thrust along the thruster axis, N (positive = forward branch).

        Raises
        ------
        SimulationError
            If any value is non-finite or outside ``[pwm_min, pwm_max]``.
        """
        pwm = np.asarray(pwm, dtype=float)
        self._check_range(pwm, self.pwm_min, self.pwm_max, "PWM", "us")
        return self._thrust(pwm)

    def pwm(self, thrust: np.ndarray) -> np.ndarray:
        """Inverse curve: the ESC command that produces ``thrust``.

        0 N maps to :attr:`neutral`.  Where the curve is flat (equal thrust at several
        commands) the command nearest to neutral is returned, so
        ``thrust(pwm(T)) == T`` (to round-off) for every reachable ``T``.

        Parameters
        ----------
        thrust : array_like, any shape
            Thrust, N.

        Returns
        -------
        ndarray, same shape as ``thrust``
            PWM, microseconds.

        Raises
        ------
        SimulationError
            If any value is non-finite or beyond ``[max_reverse, max_forward]``.
        """
        thrust = np.asarray(thrust, dtype=float)
        self._check_range(thrust, self.max_reverse, self.max_forward, "thrust", "N")
        return self._pwm(thrust)

    @property
    def max_forward(self) -> float:
        """Largest thrust the curve produces (N, >= 0)."""
        return float(self._thrust(np.array(self.pwm_max)))

    @property
    def max_reverse(self) -> float:
        """Most negative thrust the curve produces (N, <= 0)."""
        return float(self._thrust(np.array(self.pwm_min)))

    def to_mapping(self) -> dict:
        """A mapping that :func:`uvsim.thrusters.load_thrust_curve` turns back into an equal curve."""
        raise NotImplementedError

    # -- helpers for subclasses ----------------------------------------------------------
    def _thrust(self, pwm: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _pwm(self, thrust: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def _key(self) -> tuple:  # pragma: no cover - abstract
        raise NotImplementedError

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and self._key() == other._key()  # type: ignore[attr-defined]

    def __hash__(self) -> int:
        return hash(self._key())

    def _check_range(self, values, vmin, vmax, what, unit) -> None:
        """Raise :meth:`_range_error` unless every one of ``values`` lies in ``[vmin, vmax]``.
        NaN makes both comparisons False, so this also catches non-finite input."""
        if values.size and not (values.min() >= vmin and values.max() <= vmax):
            self._range_error(values, vmin, vmax, what, unit)

    def _range_error(self, values, vmin, vmax, what, unit):
        bad = ~((values >= vmin) & (values <= vmax))
        idx = np.unravel_index(int(np.argmax(bad)), values.shape) if values.ndim else ()
        first = values[idx]
        n_bad = int(bad.sum())
        where = f" at index {tuple(int(i) for i in idx)}" if values.ndim else ""
        raise SimulationError(
            f"thrust curve {self.name!r}: {what} {float(first):g} {unit}{where} is outside the "
            f"valid range [{vmin:g}, {vmax:g}] {unit} ({n_bad} of {values.size} values out of "
            f"range; values are never clipped)"
        )
