"""Torsional dynamics with backlash (thesis 3.3-3.4) and the dynamic-load coupling (3.5)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from physics.dynamics.kernels import _entry_shift
from physics.dynamics.model import (
    EXACT_PHASES,
    anti_aliased,
    anti_aliasing_filter,
    build_model,
    force_per_position,
    simulate,
    simulate_two_dof,
    time_step,
)
from physics.gear.stiffness import MeshStiffness
from physics.params import Dynamics, Operating, Scenario
from physics.signals.order_analysis import (
    LINE_ORDERS,
    MESH_ORDERS,
    mesh_harmonic_levels,
    mesh_harmonic_phases,
    mesh_lines,
)

QUIET = Dynamics(eccentricity1_um=0.0, profile_error_um=0.0)


@pytest.fixture(scope="module")
def ms():
    return MeshStiffness(Scenario().gear, Scenario().material)


def _scn(**dyn):
    return Scenario(dynamics=dataclasses.replace(Dynamics(), **dyn))


def test_spectrum_peaks_at_mesh_frequency_and_harmonics(ms):
    scn = _scn(duration_s=0.5)
    resp = simulate(build_model(scn, ms), scn.dynamics)
    x = resp.dte[0] - resp.dte[0].mean()
    f = np.fft.rfftfreq(len(x), 1 / scn.dynamics.sample_rate_hz)
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    f_mesh = 2000 * 18 / 60
    assert f[np.argmax(spec)] == pytest.approx(f_mesh, rel=0.01)
    for h in (1, 2, 3):
        band = (f > 0.9 * h * f_mesh) & (f < 1.1 * h * f_mesh)
        assert f[band][np.argmax(spec[band])] == pytest.approx(h * f_mesh, rel=0.01)


def test_static_limit_returns_the_static_transmission_error(ms):
    scn = Scenario(operating=Operating(n1_rpm=5.0),
                   dynamics=dataclasses.replace(QUIET, duration_s=1.0, transient_s=0.01,
                                                sample_rate_hz=4096.0))
    model = build_model(scn, ms)
    resp = simulate(model, scn.dynamics)
    idx = model.phase_index(resp.time)
    static = model.half_backlash + model.static_force / (model.k_a[idx] + model.k_b[idx])
    rel = np.abs(resp.dte[0] - static) / (static - model.half_backlash)
    assert np.median(rel) < 2e-3
    assert np.percentile(rel, 98) < 2e-2  # but for the ringing right after a stiffness jump


def test_static_limit_follows_the_flanks_form_deviation(ms):
    """A form deviation is a gap on every pinion flank: at a crawl the DTE is the stiffness-
    weighted mean of the pairs' gaps plus the static deflection,
    ``x = b + (W + k_a g_a + k_b g_b) / (k_a + k_b)``, by hand."""
    scn = Scenario(operating=Operating(n1_rpm=5.0),
                   dynamics=dataclasses.replace(QUIET, duration_s=1.0, transient_s=0.01,
                                                sample_rate_hz=4096.0, form_deviation_um=3.0,
                                                form_waves=3.0, form_phase_rad=0.7))
    model = build_model(scn, ms)
    assert np.ptp(model.g_a) == pytest.approx(6e-6, rel=0.02)  # the wave on the flank
    resp = simulate(model, scn.dynamics)
    i = model.phase_index(resp.time)
    k_a, k_b = model.k_a[i], model.k_b[i]
    static = model.half_backlash + (model.static_force + k_a * model.g_a[i]
                                    + k_b * model.g_b[i]) / (k_a + k_b)
    involute = model.half_backlash + model.static_force / (k_a + k_b)
    err = np.abs(resp.dte[0] - static) / np.ptp(static - involute)
    assert np.median(err) < 0.02
    assert np.median(np.abs(resp.dte[0] - involute)) > 0.2 * np.ptp(static - involute)


def test_a_flank_form_reshapes_the_transmission_error_and_none_leaves_the_involute(ms):
    """The same wave on every pinion flank repeats at the mesh frequency: it moves the mesh
    harmonics' levels and phases of the DTE (the features the surrogate reads); at amplitude 0
    the model is the declared one, table for table."""
    involute = build_model(_scn(), ms)
    zero = build_model(_scn(form_deviation_um=0.0, form_waves=3.0, form_phase_rad=1.0), ms)
    assert np.array_equal(zero.g_a, involute.g_a) and np.array_equal(zero.g_b, involute.g_b)
    formed = _scn(form_deviation_um=3.0, form_waves=3.0, form_phase_rad=1.0)
    fs, f_mesh = formed.dynamics.sample_rate_hz, 2000 * 18 / 60
    a = simulate(involute, formed.dynamics).dte
    b = simulate(build_model(formed, ms), formed.dynamics).dte
    la, lb = mesh_harmonic_levels(a, fs, f_mesh), mesh_harmonic_levels(b, fs, f_mesh)
    pa, pb = mesh_harmonic_phases(a, fs, f_mesh), mesh_harmonic_phases(b, fs, f_mesh)
    turn = [np.degrees(abs(np.angle((pb[f"mesh{k}_cos"] + 1j * pb[f"mesh{k}_sin"])
                                    / (pa[f"mesh{k}_cos"] + 1j * pa[f"mesh{k}_sin"]))))[0]
            for k in MESH_ORDERS]
    assert max(abs(lb[k] - la[k])[0] for k in la) > 1.0  # dB
    assert max(turn) > 30.0  # degrees


def _lines(response, scn) -> np.ndarray:
    """The DTE's mesh lines 1-6 against mesh phase zero (t = 0), as complex numbers [m]."""
    f_mesh = scn.operating.n1_rpm / 60 * scn.gear.z1
    z = mesh_lines(response.dte, scn.dynamics.sample_rate_hz, f_mesh,
                   2 * np.pi * f_mesh * response.time[0])
    return np.stack([z[f"line{k}_re"] + 1j * z[f"line{k}_im"] for k in LINE_ORDERS], -1)


