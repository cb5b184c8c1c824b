#!/usr/bin/env python3
"""Convert the Tartan AUV "Kingfisher" pool logs of 2022-12-01 (Tartan-AUV/TAUV-Playground) to uvsim's log format.

Usage:
    python tauv_to_logformat.py OUTDIR --mirror DIR [--runs 0,1,...] [--rate 20] [--max-gap 0.5]
                                [--vehicle-file PATH] [--nav-time stamp|record]

Source: a git clone of github.com/Tartan-AUV/TAUV-Playground (a bare one is enough).  Each run is a pair of CSV
files that the team exported from rosbags with `rostopic echo -p` (bags of 2022-12-01, ~60 s each):

    dynamics-parameter-estimation/data/bags-12-01-22/navigation_state_<i>.csv   (tauv_msgs/NavigationState)
    dynamics-parameter-estimation/data/bags-12-01-22/wrench_<i>.csv             (geometry_msgs/Wrench, no header)

(the same blobs are also under model-identification/; navigation_state.csv / wrench.csv are concatenations, and
wrench.csv is >= 4 MiB and absent from the mirror; run 16 is empty).  Files are read with `git cat-file blob`.

Columns written (uvsim docs/log_format.md, SI, NED, body x fwd / y stbd / z down):

    t                      s, uniform grid at --rate Hz, t = 0 at the start of the overlap of both streams
    x, y, z                m, navigation_state position (EKF on DVL + IMU + depth; z = depth, down positive)
    roll, pitch, yaw       rad, navigation_state orientation (r, p, y), ZYX; yaw interpolated unwrapped, wrapped
    u, v, w                m/s, navigation_state velocity, BODY frame (checked: rotating it with the ZYX angles
                           matches the derivative of x, y better than using it as world velocity)
    X, Y, Z, K, M, N       N, N m: the controller's commanded body wrench (wrench_<i>.csv), zero-order hold

Not written: navigation_state angular_velocity (all |value| < 1e-6: not populated by the 2022 estimator) and
acceleration (values like 1e-156: not populated).  There are no thruster commands and no raw gyro in the export.

Timing: navigation rows carry the estimator's header stamp (default --nav-time stamp; `record` uses the bag
receive time instead, which is 0.02-0.3 s later, up to 5.5 s during the first seconds of run 0); wrench rows only
carry the bag receive time.  Sensors use first-order hold and are never extrapolated: grid points outside the
navigation samples or in a gap longer than --max-gap are left empty (NaN).  The converter prints one line per run.
"""
from __future__ import annotations

import argparse
import io
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

DATA_DIR = "dynamics-parameter-estimation/data/bags-12-01-22"
VEHICLE_FILE = Path(__file__).resolve().parent / "tauv_kingfisher2022.yaml"

# Split chosen by us (the team published no split): runs 0-8 change depth (0-1.6 m) while translating and
# turning; runs 9-15 hold ~1 m depth and translate/turn.  Validation takes the later runs of each group.
VALIDATION = {6, 7, 8, 13, 14, 15}
ALL_RUNS = list(range(16))          # run 16 is an empty file
NAV = {"x": "field.position.x", "y": "field.position.y", "z": "field.position.z",
       "roll": "field.orientation.x", "pitch": "field.orientation.y", "yaw": "field.orientation.z",
       "u": "field.velocity.x", "v": "field.velocity.y", "w": "field.velocity.z"}
WRENCH = {"X": "field.force.x", "Y": "field.force.y", "Z": "field.force.z",
          "K": "field.torque.x", "M": "field.torque.y", "N": "field.torque.z"}


def blob(mirror: Path, path: str) -> tuple[str, bytes]:
    rev = subprocess.run(["git", "-C", str(mirror), "rev-parse", f"HEAD:{path}"], check=True,
                         capture_output=True, text=True).stdout.strip()
    data = subprocess.run(["git", "-C", str(mirror), "cat-file", "blob", rev], check=True,
                          capture_output=True).stdout
    return rev, data


