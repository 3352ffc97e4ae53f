"""Fuzz suite (issue 18): random demonstrations, demonstration files, field files and model
files, through hypothesis (derandomized: CI runs the same cases every time).

Each case ends in one of two ways, and the test says which is acceptable:

* a **clear project error**: a ``ValueError``/``TypeError`` (or a project exception such as
  :class:`~seds_casadi.ModelFileError`) raised by seds_casadi's own code (the innermost frame of
  the traceback is in the package: no error escapes from inside numpy, json or zipfile), with
  a message that names the input (the file, or the entry);
* or a **correct result**: finite numbers only, and the meaning of the input kept (the same
  demonstrations, the same entries of a field, a model file identical to the one saved).

The number of cases per class is :data:`EXAMPLES` (the report of issue 18 gives them).
"""

import json
import os

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import seds_casadi
from seds_casadi import Demonstrations, ModelFileError, SEDSError, StableDS, load_demonstrations
from seds_casadi.minigolf.fields import FIELDS_FOLDER, Field
from seds_casadi.minigolf.hitting_data import HittingDataset
from seds_casadi.minigolf.stroke import Stroke

PACKAGE = os.path.dirname(os.path.abspath(seds_casadi.__file__))
#: hypothesis examples per class of input (``SEDS_FUZZ_SCALE=20`` multiplies them, for a
#: longer hunt outside CI)
EXAMPLES = {k: v * int(os.environ.get("SEDS_FUZZ_SCALE", "1")) for k, v in
            {"arrays": 150, "npz": 150, "csv": 80, "field": 200, "model": 120}.items()}


def _fuzz(n: int):
    return settings(max_examples=n, derandomize=True, deadline=None, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                           HealthCheck.function_scoped_fixture])


def assert_project_error(exc: BaseException, names=()) -> None:
    """``exc`` is a clear project error (module docstring); its message names one of
    ``names`` when given."""
    event(f"refused ({type(exc).__name__})")
    assert isinstance(exc, (ValueError, TypeError, SEDSError)), repr(exc)
    tb = exc.__traceback__
    while tb.tb_next is not None:
        tb = tb.tb_next
    where = os.path.abspath(tb.tb_frame.f_code.co_filename)
    assert where.startswith(PACKAGE), f"{type(exc).__name__} from inside {where}: {exc}"
    text = str(exc)
    assert len(text) > 10
    if names:
        assert any(str(n) in text for n in names), text


# ------------------------------------------------------------------ demonstrations (arrays)
_values = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                    st.floats(-10, 10), st.sampled_from([0.0, 1e-300, 1e200, -1e306]))


@st.composite
def _demo_arrays(draw):
    n = draw(st.integers(0, 3))
    d = draw(st.integers(0, 3))
    kind = draw(st.sampled_from(["float", "float", "int", "complex", "bool", "str", "ragged"]))
    out = []
    for _ in range(n):
        T = draw(st.integers(0, 12))
        a = np.array(draw(st.lists(_values, min_size=T * d, max_size=T * d))).reshape(T, d)
        if draw(st.booleans()):  # mostly smooth, moving data
            a = np.cumsum(np.ones((T, d)) * draw(st.floats(-2, 2)), axis=0) + a * 1e-3
        if kind == "int":
            a = np.nan_to_num(a).clip(-1e6, 1e6).astype(int)
        elif kind == "complex":
            a = a + 1j
        elif kind == "bool":
            a = a > 0
        elif kind == "str":
            a = a.astype(str)
        elif kind == "ragged" and T > 1:
            a = [list(r) for r in a[:-1]] + [list(a[-1]) + [0.0]]
        out.append(a)
    dt = draw(st.sampled_from([0.01, 0.0, -1.0, float("nan"), 1e-300, 1.0]))
    return out, dt


@_fuzz(EXAMPLES["arrays"])
@given(_demo_arrays())
def test_fuzz_demonstration_arrays(case):
    arrays, dt = case
    try:
        d = Demonstrations(arrays, dt=dt)
    except Exception as exc:  # noqa: BLE001 - the assertion is on what was raised
        assert_project_error(exc)
        return
    event("accepted")
    assert d.n_demos == len(arrays)
    for p, v, a in zip(d.positions, d.velocities, arrays):
        a = np.asarray(a, float)
        assert np.all(np.isfinite(p)) and np.all(np.isfinite(v)) and p.shape == v.shape
        assert p.shape[1] == (a.shape[1] if a.ndim == 2 else 1)
        assert _is_slice(p, a)