def test_the_wears_vector_change_of_the_lines_is_blind_to_the_flank_form(ms):
    """The dynamic DTE is linear in the gap while the flanks stay in contact, so a wear adds
    the same vector to each mesh line whatever flank form it wears into (the premise of the
    baseline reading, ``surrogate.schema.vector_magnitudes``); the form itself moves the lines
    by more than the wear does."""
    geom = ms.geometry
    s = np.linspace(geom.s_start, geom.s_start + geom.path_length, 201)
    wear = 4e-6 * (s / np.abs(s).max()) ** 2  # deepest at root and tip, none at the pitch point
    involute, formed = _scn(), _scn(form_deviation_um=5.0, form_waves=3.0, form_phase_rad=1.0)
    models = [build_model(involute, ms), build_model(involute, ms, s, wear),
              build_model(formed, ms), build_model(formed, ms, s, wear)]
    z = _lines(simulate(models, involute.dynamics, every_phase=False), involute)
    change_involute, change_formed = z[1] - z[0], z[3] - z[2]
    assert np.abs(change_formed - change_involute).max() < 1e-3 * np.abs(change_involute).max()
    assert np.abs(z[2] - z[0]).max() > 2 * np.abs(change_involute).max()


def test_dead_zone_inert_without_contact_loss(ms):
    a, b = _scn(half_backlash_um=47.5), _scn(half_backlash_um=0.0)
    ra = simulate(build_model(a, ms), a.dynamics)
    rb = simulate(build_model(b, ms), b.dynamics)
    assert ra.force.min() > 0  # contact never lost
    assert np.allclose(ra.dte - rb.dte, 47.5e-6, atol=1e-12)
    assert np.allclose(ra.force, rb.force, rtol=1e-9)


