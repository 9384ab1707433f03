"""dyncheck.results.store: every kind of value comes back as it was saved, every float bit for bit, and saving
the same value twice gives the same bytes."""

import dataclasses
import enum
import json
import struct
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from dyncheck.results import store


@store.register
class Colour(enum.StrEnum):
    RED = "red"
    BLUE = "blue"


@store.register
@dataclasses.dataclass(frozen=True)
class Leaf:
    colour: Colour
    values: np.ndarray
    note: str | None = None


@store.register
@dataclasses.dataclass(frozen=True)
class Tree:
    leaves: tuple
    table: pd.DataFrame
    derived: int = dataclasses.field(init=False, default=0)  # not an init field: not saved


class Unregistered:
    pass


def assert_same(saved, loaded, path="value"):
    """`loaded` is `saved`: same types (numpy scalars as Python numbers), every float the same bits."""
    if isinstance(saved, np.generic):
        saved = saved.item()
    assert type(loaded) is type(saved), f"{path}: {type(loaded)} is not {type(saved)}"
    if isinstance(saved, float):
        assert bits(loaded) == bits(saved), f"{path}: {loaded!r} is not {saved!r}"
    elif isinstance(saved, (list, tuple)):
        assert len(loaded) == len(saved), path
        for i, (a, b) in enumerate(zip(saved, loaded)):
            assert_same(a, b, f"{path}[{i}]")
    elif isinstance(saved, dict):
        assert list(loaded) == list(saved), path
        for key in saved:
            assert_same(saved[key], loaded[key], f"{path}[{key!r}]")
    elif isinstance(saved, np.ndarray):
        assert (loaded.dtype, loaded.shape) == (saved.dtype, saved.shape), path
        assert loaded.tobytes() == saved.tobytes(), path
    elif isinstance(saved, pd.DataFrame):
        pd.testing.assert_frame_equal(loaded, saved, check_exact=True)
        assert_same_index(saved.index, loaded.index, f"{path}.index")
        for i in range(saved.shape[1]):
            assert_same_index(saved.iloc[:, i], loaded.iloc[:, i], f"{path}.iloc[:, {i}]")
        assert_same(saved.attrs, loaded.attrs, f"{path}.attrs")
    elif isinstance(saved, pd.Series):
        pd.testing.assert_series_equal(loaded, saved, check_exact=True)
        assert_same_index(saved, loaded, path)
        assert_same(saved.attrs, loaded.attrs, f"{path}.attrs")
    elif dataclasses.is_dataclass(saved):
        for field in dataclasses.fields(saved):
            assert_same(getattr(saved, field.name), getattr(loaded, field.name), f"{path}.{field.name}")
    else:
        assert loaded == saved, path


def assert_same_index(saved, loaded, path):
    """The bits of numeric values (assert_frame_equal takes NaN for NaN and -0.0 for 0.0)."""
    if isinstance(saved.dtype, np.dtype) and saved.dtype.kind in "biufc":
        assert loaded.to_numpy().tobytes() == saved.to_numpy().tobytes(), path


def bits(x):
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def round_trip(value):
    with tempfile.TemporaryDirectory() as folder:
        store.save(value, Path(folder) / "results")
        loaded = store.load(Path(folder) / "results")
    assert_same(value, loaded)
    return loaded


def folder_bytes(folder):
    return {file.name: file.read_bytes() for file in sorted(Path(folder).iterdir())}


def sample_frame():
    frame = pd.DataFrame({"x": [1.0, -0.0, np.nan, 5e-324], "n": [1, 2, 3, -4], "ok": [True, False, True, True],
                          "label": ["a", "θ'", None, ""]}, index=pd.Index([0.0, 0.1, 0.2, np.inf], name="t"))
    frame.attrs = {"unit": "m", "limits": (0.0, 1.0), "weights": np.arange(3.0)}
    return frame


def sample_value():
    return {"runs": {"mujoco": [sample_frame(), None], "pinocchio": pd.Series([1.5, 2.5], name="q", index=[3, 4])},
            "tuple": (1, "two", 3.0, (), [], {}), "floats": [float("nan"), float("inf"), -float("inf"), -0.0, 1e308],
            "numpy": [np.float64(0.1), np.float32(0.1), np.int64(-7), np.bool_(True)],
            "arrays": [np.zeros((0, 3)), np.array(2.5), np.arange(6, dtype=np.int16).reshape(2, 3),
                       np.array([True, False]), np.asfortranarray(np.eye(3)), np.array([1 + 2j])],
            "$type": "a dict with the store's tag as a key", "big": 10**30, "ok": False}


