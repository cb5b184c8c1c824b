"""``uvsim demo`` (the simulation part; the calibration step is covered by the calibration tests)."""
from uvsim.cli import main


def test_demo_simulation_part(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--skip-calibration"]) == 0
    out = capsys.readouterr().out
    assert "60 synthetic tank runs" in out and "position_m RMSE" in out
    assert (tmp_path / "tank_runs.png").stat().st_size > 10_000
    # the model that generated the data fits it far better than the initial estimates in sway and yaw
    rows = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 5 and parts[2] == "RMSE":
            rows[(parts[0], parts[1])] = (float(parts[3]), float(parts[4]))
    assert rows[("sway", "position_m")][0] < 0.5 * rows[("sway", "position_m")][1]
    assert rows[("yaw", "attitude_rad")][0] < 0.1 * rows[("yaw", "attitude_rad")][1]
    assert rows[("surge", "position_m")][0] < 0.015  # near the 2 mm noise plus initial-state error
