"""Issue 48: a log without x/y (an ROV's attitude, depth and DVL) gives a tether its geometry.

A tether pulls towards its anchor, so the model reads the horizontal position, which field logs
do not have.  Before, the equation-error screening put the vehicle at x = y = 0 for the whole run,
each 5-s window of a closed-loop verdict restarted at the run's origin, and a fit's window nodes
took x/y from a free simulation that had lost the heading under the autopilot: the pull pointed
the same way wherever the vehicle went.  Now all three use the track dead-reckoned from the logged
attitude and DVL velocity (uvsim.fitting.dead_reckoning)."""
from __future__ import annotations

import numpy as np
import pytest

from uvsim.fitting.dead_reckoning import dead_reckoned_xy
from uvsim.fitting.equation_error import motion_or_why
from uvsim.fitting.evaluate import windowed
from uvsim.fitting.nodes import NodeModel
from uvsim.latency import runs_for
from uvsim.logs import read_dataset
from uvsim.measurements import measurements_for
from uvsim.vehicle import load_vehicle


@pytest.fixture(scope="module")
def tether(tmp_path_factory):
    from uvsim.scenarios.field import generate_field, sample_field, simulate_field

    spec = sample_field(7, "tether")   # 41-s runs at 5 Hz, DVL drop-outs of 0.6-6 s
    sim = simulate_field(spec)         # the flight the logs were written from
    out = generate_field(spec, tmp_path_factory.mktemp("dr") / "tether7", sim=sim)
    ds = read_dataset(out)
    veh = load_vehicle(ds.vehicle_file)
    step = int(round(spec["control_hz"] / spec["log_hz"]))
    return veh, ds, sim["pos"][:, ::step], spec, sim


def test_the_track_follows_the_truth_within_the_dvl_and_heading_errors(tether):
    veh, ds, pos, *_ = tether
    for i, run in enumerate(ds.runs):
        xy = dead_reckoned_xy(run)
        truth = pos[i, : run.t.size, :2]
        assert xy.shape == (run.t.size, 2) and np.all(xy[0] == 0.0)
        run_m = np.linalg.norm(truth - truth[0], axis=1).max()
        # DVL drop-outs bridged, a filter yaw without a compass: within 15 % of the distance run
        assert np.abs(xy - (truth - truth[0])).max() < 0.15 * run_m


def test_a_run_that_logs_x_and_y_has_no_dead_reckoned_track(tether):
    run = tether[1].runs[0]
    import copy

    r = copy.copy(run)
    r.data = run.data.assign(x=0.0, y=0.0)
    assert dead_reckoned_xy(r) is None


