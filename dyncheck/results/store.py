"""Save results to a folder and load them back, byte for byte the same for the same values.

`save(value, folder)` writes a nested value; `load(folder)` returns an equal one, every float
bit-exact.  The folder holds:

- `value.json`: `{"format": "dyncheck-results", "version": 1, "value": TREE}`.  In TREE, dicts
  (order kept), lists, str, int, bool, None and finite floats are themselves; every other value is
  an object with a "$type": "float" (nan, inf), "tuple", "dict" (one with a "$type" key of its own),
  "array" (an entry of arrays.npz), "frame" and "series" (pandas; numeric columns in arrays.npz,
  string columns in the JSON), "dataclass" and "enum" (a class registered with `register`).
- `arrays.npz`: the arrays, entries `a0.npy`, `a1.npy`, ... in the order TREE meets them.

numpy scalars come back as Python numbers.  A dataclass or enum is saved with its module's name, which
`load` imports (the project's modules only) if its class is not registered yet.
"""

import dataclasses
import enum
import importlib
import io
import json
import math
import shutil
import struct
import tempfile
import zipfile
from pathlib import Path
from types import MappingProxyType

import numpy as np

FORMAT = "dyncheck-results"
VERSION = 1
TAG = "$type"
NUMERIC_KINDS = "biufc"  # bool, int, unsigned, float, complex: what a .npy entry holds without pickling
ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # zip's earliest date, instead of the time of saving

_registry = {}  # class name -> class
# The modules that saved classes lived in before the layout of a package per stage (issue 36), as results saved
# then name them: the module that now defines (or, for dyncheck.vibration's, imports) them.
MOVED = {"dyncheck.results": "dyncheck.results.values", "dyncheck.simulate": "dyncheck.run.simulate",
         "dyncheck.vibration": "dyncheck.checks.vibration", "dyncheck.campbell": "dyncheck.studies.campbell"}


def register(cls):
    """Let `save` write instances of a frozen dataclass (its init fields) or members of an enum (their
    value), under the class's name; usable as a class decorator."""
    frozen_dataclass = dataclasses.is_dataclass(cls) and cls.__dataclass_params__.frozen
    if not (isinstance(cls, type) and (frozen_dataclass or issubclass(cls, enum.Enum))):
        raise TypeError(f"dyncheck.results.store.register: {cls!r} is neither a frozen dataclass nor an enum")
    known = _registry.get(cls.__name__)
    if known is not None and (known.__module__, known.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"dyncheck.results.store.register: {cls.__module__}.{cls.__qualname__} and "
                         f"{known.__module__}.{known.__qualname__} would both be saved as {cls.__name__!r}")
    _registry[cls.__name__] = cls
    return cls


