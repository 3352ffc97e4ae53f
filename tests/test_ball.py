"""Ball physics and fields: known answers (5/7 g sin(theta), energy, capture), bad input."""

import json

import numpy as np
import pytest

from seds_casadi.minigolf.ball import capture_speed, impact, simulate_shots
from seds_casadi.minigolf.ball_physics import MU_SLIDE
from seds_casadi.minigolf.fields import Field, field_names, load_field, stimp_to_rho
from seds_casadi.motion import BALL_RADIUS, G


def _field(surface, rho=0.0, boundary="walls", hole=(2.4, 0.0), **kw):
    spec = dict(name="test", surface=surface, bounds=[-0.3, 30.0, -3.0, 3.0], boundary=boundary,
                hole={"x": hole[0], "y": hole[1], "radius": 0.054},
                ball_region=[-0.1, 0.3, -2.0, 2.0], rolling_resistance=rho)
    spec.update(kw)
    return Field.from_dict(spec)


def _plane(slope_x=0.0, slope_y=0.0, rho=0.0785, boundary="walls"):
    return _field({"shape": "plane", "slope_x": slope_x, "slope_y": slope_y}, rho=rho,
                  boundary=boundary, bounds=[-0.3, 3.0, -0.6, 0.6],
                  ball_region=[-0.1, 0.3, -0.45, 0.45])


def test_inclined_plane_rolls_with_five_sevenths_g_sin_theta():
    theta = np.deg2rad(5.0)
    f = _field({"shape": "plane", "slope_x": -np.tan(theta), "slope_y": 0.0}, hole=(25.0, 2.5))
    # launch at a tiny speed and let it settle into rolling (skid lasts microseconds)
    res = simulate_shots(f, [[0.0, 0.0]], [[1e-6, 0.0]], dt=0.001, max_time=2.0,
                         record_paths=True)
    path = res.paths[0]
    t = np.arange(len(path)) * 0.001
    s = path[:, 0] / np.cos(theta)  # distance along the slope
    a_fit = 2 * s[-1] / t[-1] ** 2
    assert a_fit == pytest.approx(5 / 7 * G * np.sin(theta), rel=3e-3)


def test_energy_is_conserved_on_a_frictionless_curved_surface():
    f = _field({"shape": "hills", "hills": [{"x": 1.0, "y": 0.1, "height": 0.05, "width": 0.2},
                                            {"x": 1.8, "y": -0.2, "height": -0.03,
                                             "width": 0.3}]}, hole=(25.0, 2.5))
    p0, u0 = np.array([[0.0, 0.0]]), np.array([[1.2, 0.1]])
    # skip the skid: simulate from a rolling state by giving a tiny launch and then the velocity
    res = simulate_shots(f, p0, u0, dt=0.0005, max_time=2.5, record_paths=True)
    path = res.paths[0]
    dt = 0.0005
    V = np.diff(path, axis=0) / dt
    P = path[1:]
    grad = f.surface.gradient(P)
    E = 0.7 * (np.sum(V * V, 1) + np.sum(grad * V, 1) ** 2) + G * f.surface.height(P)
    skid = int(np.ceil(np.linalg.norm(u0) / (3.5 * 0.2 * G) / dt)) + 2
    E = E[skid:]
    assert np.ptp(E) / E[0] < 2e-3


def test_hole_capture_slow_sinks_fast_lips_out():
    assert capture_speed(0.0, 0.054) == pytest.approx(1.64, abs=0.02)
    assert capture_speed(0.04, 0.054) < capture_speed(0.0, 0.054)
    assert capture_speed(0.06, 0.054) == 0.0
    f = _field({"shape": "plane"}, rho=0.0, hole=(1.0, 0.0))
    # frictionless: the ball keeps its rolling speed (5/7 of the launch) up to the hole
    slow = simulate_shots(f, [[0.0, 0.0]], [[1.2 * 7 / 5, 0.0]], max_time=3.0)
    fast = simulate_shots(f, [[0.0, 0.0]], [[2.2 * 7 / 5, 0.0]], max_time=0.8)
    assert slow.sunk[0]
    assert not fast.sunk[0]


