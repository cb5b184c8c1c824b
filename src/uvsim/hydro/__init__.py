"""Hydrodynamic database (seed 003 sec. III, IV-B): hull geometry, Jorgensen and DATCOM body
methods, lifting line + flat plate wings with Montgomerie blending, experimental/CFD polars and
the multifidelity lookup table.  See docs/hydro.md for the API and the methods."""