def save(value, folder):
    """Write `value` to `folder`, replacing the results there: it is written to a new sibling folder
    first and renamed into place, so a crash leaves the old results or the new ones, never half (or, at
    worst between the two renames, the old ones in a hidden `.NAME.*.old` sibling)."""
    folder = Path(folder)
    arrays = []
    document = {"format": FORMAT, "version": VERSION, "value": _encode(value, "value", arrays)}
    text = json.dumps(document, indent=1, ensure_ascii=False, allow_nan=False) + "\n"
    if folder.exists() and not (folder / "value.json").is_file() and (folder.is_file() or any(folder.iterdir())):
        raise ValueError(f"{folder}: not a results folder (no value.json), so save will not replace it")
    folder.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(dir=folder.parent, prefix=f".{folder.name}."))
    try:
        (staging / "value.json").write_text(text, encoding="utf-8")
        _write_arrays(staging / "arrays.npz", arrays)
        staging.chmod(0o755)  # mkdtemp makes it private; results are to be read by anyone
        if folder.exists():
            retired = staging.with_name(staging.name + ".old")
            folder.rename(retired)
            staging.rename(folder)
            shutil.rmtree(retired)
        else:
            staging.rename(folder)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def load(folder):
    """The value saved in `folder`; ValueError naming the file when it is missing, corrupt, of another
    format or of a newer version."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: no such results folder")
    tree_file, arrays_file = folder / "value.json", folder / "arrays.npz"
    try:
        document = json.loads(tree_file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:  # ValueError: bad JSON or UTF-8
        raise ValueError(f"{tree_file}: cannot read results: {error}") from None
    found = document.get("format") if isinstance(document, dict) else None
    if found != FORMAT:
        raise ValueError(f"{tree_file}: format {found!r}, not {FORMAT!r}")
    version = document.get("version")
    if type(version) is not int or version < 1:
        raise ValueError(f"{tree_file}: version {version!r} is not a version of {FORMAT}")
    if version > VERSION:
        raise ValueError(f"{tree_file}: version {version} is newer than this dyncheck reads ({VERSION}); "
                         "update dyncheck")
    try:
        with zipfile.ZipFile(arrays_file) as archive:
            return _decode(document["value"], "value", archive)
    except (OSError, zipfile.BadZipFile) as error:
        raise ValueError(f"{arrays_file}: cannot read arrays: {error}") from None
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as error:
        raise ValueError(f"{tree_file}: corrupt results: {error}") from None


# -- saving ---------------------------------------------------------------------------------------

def _pandas():
    """pandas, imported where a frame or series is met: importing it takes 0.4 s, which a command that saves and
    loads none (`run --quick`) does not spend."""
    import pandas
    return pandas


def _encode(value, path, arrays):
    """The JSON tree of `value`, its arrays appended to `arrays`; `path` (value["runs"][0]) names it
    in errors."""
    pd = _pandas()
    if isinstance(value, np.generic):
        return _encode(value.item(), path, arrays)
    if isinstance(value, MappingProxyType):  # a read-only view of a dict (a case's parameters): comes back a dict
        return _encode(dict(value), path, arrays)
    if value is None or type(value) in (bool, int, str):
        return value
    if type(value) is float:
        if math.isfinite(value):
            return value  # json writes repr(value), which reads back as the same float
        node = {TAG: "float", "value": repr(value)}
        if math.isnan(value) and _bits(value) != _bits(math.nan):
            node["bits"] = f"{_bits(value):016x}"  # a NaN's sign and payload
        return node
    if type(value) in (list, tuple):
        items = [_encode(item, f"{path}[{i}]", arrays) for i, item in enumerate(value)]
        return items if type(value) is list else {TAG: "tuple", "items": items}
    if type(value) is dict:
        items = {}
        for key, item in value.items():
            if type(key) is not str:
                raise TypeError(f"cannot save {path}: key {key!r} is a {type(key).__name__}, not a str")
            items[key] = _encode(item, _key_path(path, key), arrays)
        return {TAG: "dict", "items": list(items.items())} if TAG in items else items
    if type(value) is np.ndarray:
        if value.dtype.kind not in NUMERIC_KINDS:
            raise TypeError(f"cannot save {path}: an array of {value.dtype}, not of numbers or bools")
        return {TAG: "array", "entry": _add(value, arrays)}
    if type(value) is pd.DataFrame:
        return {TAG: "frame", "index": _encode_index(value.index, f"{path}.index", arrays),
                "columns": _encode_index(value.columns, f"{path}.columns", arrays),
                "data": [_encode_values(value.iloc[:, i], f"{path}.iloc[:, {i}]", arrays)
                         for i in range(value.shape[1])],
                "attrs": _encode(value.attrs, f"{path}.attrs", arrays)}
    if type(value) is pd.Series:
        return {TAG: "series", "name": _encode(value.name, f"{path}.name", arrays),
                "index": _encode_index(value.index, f"{path}.index", arrays),
                "data": _encode_values(value, path, arrays), "attrs": _encode(value.attrs, f"{path}.attrs", arrays)}
    cls = type(value)
    if _registry.get(cls.__name__) is not cls:
        raise TypeError(f"cannot save {path}: {cls.__module__}.{cls.__qualname__} is not registered "
                        "with dyncheck.results.store (decorate the class with @store.register)")
    if isinstance(value, enum.Enum):
        return {TAG: "enum", "class": cls.__name__, "module": cls.__module__,
                "value": _encode(value.value, f"{path}.value", arrays)}
    return {TAG: "dataclass", "class": cls.__name__, "module": cls.__module__,
            "fields": {field.name: _encode(getattr(value, field.name), f"{path}.{field.name}", arrays)
                       for field in dataclasses.fields(value) if field.init}}


def _registered(node, path):
    """The class a saved object names, its module imported first if that has not happened yet: a saved
    result loads in a process that imported only this module's caller.  Only the project's own modules are
    imported: a results folder is data, and must not name code to run."""
    name, module = node["class"], node.get("module", "")
    module = MOVED.get(module, module)
    if name not in _registry and module.partition(".")[0] == __name__.partition(".")[0]:
        try:
            importlib.import_module(module)
        except ImportError:
            pass  # the class has moved or gone since the save: said below
    cls = _registry.get(name)
    if cls is None:
        raise ValueError(f"{path}: class {name!r} (of {module or 'an unnamed module'}) is not registered with "
                         "dyncheck.results.store (import the module that defines it)")
    return cls


def _encode_index(index, path, arrays):
    pd = _pandas()
    name = _encode(index.name, f"{path}.name", arrays)
    if type(index) is pd.RangeIndex:
        return {"name": name, "range": [index.start, index.stop, index.step]}
    return {"name": name, **_encode_values(index, path, arrays)}


def _encode_values(values, path, arrays):
    """A Series' or an Index's values: numbers and bools as an array, strings in the JSON."""
    pd = _pandas()
    dtype = values.dtype
    if isinstance(dtype, np.dtype) and dtype.kind in NUMERIC_KINDS:
        return {"entry": _add(values.to_numpy(), arrays)}
    if not (dtype == np.dtype(object) or isinstance(dtype, pd.StringDtype)):
        raise TypeError(f"cannot save {path}: dtype {dtype}, not numbers, bools or strings")
    if dtype == np.dtype(object) and not all(isinstance(item, str) or _missing(item) for item in values):
        # a column of other values (tuples, numbers beside text): each saved as a value of its own
        return {"dtype": "object", "values": [_encode(item, f"{path}[{i}]", arrays) for i, item in enumerate(values)]}
    strings = [None if _missing(item) else str(item) for item in values]  # None: the dtype's missing value
    return {"dtype": str(dtype), "strings": strings}


def _missing(item):
    pd = _pandas()
    return item is None or item is pd.NA or (isinstance(item, float) and math.isnan(item))


def _add(array, arrays):
    arrays.append(np.array(array, order="C"))  # a copy in one memory layout: equal arrays, equal bytes
    return f"a{len(arrays) - 1}"


def _write_arrays(file, arrays):
    """arrays.npz, its bytes a function of the arrays alone (np.savez stamps the time of saving).
    Stored, not deflated: zlib builds may deflate differently, and git compresses anyway."""
    with zipfile.ZipFile(file, "w", compression=zipfile.ZIP_STORED) as archive:
        for i, array in enumerate(arrays):
            entry = zipfile.ZipInfo(f"a{i}.npy", date_time=ZIP_DATE)
            entry.create_system = 3  # Unix, whatever the platform saving
            entry.external_attr = 0o644 << 16
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, array, allow_pickle=False)
            archive.writestr(entry, buffer.getvalue())


def _bits(x):
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def _key_path(path, key):
    return f"{path}[{json.dumps(key, ensure_ascii=False)}]"


# -- loading --------------------------------------------------------------------------------------

def _decode(node, path, archive):
    pd = _pandas()
    if isinstance(node, list):
        return [_decode(item, f"{path}[{i}]", archive) for i, item in enumerate(node)]
    if not isinstance(node, dict):
        return node
    tag = node.get(TAG)
    if tag is None:
        return {key: _decode(item, _key_path(path, key), archive) for key, item in node.items()}
    if tag == "dict":
        return {key: _decode(item, _key_path(path, key), archive) for key, item in node["items"]}
    if tag == "tuple":
        return tuple(_decode(item, f"{path}[{i}]", archive) for i, item in enumerate(node["items"]))
    if tag == "float":
        return struct.unpack("<d", struct.pack("<Q", int(node["bits"], 16)))[0] if "bits" in node \
            else float(node["value"])
    if tag == "array":
        return _read_array(node["entry"], path, archive)
    if tag == "frame":
        index = _decode_index(node["index"], f"{path}.index", archive)
        columns = [pd.Series(_decode_values(spec, f"{path}.iloc[:, {i}]", archive), dtype=spec.get("dtype"))
                   for i, spec in enumerate(node["data"])]
        frame = pd.DataFrame(dict(enumerate(columns)), index=pd.RangeIndex(len(index)))
        frame.columns = _decode_index(node["columns"], f"{path}.columns", archive)
        frame.index = index  # set, not aligned: the index may repeat values or hold NaN
        frame.attrs = _decode(node["attrs"], f"{path}.attrs", archive)
        return frame
    if tag == "series":
        series = pd.Series(_decode_values(node["data"], path, archive), dtype=node["data"].get("dtype"),
                           index=_decode_index(node["index"], f"{path}.index", archive),
                           name=_decode(node["name"], f"{path}.name", archive))
        series.attrs = _decode(node["attrs"], f"{path}.attrs", archive)
        return series
    if tag in ("enum", "dataclass"):
        cls = _registered(node, path)
        try:
            if tag == "enum":
                return cls(_decode(node["value"], f"{path}.value", archive))
            return cls(**{name: _decode(item, f"{path}.{name}", archive) for name, item in node["fields"].items()})
        except TypeError as error:  # the class has changed since the save
            raise ValueError(f"{path}: cannot rebuild {node['class']}: {error}") from None
    raise ValueError(f"{path}: unknown {TAG} {tag!r}")


def _decode_index(spec, path, archive):
    pd = _pandas()
    name = _decode(spec["name"], f"{path}.name", archive)
    if "range" in spec:
        return pd.RangeIndex(*spec["range"], name=name)
    return pd.Index(_decode_values(spec, path, archive), dtype=spec.get("dtype"), name=name)


def _decode_values(spec, path, archive):
    if "values" in spec:
        values = np.empty(len(spec["values"]), dtype=object)  # not np.array: tuples would make it 2-d
        for i, item in enumerate(spec["values"]):
            values[i] = _decode(item, f"{path}[{i}]", archive)
        return values
    return spec["strings"] if "strings" in spec else _read_array(spec["entry"], path, archive)


def _read_array(entry, path, archive):
    try:
        with archive.open(f"{entry}.npy") as file:
            return np.lib.format.read_array(file, allow_pickle=False)
    except KeyError:
        raise ValueError(f"{path}: arrays.npz has no entry {entry!r}") from None