def test_straight_putt_on_the_flat_field_sinks_at_the_right_angle():
    f = load_field("flat")
    ball = np.array([0.0, 0.0])
    angles = np.deg2rad(np.linspace(-6, 6, 25))
    v = 2.15  # skid ~0.58 m, then rolls to the hole at ~0.5 m/s
    V = v * np.column_stack([np.cos(angles), np.sin(angles)])
    res = simulate_shots(f, np.tile(ball, (25, 1)), V)
    sunk_angles = np.degrees(angles[res.sunk])
    assert res.sunk[12]  # straight at the hole
    assert sunk_angles.size >= 1 and np.all(np.abs(sunk_angles) < 2.0)
    # too soft stops short, too hard lips out or rebounds from the wall
    assert not simulate_shots(f, [ball], [[0.8, 0.0]]).sunk[0]


def test_walls_reflect_and_edges_lose_the_ball():
    walls = _field({"shape": "plane"}, rho=0.0, hole=(25.0, 2.5))
    r = simulate_shots(walls, [[0.0, 0.0]], [[0.0, 2.0]], max_time=1.5, record_paths=True)
    assert r.paths[0][:, 1].max() <= 3.0 - BALL_RADIUS + 1e-9
    assert not r.out[0]
    edges = _field({"shape": "plane"}, rho=0.0, boundary="edges", hole=(25.0, 2.5))
    r = simulate_shots(edges, [[0.0, 0.0]], [[0.0, 2.0]], max_time=3.0)
    assert r.out[0]


@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_shots_are_vectorised_and_deterministic(engine):
    f = load_field("rough_flat")
    rng = np.random.default_rng(0)
    B = np.column_stack([rng.uniform(-0.1, 0.3, 40), rng.uniform(-0.4, 0.4, 40)])
    V = np.column_stack([rng.uniform(1.5, 2.5, 40), rng.uniform(-0.3, 0.3, 40)])
    a = simulate_shots(f, B, V, engine=engine)
    b = simulate_shots(f, B, V, engine=engine)
    np.testing.assert_array_equal(a.final_position, b.final_position)
    one = simulate_shots(f, B[7:8], V[7:8], engine=engine)
    np.testing.assert_allclose(one.final_position[0], a.final_position[7])
    assert np.all(a.sunk | a.out | a.stopped)


def test_impact_mass_ratio_and_restitution():
    v = impact([1.0, 0.0, 0.3])
    assert v.shape == (2,)
    assert v[0] == pytest.approx(1.8 * 0.35 / (0.35 + 0.0459))
    with pytest.raises(ValueError):
        impact([1.0, 0.0], restitution=1.5)


def test_shipped_fields_and_surface_derivatives():
    assert set(field_names()) >= {"flat", "rough_flat", "double_hill", "arctan"}
    rng = np.random.default_rng(1)
    for name in field_names():
        f = load_field(name)
        P = np.column_stack([rng.uniform(0, 2.5, 20), rng.uniform(-0.5, 0.5, 20)])
        h = 1e-6
        for j in range(2):
            e = np.zeros(2)
            e[j] = h
            fd = (f.surface.height(P + e) - f.surface.height(P - e)) / (2 * h)
            np.testing.assert_allclose(f.surface.gradient(P)[:, j], fd, atol=1e-7)
            fdg = (f.surface.gradient(P + e) - f.surface.gradient(P - e)) / (2 * h)
            np.testing.assert_allclose(f.surface.hessian(P)[:, :, j], fdg, atol=1e-5)
    assert stimp_to_rho(8) == pytest.approx(0.0985)


def test_heightmap_surface_matches_the_function_it_samples(tmp_path):
    xs, ys = np.linspace(-0.5, 3.5, 81), np.linspace(-1.0, 1.0, 41)
    X, Y = np.meshgrid(xs, ys)
    Z = 0.02 * np.sin(X) * np.cos(2 * Y)
    spec = json.loads(json.dumps(load_field("flat").spec))
    spec["surface"] = {"shape": "heightmap", "extent": [-0.5, 3.5, -1.0, 1.0],
                       "heights": Z.tolist()}
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(spec))
    f = load_field(path)
    P = np.array([[0.7, 0.2], [2.0, -0.3]])
    np.testing.assert_allclose(f.surface.height(P), 0.02 * np.sin(P[:, 0]) * np.cos(2 * P[:, 1]),
                               atol=2e-5)


