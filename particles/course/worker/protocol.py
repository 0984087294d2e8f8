"""The data protocol between the grader and a worker: JSON plus NumPy arrays.

Nothing crosses the process boundary as pickle. A message is one frame::

    8 bytes   big-endian length of the rest of the frame
    4 bytes   big-endian length J of the JSON header
    J bytes   the JSON header (UTF-8)
    ...       the arrays, one after the other, each in NumPy's ``.npy`` format

The JSON header describes a value tree made of ``None``, ``bool``, ``int``,
``float`` (``NaN`` and ``inf`` allowed), ``str``, ``list``, ``dict`` with string
keys, and tagged objects:

* ``{"__array__": k}``: the ``k``-th array of the frame (numeric or boolean
  dtypes only, read back with ``allow_pickle=False``);
* ``{"__tuple__": [...]}``: a tuple;
* ``{"__scalar__": k}``: a NumPy scalar, stored as the 0-d array ``k``;
* ``{"__callable__": spec}``: a function the worker builds from the registry
  (:mod:`particles.course.worker.registry`), e.g. the right-hand side of a test problem;
* ``{"__unsupported__": type name, "repr": text}``: a value the protocol cannot
  carry (a generator, a custom object); the grader reports its type.

Decoding never runs code and refuses malformed frames with
:class:`ProtocolError`, so a worker that writes garbage cannot crash the grader.
"""

import io
import json
import math
import os
import struct

import numpy as np

__all__ = ["ProtocolError", "Unsupported", "encode", "decode", "write_frame", "read_frame", "MAX_FRAME"]

MAX_FRAME = 256 * 2**20
"""Largest frame accepted by :func:`read_frame`, in bytes (256 MiB)."""

_ALLOWED_KINDS = "biufc"  # bool, signed and unsigned integers, floats, complex


class ProtocolError(RuntimeError):
    """A frame is malformed, too large, or holds a value the protocol cannot carry."""


class Unsupported:
    """A value the worker could not encode, with its type name and a short repr."""

    def __init__(self, type_name, text=""):
        self.type_name, self.text = str(type_name), str(text)

    def __repr__(self):
        return f"<unsupported {self.type_name}: {self.text}>"

    def __eq__(self, other):
        return isinstance(other, Unsupported) and (self.type_name, self.text) == (other.type_name, other.text)


def _short_repr(value, limit=80):
    try:
        text = repr(value)
    except BaseException:  # a student's __repr__ may raise anything
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _encode_value(value, arrays, strict):
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int) and type(value) is int:
        return value
    if isinstance(value, float) and type(value) is float:
        if math.isfinite(value):
            return value
        return {"__float__": repr(value)}  # 'nan', 'inf', '-inf'
    if isinstance(value, np.ndarray):
        array = np.asarray(value).view(np.ndarray) if type(value) is not np.ndarray else value
        if array.dtype.kind not in _ALLOWED_KINDS or array.dtype.hasobject:
            return _unsupported(value, strict, f"array of dtype {array.dtype}")
        arrays.append(array)
        return {"__array__": len(arrays) - 1}
    if isinstance(value, np.generic) and np.dtype(type(value)).kind in _ALLOWED_KINDS:
        arrays.append(np.asarray(value))
        return {"__scalar__": len(arrays) - 1}
    if type(value) is tuple:
        return {"__tuple__": [_encode_value(v, arrays, strict) for v in value]}
    if type(value) is list:
        return [_encode_value(v, arrays, strict) for v in value]
    if type(value) is dict and all(type(k) is str for k in value):
        if any(k.startswith("__") and k.endswith("__") for k in value):
            return {"__dict__": [[k, _encode_value(v, arrays, strict)] for k, v in value.items()]}
        return {k: _encode_value(v, arrays, strict) for k, v in value.items()}
    spec = getattr(value, "__remote_spec__", None)
    if spec is not None and callable(value):
        return {"__callable__": spec}
    if isinstance(value, Unsupported):
        return {"__unsupported__": value.type_name, "repr": value.text}
    return _unsupported(value, strict, type(value).__name__)