# -- round trips ------------------------------------------------------------------------------------

def test_every_kind_of_value_round_trips():
    loaded = round_trip(sample_value())
    assert loaded["numpy"] == [0.1, float(np.float32(0.1)), -7, True]


def test_frames_and_series():
    frame = sample_frame()
    loaded = round_trip({"frame": frame})["frame"]
    assert loaded.index.name == "t" and loaded.attrs["limits"] == (0.0, 1.0)
    round_trip(pd.DataFrame())
    round_trip(pd.DataFrame(columns=["a", "b"]))
    round_trip(pd.DataFrame(index=pd.Index([0.5, 1.5], name="t")))
    round_trip(pd.DataFrame({"s": pd.Series(["x", None], dtype=object)}, index=pd.Index(["p", "q"], name="k")))
    duplicated = pd.DataFrame([[1.0, 2.0]], columns=["a", "a"], index=pd.Index([np.nan], name="t"))
    round_trip(duplicated)
    series = pd.Series([True, False], index=pd.RangeIndex(10, 14, 2, name="i"), name=3)
    series.attrs = {"why": "a test"}
    round_trip(series)


def test_registered_dataclasses_and_enums():
    tree = Tree(leaves=(Leaf(Colour.RED, np.arange(3.0)), Leaf(Colour.BLUE, np.zeros(0), "empty")),
                table=sample_frame())
    loaded = round_trip({"tree": tree, "colour": Colour.BLUE})
    assert loaded["colour"] is Colour.BLUE and loaded["tree"].leaves[1].colour is Colour.BLUE


floats = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
nan_payloads = st.integers(0, 2**52 - 1).map(lambda payload: struct.unpack("<d", struct.pack(
    "<Q", 0xFFF0000000000000 | payload | 1))[0])  # negative NaNs with any payload, quiet or signalling
shapes = hnp.array_shapes(min_dims=0, min_side=0)
float_arrays = (hnp.arrays(st.sampled_from([np.float64, np.float32, np.float16]), shapes,
                           elements={"allow_nan": True, "allow_subnormal": True})
                | hnp.arrays(np.uint64, shapes).map(lambda words: words.view(np.float64)))  # any bits at all


@settings(max_examples=60, deadline=None)
@given(st.lists(floats | nan_payloads, max_size=5), float_arrays)
def test_floats_round_trip_bit_exactly(scalars, array):
    round_trip({"scalars": scalars, "array": array})


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_frames_of_random_floats_round_trip_bit_exactly(data):
    rows = data.draw(st.integers(0, 6))
    column = lambda elements: data.draw(st.lists(elements, min_size=rows, max_size=rows))
    frame = pd.DataFrame({"x": np.array(column(floats | nan_payloads), dtype=float),
                          "n": np.array(column(st.integers(-2**63, 2**63 - 1)), dtype=np.int64),
                          "ok": np.array(column(st.booleans()), dtype=bool), "s": column(st.text(max_size=3))},
                         index=pd.Index(np.array(column(floats), dtype=float), name="t"))
    frame.attrs = {"seed": data.draw(st.integers()), "scale": data.draw(floats)}
    round_trip(frame)


values = st.recursive(
    st.none() | st.booleans() | st.integers() | floats | st.text(),
    lambda children: st.lists(children, max_size=3) | st.lists(children, max_size=3).map(tuple)
    | st.dictionaries(st.text(max_size=5), children, max_size=3),
    max_leaves=12)


@settings(max_examples=60, deadline=None)
@given(values)
def test_nested_values_round_trip(value):
    round_trip(value)


# -- the bytes --------------------------------------------------------------------------------------