@pytest.mark.parametrize(
    "change, match",
    [
        (lambda s: s.pop("hole"), "missing entry 'hole'"),
        (lambda s: s.update(hole={"x": 9.0, "y": 0.0}), "outside the field"),
        (lambda s: s.update(surface={"shape": "volcano"}), "unknown shape"),
        (lambda s: s.update(surface={"shape": "hills", "hills": []}), "hills"),
        (lambda s: s.update(surface={"shape": "heightmap", "extent": [-0.3, 3.0, -0.6, 0.6],
                                     "heights": [[0.0, np.nan] * 3] * 5}), "NaN"),
        (lambda s: s.update(surface={"shape": "heightmap", "extent": [-0.3, 3.0, -0.6, 0.6],
                                     "heights": [1.0, 2.0]}), "2-D grid"),
        (lambda s: s.update(bounds=[1, 0, 0, 1]), "bounds"),
        (lambda s: s.update(stimp=20), "stimp"),
        (lambda s: s.update(ball_region=[-5, 0, 0, 0.1]), "ball_region"),
        (lambda s: s.update(boundary="moat"), "boundary"),
        (lambda s: s.update(situations={"ball": {"circle": [0, 0]}}), r"situations\.ball: one of"),
        (lambda s: s.update(situations={"hole": {"slider": [[2.4, 0.1], [2.4, 0.1]]}}),
         "same point"),
        (lambda s: s.update(situations={"hole": {"region": [2.0, 1.9, -0.2, 0.2]}}),
         "min < max"),
        (lambda s: s.update(situations={"ball": {"fixed": [0.5, 0.0]}}),
         r"leaves the field's ball_region \[-0.1, 0.3, -0.45, 0.45\]"),
        (lambda s: s.update(situations={"hole": {"slider": [[2.4, -0.58], [2.4, 0.2]]}}),
         r"keep it within x -0.246..2.946, y -0.546..0.546"),
        (lambda s: s.update(situations={"ball": {"fixed": [0.1, 0.0]}}),
         "both fixed, which is a single situation"),
        (lambda s: s.update(situations={"hole": {"region": [0.2, 0.4, -0.2, 0.2]}}),
         "would lie in the hole"),
        (lambda s: s.update(situations={"balls": {"fixed": [0.1, 0.0]}}), "unknown entry 'balls'"),
        (lambda s: s.update(teacher={"strategy": "fastest"}), "valid: fixed_speed, minimal_speed"),
        (lambda s: s.update(teacher={"kappa_range": [2.0, 1.0]}), r"teacher\.kappa_range"),
        (lambda s: s.update(teacher={"speed": 1.0}), "unknown entry 'speed'"),
        (lambda s: s.update(teacher={"banks": "yes"}), "true or false"),
    ],
)
def test_bad_field_files_name_the_entry(change, match):
    spec = json.loads(json.dumps(load_field("flat").spec))
    change(spec)
    with pytest.raises(ValueError, match=match):
        Field.from_dict(spec)


def test_declared_situations_placements_and_their_default():
    flat = load_field("flat")
    # no "situations" in the file: the ball anywhere in the ball region, the field's hole
    sit = flat.situations
    assert not sit.declared and sit.ball.kind == "region" and sit.hole.kind == "fixed"
    assert sit.dim == 2 and "the default" in sit.describe()
    np.testing.assert_array_equal(sit.ball.box, flat.ball_region)
    rng = np.random.default_rng(0)
    B, H = sit.sample(500, rng)
    r = flat.ball_region
    assert (B[:, 0] >= r[0]).all() and (B[:, 0] <= r[1]).all() and np.allclose(H, flat.hole)
    assert (B[:, 1] >= r[2]).all() and (B[:, 1] <= r[3]).all() and np.ptp(B[:, 1]) > 0.8
    # a slider: one-dimensional, equally spaced from end to end; a hole region with a fixed
    # ball: two-dimensional
    spec = json.loads(json.dumps(flat.spec))
    spec["situations"] = {"ball": {"fixed": [0.1, 0.0]},
                          "hole": {"slider": [[2.0, -0.3], [2.6, 0.3]]}}
    sl = Field.from_dict(spec).situations
    assert sl.dim == 1 and sl.declared
    b, h = sl.design()
    assert len(b) == 20 and np.allclose(b, [0.1, 0.0])
    np.testing.assert_allclose(h[[0, -1]], [[2.0, -0.3], [2.6, 0.3]])
    np.testing.assert_allclose(np.diff(h, axis=0), np.tile((h[-1] - h[0]) / 19, (19, 1)))
    t = sl.sample(200, rng)[1]
    assert np.allclose(t[:, 1] - t[:, 0], -2.3) and t[:, 0].min() >= 2.0 and t[:, 0].max() <= 2.6
    # both moving is allowed on a plane (s alone says where the shot is played)
    spec["situations"] = {"hole": {"region": [2.0, 2.6, -0.3, 0.3]}}
    both = Field.from_dict(spec).situations
    assert both.dim == 2 and both.ball.kind == "region"
    b, h = both.design(56)
    assert len(b) >= 56 and len({tuple(x) for x in np.round(h - b, 9)}) == len(b)
    assert Field.from_dict({**spec, "situations": both.to_spec()}).situations.to_spec() == \
        both.to_spec()
    # ... but not on a curved surface
    spec["surface"] = load_field("double_hill").spec["surface"]
    with pytest.raises(ValueError, match="both the ball and the hole move"):
        Field.from_dict(spec)


