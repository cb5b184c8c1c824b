"""Hull geometry: Myring profile, derived areas/volumes, bad input."""
import numpy as np
import pytest

from uvsim.errors import HydroError
from uvsim.hydro.geometry import (HullGeometry, builtin_hulls, hull_from_dict, hull_from_stations,
                                  load_hull, myring_profile)


def test_remus_myring_matches_prestero_dimensions():
    # Prestero (2001) Table 2.1: L = 1.33 m, l_f = 82.8 cm, d = 19.1 cm.
    h = load_hull("remus100")
    assert "remus100" in builtin_hulls()
    assert h.length == pytest.approx(1.3327, abs=1e-4)
    assert h.meta["a"] - h.meta["a_offset"] + h.meta["b"] == pytest.approx(0.828, abs=1e-3)
    assert h.diameter == pytest.approx(0.191, rel=1e-9)
    # Volume between a cylinder of the same L, d and half of it (nose/tail taper)
    cyl = np.pi * 0.0955 ** 2 * h.length
    assert 0.6 * cyl < h.volume < cyl
    # Tail is truncated: base diameter > 0, x0 on the tail, S0 < max area
    assert 0 < h.base_area < h.frontal_area
    assert h.x0 > 0.8285 and 0 < h.s0 < h.frontal_area


def test_cylinder_integrals_exact():
    x = np.linspace(0, 2.0, 201)
    h = hull_from_stations(x, np.full_like(x, 0.1))
    assert h.volume == pytest.approx(np.pi * 0.01 * 2.0, rel=1e-12)
    assert h.planform_area == pytest.approx(0.4, rel=1e-12)
    assert h.planform_centroid == pytest.approx(1.0, rel=1e-12)
    assert h.wetted_area == pytest.approx(2 * np.pi * 0.1 * 2.0, rel=1e-12)
    assert h.base_area == pytest.approx(np.pi * 0.01)


def test_cone_volume_and_centroid():
    x = np.linspace(0, 1.0, 2001)
    h = hull_from_stations(x, 0.2 * x)  # cone, apex at the nose
    assert h.volume == pytest.approx(np.pi * 0.04 / 3, rel=1e-5)
    assert h.volume_centroid == pytest.approx(0.75, rel=1e-4)
    assert h.planform_centroid == pytest.approx(2 / 3, rel=1e-4)


@pytest.mark.parametrize("kw,match", [
    (dict(a=-0.1, b=0.5, c=0.5, d=0.2), "a must be > 0"),
    (dict(a=0.1, b=0.5, c=0.5, d=0.0), "d must be > 0"),
    (dict(a=0.1, b=-0.5, c=0.5, d=0.2), "b must be >= 0"),
    (dict(a=0.1, b=0.5, c=0.5, d=0.2, a_offset=0.2), "offsets"),
])
def test_bad_myring_parameters(kw, match):
    with pytest.raises(HydroError, match=match):
        myring_profile(**kw)


def test_bad_stations():
    with pytest.raises(HydroError, match="strictly increasing"):
        hull_from_stations([0, 1, 0.5], [0, 0.1, 0])
    with pytest.raises(HydroError, match="maximum diameter"):
        hull_from_stations([0, 1, 2], [0, 0, 0])
    with pytest.raises(HydroError, match=">= 0"):
        hull_from_stations([0, 1, 2], [0, -0.1, 0])
    with pytest.raises(HydroError, match="strictly increasing"):  # zero length
        hull_from_stations([0, 0, 0], [0, 0.1, 0])
    with pytest.raises(HydroError, match="unknown myring"):
        hull_from_dict({"myring": {"a": 1, "b": 1, "c": 1, "d": 0.1, "lenght": 3}})
    with pytest.raises(HydroError, match="unknown hull"):
        load_hull("no_such_hull")


def test_hull_yaml_file(tmp_path):
    p = tmp_path / "tube.yaml"
    p.write_text("name: tube\nstations:\n  x: [0, 0.5, 1.0]\n  r: [0.05, 0.05, 0.05]\n")
    h = load_hull(p)
    assert h.name == "tube" and h.length == 1.0
    p.write_text("name: tube\nstations:\n  x: [0, 0.5]\n")
    with pytest.raises(HydroError, match="tube.yaml"):
        load_hull(p)


def _cylinder_triangles(n=64, r=0.1, length=1.0):
    th = np.linspace(0, 2 * np.pi, n + 1)
    tris = []
    for i in range(n):
        p = [np.array([x, r * np.cos(t), r * np.sin(t)]) for x in (0.0, length) for t in (th[i], th[i + 1])]
        tris += [[p[0], p[1], p[3]], [p[0], p[3], p[2]]]
    return np.array(tris)


def test_mesh_slicing():
    from uvsim.hydro.geometry import hull_from_triangles
    h = hull_from_triangles(_cylinder_triangles(), n_stations=50)
    assert h.length == pytest.approx(1.0)
    assert h.diameter == pytest.approx(0.2, rel=1e-3)
    assert h.volume == pytest.approx(np.pi * 0.01, rel=2e-3)
    with pytest.raises(HydroError, match="shape"):
        hull_from_triangles(np.zeros((4, 3)))


def test_stl_file(tmp_path):
    stl = pytest.importorskip("stl")  # optional extra 'cad' (numpy-stl)
    from uvsim.hydro.geometry import hull_from_stl
    tris = _cylinder_triangles()
    m = stl.mesh.Mesh(np.zeros(len(tris), dtype=stl.mesh.Mesh.dtype))
    m.vectors[:] = tris
    f = tmp_path / "cyl.stl"
    m.save(str(f))
    assert hull_from_stl(f, n_stations=50).diameter == pytest.approx(0.2, rel=1e-3)


def test_geometry_dataclass_is_validated():
    with pytest.raises(HydroError, match="equal length"):
        HullGeometry(x=np.array([0.0, 1.0, 2.0]), r=np.array([0.1, 0.1]))