def test_the_screening_and_the_fit_nodes_read_the_track(tether):
    veh, ds, *_ = tether
    run = runs_for(veh, ds.train)[0]
    xy = dead_reckoned_xy(run)
    motion, why = motion_or_why(run)
    assert why is None and np.allclose(motion.y[:, :2], xy)          # was 0 over the whole run
    m = measurements_for(run, veh, run_weight=1.0)
    idx = np.array([0, run.t.size // 2, run.t.size - 1])
    ref, sigma = NodeModel(run, m).references(idx, np.zeros((run.t.size, 13)))
    assert np.allclose(ref[:, :2], xy[idx])                          # was the reference simulation's
    # a model that reads no x/y keeps the reference simulation's (they only shift its windows)
    ref0, _ = NodeModel(run, m).references(idx, np.zeros((run.t.size, 13)), xy_track=False)
    assert np.all(ref0[:, :2] == 0.0)


def test_a_window_starts_where_the_track_is_when_a_term_reads_the_position(tether):
    veh, ds, _, spec, _ = tether
    teth = veh.with_effects([{"type": "tether", "stiffness": 1.0, "anchor_n": 5.0, "anchor_e": 4.0}])
    val = runs_for(teth, ds.validation)
    meas = [measurements_for(r, teth, run_weight=1.0) for r in val]
    for run, r in zip(val, windowed(teth, val, 4.0, meas=meas)):
        xy = dead_reckoned_xy(run)
        assert len(r["starts"]) >= 8
        for s in r["starts"]:   # before: every window at x = y = 0
            assert np.allclose(r["states"][s, :2], xy[s], atol=1e-9)


def test_with_a_track_the_horizontal_tethers_are_screened_and_not_reported_unobservable(tether):
    """Before, a log without x/y left the horizontal pulls out ("not observable": the model's own
    x/y); the field tethers pull mostly horizontally (a spool at the surface, 3-8 m away)."""
    from uvsim.diagnosis.candidates import catalogue, observability
    from uvsim.diagnosis.core import _split
    from uvsim.diagnosis.selector import Selector

    veh, ds, *_ = tether
    train, val, _ = _split(ds)
    sel = Selector(veh, train, val, retune=[], noise=None, weights=None, horizon=3.0, max_iter=12, workers=1,
                   say=lambda m: None)
    has_pos, p_ref, z_max, has_depth = sel.signals()
    assert sel.has_track and has_pos and has_depth
    got = {c.variant for c in catalogue(input_kind=train[0].input_kind, n_thrusters=veh.n_thrusters, dt=0.2,
                                        p_ref=p_ref, has_position=has_pos, z_max=z_max, has_depth=has_depth,
                                        only=["tether"])}
    assert {"horizontal", "horizontal_slack", "horizontal_full", "3d_attach"} <= got
    assert not [o for o in observability(has_position=has_pos, has_depth=has_depth, has_velocity=True, z_max=z_max,
                                         n_thrusters=veh.n_thrusters) if o["effect"] == "tether"]


def test_nodes_read_channels_logged_at_5_hz(tether):
    """Issue 48 item 3: the window-start states take a 5 Hz channel's own samples (a local fit over
    +-2.5 of its sample intervals), not the whole-run simulation's value: at +-0.3 s a 5 Hz DVL or a
    5 Hz log held 3 samples, fewer than the quadratic's 5, and every node velocity, angle and rate came
    from a simulation that under the autopilot had lost the heading."""
    from uvsim.fitting.nodes import NODE_HALF_WINDOW_S, PRIOR_SIGMA, half_width

    veh, ds, _, spec, sim = tether
    assert spec["log_hz"] == 5.0
    run = runs_for(veh, ds.train)[0]
    m = measurements_for(run, veh, run_weight=1.0)
    assert half_width(run.t, run.velocity[:, 0]) == pytest.approx(0.5, abs=0.02)      # the DVL's 0.2 s
    assert half_width(run.t, run.depth) == pytest.approx(0.5, abs=0.02)               # the log's 5 Hz
    assert half_width(np.arange(0.0, 10.0, 0.02), np.ones(500)) == NODE_HALF_WINDOW_S  # 50 Hz as before
    idx = np.arange(5, run.t.size - 5, 15)
    wrong = np.zeros((run.t.size, 13))
    wrong[:, 3] = 1.0                  # a reference simulation that knows nothing: level, at rest, heading 0
    ref, sigma = NodeModel(run, m).references(idx, wrong)
    dvl = np.isfinite(run.velocity[:, 0])
    h = half_width(run.t, run.velocity[:, 0])
    near = np.array([(dvl & (np.abs(run.t - run.t[i]) <= h)).sum() >= 5 for i in idx])
    assert near.sum() >= 5
    step = int(round(spec["control_hz"] / spec["log_hz"]))
    nu_true = sim["nu"][0, ::step][idx]
    # the DVL's velocities where it has samples around the node: measured, within 3 cm/s of the truth
    assert np.all(sigma[near, 6:9] == PRIOR_SIGMA["measured"][6:9])
    assert np.abs(ref[near, 7:10] - nu_true[near, :3]).max() < 0.03
    # the angles and rates of the 5 Hz log everywhere: measured, not the reference's zeros
    assert np.all(sigma[:, 3:6] == PRIOR_SIGMA["measured"][3:6]) and np.all(sigma[:, 9:12] == PRIOR_SIGMA["measured"][9:12])
    assert np.abs(ref[:, 10:13] - nu_true[:, 3:]).max() < 0.05