def test_bad_situations_and_names():
    f = load_field("flat")
    with pytest.raises(ValueError, match="ball region"):
        simulate_shots(f, [[2.0, 0.0]], [[1.0, 0.0]])
    with pytest.raises(ValueError, match="NaN"):
        simulate_shots(f, [[0.0, 0.0]], [[np.nan, 0.0]])
    with pytest.raises(ValueError, match="no field"):
        load_field("moon")


def _aimed_shots(f, n, seed):
    rng = np.random.default_rng(seed)
    r = f.ball_region
    B = np.column_stack([rng.uniform(r[0], r[1], n), rng.uniform(r[2], r[3], n)])
    d = f.hole - B
    a = np.arctan2(d[:, 1], d[:, 0]) + rng.uniform(-0.12, 0.12, n)
    s = rng.uniform(0.8, 3.0, n)
    return B, np.column_stack([s * np.cos(a), s * np.sin(a)])


@pytest.mark.parametrize("name", ["flat", "double_hill", "arctan"])
def test_compiled_engine_equals_the_numpy_reference(name):
    # same equations, same step: the CasADi kernel must reproduce the numpy reference
    f = load_field(name)
    B, V = _aimed_shots(f, 300, 1)
    ref = simulate_shots(f, B, V, engine="numpy")
    fast = simulate_shots(f, B, V, engine="compiled")
    np.testing.assert_array_equal(fast.sunk, ref.sunk)
    np.testing.assert_array_equal(fast.stopped, ref.stopped)
    np.testing.assert_allclose(fast.final_position, ref.final_position, atol=1e-9)
    np.testing.assert_allclose(fast.time, ref.time, atol=1e-9)
    assert ref.sunk.any() or name == "arctan"


def test_compiled_engine_on_edges_and_slopes():
    f = _plane(slope_x=0.01, slope_y=-0.02, boundary="edges")
    B, V = _aimed_shots(f, 200, 2)
    ref = simulate_shots(f, B, V, engine="numpy")
    fast = simulate_shots(f, B, V, engine="compiled")
    np.testing.assert_array_equal(fast.out, ref.out)
    np.testing.assert_array_equal(fast.sunk, ref.sunk)
    np.testing.assert_allclose(fast.final_position, ref.final_position, atol=1e-9)


def test_tabulated_rough_field_is_close_to_the_exact_surface():
    # rough fields: the compiled engine interpolates a 1 cm table of the derivatives
    f = load_field("rough_flat")
    B, V = _aimed_shots(f, 200, 3)
    ref = simulate_shots(f, B, V, engine="numpy")
    fast = simulate_shots(f, B, V, engine="compiled")
    assert np.mean(fast.sunk == ref.sunk) >= 0.95
    dist = np.linalg.norm(fast.final_position - ref.final_position, axis=1)
    assert np.median(dist) < 0.01


def test_flat_field_is_exact_for_any_step():
    # constant deceleration, exact skid-to-roll and stopping steps: the stop point does not
    # depend on the step (v0^2 / (2 mu g) skidding, then rolling from 5/7 v0)
    f = _plane(rho=0.08)
    v0 = 1.4
    t_skid = v0 / (3.5 * MU_SLIDE * G)
    d_skid = v0 * t_skid - 0.5 * MU_SLIDE * G * t_skid**2
    v1 = 5 / 7 * v0
    d_roll = v1**2 / (2 * 5 / 7 * 0.08 * G)
    for dt in (0.002, 0.01, 0.03):
        r = simulate_shots(f, [[0.0, 0.0]], [[v0, 0.0]], dt=dt, engine="numpy")
        assert r.stopped[0]
        assert r.final_position[0, 0] == pytest.approx(d_skid + d_roll, abs=2e-3)


