"""The grader-worker protocol: JSON plus .npy arrays, never pickle, malformed frames refused."""

import io
import struct

import numpy as np
import pytest

from particles.course.worker.protocol import MAX_FRAME, ProtocolError, Unsupported, decode, encode, read_frame
from particles.course.worker.registry import CountingFunction, remote


def test_round_trip_of_nested_values():
    """Arrays, tuples, dicts, NaN and NumPy scalars come back equal, with dtypes and shapes."""
    value = {"X": np.arange(6.0).reshape(1, 2, 3), "t": (0.5, float("nan"), float("-inf")),
             "n": np.int32(3), "flags": np.array([True, False]), "name": "euler", "none": None,
             "__array__": [1, 2]}
    back = decode(encode(value))
    assert back["X"].dtype == np.float64 and np.array_equal(back["X"], value["X"])
    assert isinstance(back["t"], tuple) and np.isnan(back["t"][1]) and back["t"][2] == -np.inf
    assert back["n"] == 3 and back["n"].dtype == np.int32
    assert back["flags"].dtype == bool and back["__array__"] == [1, 2] and back["none"] is None


def test_object_arrays_and_unknown_types_are_refused_or_marked():
    """Object arrays never cross (that would need pickle); odd values become Unsupported on the worker side."""
    with pytest.raises(ProtocolError):
        encode(np.array([object()], dtype=object))
    back = decode(encode({"g": (i for i in range(3))}, strict=False))
    assert isinstance(back["g"], Unsupported) and back["g"].type_name == "generator"


def test_pickled_array_in_a_frame_is_refused():
    """A frame carrying a pickled object array is refused, not unpickled."""
    header = b'{"__array__": 0}'
    body = io.BytesIO()
    np.lib.format.write_array(body, np.array([1, None], dtype=object), allow_pickle=True)
    with pytest.raises(ProtocolError):
        decode(struct.pack(">I", len(header)) + header + body.getvalue())


@pytest.mark.parametrize("frame", [b"", b"\x00\x00\x00\x05{bad", struct.pack(">I", 14) + b'{"__array__":3}'])
def test_malformed_frames_raise_protocol_error(frame):
    """Garbage from a worker raises ProtocolError, never anything else."""
    with pytest.raises(ProtocolError):
        decode(frame)


def test_oversized_frames_are_refused_before_reading():
    """A frame announcing more than MAX_FRAME bytes is refused without reading it."""
    stream = io.BytesIO(struct.pack(">Q", MAX_FRAME + 1))
    with pytest.raises(ProtocolError, match="larger than"):
        read_frame(stream.read)


def test_registry_functions_cross_by_name():
    """A remote function is sent as a spec and rebuilt as a counting function on the other side."""
    f = remote("harmonic_oscillator", omega=np.float64(2.0))
    back = decode(encode([f]))[0]
    assert isinstance(back, CountingFunction)
    X = np.array([[[1.0], [0.0]]])
    assert np.array_equal(back(X, 0.0), f(X, 0.0)) and back.calls == 1
    with pytest.raises(ValueError, match="unknown problem"):
        remote("no_such_problem")


def test_a_grader_token_becomes_a_function_only_in_a_worker():
    """A counted function crosses as an opaque token: outside a worker (here, the grader) decoding it is refused."""
    from particles.course.worker.registry import Token

    frame = encode([Token("0123abcd")])
    assert b"harmonic" not in frame and b"0123abcd" in frame
    with pytest.raises(ProtocolError, match="exists only in a worker"):
        decode(frame)