def load(mirror: Path, name: str) -> tuple[str, pd.DataFrame]:
    rev, data = blob(mirror, f"{DATA_DIR}/{name}")
    if not data.strip():
        return rev, pd.DataFrame()
    return rev, pd.read_csv(io.BytesIO(data))


def hold_linear(tq: np.ndarray, ts: np.ndarray, ys: np.ndarray, max_gap: float) -> np.ndarray:
    """First-order hold of samples (ts, ys) at tq; NaN outside [ts0, ts-1] and inside gaps > max_gap."""
    out = np.interp(tq, ts, ys)
    idx = np.searchsorted(ts, tq, side="right")
    bad = (idx == 0) | (idx == len(ts))
    inner = ~bad
    gap = np.zeros_like(tq, dtype=bool)
    gap[inner] = (ts[idx[inner]] - ts[idx[inner] - 1]) > max_gap
    out[bad | gap] = np.nan
    return out


def convert_run(mirror: Path, i: int, rate: float, max_gap: float, nav_time: str):
    rev_n, nav = load(mirror, f"navigation_state_{i}.csv")
    rev_w, wr = load(mirror, f"wrench_{i}.csv")
    if nav.empty or wr.empty:
        return None
    tn = (nav["field.header.stamp"] if nav_time == "stamp" else nav["%time"]).to_numpy(np.int64)
    tw = wr["%time"].to_numpy(np.int64)
    # sort and drop duplicate stamps (none in these files, kept for safety)
    order = np.argsort(tn, kind="stable")
    nav, tn = nav.iloc[order], tn[order]
    keep = np.r_[True, np.diff(tn) > 0]
    nav, tn = nav[keep], tn[keep]
    order = np.argsort(tw, kind="stable")
    wr, tw = wr.iloc[order], tw[order]

    t0_ns = max(tn[0], tw[0])
    t1_ns = min(tn[-1], tw[-1])
    n = int(np.floor((t1_ns - t0_ns) * 1e-9 * rate)) + 1
    tq = np.arange(n) / rate
    tn_s = (tn - t0_ns) * 1e-9
    tw_s = (tw - t0_ns) * 1e-9

    cols = {"t": tq}
    for key, col in NAV.items():
        y = nav[col].to_numpy(float)
        if key in ("roll", "pitch", "yaw"):
            y = np.unwrap(y)
        v = hold_linear(tq, tn_s, y, max_gap)
        if key in ("roll", "pitch", "yaw"):
            v = (v + np.pi) % (2 * np.pi) - np.pi
        cols[key] = v
    # zero-order hold of the commanded wrench: latest command at or before each grid time
    j = np.searchsorted(tw_s, tq, side="right") - 1
    j = np.clip(j, 0, len(tw_s) - 1)
    for key, col in WRENCH.items():
        cols[key] = wr[col].to_numpy(float)[j]
    df = pd.DataFrame(cols)

    angv = nav[["field.angular_velocity.x", "field.angular_velocity.y", "field.angular_velocity.z"]].abs().max().max()
    info = {
        "run": i, "rev_nav": rev_n, "rev_wrench": rev_w, "nav_samples": len(nav),
        "nav_median_dt": float(np.median(np.diff(tn_s))), "nav_p99_dt": float(np.percentile(np.diff(tn_s), 99)),
        "wrench_samples": len(wr), "duration": float(tq[-1]), "rows": n,
        "nan_rows": int(df[list(NAV)].isna().any(axis=1).sum()),
        "angular_velocity_max_abs": float(angv),
        "record_minus_stamp_median": float(np.median((nav["%time"].to_numpy(np.int64) - nav["field.header.stamp"].to_numpy(np.int64)) * 1e-9)),
    }
    return df, info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir", type=Path)
    ap.add_argument("--mirror", type=Path, required=True, help="a git clone (bare or not) of Tartan-AUV/TAUV-Playground")
    ap.add_argument("--runs", default=",".join(map(str, ALL_RUNS)), help="comma-separated run numbers (0-15)")
    ap.add_argument("--rate", type=float, default=20.0, help="output grid rate, Hz (default 20)")
    ap.add_argument("--max-gap", type=float, default=0.5, help="longest navigation gap bridged, s (default 0.5)")
    ap.add_argument("--nav-time", choices=("stamp", "record"), default="stamp")
    ap.add_argument("--vehicle-file", type=Path, default=VEHICLE_FILE)
    ap.add_argument("--name", default="tauv_kingfisher_20221201")
    opts = ap.parse_args(argv)

    runs = [int(r) for r in opts.runs.split(",") if r.strip()]
    ds = opts.outdir / opts.name
    ds.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(opts.vehicle_file, ds / opts.vehicle_file.name)
    head = subprocess.run(["git", "-C", str(opts.mirror), "rev-parse", "HEAD"], check=True, capture_output=True,
                          text=True).stdout.strip()

    lines = []
    for i in runs:
        res = convert_run(opts.mirror, i, opts.rate, opts.max_gap, opts.nav_time)
        if res is None:
            print(f"run {i}: empty, skipped")
            continue
        df, info = res
        fname = f"run{i:02d}.csv"
        df.to_csv(ds / fname, index=False, float_format="%.6g")
        split = "validation" if i in VALIDATION else "train"
        rng = lambda c: f"{np.nanmin(df[c]):+.2f}..{np.nanmax(df[c]):+.2f}"
        print(f"run {i:2d} -> {fname} [{split}]: {info['duration']:.2f} s, {info['rows']} rows at {opts.rate:g} Hz; "
              f"nav {info['nav_samples']} samples (median dt {info['nav_median_dt']:.3f} s, p99 {info['nav_p99_dt']:.3f} s), "
              f"wrench {info['wrench_samples']}; NaN rows {info['nan_rows']}; z {rng('z')} m, yaw {rng('yaw')} rad, "
              f"X {rng('X')} Y {rng('Y')} Z {rng('Z')} N, K {rng('K')} M {rng('M')} N {rng('N')} N m; "
              f"|angular_velocity| max {info['angular_velocity_max_abs']:.1e} (not exported)")
        lines.append((fname, split, info))

    with open(ds / "manifest.yaml", "w") as f:
        f.write(f"# Tartan AUV Kingfisher, pool logs 2022-12-01, github.com/Tartan-AUV/TAUV-Playground (HEAD {head[:8]}),\n")
        f.write(f"# {DATA_DIR}/navigation_state_<i>.csv + wrench_<i>.csv.  NO LICENCE: use on your own machine only,\n")
        f.write("# never commit or redistribute these files.  Converted by tauv_to_logformat.py.\n")
        f.write(f"# Options: rate {opts.rate:g} Hz, max gap {opts.max_gap:g} s, nav time {opts.nav_time}.\n")
        f.write("# Inputs X..N are the controller's COMMANDED body wrench (before allocation and thruster saturation);\n")
        f.write("# K is saturated at -1 N m and M near -6 N m in every run (controller limits; a trim moment).\n")
        f.write("# No p, q, r (not logged); u, v, w are DVL/EKF body velocities; x, y dead-reckoned.\n")
        f.write(f"vehicle: {opts.vehicle_file.name}\n")
        f.write("description: Tartan AUV Kingfisher 2022-12-01 pool runs (commanded wrench, EKF pose and body velocity)\n")
        f.write("runs:\n")
        for fname, split, info in lines:
            f.write(f"  # run {info['run']}: nav blob {info['rev_nav'][:10]}, wrench blob {info['rev_wrench'][:10]}, "
                    f"{info['nav_samples']} nav samples, receive-minus-stamp median {info['record_minus_stamp_median']:.3f} s\n")
            f.write(f"  - file: {fname}\n    dof: mixed\n    split: {split}\n")
    print(f"wrote {ds}/manifest.yaml ({len(lines)} runs)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