def _is_slice(p: np.ndarray, a: np.ndarray) -> bool:
    """p is a contiguous run of the rows of a (trimming standstill keeps a slice)."""
    a = a.reshape(len(a), -1)
    return any(np.array_equal(p, a[i:i + len(p)]) for i in range(len(a) - len(p) + 1))


# ------------------------------------------------------------------ demonstration files
_KEYS = ["pos_0", "pos_1", "pos_2", "pos_3", "vel_0", "vel_1", "t_0", "t_1", "dt", "target",
         "trget", "pos0", "position_0", "vel_2"]


@st.composite
def _npz_keys(draw):
    """Entry names: a well-formed file (pos_0..pos_{n-1} with dt, vel_n or t_n), perhaps with
    one entry dropped or added, or a random choice of names."""
    if draw(st.booleans()):
        return draw(st.lists(st.sampled_from(_KEYS), min_size=1, max_size=6, unique=True))
    n = draw(st.integers(1, 3))
    extra = draw(st.sampled_from(["dt", "vel", "t"]))
    keys = [f"pos_{i}" for i in range(n)] + (["dt"] if extra == "dt" else
                                             [f"{extra}_{i}" for i in range(n)])
    if draw(st.booleans()):
        keys.append("target")
    change = draw(st.sampled_from(["none", "none", "drop", "add"]))
    if change == "drop" and len(keys) > 1:
        keys.pop(draw(st.integers(0, len(keys) - 1)))
    elif change == "add":
        keys.append(draw(st.sampled_from([k for k in _KEYS if k not in keys])))
    return keys


@st.composite
def _npz_case(draw):
    keys = draw(_npz_keys())
    T, d = draw(st.integers(2, 10)), draw(st.integers(1, 3))
    data = {}
    for k in keys:
        if k == "dt":
            data[k] = np.array(draw(st.sampled_from([0.05, -1.0, 0.0, np.nan])))
        elif k == "target":
            data[k] = np.zeros(draw(st.sampled_from([d, d, 1, 3])))
        elif k.startswith("t_"):
            data[k] = np.arange(T + draw(st.integers(-1, 1))) * 0.05
        else:
            a = np.linspace(1.0, 0.0, T)[:, None] * (np.arange(d) + 1.0)
            if k.startswith("vel"):
                a = np.gradient(a, 0.05, axis=0) if T > 1 else a
            if draw(st.sampled_from([False, False, False, True])):
                a = a + 1j * draw(st.floats(-1, 1))
            data[k] = a
    return data


def _pos_count(data: dict) -> int:
    n = 0
    while f"pos_{n}" in data:
        n += 1
    return n


