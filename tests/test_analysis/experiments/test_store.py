"""The SQLite results store: stable keys, lossless arrays, no duplicates, reopening."""

from __future__ import annotations

import sqlite3

import numpy as np
import pytest

from analysis.experiments.store import ResultStore, canonical_json, task_key


def test_task_key_is_stable_and_canonical():
    a = task_key("ens", {"spins": 100, "coupling": 4.0, "seed": 7})
    # key order, numpy scalar types and integral floats do not matter
    b = task_key("ens", {"seed": np.int64(7), "coupling": np.float64(4), "spins": 100.0})
    assert a == b
    assert len(a) == 64 and int(a, 16) >= 0
    # a fixed value: the key must never change between versions (stored files stay valid)
    assert canonical_json({"b": 1.5, "a": [1, 2.0, "x"]}) == '{"a":[1,2,"x"],"b":1.5}'
    assert a != task_key("ens", {"spins": 100, "coupling": 4.0, "seed": 8})
    assert a != task_key("ens", {"spins": 100, "coupling": 4.0000001, "seed": 7})
    assert a != task_key("other", {"spins": 100, "coupling": 4.0, "seed": 7})
    with pytest.raises(TypeError):
        task_key("ens", {"f": object()})
    with pytest.raises(ValueError):
        task_key("", {"a": 1})


def _arrays():
    rng = np.random.default_rng(3)
    return {
        "f64": np.array([0.1, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1.7976931348623157e308]),
        "f32": rng.normal(size=(3, 4)).astype(np.float32),
        "int": np.arange(-5, 5, dtype=np.int64).reshape(2, 5),
        "uint8": np.array([0, 255], dtype=np.uint8),
        "bool": np.array([True, False, True]),
        "complex": np.array([1 + 2j, -3.5j]),
        "scalar": np.array(2.5),
        "empty": np.zeros((0, 3)),
        "fortran": np.asfortranarray(rng.normal(size=(4, 3))),
        "structured": np.array([(1, 2.5), (3, -1.0)], dtype=[("i", "<i4"), ("x", "<f8")]),
    }


def test_arrays_round_trip_exactly(tmp_path):
    arrays = _arrays()
    results = {"arrays": arrays, "list": [np.arange(3), 1.0, "s"], "top": np.linspace(0, 1, 7)}
    with ResultStore(tmp_path / "r.sqlite") as store:
        key = store.put("exp", {"seed": 1}, results, wall_time=0.25)
    with ResultStore(tmp_path / "r.sqlite") as store:  # reopen: persisted
        got = store.get(key)
    for name, a in arrays.items():
        b = got.results["arrays"][name]
        assert b.dtype == a.dtype and b.shape == a.shape, name
        assert b.tobytes(order="A") == a.tobytes(order="A"), name  # bit-exact (nan, -0.0)
    assert np.array_equal(got.results["list"][0], np.arange(3))
    assert got.results["list"][1:] == [1.0, "s"]
    assert np.array_equal(got.results["top"], np.linspace(0, 1, 7))
    assert got.wall_time == 0.25
    assert got.code_version.startswith("hysteresis-toolkit")
    assert got.params == {"seed": 1}


def test_scalars_and_nested_round_trip(tmp_path):
    res = {
        "d_ky": 1.2345678901234567,
        "n": 3,
        "flag": True,
        "none": None,
        "nan": float("nan"),
        "numpy_scalar": np.float64(0.1) + np.float64(0.2),
        "nested": {"a": [1, 2, {"b": "c"}]},
        "tuple": (1, 2),
    }
    with ResultStore(tmp_path / "r.sqlite") as store:
        key = store.put("exp", {"x": 1}, res)
        got = store.get(key).results
    assert got["d_ky"] == 1.2345678901234567
    assert got["numpy_scalar"] == 0.1 + 0.2 and type(got["numpy_scalar"]) is float
    assert got["n"] == 3 and got["flag"] is True and got["none"] is None
    assert np.isnan(got["nan"])
    assert got["nested"] == {"a": [1, 2, {"b": "c"}]}
    assert got["tuple"] == [1, 2]


def test_insert_or_ignore_never_duplicates(tmp_path):
    path = tmp_path / "r.sqlite"
    with ResultStore(path) as store:
        k1 = store.put("exp", {"seed": 1, "c": 4.0}, {"v": np.array([1.0, 2.0])})
        k2 = store.put("exp", {"c": 4, "seed": 1}, {"v": np.array([9.0])})  # same key
        assert k1 == k2
        assert len(store) == 1
        assert np.array_equal(store.get(k1).results["v"], [1.0, 2.0])  # first result wins
    con = sqlite3.connect(path)
    assert con.execute("SELECT COUNT(*) FROM tasks").fetchone()[0] == 1
    assert con.execute("SELECT COUNT(*) FROM arrays").fetchone()[0] == 1
    # a rollback journal, not a write-ahead log: the committed tasks are in the file itself
    assert con.execute("PRAGMA journal_mode").fetchone()[0] == "delete"
    con.close()
    assert not path.with_name(path.name + "-wal").exists()


def test_queries_and_table(tmp_path):
    with ResultStore(tmp_path / "r.sqlite") as store:
        for spins in (10, 20):
            for seed in range(3):
                store.put(
                    "ens",
                    {"spins": spins, "coupling": 4.0, "seed": seed},
                    {"m": spins + seed / 10, "section": np.full((2, 3), seed, dtype=float)},
                )
        store.put("other", {"x": 1}, {"m": 0.0})
        assert store.experiments() == ["ens", "other"]
        assert len(store.keys("ens")) == 6 and len(store.keys()) == 7
        key = task_key("ens", {"spins": 20, "coupling": 4, "seed": 2})
        assert store.has(key) and key in store
        assert store.get(key).results["m"] == pytest.approx(20.2)
        assert not store.has(task_key("ens", {"spins": 30, "coupling": 4, "seed": 2}))
        with pytest.raises(KeyError):
            store.get("0" * 64)
        loaded = store.load("ens")
        assert [p["seed"] for p, _ in loaded] == [0, 1, 2, 0, 1, 2]  # insertion order
        tab = store.table("ens")
        assert tab["spins"].tolist() == [10, 10, 10, 20, 20, 20]
        assert tab["m"] == pytest.approx([10.0, 10.1, 10.2, 20.0, 20.1, 20.2])
        assert tab["section"].shape == (6, 2, 3)
        sub = store.table("ens", fields=["m"], where={"spins": 20.0})
        assert sub["m"] == pytest.approx([20.0, 20.1, 20.2]) and set(sub) == {
            "spins",
            "coupling",
            "seed",
            "m",
        }
        assert store.table("ens", where={"spins": 99}) == {}


def test_put_rejects_unstorable(tmp_path):
    with ResultStore(tmp_path / "r.sqlite") as store:
        with pytest.raises(TypeError):
            store.put("exp", {"a": 1}, {"obj": np.array([object()], dtype=object)})
        with pytest.raises(TypeError):
            store.put("exp", {"a": 1}, [1, 2])  # type: ignore[arg-type]
        assert len(store) == 0  # nothing half-written
