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