@_fuzz(EXAMPLES["npz"])
@given(_npz_case())
def test_fuzz_npz_demonstration_files(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("npz") / "demos.npz"
    np.savez(p, **data)
    try:
        d = load_demonstrations(p)
    except Exception as exc:  # noqa: BLE001
        assert_project_error(exc, [p])
        return
    event("accepted")
    # accepted: every entry was understood, nothing dropped
    assert set(data) <= {f"{w}_{i}" for w in ("pos", "vel", "t") for i in range(4)} | {
        "dt", "target"}
    assert d.n_demos == _pos_count(data) == sum(k.startswith("pos_") for k in data)
    for i, pos in enumerate(d.positions):
        assert np.isrealobj(data[f"pos_{i}"]) and _is_slice(pos, data[f"pos_{i}"])


@st.composite
def _csv_case(draw):
    d = draw(st.integers(1, 3))
    cols = ["demo", "t"] + [f"x{j}" for j in range(d)]
    if draw(st.booleans()):
        cols += [f"v{j}" for j in range(d)]
    mutation = draw(st.sampled_from(["none", "none", "drop", "duplicate", "rename", "shuffle",
                                     "bom", "quote", "interleave", "text", "short_row"]))
    if mutation == "drop" and len(cols) > 3:
        cols.pop(draw(st.integers(0, len(cols) - 1)))
    elif mutation == "duplicate":
        cols.append(draw(st.sampled_from(cols)))
    elif mutation == "rename":
        cols[draw(st.integers(0, len(cols) - 1))] = draw(st.sampled_from(
            ["time", "x", "X0", "y1", "x9", "v", "Demo", "t "]))
    elif mutation == "shuffle":
        cols = draw(st.permutations(cols))
    n_demos, T = draw(st.integers(1, 3)), draw(st.integers(2, 8))
    order = list(range(n_demos)) + ([0] if mutation == "interleave" and n_demos > 1 else [])
    rows = []
    for k in order:
        for i in range(T):
            val = {"demo": k, "t": 0.1 * i}
            for j in range(3):
                val[f"x{j}"] = (j + 1.0) * (1 - i / T) + 0.1 * k
                val[f"v{j}"] = -(j + 1.0) / (T * 0.1)
            rows.append([val.get(c.strip(), 0.5) for c in cols])
    lines = [",".join(f'"{c}"' if mutation == "quote" else c for c in cols)]
    lines += [",".join(repr(float(v)) for v in r) for r in rows]
    if mutation == "text":
        lines[-1] = lines[-1].replace("0.", "a.", 1)
    if mutation == "short_row":
        lines[-1] = lines[-1].rsplit(",", 1)[0]
    text = ("\ufeff" if mutation == "bom" else "") + "\n".join(lines) + "\n"
    return cols, rows, text


@_fuzz(EXAMPLES["csv"])
@given(_csv_case())
def test_fuzz_csv_demonstration_files(tmp_path_factory, case):
    cols, rows, text = case
    p = tmp_path_factory.mktemp("csv") / "demos.csv"
    p.write_text(text, encoding="utf-8")
    try:
        d = load_demonstrations(p)
    except Exception as exc:  # noqa: BLE001
        assert_project_error(exc, [p])
        return
    event("accepted")
    # accepted: the columns were x0..x{d-1} exactly, and the positions are those columns
    xs = sorted((c for c in cols if c.startswith("x")), key=lambda c: int(c[1:]))
    assert xs == [f"x{j}" for j in range(len(xs))] and len(set(cols)) == len(cols)
    table = np.array(rows, float)
    ids = table[:, cols.index("demo")]
    assert d.n_demos == len(np.unique(ids)) and d.n_dims == len(xs)
    for k, pos in enumerate(d.positions):
        own = table[ids == k][:, [cols.index(c) for c in xs]]
        assert _is_slice(pos, own)


# ------------------------------------------------------------------ field files
def _spec(name):
    with open(os.path.join(FIELDS_FOLDER, name + ".json")) as fh:
        return json.load(fh)


_FIELDS = {n: _spec(n) for n in ("flat", "rough_flat", "double_hill", "arctan")}
_json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-10**9, 10**9),
              st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=6),
              st.sampled_from([0, 1, -1, 0.5, 1e6, 1e300, 5001, 2.5])),
    lambda inner: st.one_of(st.lists(inner, max_size=5),
                            st.dictionaries(st.text(max_size=5), inner, max_size=3)),
    max_leaves=10)


def _paths(spec, prefix=()):
    """Every (path of keys/indices) inside a JSON value."""
    yield prefix
    if isinstance(spec, dict):
        for k, v in spec.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(spec, list) and len(spec) <= 8:
        for i, v in enumerate(spec):
            yield from _paths(v, prefix + (i,))


@st.composite
def _field_case(draw):
    name = draw(st.sampled_from(sorted(_FIELDS)))
    spec = json.loads(json.dumps(_FIELDS[name]))
    for _ in range(draw(st.integers(0, 2))):
        paths = [p for p in _paths(spec) if p]
        path = draw(st.sampled_from(paths))
        parent = spec
        for k in path[:-1]:
            parent = parent[k]
        action = draw(st.sampled_from(["replace", "scale", "scale", "delete", "misspell",
                                       "add"]))
        key = path[-1]
        if action == "scale":  # a plausible edit: a number changed by up to 50 %
            v = parent[key]
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                parent[key] = v * draw(st.floats(0.5, 1.5))
        elif action == "replace":
            parent[key] = draw(_json_values)
        elif action == "delete":
            del parent[key]
        elif isinstance(parent, dict) and isinstance(key, str):
            new = (key[:-1] if len(key) > 2 else key + "_") if action == "misspell" else \
                draw(st.text(min_size=1, max_size=8))
            parent[new] = parent.pop(key) if action == "misspell" else draw(_json_values)
    return name, spec


@_fuzz(EXAMPLES["field"])
@given(_field_case())
def test_fuzz_field_files(case):
    name, spec = case
    original = json.dumps(spec, sort_keys=True)
    try:
        f = Field.from_dict(spec, source="fuzz.json")
    except Exception as exc:  # noqa: BLE001
        assert_project_error(exc, ["fuzz.json"])
        return
    event("accepted")
    assert json.dumps(spec, sort_keys=True) == original  # the input is not changed
    # accepted: every entry is one the format knows, and it means what it says
    from seds_casadi.minigolf.field_schema import FIELD_KEYS, SURFACE_KEYS

    assert set(spec) <= set(FIELD_KEYS)
    assert set(spec["surface"]) <= {"shape", *SURFACE_KEYS[spec["surface"]["shape"]]}
    assert f.wall_restitution == spec.get("wall_restitution", 0.6)
    assert list(f.bounds) == spec["bounds"] and list(f.ball_region) == spec["ball_region"]
    assert f.hole.tolist() == [spec["hole"]["x"], spec["hole"]["y"]]
    assert np.isfinite(f.rolling_resistance) and f.rolling_resistance >= 0
    b = f.bounds
    P = np.column_stack([np.linspace(b[0], b[1], 7), np.linspace(b[2], b[3], 7)])
    assert np.all(np.isfinite(f.surface.height(P))) and np.all(np.isfinite(f.surface.gradient(P)))


