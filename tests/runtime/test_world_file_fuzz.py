"""Fuzzing of :func:`relloc.runtime.airground.load_world`: a world file (``.npz``) whose arrays
are dropped, reshaped, of another dtype or hold NaN/inf, or whose bytes are cut or replaced,
reads as the run it holds or is refused with a DataError naming the file."""

from __future__ import annotations

import io
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from relloc.errors import DataError
from relloc.runtime.airground import MEASUREMENT_FIELDS, load_world, save_world
from relloc.sim.airground import AirGroundScenario, AirGroundWorld

SC = AirGroundScenario(offsets=((0.5, 0.5), (-0.5, 0.5)), offset_frame="global", duration=0.5)
NAMES = ("truth", "commands", "formation_error", *(f"m_{n}" for n in MEASUREMENT_FIELDS))


def _valid_arrays() -> dict[str, np.ndarray]:
    world = AirGroundWorld.start(SC, np.random.default_rng(5))
    for _ in range(3):  # a camera frame and UWB ranges
        world.step(np.tile([0.1, 0.0], (3, 1)), np.zeros((1, 2)))
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "world.npz"
        save_world(world, path)
        with np.load(path) as f:
            return {k: f[k] for k in f.files}


VALID = _valid_arrays()

_dtypes = st.sampled_from(
    [np.float64, np.float32, np.int64, np.int8, np.uint8, np.bool_, np.complex128, "U3", "S2"]
)
_shapes = st.lists(st.integers(0, 4), max_size=4).map(tuple)
_fill = st.sampled_from([0.0, 1.0, -1.0, 2.0, np.nan, np.inf, -np.inf, 1e308, -7.0, 300.0])


@st.composite
def _replacement(draw: st.DrawFn, name: str) -> np.ndarray:
    """Another array for ``name``: of another shape or dtype, with the valid one's values cut,
    padded or overwritten by NaN/inf/huge/negative entries."""
    base = VALID[name]
    how = draw(st.sampled_from(["shape", "dtype", "values", "transpose", "scalar"]))
    if how == "shape":
        return np.full(draw(_shapes), draw(_fill))
    if how == "dtype":
        with np.errstate(invalid="ignore"):
            return base.astype(draw(_dtypes))
    if how == "transpose":
        return base.T.copy()
    if how == "scalar":
        return np.asarray(draw(_fill))
    out = base.astype(float) if base.dtype.kind == "f" else base.copy()
    if out.size:
        flat = out.reshape(-1)
        i = draw(st.integers(0, flat.size - 1))
        value = draw(_fill)
        if out.dtype.kind == "f":
            flat[i] = value
        elif np.isfinite(value) and abs(value) < 2**62:
            flat[i] = int(value)
    return out


@st.composite
def _world_arrays(draw: st.DrawFn) -> dict[str, np.ndarray]:
    """The arrays of a world file with 1–3 of them replaced or dropped, and one added."""
    arrays = dict(VALID)
    for name in draw(st.lists(st.sampled_from(NAMES), min_size=1, max_size=3, unique=True)):
        action = draw(st.sampled_from(["replace", "replace", "drop"]))
        if action == "drop":
            del arrays[name]
        else:
            arrays[name] = draw(_replacement(name))
    if draw(st.booleans()):
        arrays["extra"] = np.zeros(2)
    return arrays


def _load(tmp: Path, data: bytes) -> None:
    path = tmp / "fuzzed_world.npz"
    path.write_bytes(data)
    try:
        recording, formation_error = load_world(path, SC)
    except DataError as exc:
        assert "fuzzed_world.npz" in str(exc), str(exc)
        return
    assert len(recording.robots) == 4
    assert isinstance(formation_error, np.ndarray) and formation_error.dtype == np.float64
    assert formation_error.ndim == 3 and formation_error.shape[1:] == (2, 2)
    assert np.all(np.isfinite(formation_error))


@settings(derandomize=True, max_examples=150, deadline=None)
@given(arrays=_world_arrays())
def test_a_fuzzed_world_file_is_read_or_refused_naming_the_file(arrays):
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    with tempfile.TemporaryDirectory() as folder:
        _load(Path(folder), buffer.getvalue())


def _zip(arrays: dict[str, np.ndarray], junk: bytes, member: str, method: int) -> bytes:
    """A zip of ``.npy`` members, compressed by ``method``, with ``member`` holding ``junk``."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", compression=method) as z:
        for name, array in arrays.items():
            inner = io.BytesIO()
            np.save(inner, array)
            z.writestr(f"{name}.npy", junk if f"{name}.npy" == member else inner.getvalue())
    return buffer.getvalue()


@settings(derandomize=True, max_examples=80, deadline=None)
@given(
    cut=st.integers(0, 4000),
    flips=st.lists(st.tuples(st.integers(0, 4000), st.integers(0, 255)), max_size=4),
    junk=st.binary(max_size=64),
    member=st.sampled_from(["truth.npy", "m_t.npy", "formation_error.npy", "none"]),
    method=st.sampled_from([zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED]),
    header=st.tuples(
        st.sampled_from([b"PK\x03\x04", b"PK\x01\x02"]),
        st.integers(4, 13),
        st.sampled_from([0, 1, 9, 12, 14, 32, 64, 93, 99, 255]),
    ),
)
def test_cut_or_corrupted_world_file_bytes_are_refused_naming_the_file(
    cut, flips, junk, member, method, header
):
    """A file cut short, with bytes overwritten (anywhere, or in the version, flags and
    compression method of a zip header: encrypted, unsupported), bytes of another kind, and a
    zip (stored or deflated) whose member is not a ``.npy``."""
    whole = _zip(VALID, junk, member, method)
    flipped = bytearray(whole)
    for at, byte in flips:
        flipped[at % len(flipped)] = byte
    signature, offset, byte = header
    flipped[whole.index(signature) + offset] = byte
    with tempfile.TemporaryDirectory() as folder:
        for data in (whole[:cut], bytes(flipped), junk, whole):
            _load(Path(folder), data)


def test_the_valid_world_file_reads_back():
    buffer = io.BytesIO()
    np.savez(buffer, **VALID)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "w.npz"
        path.write_bytes(buffer.getvalue())
        recording, formation_error = load_world(path, SC)
    np.testing.assert_array_equal(formation_error, VALID["formation_error"])
    np.testing.assert_array_equal(recording.measurements.t, VALID["m_t"])
