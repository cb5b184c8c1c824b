"""``uvsim hydro``: body damping coefficients of a hull, and coefficient tables.

    uvsim hydro HULL [--re RE | --speed U] [--json]
    uvsim hydro table NAME --out DIR [--plot]

HULL / NAME: a built-in hull (``remus100``), a hull YAML file, or for ``table`` also
``naca0015`` (NACA 0015 section: Sheldahl data + analytic blend).
"""
from __future__ import annotations

import json

import numpy as np

from uvsim.constants import NU_WATER, RHO_SEA
from uvsim.errors import HydroError
from uvsim.vehicle_schema import check_water_density


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "hydro", help="hydrodynamic database: hull damping coefficients and coefficient tables",
        description="'uvsim hydro HULL --re RE --json' prints |Xuu|, |Yvv|, |Zww| (kg/m) by Jorgensen "
                    "and DATCOM; 'uvsim hydro table NAME --out DIR --plot' builds a multifidelity table "
                    "(CSV) and plots it.  Built-in hulls: remus100; tables also: naca0015.")
    p.add_argument("target", help="hull name or YAML path, or the word 'table'")
    p.add_argument("name", nargs="?", help="(with 'table') hull name/path or 'naca0015'")
    p.add_argument("--re", type=float, help="length Reynolds number (hull) or chord Reynolds number")
    p.add_argument("--speed", type=float, help="speed, m/s (gives Re = speed*L/nu if --re is absent)")
    p.add_argument("--nu", type=float, default=NU_WATER, help=f"kinematic viscosity, m^2/s (default {NU_WATER})")
    p.add_argument("--rho", type=float, default=RHO_SEA, help=f"water density, kg/m^3 (default {RHO_SEA})")
    p.add_argument("--cdn-model", choices=["subcritical", "reynolds"], default="subcritical",
                   help="cross-flow drag model (default subcritical, Jorgensen's method; reynolds includes "
                        "the smooth-cylinder drag crisis, whose force falls as the speed rises)")
    p.add_argument("--friction-line", choices=["schoenherr", "ittc57"], default="schoenherr")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--out", help="(table) output directory")
    p.add_argument("--plot", action="store_true", help="(table) also write PNG plots")
    p.add_argument("--method", choices=["multifidelity", "jorgensen", "datcom"], default="multifidelity",
                   help="(table, hulls) assembly method")
    p.add_argument("--re-min", type=float, help="(table) smallest Re (default 1e5 hull, 1e4 wing)")
    p.add_argument("--re-max", type=float, help="(table) largest Re (default 1e7 hull, 1e6 wing)")
    p.add_argument("--n-re", type=int, default=21, help="(table) number of Re rows, log-spaced")
    p.add_argument("--cfd", help="(table) CFD CSV: Re,alpha,CL,CD,CM (alpha in deg)")
    p.add_argument("--expt", help="(table) experimental CSV: Re,alpha,CL,CD,CM (alpha in deg)")
    p.add_argument("--no-smooth", action="store_true", help="(table) skip makima smoothing")
    p.add_argument("--aspect-ratio", type=float, default=float("inf"),
                   help="(table naca0015) effective aspect ratio; inf = 2-D section with Sheldahl data")
    p.set_defaults(func=run)


def _body(args, hull_name):
    from uvsim.hydro.body import BodyModel
    from uvsim.hydro.geometry import load_hull
    return BodyModel(load_hull(hull_name), cdn_model=args.cdn_model, friction_line=args.friction_line,
                     nu=args.nu)


def run(args) -> int:
    if args.target == "table":
        return _run_table(args)
    return _run_coefficients(args)


def _run_coefficients(args) -> int:
    from uvsim.hydro.coefficients import quadratic_damping
    if args.name is not None:
        raise HydroError(f"unexpected extra argument {args.name!r} (did you mean 'uvsim hydro table NAME'?)")
    check_water_density(args.rho, "--rho", HydroError)
    body = _body(args, args.target)
    if args.re is not None:
        re = args.re
    elif args.speed is not None:
        if not (np.isfinite(args.speed) and args.speed > 0):
            raise HydroError(f"--speed must be a positive speed in m/s, got {args.speed}")
        re = body.re_from_speed(args.speed)
    else:
        raise HydroError("give --re (length Reynolds number) or --speed (m/s)")
    if not (re > 0 and np.isfinite(re)):
        raise HydroError(f"--re must be > 0, got {re}")
    res = quadratic_damping(body, re, args.rho)
    if args.json:
        print(json.dumps(res, indent=2))
        return 0
    h = body.hull
    print(f"hull {h.name}: L = {h.length:.4g} m, d = {h.diameter:.4g} m, Re = {re:.4g}, rho = {args.rho:g} kg/m^3, "
          f"c_dn model {args.cdn_model}, friction line {args.friction_line}")
    print(f"{'method':<10} {'|Xuu| kg/m':>12} {'|Yvv| kg/m':>12} {'|Zww| kg/m':>12}")
    for m, v in res.items():
        print(f"{m:<10} {v['Xuu']:12.4g} {v['Yvv']:12.4g} {v['Zww']:12.4g}")
    if args.speed is not None:
        u = args.speed
        print(f"at u = {u:g} m/s: axial drag {res['datcom']['Xuu'] * u * u:.4g} N (DATCOM), "
              f"{res['jorgensen']['Xuu'] * u * u:.4g} N (Jorgensen)")
    return 0


def _run_table(args) -> int:
    from pathlib import Path

    from uvsim.hydro.assembly import build_body_table, default_re_grid, naca0015_table
    from uvsim.hydro.polars import read_polar_csv
    if not args.name:
        raise HydroError("usage: uvsim hydro table NAME --out DIR [--plot]")
    if not args.out:
        raise HydroError("uvsim hydro table needs --out DIR")
    from uvsim.commands.checks import check_outputs

    check_outputs(dirs={"--out": args.out})
    cfd = read_polar_csv(args.cfd, kind="cfd") if args.cfd else None
    expt = read_polar_csv(args.expt, kind="experiment") if args.expt else None
    if args.name == "naca0015":
        re_grid = default_re_grid(args.re_min or 1e4, args.re_max or 1e6, args.n_re)
        if cfd is not None or expt is not None:
            raise HydroError("--cfd/--expt are not supported with naca0015 (its data are Sheldahl's)")
        table = naca0015_table(re_grid, aspect_ratio=args.aspect_ratio)
    else:
        re_grid = default_re_grid(args.re_min or 1e5, args.re_max or 1e7, args.n_re)
        table = build_body_table(_body(args, args.name), re_grid, method=args.method, cfd=cfd,
                                 experiment=expt, smooth=not args.no_smooth)
    out = Path(args.out)
    path = table.save(out / f"{table.name}.csv")
    print(f"wrote {path}")
    labels, counts = np.unique(table.method.astype(str), return_counts=True)
    print("cells by method: " + ", ".join(f"{m} {c}" for m, c in zip(labels, counts))
          + f"; smoothed {int(table.smoothed.sum())}")
    if args.plot:
        from uvsim.plotting.hydro import plot_table
        for p in plot_table(table, out):
            print(f"wrote {p}")
    return 0
