"""gz-sim (Gazebo) model export: SDF with the Hydrodynamics and Thruster systems.

What is written (frames and signs: :mod:`uvsim.export.frames`):

* ``<link name="base_link">`` with ``<inertial>``: mass, centre of gravity (``<pose>``,
  FLU) and the inertia tensor about it (``S J S``; SDF ``ixy`` etc. are tensor entries);
* a ``buoyancy_volume`` collision sphere at the centre of buoyancy whose volume is
  ``B / (rho g)``, for the gz-sim Buoyancy system (world plugin, ``uniform_fluid_density``
  = rho), so that ``rho g V = B``;
* the ``gz::sim::systems::Hydrodynamics`` plugin: linear damping ``<xU>`` .. ``<nR>`` and
  quadratic damping ``<xUabsU>`` .. ``<nRabsR>`` (paper sign, negative), each term of the
  FLU matrices ``S6 A S6`` that is non-zero, diagonal always;
* the added mass, by default (``added_mass="fluid"``) as SDF ``<fluid_added_mass>``
  (positive, FLU, about the link origin: gz-math ``Inertial.hh:76-77``; 21 upper-triangle
  entries ``xx`` .. ``rr``), so that the physics engine carries ``M_A`` in the link's
  inertia and applies ``-C_A(v) v`` itself: uvsim's dynamics (:mod:`uvsim.export.plugins`);
* or, only when asked (``added_mass="plugin"``), as the plugin's ``<xDotU>`` .. ``<nDotR>``
  (SNAME sign, the negative of uvsim's ``M_A``), never both.  gz-sim then applies the
  added-mass Coriolis term with the sign opposite to Fossen's (``+C_A(v) v``:
  :data:`uvsim.export.plugins.GZ_CORIOLIS_SOURCE`), uses only the diagonal of ``M_A`` for
  it, and integrates ``M_A v_dot`` from the previous step's finite difference, which
  diverges when ``M_A >= M_RB`` in a DOF (gz-sim#1923); the export warns of each;
* one thruster link (:data:`uvsim.export.frames.THRUSTER_LINK_MASS`, taken out of the
  base link so that the model keeps uvsim's mass, CG and inertia:
  :func:`uvsim.export.frames.base_link_inertial`) + revolute joint per thruster (joint axis =
  thrust direction, FLU) and a ``gz::sim::systems::Thruster`` plugin taking thrust commands
  in newtons (velocity control: no propeller torque), clamped to the curve's range over all
  its voltages.  gz-sim has no PWM input and no table: the curve's PWM -> thrust table
  (:mod:`uvsim.export.thrust_tables`; every voltage sheet of a battery-aware curve) is
  written into the plugin block as ``<uvsim_pwm_to_thrust>`` for the bridge that sends the
  thrust commands (gz-sim ignores it); the replay check reads it from there.

gz-sim integrates the plugin's added mass explicitly from the previous step's
acceleration; with added mass comparable to the rigid mass this diverges (gz-sim issue
#1923: stable only while ``M_A < M_RB`` element-wise).  :func:`added_mass_warnings`
says when a model is in that regime; ``fluid_added_mass`` (DART physics) avoids it.

How the physics engine takes ``<fluid_added_mass>`` (gazebosim/gz-physics commit a43f638a3aef,
``dartsim/src/AddedMassFeatures.cc:35-71``): DART's rigid spatial inertia is built from the
mass, the centre of mass and the inertia about it (DART ``Inertia::computeSpatialTensor``
adds the parallel-axis term), the added mass (read symmetric from its upper triangle:
sdformat ``src/Link.cc:249-295``, commit 2ace536244ac) is added to it about the link origin,
and DART's gravity is switched off for the link and applied as ``m g`` at the centre of mass
instead (``SimulationFeatures.cc:98-111``).  So a CG off the link origin goes across in the
default mode; the replay check uses the same inertia.  Only the dartsim plugin reads
``<fluid_added_mass>`` (``SDFFeatures.cc:747-761``); the bullet-featherstone and mujoco
plugins have no code for it at that commit, so with them the default export would have no
added mass at all: that is what the plugin mode is for, with its warning.
"""
from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from uvsim.errors import VehicleError
from uvsim.export.frames import (FORCE, S3, THRUSTER_LINK_INERTIA, THRUSTER_LINK_MASS, VEL, base_link_inertial,
                                 damping_matrices, frd_to_flu_matrix, frd_to_flu_vector, ned_to_enu)