def test_contact_loss_enters_the_dead_zone(ms):
    """Mesh resonance at a light load throws the teeth apart: x < Delta_n, no elastic force."""
    j1, j2 = build_model(Scenario(), ms).inertias
    dyn = dataclasses.replace(Dynamics(), inertia1_kg_m2=100 * j1, inertia2_kg_m2=100 * j2,
                              damping_ratio=0.02)
    f_n = build_model(Scenario(dynamics=dyn), ms).omega_max / (2 * np.pi)
    scn = Scenario(operating=Operating(n1_rpm=f_n * 60 / 18, torque_Nm=50.0), dynamics=dyn)
    model = build_model(scn, ms)
    resp = simulate(model, dyn)
    # the state at the sample instants: the DTE the integrator reached and the pairs' loads
    # there (resp.dte and resp.force are the sensors' band-limited records of them)
    force = resp.load_a[0] + resp.load_b[0]
    apart = force == 0.0
    assert apart.mean() > 0.05
    # while apart the teeth transmit nothing, and the mesh force never pulls
    assert force.min() >= 0.0
    assert force.max() > 2 * model.static_force  # and the impacts that follow are hard
    # the sensed DTE dips below the dead zone's edge where the flanks parted
    assert np.mean(resp.dte[0][apart] < model.half_backlash) > 0.5


def test_two_dof_and_reduced_forms_agree(ms):
    """The compiled reduced integrator against solve_ivp on the two-inertia equations, the
    reference sampled like the integrator's record (the DTE at every step, the force averaged
    over every step by Simpson's rule) and passed through the same anti-aliasing filter as
    the sensors' records. The reference's tolerances (rtol 1e-7) move the difference by less
    than 1e-6 of the range from rtol 1e-9's; the two agree within 0.03 % (DTE) and 0.05 %
    (force) of the range."""
    scn = _scn(duration_s=0.004, transient_s=0.0)
    model = build_model(scn, ms)
    resp = simulate(model, scn.dynamics)
    dt, n_sub = time_step([model], scn.dynamics)
    half = (len(anti_aliasing_filter(n_sub)) - 1) // (2 * n_sub)
    n_out = resp.dte.shape[1]
    steps = np.arange(2 * (n_sub - half * n_sub), 2 * (n_out + half) * n_sub + 3) / 2
    x, force = simulate_two_dof(model, resp.time[0] + (steps - n_sub) * dt, rtol=1e-7,
                                atol=1e-11)
    x = x[:-2:2]
    force = (force[:-2:2] + 4 * force[1::2] + force[2::2]) / 6
    assert np.max(np.abs(anti_aliased(x, n_sub, n_out) - resp.dte[0])) < 1e-3 * np.ptp(resp.dte)
    assert (np.max(np.abs(anti_aliased(force, n_sub, n_out) - resp.force[0]))
            < 1e-3 * np.ptp(resp.force))


def test_records_are_anti_aliased():
    """A tone the integrator's record carries above (1 - PASS_EDGE) fs does not fold into the
    band; one below PASS_EDGE fs passes unchanged, at its own sample instants."""
    n_sub, n_out = 10, 4096
    half = (len(anti_aliasing_filter(n_sub)) - 1) // (2 * n_sub)
    steps = np.arange(n_sub - half * n_sub, (n_out + half) * n_sub + 1)
    phase = 2 * np.pi * steps / n_sub  # one cycle per output sample: frequency fs
    for f_rel, gain in ((0.3, 1.0), (0.45, 1.0), (0.58, 0.0), (0.97, 0.0), (3.02, 0.0)):
        y = anti_aliased(np.cos(f_rel * phase), n_sub, n_out)
        expected = gain * np.cos(2 * np.pi * f_rel * (np.arange(n_out) + 1))
        assert np.max(np.abs(y - expected)) < 2e-4, f_rel