def _unsupported(value, strict, what):
    if strict:
        raise ProtocolError(f"cannot send a value of type {what} to the worker")
    return {"__unsupported__": what, "repr": _short_repr(value)}


def encode(value, strict=True):
    """Encode `value` as frame bytes (without the 8-byte length prefix).

    Parameters
    ----------
    value : object
        A tree of the supported types (see the module docstring).
    strict : bool
        Raise :class:`ProtocolError` on an unsupported value (the grader's
        side); with ``False`` it becomes an ``Unsupported`` marker (the
        worker's side, so a student's odd return value is reported, not fatal).

    Returns
    -------
    bytes
    """
    arrays = []
    tree = _encode_value(value, arrays, strict)
    header = json.dumps(tree, allow_nan=False).encode()
    out = io.BytesIO()
    out.write(struct.pack(">I", len(header)))
    out.write(header)
    for array in arrays:
        np.lib.format.write_array(out, np.ascontiguousarray(array) if array.ndim else array, allow_pickle=False)
    return out.getvalue()


def _decode_value(node, arrays):
    if node is None or isinstance(node, (bool, int, float, str)):
        return node
    if isinstance(node, list):
        return [_decode_value(v, arrays) for v in node]
    if not isinstance(node, dict):
        raise ProtocolError(f"unexpected JSON node {type(node).__name__}")
    if len(node) == 1:
        (key, inner), = node.items()
        if key == "__array__":
            return _array(inner, arrays).copy()
        if key == "__scalar__":
            return _array(inner, arrays)[()]
        if key == "__tuple__" and isinstance(inner, list):
            return tuple(_decode_value(v, arrays) for v in inner)
        if key == "__float__" and inner in ("nan", "inf", "-inf"):
            return float(inner)
        if key == "__callable__" and isinstance(inner, dict):
            from .registry import build  # the worker builds functions from names only

            return build(inner)
        if key == "__dict__" and isinstance(inner, list):
            return {str(k): _decode_value(v, arrays) for k, v in inner}
    if set(node) == {"__unsupported__", "repr"}:
        return Unsupported(node["__unsupported__"], node["repr"])
    return {str(k): _decode_value(v, arrays) for k, v in node.items()}


def _array(index, arrays):
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(arrays):
        raise ProtocolError(f"array reference {index!r} out of range")
    return arrays[index]


def decode(data):
    """Decode frame bytes made by :func:`encode`; never unpickles anything.

    Raises
    ------
    ProtocolError
        On a malformed frame.
    """
    try:
        stream = io.BytesIO(data)
        (n,) = struct.unpack(">I", stream.read(4))
        header = json.loads(stream.read(n).decode())
        arrays = []
        while stream.tell() < len(data):
            array = np.lib.format.read_array(stream, allow_pickle=False)
            if array.dtype.kind not in _ALLOWED_KINDS:
                raise ProtocolError(f"array of dtype {array.dtype} is not allowed")
            arrays.append(array)
        return _decode_value(header, arrays)
    except ProtocolError:
        raise
    except Exception as error:  # struct, JSON, numpy format errors: all one kind for the caller
        raise ProtocolError(f"malformed frame: {type(error).__name__}: {error}") from None


def write_frame(fd, value, strict=True):
    """Encode `value` and write it to the file descriptor `fd` as one frame."""
    payload = encode(value, strict=strict)
    data = struct.pack(">Q", len(payload)) + payload
    view = memoryview(data)
    while view:
        written = os.write(fd, view)
        view = view[written:]


def read_frame(read_exactly, max_bytes=MAX_FRAME):
    """Read one frame with ``read_exactly(n) -> bytes`` and decode it.

    Raises
    ------
    EOFError
        When the stream ends before a frame starts or completes.
    ProtocolError
        When the frame is larger than `max_bytes` or malformed.
    """
    head = read_exactly(8)
    (n,) = struct.unpack(">Q", head)
    if n > max_bytes:
        raise ProtocolError(f"a reply of {n / 2**20:.0f} MiB is larger than the {max_bytes / 2**20:.0f} MiB the grader accepts")
    return decode(read_exactly(n))
