"""Hydrodynamic database (seed 003 sec. III, IV-B): hull geometry, Jorgensen and DATCOM body
methods, lifting line + flat plate wings with Montgomerie blending, experimental/CFD polars and
the multifidelity lookup table.  See docs/hydro.md for the API and the methods.

Main entry points::

    from uvsim.hydro import (load_hull, myring_profile, hull_from_stations, BodyModel,
                             build_body_table, naca0015_table, build_wing_table, WingModel,
                             HydroTable, read_polar_csv, read_sheldahl, total_incidence)
"""
from uvsim.hydro.assembly import build_body_table, build_wing_table, default_re_grid, naca0015_table  # noqa: F401
from uvsim.hydro.body import BodyModel, Coefficients, reynolds, total_incidence  # noqa: F401
from uvsim.hydro.datcom import datcom  # noqa: F401
from uvsim.hydro.geometry import (HullGeometry, builtin_hulls, hull_from_stations, hull_from_stl,  # noqa: F401
                                  hull_from_triangles,
                                  load_hull, myring_profile)
from uvsim.hydro.jorgensen import jorgensen  # noqa: F401
from uvsim.hydro.polars import PolarSet, read_polar_csv, read_sheldahl  # noqa: F401
from uvsim.hydro.table import HydroTable  # noqa: F401
from uvsim.hydro.wings import WingModel, flat_plate, lifting_line, montgomerie_blend  # noqa: F401