def test_bad_engine_is_refused():
    f = load_field("flat")
    with pytest.raises(ValueError, match="engine"):
        simulate_shots(f, [[0.0, 0.0]], [[1.0, 0.0]], engine="gpu")
    with pytest.raises(ValueError, match="record_paths"):
        simulate_shots(f, [[0.0, 0.0]], [[1.0, 0.0]], engine="compiled", record_paths=True)


def test_impact_with_a_turned_face_leaves_along_its_normal():
    v = np.array([1.0, 0.0, 0.0])
    square = impact(v)
    np.testing.assert_allclose(impact(v, face_normal=[1.0, 0.0, 0.0]), square)
    th = np.deg2rad(10.0)
    out = impact(v, face_normal=[np.cos(th), np.sin(th), 0.0])
    assert np.degrees(np.arctan2(out[1], out[0])) == pytest.approx(10.0)
    assert np.linalg.norm(out) == pytest.approx(np.linalg.norm(square) * np.cos(th))
    with pytest.raises(ValueError, match="3-D"):
        impact([1.0, 0.0], face_normal=[1.0, 0.0, 0.0])


@pytest.mark.slow
@pytest.mark.parametrize("name", ["flat", "double_hill", "arctan", "rough_flat"])
def test_simd_backend_equals_the_casadi_kernel(name):
    # the vectorised C loop is generated from the same SX step as CasADi's kernel
    from seds_casadi.minigolf.ball_kernel import BallKernel

    f = load_field(name)
    B, V = _aimed_shots(f, 700, 5)  # > 2 x 256: both threads, blocks of 64 and a remainder
    simd = BallKernel(f, backend="simd")
    assert simd.backend == "simd"
    a = simd.run(B, V, 20.0)
    b = BallKernel(f, backend="casadi").run(B, V, 20.0)
    np.testing.assert_array_equal(a.sunk, b.sunk)
    np.testing.assert_array_equal(a.stopped, b.stopped)
    np.testing.assert_allclose(a.final_position, b.final_position, atol=1e-9)
    np.testing.assert_allclose(a.time, b.time, atol=1e-9)
    # shots still moving at the time limit are reported as such by both
    c = simd.run(B[:50], V[:50], 0.3)
    assert not (c.sunk | c.stopped | c.out).any() and np.all(c.time == 0.3)
    with pytest.raises(ValueError, match="backend"):
        BallKernel(f, backend="gpu")


def test_simd_translator_against_casadi_on_random_states():
    import casadi as ca

    from seds_casadi.codegen.simd import SimdLoop, UnsupportedOperation

    x = ca.SX.sym("x", 4)
    y = ca.vertcat(ca.if_else(x[0] < x[1], ca.sqrt(ca.fabs(x[2])), -x[3]),
                   ca.fmin(x[0], x[1]) * ca.exp(-x[2] ** 2) + x[3] / (1 + x[1] ** 2),
                   ca.atan(x[0]) - ca.tanh(x[1]) + ca.fmax(x[2], 0.5),
                   ca.logic_or(x[2] > 0, ca.logic_not(x[3] <= 1)) * 2.0)
    f = ca.Function("g", [x], [y])
    loop = SimdLoop(f, "g_loop")
    S = np.random.default_rng(1).normal(size=(4, 301))
    ref = S.copy()
    for _ in range(3):
        ref = np.asarray(f.map(ref.shape[1])(ref))
    loop.run(S, 3)
    np.testing.assert_allclose(S, ref, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="C-contiguous"):
        loop.run(S.T, 1)
    aux = ca.SX.sym("aux", 2)
    tab = ca.Function("t", [x, aux], [x + ca.vertcat(aux, aux)])
    lookup = dict(ix=0, iy=1, x0=0.0, dx=1.0, nx=3, y0=0.0, dy=1.0, ny=3, channels=2)
    with pytest.raises(ValueError, match="the table has 5 values, the lookup needs 18"):
        SimdLoop(tab, "t_loop", lookup=lookup, table=np.zeros(5))
    g = ca.Function("h", [x], [ca.interpolant("t", "linear", [[0.0, 1.0, 2.0]],
                                              [0.0, 1.0, 4.0])(x[0]) * x])
    with pytest.raises(UnsupportedOperation, match="not translated|SX"):
        SimdLoop(g, "h_loop")