def test_saving_twice_gives_the_same_bytes(tmp_path):
    store.save(sample_value(), tmp_path / "first")
    store.save(sample_value(), tmp_path / "second")
    first = folder_bytes(tmp_path / "first")
    assert set(first) == {"value.json", "arrays.npz"}
    assert first == folder_bytes(tmp_path / "second")
    with zipfile.ZipFile(tmp_path / "first" / "arrays.npz") as archive:
        assert {entry.date_time for entry in archive.infolist()} == {(1980, 1, 1, 0, 0, 0)}
    # an array's memory layout does not show: the same values in Fortran order save the same
    store.save({"a": np.eye(3)}, tmp_path / "c")
    store.save({"a": np.asfortranarray(np.eye(3))}, tmp_path / "fortran")
    assert folder_bytes(tmp_path / "c") == folder_bytes(tmp_path / "fortran")


def test_json_is_standard_and_keeps_dict_order(tmp_path):
    store.save({"b": float("nan"), "a": 1.0}, tmp_path / "r")
    text = (tmp_path / "r" / "value.json").read_text()
    assert "NaN" not in text
    document = json.loads(text)
    assert (document["format"], document["version"]) == ("dyncheck-results", 1)
    assert list(document["value"]) == ["b", "a"]


def test_save_replaces_results_and_leaves_nothing_else(tmp_path):
    store.save({"old": 1, "array": np.zeros(2)}, tmp_path / "r")
    store.save({"new": 2}, tmp_path / "r")
    assert store.load(tmp_path / "r") == {"new": 2}
    assert [path.name for path in tmp_path.iterdir()] == ["r"]


def test_save_will_not_replace_a_folder_of_other_files(tmp_path):
    (tmp_path / "reports").mkdir()
    (tmp_path / "reports" / "index.md").write_text("# not results")
    with pytest.raises(ValueError, match="not a results folder"):
        store.save({}, tmp_path / "reports")
    assert (tmp_path / "reports" / "index.md").exists()


# -- errors -----------------------------------------------------------------------------------------

def test_an_unregistered_type_is_named_with_its_path(tmp_path):
    store.save({"kept": 1}, tmp_path / "r")
    with pytest.raises(TypeError, match=r'value\["runs"\]\["mujoco"\]\[0\]: .*Unregistered is not registered'):
        store.save({"runs": {"mujoco": [Unregistered()]}}, tmp_path / "r")
    assert store.load(tmp_path / "r") == {"kept": 1}  # the failed save touched nothing
    with pytest.raises(TypeError, match=r"value\[1\]: key 2 is a int"):
        store.save([0, {2: "x"}], tmp_path / "s")
    with pytest.raises(TypeError, match=r"value\.iloc\[:, 0\]\[0\]: .*Unregistered is not registered"):
        store.save(pd.DataFrame({"mixed": [Unregistered(), 1]}, dtype=object), tmp_path / "s")
    with pytest.raises(TypeError, match="array of <U1"):
        store.save(np.array(["a"]), tmp_path / "s")


def test_register_refuses_what_it_cannot_rebuild():
    @dataclasses.dataclass
    class Mutable:
        x: int

    with pytest.raises(TypeError, match="neither a frozen dataclass nor an enum"):
        store.register(Mutable)
    with pytest.raises(ValueError, match="both be saved as 'Leaf'"):
        store.register(dataclasses.dataclass(frozen=True)(type("Leaf", (), {"__module__": "elsewhere"})))


def edit_document(folder, **changes):
    file = folder / "value.json"
    file.write_text(json.dumps({**json.loads(file.read_text()), **changes}))


def test_load_refuses_another_format_or_a_newer_version(tmp_path):
    store.save({"x": 1}, tmp_path / "r")
    edit_document(tmp_path / "r", version=2)
    with pytest.raises(ValueError, match=r"r/value\.json: version 2 is newer than this dyncheck reads \(1\)"):
        store.load(tmp_path / "r")
    edit_document(tmp_path / "r", version=1, format="something-else")
    with pytest.raises(ValueError, match=r"value\.json: format 'something-else', not 'dyncheck-results'"):
        store.load(tmp_path / "r")