HYDRO_PLUGIN = ("gz-sim-hydrodynamics-system", "gz::sim::systems::Hydrodynamics")
THRUSTER_PLUGIN = ("gz-sim-thruster-system", "gz::sim::systems::Thruster")
FLUID_KEYS = [a + b for i, a in enumerate("xyzpqr") for b in "xyzpqr"[i:]]
_DOF = ("surge", "sway", "heave", "roll", "pitch", "yaw")


def _num(x) -> str:
    return repr(float(x))


def _sub(parent, tag, text=None, **attrib):
    e = ET.SubElement(parent, tag, attrib)
    if text is not None:
        e.text = text
    return e


def added_mass_warnings(vehicle) -> list[str]:
    """DOFs whose added mass is not below the rigid-body mass/inertia (gz-sim #1923)."""
    MA, MRB = np.diag(vehicle.added_mass_matrix), np.diag(vehicle.M_RB)
    return [f"{_DOF[i]}: added mass {MA[i]:.4g} >= rigid {MRB[i]:.4g}" for i in range(6) if MA[i] >= MRB[i]]


def gz_sdf(vehicle, *, added_mass: str = "fluid", link: str = "base_link") -> tuple[str, list[str]]:
    """SDF text of ``vehicle`` for gz-sim and the warnings to print before writing it.

    ``added_mass``: "fluid" (default: SDF ``<fluid_added_mass>``, carried by the physics
    engine, DART; reproduces uvsim's dynamics) or "plugin" (Hydrodynamics ``xDotU``..
    terms: a warning names where gz-sim's Coriolis sign differs, module docstring).
    What the SDF cannot hold is refused (:class:`uvsim.errors.VehicleError`) or warned."""
    from uvsim.export.plugins import GZ_CORIOLIS_SOURCE

    if added_mass not in ("plugin", "fluid"):
        raise VehicleError(f"added_mass {added_mass!r}: expected 'fluid' or 'plugin'")
    MA = vehicle.added_mass_matrix
    if added_mass == "fluid" and not np.allclose(MA, MA.T, rtol=0, atol=1e-12 * max(1.0, np.abs(MA).max())):
        raise VehicleError(f"{vehicle.source}: the added mass matrix is not symmetric, and SDF <fluid_added_mass> "
                           "holds a symmetric one (sdformat src/Link.cc:249-295 reads its upper triangle); "
                           "symmetrize it in the vehicle file, or export with --added-mass plugin")
    warnings = []
    heavy = added_mass_warnings(vehicle)
    if added_mass == "plugin":
        warnings.append(
            "with plugin added mass gz-sim applies the added-mass Coriolis/centripetal wrench as +C_A(v)v, the "
            "opposite of Fossen's -C_A(v)v that uvsim uses, so the Munk moment is stabilizing in Gazebo and the "
            f"vehicle turns differently: {GZ_CORIOLIS_SOURCE}. Use the default --added-mass fluid (DART), or patch "
            "the plugin (https://github.com/gazebosim/gz-sim/issues).")
        if np.any(MA - np.diag(np.diag(MA))):
            warnings.append("the plugin's Coriolis term uses only the diagonal of the added mass "
                            "(HydrodynamicsUtils.hh:38): the off-diagonal added mass acts in M_A v_dot only")
        if heavy:
            warnings.append(
                "gz-sim integrates the Hydrodynamics plugin's added mass from the previous step's finite-difference "
                "acceleration, which diverges at any physics step when the added mass is not below the rigid-body "
                "mass (gz-sim issue #1923): " + "; ".join(heavy) + ".")
    if vehicle.effects:
        warnings.append(f"effects {[e.kind for e in vehicle.effects]} have no gz-sim counterpart and are not exported: "
                        "the Gazebo model lacks them")
    if added_mass == "fluid" and np.any(np.asarray(vehicle.current_ned, float) != 0):
        warnings.append(
            "with a current the physics engine applies -M_A v_dot with the absolute acceleration (gz-physics "
            "AddedMassFeatures.cc:45-70); the plugin corrects only the Coriolis term to the relative velocity "
            "(Hydrodynamics.cc:593-621), so the Gazebo model lacks uvsim's M_A (w x R^T v_c) (docs/model.md, "
            "nu_r_dot); uvsim export --check measures the difference")
    DL, DQ = damping_matrices(vehicle)
    MA_f, DL_f, DQ_f = (frd_to_flu_matrix(A) for A in (MA, DL, DQ))
    rho, g = vehicle.rho, vehicle.g
    units = _thruster_units(vehicle, warnings)

    sdf = ET.Element("sdf", version="1.11")
    model = _sub(sdf, "model", name=vehicle.name)
    model.append(ET.Comment(
        " exported by uvsim export: link frame FLU (x fwd, y left, z up), world ENU; uvsim's FRD/NED "
        "coefficients A became S A S with S = diag(1,-1,-1,1,-1,-1) (docs/import_export.md) "))
    if added_mass == "fluid":
        model.append(ET.Comment(" the added mass is <fluid_added_mass>, which only the DART physics engine (gz-sim's "
                                "default) carries; other engines ignore it: for them export in the plugin added-mass mode "))
    base = _sub(model, "link", name=link)
    inertial = _sub(base, "inertial")
    mb, cb, Jb = base_link_inertial(vehicle, [u["position"] for u in units])
    if units:
        inertial.append(ET.Comment(f" {len(units)} thruster links of {THRUSTER_LINK_MASS:g} kg are taken out of this "
                                   "link: with them the model has uvsim's mass, CG and inertia "))
    _sub(inertial, "pose", " ".join(_num(x) for x in frd_to_flu_vector(cb)) + " 0 0 0")
    _sub(inertial, "mass", _num(mb))
    J = S3 @ Jb @ S3
    iner = _sub(inertial, "inertia")
    for tag, (i, j) in zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
        _sub(iner, tag, _num(J[i, j]))
    if added_mass == "fluid":
        fam = _sub(inertial, "fluid_added_mass")
        idx = "xyzpqr"
        for key in FLUID_KEYS:
            _sub(fam, key, _num(MA_f[idx.index(key[0]), idx.index(key[1])]))
    V = vehicle.buoyancy / (rho * g)
    col = _sub(base, "collision", name="buoyancy_volume")
    col.append(ET.Comment(f" sphere of volume B/(rho g) = {V:.6g} m^3 at the centre of buoyancy, for the Buoyancy "
                          f"system with uniform_fluid_density {rho:g} and world gravity {g:g} m/s^2 "))
    _sub(col, "pose", " ".join(_num(x) for x in frd_to_flu_vector(vehicle.r_b)) + " 0 0 0")
    _sub(_sub(_sub(col, "geometry"), "sphere"), "radius", _num((3.0 * V / (4.0 * np.pi)) ** (1.0 / 3.0)))

    hyd = _sub(model, "plugin", filename=HYDRO_PLUGIN[0], name=HYDRO_PLUGIN[1])
    _sub(hyd, "link_name", link)
    _sub(hyd, "water_density", _num(rho))
    if np.any(vehicle.current_ned != 0):
        _sub(hyd, "default_current", " ".join(_num(x) for x in ned_to_enu(vehicle.current_ned)))
    for i in range(6):
        for j in range(6):
            name = FORCE[i] + VEL[j]
            if added_mass == "plugin" and (i == j or MA_f[i, j] != 0):
                _sub(hyd, name[0] + "Dot" + name[1], _num(-MA_f[i, j]))
            if i == j or DL_f[i, j] != 0:
                _sub(hyd, name, _num(DL_f[i, j]))
            if i == j or DQ_f[i, j] != 0:
                _sub(hyd, f"{name}abs{VEL[j]}", _num(DQ_f[i, j]))
    _thrusters(model, vehicle, units, link, rho, warnings)
    ET.indent(sdf, "  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(sdf, encoding="unicode") + "\n", warnings


def _thruster_units(vehicle, warnings) -> list[dict]:
    """The vehicle's thruster units (position, direction FRD) or [] with a warning when it has
    thrusters but no geometry to export."""
    act = vehicle.actuators
    spec = (vehicle.raw.get("thrusters") or {}).get("units")
    if act.matrix is None or not spec:
        if act.matrix is not None:
            warnings.append("thrusters given as a configuration matrix: no positions to export, thrusters omitted "
                            "(drive the model with generalized forces)")
        return []
    return list(spec)


def _thrusters(model, vehicle, units, link, rho, warnings) -> None:
    from uvsim.export.thrust_tables import curve_knots, table_warnings, thrust_range

    act = vehicle.actuators
    if units and act.curves:
        warnings.extend(table_warnings(vehicle, "gz-sim"))
    for i, unit in enumerate(units):
        name = f"thruster_{i + 1}"
        d = np.asarray(unit["direction"], float)
        d = frd_to_flu_vector(d / np.linalg.norm(d))
        p = frd_to_flu_vector(unit["position"])
        lk = _sub(model, "link", name=name)
        lk.append(ET.Comment(f" {act.names[i]} "))
        _sub(lk, "pose", " ".join(_num(x) for x in p) + " 0 0 0")
        li = _sub(lk, "inertial")
        _sub(li, "mass", _num(THRUSTER_LINK_MASS))  # taken out of base_link (frames.base_link_inertial)
        ii = _sub(li, "inertia")
        for tag in ("ixx", "iyy", "izz"):
            _sub(ii, tag, _num(THRUSTER_LINK_INERTIA))
        jt = _sub(model, "joint", name=f"{name}_joint", type="revolute")
        _sub(jt, "parent", link)
        _sub(jt, "child", name)
        _sub(_sub(jt, "axis"), "xyz", " ".join(_num(x) for x in d))
        pl = _sub(model, "plugin", filename=THRUSTER_PLUGIN[0], name=THRUSTER_PLUGIN[1])
        _sub(pl, "namespace", vehicle.name)
        _sub(pl, "joint_name", f"{name}_joint")
        _sub(pl, "fluid_density", _num(rho))
        # velocity control: the plugin commands the propeller joint's speed and applies no PID torque
        # about the thrust axis (gz-sim Thruster.cc:725-760, commit 93bbf3ed1bd2), so the base link gets
        # the thrust alone, as in uvsim (which models no propeller reaction torque)
        _sub(pl, "velocity_control", "true")
        curve = act.curves[i] if act.curves else None
        if curve is None:
            continue
        lo, hi = thrust_range(curve)
        _sub(pl, "max_thrust_cmd", _num(hi))
        _sub(pl, "min_thrust_cmd", _num(lo))
        pwm, thrust = curve_knots(curve)
        tab = _sub(pl, "uvsim_pwm_to_thrust", curve=str(curve.name))
        tab.append(ET.Comment(" for the bridge that turns ESC PWM into this plugin's thrust commands (N), interpolated "
                              "linearly; gz-sim ignores this element "))
        _sub(tab, "pwm_us", " ".join(_num(x) for x in pwm))
        _sub(tab, "thrust_n", " ".join(_num(x) for x in thrust))
        if getattr(curve, "voltage_dependent", False):
            tab.set("nominal_voltage", _num(curve.nominal_voltage))
            for v, sheet in zip(curve.voltages, curve.table_thrust):
                _sub(tab, "thrust_n", " ".join(_num(x) for x in sheet), voltage=_num(v))


def _floats(text: str) -> np.ndarray:
    return np.array([float(x) for x in text.split()])


def parse_gz_sdf(text: str) -> dict:
    """Numbers of an SDF written by :func:`gz_sdf`, in the file's own frame (FLU) and signs.

    ``mass``, ``cg``, ``inertia_cg``: the base link's; ``thrusters``: one dict per thruster
    joint with ``position``, ``axis``, ``mass``, ``inertia`` of its link, the plugin's
    ``min``/``max`` thrust command and, when written, its PWM table (``pwm``, ``thrust``,
    ``sheets`` {voltage: thrust})."""
    root = ET.fromstring(text)
    model = root.find("model")
    base = model.find("link")
    inertial = base.find("inertial")
    out = {"mass": float(inertial.find("mass").text), "inertia_cg": _inertia(inertial),
           "cg": _floats(inertial.find("pose").text)[:3]}
    fam = inertial.find("fluid_added_mass")
    hyd = next(p for p in model.findall("plugin") if p.get("name") == HYDRO_PLUGIN[1])
    MA, DL, DQ = np.zeros((6, 6)), np.zeros((6, 6)), np.zeros((6, 6))
    for i in range(6):
        for j in range(6):
            name = FORCE[i] + VEL[j]
            for tag, A, sign in ((name[0] + "Dot" + name[1], MA, -1.0), (name, DL, 1.0), (f"{name}abs{VEL[j]}", DQ, 1.0)):
                e = hyd.find(tag)
                if e is not None:
                    A[i, j] = sign * float(e.text)
    if fam is not None:
        if np.any(MA):
            raise VehicleError("SDF has both <fluid_added_mass> and Hydrodynamics xDotU terms")
        idx = "xyzpqr"
        for key in FLUID_KEYS:
            i, j = idx.index(key[0]), idx.index(key[1])
            MA[i, j] = MA[j, i] = float(fam.find(key).text)
    cur = hyd.find("default_current")
    out.update(added_mass=MA, linear=DL, quadratic=DQ, fluid_added_mass=fam is not None,
               water_density=float(hyd.find("water_density").text),
               current_enu=np.zeros(3) if cur is None else _floats(cur.text))
    col = base.find("collision")
    r = float(col.find("geometry/sphere/radius").text)
    out["buoyancy_volume"] = 4.0 / 3.0 * np.pi * r ** 3
    out["cb"] = _floats(col.find("pose").text)[:3]
    plugins = {p.find("joint_name").text: p for p in model.findall("plugin") if p.get("name") == THRUSTER_PLUGIN[1]}
    thr = []
    for jt in model.findall("joint"):
        child = model.find(f"link[@name='{jt.find('child').text}']")
        li = child.find("inertial")
        th = {"position": _floats(child.find("pose").text)[:3], "axis": _floats(jt.find("axis/xyz").text),
              "mass": float(li.find("mass").text), "inertia": _inertia(li)}
        pl = plugins.get(jt.get("name"))
        if pl is not None and pl.find("max_thrust_cmd") is not None:
            th.update(min=float(pl.find("min_thrust_cmd").text), max=float(pl.find("max_thrust_cmd").text))
        tab = None if pl is None else pl.find("uvsim_pwm_to_thrust")
        if tab is not None:
            th["pwm"] = _floats(tab.find("pwm_us").text)
            th["sheets"] = {}
            for e in tab.findall("thrust_n"):
                if e.get("voltage") is None:
                    th["thrust"] = _floats(e.text)
                else:
                    th["sheets"][float(e.get("voltage"))] = _floats(e.text)
        thr.append(th)
    out["thrusters"] = thr
    return out


def _inertia(inertial) -> np.ndarray:
    """3x3 inertia tensor of an SDF ``<inertial>`` (missing products are 0)."""
    J = np.zeros((3, 3))
    for tag, (i, j) in zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
        e = inertial.find(f"inertia/{tag}")
        J[i, j] = J[j, i] = 0.0 if e is None else float(e.text)
    return J