# ------------------------------------------------------------------ model files
def _stable_ds() -> StableDS:
    I2 = np.eye(2)
    cov = np.block([[I2, -I2], [-I2, 2 * I2]])
    cov2 = np.block([[2 * I2, -3 * I2], [-3 * I2, 5 * I2]])
    return StableDS(np.array([0.4, 0.6]), np.array([[1.0, 0.0, -1.0, 0.0],
                                                    [0.0, 1.0, 0.0, -1.5]]),
                    np.stack([cov, cov2]), np.zeros(2), fit_info={"status": "fuzz"})


def _dataset() -> HittingDataset:
    n = 5
    return HittingDataset("flat", "centre", np.column_stack([np.full(n, 0.1),
                                                             np.linspace(-.2, .2, n)]),
                          np.tile([2.5, 0.0], (n, 1)), np.linspace(-0.1, 0.1, n),
                          np.linspace(1.0, 1.4, n),
                          Stroke(np.array([0.995, 0.097, -0.003]), 0.99))


_MODELS = {"stable_ds": (_stable_ds, StableDS.load), "dataset": (_dataset, HittingDataset.load)}


@st.composite
def _tamper(draw):
    kind = draw(st.sampled_from(sorted(_MODELS)))
    how = draw(st.sampled_from(["bytes", "truncate", "entry", "entry", "drop", "none"]))
    return kind, how, draw(st.integers(0, 2**31)), draw(st.sampled_from(
        [np.nan, np.inf, 0.0, -1.0, 1e300, 147.0, "text", "shape", "int", "complex"]))


def _same(a, b, kind) -> bool:
    if kind == "stable_ds":
        return (np.array_equal(a.priors, b.priors) and np.array_equal(a.means, b.means)
                and np.array_equal(a.covariances, b.covariances))
    return (np.array_equal(a.ball, b.ball) and np.array_equal(a.hole, b.hole)
            and np.allclose(a.alpha, b.alpha, rtol=0, atol=1e-15)
            and np.array_equal(a.kappa, b.kappa) and a.stroke.speed == b.stroke.speed
            and np.allclose(a.stroke.direction, b.stroke.direction, rtol=0, atol=1e-15))


@_fuzz(EXAMPLES["model"])
@given(_tamper())
def test_fuzz_model_files(tmp_path_factory, case):
    kind, how, seed, value = case
    make, load = _MODELS[kind]
    model = make()
    p = tmp_path_factory.mktemp("model") / f"{kind}.npz"
    model.save(p)
    rng = np.random.default_rng(seed)
    raw = bytearray(p.read_bytes())
    if how == "bytes":
        for i in rng.integers(0, len(raw), rng.integers(1, 4)):
            raw[i] ^= 1 << int(rng.integers(0, 8))
        p.write_bytes(bytes(raw))
    elif how == "truncate":
        p.write_bytes(bytes(raw[: int(rng.integers(0, len(raw)))]))
    elif how in ("entry", "drop"):
        with np.load(p) as z:
            data = {k: z[k] for k in z.files}
        key = sorted(data)[int(rng.integers(0, len(data)))]
        if how == "drop":
            del data[key]
        elif value == "shape":
            data[key] = np.zeros((2, 3))
        elif value == "int":
            data[key] = np.asarray(data[key]).astype(np.int64) if data[key].dtype.kind in "fi" \
                else np.array(3)
        elif value == "complex":
            data[key] = np.asarray(data[key], complex) if data[key].dtype.kind in "fi" \
                else np.array(1j)
        elif value == "text":
            data[key] = np.array("{}")
        else:
            a = np.array(data[key], dtype=float) if data[key].dtype.kind in "fi" else None
            if a is None or a.size == 0:
                data[key] = np.array(value)
            else:
                a.flat[int(rng.integers(0, a.size))] = value
                data[key] = a
        np.savez(p, **data)
    try:
        back = load(p)
    except Exception as exc:  # noqa: BLE001
        assert isinstance(exc, ModelFileError), repr(exc)
        assert_project_error(exc, [p])
        return
    event("accepted")
    # loaded: the file still holds exactly what was saved
    assert _same(model, back, kind), f"{how} {value}: a changed file loaded"
