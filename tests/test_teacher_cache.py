"""The cache of the teacher's data sets (seds_casadi.app.teacher_cache): real teacher runs."""

import json

import numpy as np
import pytest

from seds_casadi.app.teacher_cache import cached_dataset, dataset_key
from seds_casadi.minigolf.fields import Field, load_field
from seds_casadi.minigolf.stroke import Stroke

SETTINGS = {"n": 4, "resolution": (41, 13)}


@pytest.fixture()
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SEDS_CASADI_CACHE", str(tmp_path))
    return tmp_path


def test_a_second_request_comes_from_the_cache_and_is_the_same(cache):
    field, stroke = load_field("flat"), Stroke(np.array([1.0, 0.0, 0.0]), 1.0)
    first, hit1 = cached_dataset(field, stroke, **SETTINGS)
    second, hit2 = cached_dataset(field, stroke, **SETTINGS)
    assert (hit1, hit2) == (False, True)
    assert len(first) == len(second) > 0
    assert np.array_equal(first.situations, second.situations)
    assert np.array_equal(first.outputs, second.outputs)
    assert len(list((cache / "teacher").glob("*.npz"))) == 1
    # without the cache the teacher runs again and gives the same shots
    third, hit3 = cached_dataset(field, stroke, use_cache=False, **SETTINGS)
    assert not hit3 and np.array_equal(third.outputs, first.outputs)


def test_the_key_changes_with_the_field_the_stroke_and_the_settings():
    field, stroke = load_field("flat"), Stroke(np.array([1.0, 0.0, 0.0]), 1.0)
    spec = json.loads(json.dumps(field.spec))
    spec["hole"]["x"] = spec["hole"]["x"] - 0.1
    moved = Field.from_dict(spec, source="moved")
    keys = {dataset_key(field, stroke, SETTINGS), dataset_key(moved, stroke, SETTINGS),
            dataset_key(field, Stroke(np.array([1.0, 0.0, 0.0]), 1.01), SETTINGS),
            dataset_key(field, stroke, dict(SETTINGS, n=5))}
    assert len(keys) == 4
    assert dataset_key(field, stroke, SETTINGS) == dataset_key(load_field("flat"), stroke,
                                                               dict(SETTINGS))


def test_a_damaged_entry_is_taught_again(cache, caplog):
    field, stroke = load_field("flat"), Stroke(np.array([1.0, 0.0, 0.0]), 1.0)
    good, _ = cached_dataset(field, stroke, **SETTINGS)
    (entry,) = (cache / "teacher").glob("*.npz")
    entry.write_bytes(b"not an npz file")
    again, hit = cached_dataset(field, stroke, **SETTINGS)
    assert not hit and np.array_equal(again.outputs, good.outputs)
    assert "unreadable" in caplog.text
    assert cached_dataset(field, stroke, **SETTINGS)[1]   # and stored again
