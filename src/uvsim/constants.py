"""Physical constants used as defaults.  A vehicle file may override ``g`` and ``rho``."""

#: Standard gravity, m/s^2 (CGPM 1901; ISO 80000-3).  The BlueROV2 paper (seed 000)
#: does not state its g; 9.81 is used in Fossen (2021) examples.  We use 9.81 and say so
#: in every vehicle file.
G = 9.81

#: Fresh water density at about 20 degC, kg/m^3 (seed 002 sec. 3 runs its CFD at 20 degC).
RHO_FRESH = 998.0

#: Sea water density, kg/m^3: the value used throughout Fossen (2021) for sea water.
RHO_SEA = 1025.0

#: Kinematic viscosity of water at 20 degC, m^2/s (ITTC 2011 fresh-water tables).
NU_WATER = 1.0e-6

#: Largest water current accepted, m/s (``--current``, a vehicle file's ``current_ned``).
#: Open-ocean currents stay below about 2.5 m/s (the Gulf Stream's core); the fastest tidal
#: races reach 8-11 m/s (Pentland Firth 16 kn, Saltstraumen 22 kn), where no ROV or AUV is
#: flown. Beyond 5 m/s a value is a unit slip (knots, km/h) or a typo, not a current.
MAX_CURRENT_SPEED = 5.0

#: Water densities accepted, kg/m^3 (``environment.rho`` of a vehicle file, ``uvsim hydro --rho``,
#: ``uvsim import --water``): fresh water is 998-1000 (RHO_FRESH), sea water 1020-1030 (RHO_SEA),
#: the saltiest lake water (the Dead Sea) 1240.  A specific gravity (1.025) or g/cm^3 is a unit slip.
WATER_DENSITY_RANGE = (900.0, 1250.0)

#: Gravitational accelerations accepted, m/s^2 (``environment.g``): from Enceladus' 0.11 (the smallest
#: ocean world proposed for a submersible) to Jupiter's 24.8 (the largest surface gravity of the solar
#: system).  32.2 is g in ft/s^2, 981 in cm/s^2 (Earth: 9.78-9.83).
GRAVITY_RANGE = (0.1, 25.0)

#: Accepted ESC command range, microseconds.  Hobby/RC ESCs take 1000-2000 us
#: pulses with 1500 us neutral; the Blue Robotics BlueESC is specified for
#: 1000-2000 us and the Basic ESC for 1100-1900 us (Blue Robotics forum,
#: discuss.bluerobotics.com/t/380 and /t/712).  A value outside 1000-2000 us
#: is not a command any of these ESCs understands (e.g. 0 = "no pulse", or a
#: column logged in percent or in normalized units), so it is rejected
#: (a logged PWM column, uvsim.log_columns, and a thrust table's pwm, uvsim.thrust_curves).
PWM_RANGE_US = (1000.0, 2000.0)