def test_step_halving_converges(ms):
    peaks = []
    for factor in (0.5, 0.25, 0.125):
        scn = _scn(step_factor=factor, duration_s=0.02)
        resp = simulate(build_model(scn, ms), scn.dynamics)
        peaks.append(resp.dte[0])
    d1 = np.max(np.abs(peaks[0] - peaks[1]))
    d2 = np.max(np.abs(peaks[1] - peaks[2]))
    assert d2 < 0.25 * d1 or d2 < 1e-9
    assert d2 < 1e-3 * np.ptp(peaks[2])


def test_step_is_chosen_from_the_highest_natural_frequency(ms):
    model = build_model(Scenario(), ms)
    dt, n_sub = time_step([model], Dynamics())
    assert dt * model.omega_max <= 0.25
    assert n_sub * dt == pytest.approx(1 / 40960)


def test_batch_equals_single_runs(ms):
    a = build_model(Scenario(), ms)
    b = build_model(Scenario(operating=Operating(n1_rpm=1800.0, torque_Nm=290.0)), ms)
    dyn = dataclasses.replace(Dynamics(), duration_s=0.01)
    both = simulate([a, b], dyn)
    assert np.array_equal(both.dte[1], simulate(b, dyn).dte[0])
    assert np.array_equal(both.force[0], simulate(a, dyn).force[0])


def test_mean_dynamic_force_is_the_static_load(ms):
    """Over whole mesh periods the mean mesh force balances the torque (momentum balance)."""
    scn = _scn(duration_s=0.5)
    model = build_model(scn, ms)
    resp = simulate(model, scn.dynamics)
    assert resp.force.mean() == pytest.approx(model.static_force, rel=5e-3)
    s = model.geometry.grid(401)
    per_position = force_per_position(model, resp.force_by_phase[0], s)
    assert per_position.min() < model.static_force < per_position.max()