def test_load_names_what_is_missing_or_corrupt(tmp_path):
    with pytest.raises(ValueError, match=r"nowhere: no such results folder"):
        store.load(tmp_path / "nowhere")
    store.save({"a": np.zeros(3), "leaf": Leaf(Colour.RED, np.zeros(1))}, tmp_path / "r")
    (tmp_path / "r" / "arrays.npz").write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"arrays\.npz: cannot read arrays"):
        store.load(tmp_path / "r")
    (tmp_path / "r" / "arrays.npz").unlink()
    with pytest.raises(ValueError, match=r"arrays\.npz: cannot read arrays"):
        store.load(tmp_path / "r")
    with zipfile.ZipFile(tmp_path / "r" / "arrays.npz", "w"):
        pass
    missing_entry = r"""value\.json: corrupt results: value\["a"\]: arrays\.npz has no entry 'a0'"""
    with pytest.raises(ValueError, match=missing_entry):
        store.load(tmp_path / "r")
    (tmp_path / "r" / "value.json").write_text("{")
    with pytest.raises(ValueError, match=r"value\.json: cannot read results"):
        store.load(tmp_path / "r")
    (tmp_path / "r" / "value.json").unlink()
    with pytest.raises(ValueError, match=r"value\.json: cannot read results"):
        store.load(tmp_path / "r")


def test_load_names_an_unknown_class(tmp_path):
    store.save({"leaf": Leaf(Colour.RED, np.zeros(1))}, tmp_path / "r")
    file = tmp_path / "r" / "value.json"
    file.write_text(file.read_text().replace('"Leaf"', '"Gone"'))
    with pytest.raises(ValueError, match=r"""value\["leaf"\]: class 'Gone' \(of [\w.]+\) is not registered"""):
        store.load(tmp_path / "r")


def test_load_imports_the_project_module_a_class_names_and_no_other(tmp_path, monkeypatch):
    """A saved class's module is imported on load if it is the project's (a result loads in a process that
    imported nothing else: tests/test_campbell.py runs that); a results file naming another module runs
    none of its code."""
    store.save({"leaf": Leaf(Colour.RED, np.zeros(1))}, tmp_path / "r")
    (tmp_path / "planted.py").write_text("import pathlib; pathlib.Path(__file__).with_suffix('.ran').touch()\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    file = tmp_path / "r" / "value.json"
    text = file.read_text()
    assert f'"module": "{Leaf.__module__}"' in text
    file.write_text(text.replace('"Leaf"', '"Gone"').replace(f'"{Leaf.__module__}"', '"planted"'))
    with pytest.raises(ValueError, match=r"class 'Gone' \(of planted\) is not registered"):
        store.load(tmp_path / "r")
    assert not (tmp_path / "planted.ran").exists()


def test_an_object_column_of_any_values_round_trips(tmp_path):
    """A study's tidy table may hold tuples (a start state) or numbers beside text in one column."""
    frame = pd.DataFrame({"start": [(0.5, 1.0), (3.0, 3.1)], "mixed": ["a", 1.5], "x": [1.0, 2.0]})
    store.save(frame, tmp_path / "s")
    back = store.load(tmp_path / "s")
    assert list(back["start"]) == [(0.5, 1.0), (3.0, 3.1)] and list(back["mixed"]) == ["a", 1.5]
    pd.testing.assert_frame_equal(back, frame)


def test_a_read_only_mapping_comes_back_a_dict(tmp_path):
    """A case's parameters are a read-only view; a study may keep them in what it returns."""
    from types import MappingProxyType
    store.save({"params": MappingProxyType({"k": 2000.0})}, tmp_path / "s")
    assert store.load(tmp_path / "s") == {"params": {"k": 2000.0}}


@pytest.mark.parametrize("name, module", [("Vibration", "dyncheck.vibration"), ("Floquet", "dyncheck.vibration"),
                                          ("Sweep", "dyncheck.campbell"), ("Escape", "dyncheck.simulate"),
                                          ("Row", "dyncheck.results")])
def test_a_class_saved_under_its_module_before_the_move_loads_in_a_fresh_process(name, module):
    """Results saved before the layout of a package per stage name the old modules (dyncheck.vibration, ...): a
    process that imported only the store still finds each class (store.MOVED)."""
    code = ("from dyncheck.results import store\n"
            f"cls = store._registered({{'class': {name!r}, 'module': {module!r}}}, 'value')\n"
            "print(cls.__name__, cls.__module__)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[0] == name and done.stdout.split()[1].startswith("dyncheck.")

