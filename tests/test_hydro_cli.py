"""`uvsim hydro` command line and the benchmark entry point."""
import json


from uvsim.cli import main


def test_hull_json(capsys):
    assert main(["hydro", "remus100", "--re", "2.9e6", "--speed", "1.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"jorgensen", "datcom"}
    for m in out.values():
        assert set(m) == {"Xuu", "Yvv", "Zww"} and all(v > 0 for v in m.values())


def test_hull_from_speed_text(capsys):
    assert main(["hydro", "remus100", "--speed", "1.5"]) == 0
    assert "Re = 1.999e+06" in capsys.readouterr().out  # 1.5 * 1.3327 / 1e-6


def test_errors(capsys):
    assert main(["hydro", "no_such_hull", "--re", "1e6"]) == 2
    assert "unknown hull" in capsys.readouterr().err
    assert main(["hydro", "remus100"]) == 2
    assert main(["hydro", "table", "remus100"]) == 2  # --out missing


def test_table_command(tmp_path, capsys):
    assert main(["hydro", "table", "remus100", "--out", str(tmp_path), "--n-re", "5", "--plot"]) == 0
    assert (tmp_path / "remus100_multifidelity.csv").exists()
    for k in ("CL", "CD", "CM"):
        assert (tmp_path / f"remus100_multifidelity_{k}.png").stat().st_size > 1000
    assert main(["hydro", "table", "naca0015", "--out", str(tmp_path), "--n-re", "3"]) == 0
    assert (tmp_path / "naca0015.csv").exists()


def test_benchmark_quick():
    from uvsim.benchmarks import hydro
    res = hydro.run(quick=True)
    assert set(res) <= set(hydro.DESCRIPTIONS) and res["hydro_lookup_us"] > 0