def test_wear_gap_unloads_the_worn_pair(ms):
    g = ms.geometry
    s = g.grid(401)
    wear = np.where(s < g.single_zone[0], 5e-6, 0.0)  # the approach flank worn by 5 um
    scn = Scenario(dynamics=QUIET)
    worn = simulate(build_model(scn, ms, s, wear, np.zeros_like(s)), scn.dynamics)
    healthy = simulate(build_model(scn, ms), scn.dynamics)
    share = worn.load_a / (worn.load_a + worn.load_b)
    share0 = healthy.load_a / (healthy.load_a + healthy.load_b)
    double = healthy.load_b > 100
    assert np.mean(share[double]) < np.mean(share0[double]) - 0.05


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"half_backlash_um": -1.0}, r"half_backlash_um = -1.0 must lie in \[0, "),
        ({"damping_ratio": 1.0}, r"damping_ratio = 1.0 must lie in \[0, 1\)"),
        ({"step_factor": 3.0}, "unstable"),
    ],
)
def test_bad_dynamics_input(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Dynamics(**kwargs)


def test_speed_and_torque_scope(ms):
    with pytest.raises(ValueError, match="n1_rpm = 12000 puts the mesh frequency"):
        build_model(Scenario(operating=Operating(n1_rpm=12000.0)), ms)
    with pytest.raises(ValueError, match=r"torque_Nm = 2000 .* static capacity"):
        build_model(Scenario(operating=Operating(torque_Nm=2000.0)), ms)


def test_coast_flank_impacts_do_not_enter_the_drive_flank_load(ms):
    """Small backlash, light damping and a large error: the flanks separate and the coast flanks
    strike (negative mesh force); the load fed back to the drive-flank wear stays >= 0."""
    scn = Scenario(dynamics=Dynamics(half_backlash_um=1.0, damping_ratio=0.005,
                                     profile_error_um=200.0, duration_s=0.05))
    resp = simulate(build_model(scn, ms), scn.dynamics)
    assert resp.force.min() < 0  # coast impacts happen
    assert np.all(resp.force_by_phase >= 0)


def test_lengths_scale_out_of_the_equation_of_motion(ms):
    """``m x'' + c x' + k(t) (x - e) = W`` with its dead zone is homogeneous in length: with
    ``m/g``, ``c/g``, ``k/g`` and every length (errors, wear gaps, backlash) times ``g`` the mesh
    force is the same and the DTE ``g`` times larger, here through contact loss and a worn
    flank. So a DTE gain is not identifiable against an uncertain stiffness level with the
    error amplitudes, from DTE and force (housing acceleration) records alike
    (docs/loop.md, the sensor gain)."""
    j1, j2 = build_model(Scenario(), ms).inertias
    dyn = dataclasses.replace(Dynamics(), inertia1_kg_m2=100 * j1, inertia2_kg_m2=100 * j2,
                              damping_ratio=0.02)
    f_n = build_model(Scenario(dynamics=dyn), ms).omega_max / (2 * np.pi)
    scn = Scenario(operating=Operating(n1_rpm=f_n * 60 / 18, torque_Nm=50.0), dynamics=dyn)
    s = ms.geometry.grid(401)
    wear = np.where(s < ms.geometry.single_zone[0], 5e-6, 0.0)
    m = build_model(scn, ms, s, wear, np.zeros_like(s))
    g = 1.37
    scaled = dataclasses.replace(
        m, mass=m.mass / g, damping=m.damping / g, k_a=m.k_a / g, k_b=m.k_b / g,
        g_a=m.g_a * g, g_b=m.g_b * g, half_backlash=m.half_backlash * g,
        long_error=m.long_error * g, short_error=m.short_error * g,
        inertias=(m.inertias[0] / g, m.inertias[1] / g))
    a, b = simulate(m, dyn), simulate(scaled, dyn)
    assert np.mean(a.load_a[0] + a.load_b[0] == 0.0) > 0.05  # the flanks part
    assert np.allclose(b.dte, g * a.dte, rtol=1e-9, atol=1e-15)
    assert np.allclose(b.force, a.force, rtol=1e-9, atol=1e-9 * m.static_force)


@given(shift=st.floats(-40.0, 40.0), h=st.floats(1e-6, 0.5))
@settings(max_examples=60, deadline=None)
def test_a_moved_entry_keeps_the_stiffness_it_moves(shift, h):
    """The gear run-out moves a pair's entry by ``shift`` table cells: the share of the
    entering pair's stiffness it adds or removes integrates to exactly ``-shift`` cells, never
    exceeds the pair, vanishes with the shift and is continuous (Lipschitz 1 in the cell), so
    the RK4 kernel never meets a jump there."""
    q = np.linspace(-64.0, 64.0, 2**13 + 1)  # 1/64 cell: trapezoid error < 1e-4 a kink
    share = np.array([_entry_shift(x, shift) for x in q])
    assert np.trapezoid(share, q) == pytest.approx(-shift, abs=1e-3)
    assert np.all(np.abs(share) <= 1.0)
    assert np.all(np.abs(np.diff(share)) <= np.diff(q) + 1e-12)
    assert _entry_shift(0.3, 0.0) == 0.0
    assert abs(_entry_shift(-0.5, h) - _entry_shift(-0.5, 0.0)) <= h + 1e-12


def test_drive_flank_wear_never_closes_the_coast_side(ms):
    """Wear removed from the drive flanks widens that pair's backlash: with a gap far beyond
    twice the half backlash (150 um against 47.5 um) the worn pairs stay off their coast
    flanks, and the mesh force balances the torque without pulling."""
    g = ms.geometry
    s = g.grid(401)
    scn = Scenario(dynamics=dataclasses.replace(QUIET, duration_s=0.05))
    worn = build_model(scn, ms, s, np.full_like(s, 150e-6), np.zeros_like(s))
    resp = simulate(worn, scn.dynamics)
    assert resp.force.min() > 0.0
    assert resp.force.mean() == pytest.approx(worn.static_force, rel=5e-3)
    # a uniform gap is a rotation: the force of the same (thinned) teeth without it, the DTE
    # moved by the gap
    new = simulate(dataclasses.replace(worn, g_a=0 * worn.g_a, g_b=0 * worn.g_b), scn.dynamics)
    assert np.allclose(resp.force, new.force, rtol=1e-6)
    assert np.allclose(resp.dte - new.dte, 150e-6, atol=1e-9)


def _worn_exact(ms, depth=30e-6, **dyn):
    g = ms.geometry
    s = g.grid(401)
    shape = np.clip((g.single_zone[0] - s) / (g.single_zone[0] - g.s_start), 0.0, 1.0) ** 2
    scn = _scn(flank_contact="exact", **dyn)
    return scn, build_model(scn, ms, s, depth * shape, 0.3 * depth * shape[::-1])


@pytest.mark.slow  # the reference's pure-Python right-hand side: 30 s for one mesh period
def test_exact_contact_two_dof_and_reduced_forms_agree(ms):
    """The off-path pairs and the damping shared among the pairs in contact, in the compiled
    kernel and in the unreduced reference, on a worn pair whose entry separates."""
    scn, model = _worn_exact(ms, duration_s=0.0015, transient_s=0.0)  # 0.9 mesh periods
    assert model.k_off is not None and np.any(model.k_off > 0)
    resp = simulate(model, scn.dynamics, every_phase=False)
    dt, n_sub = time_step([model], scn.dynamics)
    half = (len(anti_aliasing_filter(n_sub)) - 1) // (2 * n_sub)
    n_out = resp.dte.shape[1]
    steps = np.arange(2 * (n_sub - half * n_sub), 2 * (n_out + half) * n_sub + 3) / 2
    x, force = simulate_two_dof(model, resp.time[0] + (steps - n_sub) * dt, rtol=1e-7, atol=1e-11)
    x = x[:-2:2]
    force = (force[:-2:2] + 4 * force[1::2] + force[2::2]) / 6
    # the contacts switch on within a step (a kink the fixed step does not locate): 2 %
    assert np.max(np.abs(anti_aliased(x, n_sub, n_out) - resp.dte[0])) < 0.02 * np.ptp(resp.dte)
    assert (np.max(np.abs(anti_aliased(force, n_sub, n_out) - resp.force[0]))
            < 0.02 * np.ptp(resp.force))


def test_exact_contact_step_halving_converges_through_the_impacts(ms):
    """Worn 60 um at the root: the entering pair strikes. The record converges with the step,
    below fourth order (a contact switches on within a step: a kink in the force), and the
    force's RMS, what the features read, is within 0.5 % at the default step."""
    records = []
    for factor in (0.5, 0.25, 0.125):
        scn, model = _worn_exact(ms, depth=60e-6, step_factor=factor, duration_s=0.02)
        records.append(simulate(model, scn.dynamics).force[0])
    d1 = np.max(np.abs(records[0] - records[1]))
    d2 = np.max(np.abs(records[1] - records[2]))
    assert d2 < 0.6 * d1
    rms = [r.std() for r in records]
    assert abs(rms[1] - rms[2]) < 0.5 * abs(rms[0] - rms[1])
    assert abs(rms[1] - rms[2]) < 5e-3 * rms[2]


def test_exact_contact_of_new_teeth_takes_the_corners_load(ms):
    """Unmodified new teeth under load touch before and after the theoretical path (extended
    contact): the mesh force's swing is smaller than with contact on the path alone, and its
    mean still balances the torque."""
    path = simulate(build_model(_scn(duration_s=0.1), ms), _scn(duration_s=0.1).dynamics)
    scn = _scn(flank_contact="exact", duration_s=0.1)
    exact = simulate(build_model(scn, ms), scn.dynamics)
    assert exact.force.std() < path.force.std()
    assert exact.force.mean() == pytest.approx(path.force.mean(), rel=5e-3)


def test_exact_contact_converges_in_the_tables_phases(ms):
    """The early and late contact of the exact contact engage over a few per cent of the mesh
    period: at EXACT_PHASES the new pair's force spread is within 2 % of four times as many
    phases' (each pair interpolated to its own value where the slots move on)."""
    scn = _scn(flank_contact="exact", eccentricity1_um=0.0, duration_s=0.05)
    spread = [simulate([build_model(scn, ms, n_phase=n)], scn.dynamics,
                       every_phase=False).force.std() for n in (EXACT_PHASES, 4 * EXACT_PHASES)]
    assert spread[0] == pytest.approx(spread[1], rel=0.02)



def _energy_residual(ms, step_factor: float) -> tuple[float, int]:
    """Largest drift of ``m v^2 / 2 + U(x) - int W v dt`` over a record of the compiled
    integrator, relative to the largest mechanical energy ``m v^2 / 2 + U``, and the number of
    coast-flank strikes: one undamped pair of constant stiffness driven through its backlash by
    a force ripple 1.6 times the static force (``U = k dz(x)^2 / 2``, ``dz`` the dead zone's
    deflection on either flank). ``v`` by the five-point central difference of the DTE at every
    step, the work by the trapezoid rule (together 0.2 % of drift without separation)."""
    scn = _scn(duration_s=0.02, transient_s=0.0, step_factor=step_factor)
    m = build_model(scn, ms)
    k0 = float(np.mean(m.k_a))
    m = dataclasses.replace(
        m, k_a=np.full_like(m.k_a, k0), k_b=np.zeros_like(m.k_b), g_a=np.zeros_like(m.g_a),
        g_b=np.zeros_like(m.g_b), lam_a=None, lam_b=None, damping=0.0, long_error=0.0,
        short_error=0.0, ripple_force=1.6 * m.static_force,
        omega_ripple=0.27 * np.sqrt(k0 / m.mass), k_off=None, g_off=None)
    resp = simulate(m, scn.dynamics)
    dt, n_sub = resp.time_step, resp.steps_per_sample
    half = (len(anti_aliasing_filter(n_sub)) - 1) // (2 * n_sub)
    x = resp.dte_steps[0]
    t = resp.time[0] + (np.arange(len(x)) - half * n_sub) * dt  # the steps' instants
    v = (x[:-4] - 8 * x[1:-3] + 8 * x[3:-1] - x[4:]) / (12 * dt)
    x, t = x[2:-2], t[2:-2]
    dz = np.where(x > m.half_backlash, x - m.half_backlash,
                  np.where(x < -m.half_backlash, x + m.half_backlash, 0.0))
    w = m.static_force + m.ripple_force * np.sin(m.omega_ripple * t)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] * v[1:] + w[:-1] * v[:-1]) * dt)])
    mechanical = 0.5 * m.mass * v**2 + 0.5 * k0 * dz**2
    strikes = int(np.sum(np.diff((x < -m.half_backlash).astype(int)) == 1))
    return np.ptp(mechanical - work) / mechanical.max(), strikes


def test_energy_is_conserved_through_separations_and_coast_flank_strikes(ms):
    """The undamped mesh driven through its backlash: the flanks part, the coast flanks strike
    (dozens of times in 20 ms) and the drive flanks re-engage; the energy balance holds within
    a few per cent of the mechanical energy at the default step and converges at second order
    as the step halves (the dead zone's kinks are where the fixed-step RK4 loses its fourth)."""
    coarse, strikes = _energy_residual(ms, Dynamics().step_factor)
    fine, _ = _energy_residual(ms, Dynamics().step_factor / 2)
    assert strikes >= 10
    assert coarse < 0.03
    assert fine < coarse / 3