@pytest.mark.parametrize("e", [0.6, 0.9])
def test_a_rolling_ball_comes_off_a_wall_at_five_e_minus_two_sevenths(e):
    # the wall reverses the velocity, not the spin: after the ground friction has brought the
    # ball back to rolling, it moves away at (5e - 2)/7 of its rolling speed (a known answer of
    # rigid-ball mechanics; e v_n if the spin were reversed too)
    f = _field({"shape": "plane", "slope_x": 0.0, "slope_y": 0.0}, rho=0.0, hole=(0.5, 0.5),
               bounds=[-0.3, 1.0, -0.6, 0.6], ball_region=[-0.1, 0.3, -0.45, 0.45],
               wall_restitution=e)
    v0, dt = 1.0, 0.001
    res = simulate_shots(f, [[0.0, -0.3]], [[v0, 0.0]], dt=dt, max_time=2.0,
                         record_paths=True)
    x = res.paths[0][:, 0]
    v_end = (x[-1] - x[-101]) / (100 * dt)
    assert v_end == pytest.approx(-(5 * e - 2) / 7 * (5 / 7 * v0), rel=0.02)
    fast = simulate_shots(f, [[0.0, -0.3]], [[v0, 0.0]], dt=dt, max_time=2.0, engine="compiled")
    assert fast.final_position[0, 0] == pytest.approx(x[-1], abs=1e-9)


def test_wall_contacts_are_counted_and_banks_can_be_left_out_of_a_success_map():
    from seds_casadi.minigolf import Stroke, success_map

    f = _plane(rho=0.0785)
    # straight into the side wall at y = 0.6, and straight along the field
    res = simulate_shots(f, [[0.0, 0.0], [0.0, 0.0]], [[0.3, 1.0], [1.0, 0.0]], engine="numpy")
    fast = simulate_shots(f, [[0.0, 0.0], [0.0, 0.0]], [[0.3, 1.0], [1.0, 0.0]],
                          engine="compiled")
    assert res.wall_contacts[0] >= 1 and res.wall_contacts[1] == 0
    np.testing.assert_array_equal(fast.wall_contacts, res.wall_contacts)
    stroke = Stroke(np.array([1.0, 0.0, 0.0]), 1.0)
    al, ka = np.deg2rad(np.linspace(-40, 40, 81)), np.linspace(0.8, 2.4, 17)
    ball = np.array([0.0, 0.3])
    with_banks = success_map(f, stroke, ball, f.hole, al, ka)
    direct = success_map(f, stroke, ball, f.hole, al, ka, banks=False)
    assert direct.sum() > 0 and np.all(with_banks >= direct)
    A, K = np.meshgrid(al, ka)
    r = simulate_shots(f, np.tile(ball, (A.size, 1)), stroke.launch_velocity(A.ravel(), K.ravel()))
    np.testing.assert_array_equal(direct.ravel(), r.sunk & (r.wall_contacts == 0))
    assert (with_banks & ~direct).any()  # this field has bank shots, and they were left out


@pytest.mark.parametrize("name", ["flat", "arctan", "double_hill"])
@pytest.mark.parametrize("engine", ["numpy", "compiled"])
def test_stopping_at_walls_keeps_every_direct_shot_and_ends_the_others(name, engine):
    # the teacher without banks counts only shots that sink before any wall contact: ending a
    # shot at its first contact must leave exactly those unchanged, on both engines
    f = load_field(name)
    B, V = _aimed_shots(f, 400, 11)
    V = V * 1.6   # fast enough that many reach the far wall
    full = simulate_shots(f, B, V, engine=engine)
    cut = simulate_shots(f, B, V, engine=engine, stop_at_walls=True)
    direct = full.wall_contacts == 0
    assert (~direct).sum() > 20 and (full.sunk & direct).any() or name == "arctan"
    np.testing.assert_array_equal(cut.sunk & (cut.wall_contacts == 0), full.sunk & direct)
    np.testing.assert_array_equal(cut.wall_contacts == 0, direct)
    np.testing.assert_allclose(cut.final_position[direct], full.final_position[direct],
                               atol=1e-12)
    np.testing.assert_array_equal(cut.stopped[direct], full.stopped[direct])
    # the others ended no later than before, none of them reported stopped or out
    walled = ~direct & ~full.sunk
    assert np.all(cut.time[walled] <= full.time[walled] + 1e-9)
    if engine == "numpy":   # checked every step (the compiled engine every 0.5 s)
        assert not (cut.stopped[walled] | cut.out[walled]).any()
    assert cut.time[walled].sum() < 0.8 * full.time[walled].sum()
