"""Python binding of libcsculpt, the stable C ABI of the cSculpt SDK (capi/include/csculpt.h).

Pure ctypes: no compiled extension, so the same file works in Blender's bundled Python and in
any CPython 3.8+ with numpy. The C header is the contract; this module mirrors it (every
function's prototype, every struct and enum) and adds a thin Pythonic layer:

    with csculpt.Mesh(positions, triangles) as base, csculpt.Hierarchy(base) as h:
        a = csculpt.Diff.capture(base, positions=artist_a_positions)
        b = csculpt.Diff.capture(base, positions=artist_b_positions)
        merged = csculpt.Merger(h).merge(base, [a, b])
        merged.apply_to_arrays(base, positions=scene_positions)   # in place

Sessions (serverless collaboration over ZeroMQ) work on the host's arrays in place too:

    with csculpt.Session.create(base, name="ana") as s:      # others: Session.join(invite)
        s.update(positions, channels)     # merged versions in, local edits rebased
        s.submit(positions, channels, strokes=1)
        for event in s.events(): ...

Finding the library: $CSCULPT_LIBRARY (a full path; nothing else is tried when it is set),
else libcsculpt.so.0 beside this file, in ../../build/capi (the source tree's build), in the
install prefix's lib directories (this file installs to <prefix>/share/csculpt/python), else
ctypes.util.find_library("csculpt").

Errors: every failing C call raises a CsculptError subclass (InvalidArgument, InvalidInput,
IoError, UnknownBaseVersion, OutOfMemory, InternalError) carrying `status` and the library's
message (csc_last_error()). Bad arguments caught on the Python side, before the library would
read past a too-small array, raise InvalidArgument too.

Lifetimes: handles are released by close(), by leaving a `with` block, or when the object is
garbage-collected. An object that the C contract requires to outlive another is kept alive by
it: a Merger holds its Hierarchy, a read-only array view holds its Mesh. close() on an object
still held that way only forbids further use through it; the C handle is destroyed when the
last holder goes.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import dataclasses
import enum
import math
import os
import sysconfig
import weakref
from ctypes import (POINTER, c_char_p, c_double, c_float, c_int, c_int32, c_size_t, c_uint8,
                    c_uint32, c_uint64, c_void_p, sizeof)
from typing import Dict, Iterable, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

__all__ = [
    "EXPECTED_VERSION", "Status", "Linearisation", "MergeMethod", "CsculptError",
    "InvalidArgument", "InvalidInput", "IoError", "UnknownBaseVersion", "OutOfMemory",
    "InternalError", "Mesh", "Channel", "Hierarchy", "HierarchyStats", "Diff", "DiffInfo",
    "MessageInfo", "Tolerances", "LOSSLESS", "Merger", "MergeTimings", "EventKind", "Session",
    "SessionEvent", "SessionStats", "SESSION_OPTIONS", "PeerState", "Presence", "PeerInfo", "peek", "version",
    "version_string", "wire_protocol_version", "merge_method_names", "check_version",
    "library_path"
]

# The header version this module was written against: it runs with a library of the same
# major and a minor at least this high (the ABI only grows within a major).
EXPECTED_VERSION = (0, 5)

# ---- Enums (32-bit in C) -------------------------------------------------------------------


class Status(enum.IntEnum):
    OK = 0
    ERROR_INVALID_ARGUMENT = 1
    ERROR_INVALID_INPUT = 2
    ERROR_IO = 3
    ERROR_UNKNOWN_BASE_VERSION = 4
    ERROR_OUT_OF_MEMORY = 5
    ERROR_INTERNAL = 6
    STATUS_MAX_ENUM = 0x7FFFFFFF


class Linearisation(enum.IntEnum):
    IDENTITY = 0
    SQUARE = 1
    SRGB = 2
    MAX_ENUM = 0x7FFFFFFF


class MergeMethod(enum.IntEnum):
    FULL = 0
    SINGLE_PARENT = 1
    SINGLE_LEVEL_ISOMETRY = 2
    MULTISCALE_TRANSLATION = 3
    WEIGHTED_TRANSLATION = 4
    AVERAGE = 5
    SUM = 6
    PAPER_BLEND = 7
    HIERARCHY_BLEND = 8
    FRAME_TRANSPORT = 9
    METHOD_MAX_ENUM = 0x7FFFFFFF


class EventKind(enum.IntEnum):
    JOINED = 0
    VERSION = 1
    PEER_JOINED = 2
    PEER_EVASIVE = 3
    PEER_LEFT = 4
    MERGER_CHANGED = 5
    DROPPED = 6
    ERROR = 7
    PEER_LIVE = 8
    KIND_MAX_ENUM = 0x7FFFFFFF


class PeerState(enum.IntEnum):
    LIVE = 0
    EVASIVE = 1
    LEFT = 2
    STATE_MAX_ENUM = 0x7FFFFFFF


# ---- Structs (mirrors of the header's, named as in C) --------------------------------------

# Opaque handle types: distinct pointer types let ctypes refuse a handle of the wrong kind.
class csc_mesh(ctypes.Structure):
    pass


class csc_hierarchy(ctypes.Structure):
    pass


class csc_diff(ctypes.Structure):
    pass


class csc_merger(ctypes.Structure):
    pass


class csc_bytes(ctypes.Structure):
    pass


class csc_session(ctypes.Structure):
    pass


_c_enum = c_int  # C enums whose values fit an int are int-sized; the header pins them to 32 bits


class csc_channel_desc(ctypes.Structure):
    _fields_ = [("name", c_char_p), ("width", c_uint32), ("linearisation", _c_enum),
                ("min_value", c_float), ("max_value", c_float)]


class _Sized(ctypes.Structure):
    """A struct starting with struct_size: set from sizeof, as the CSC_*_INIT macros do."""
    _defaults_: Dict[str, object] = {}

    def __init__(self, **fields):
        super().__init__()
        self.struct_size = sizeof(type(self))
        for name, value in {**self._defaults_, **fields}.items():
            setattr(self, name, value)


class csc_mesh_desc(_Sized):
    _fields_ = [("struct_size", c_uint32), ("vertex_count", c_uint32),
                ("positions", POINTER(c_float)), ("triangle_count", c_uint32),
                ("triangles", POINTER(c_uint32)), ("channel_count", c_uint32),
                ("channels", POINTER(csc_channel_desc)),
                ("channel_values", POINTER(POINTER(c_float)))]


class csc_channel_view(_Sized):
    _fields_ = [("struct_size", c_uint32), ("desc", csc_channel_desc),
                ("values", POINTER(c_float))]


class csc_hierarchy_options(_Sized):
    _fields_ = [("struct_size", c_uint32), ("max_parents", c_uint32)]
    _defaults_ = {"max_parents": 7}


class csc_hierarchy_stats(_Sized):
    _fields_ = [("struct_size", c_uint32), ("vertices", c_uint32), ("faces", c_uint32),
                ("levels", c_uint32), ("nodes", c_uint64), ("node_ratio", c_double),
                ("mean_level_ratio", c_double), ("top_nodes", c_uint32)]


class csc_vertex_arrays(_Sized):
    _fields_ = [("struct_size", c_uint32), ("vertex_count", c_uint32),
                ("positions", POINTER(c_float)), ("channel_count", c_uint32),
                ("channels", POINTER(POINTER(c_float)))]


class csc_diff_info(_Sized):
    _fields_ = [("struct_size", c_uint32), ("vertex_count", c_uint32),
                ("touched_vertices", c_uint32), ("position_changes", c_uint32),
                ("channel_count", c_uint32), ("digest", c_uint64)]


class csc_message_info(_Sized):
    _fields_ = [("struct_size", c_uint32), ("protocol", c_uint32), ("base_version", c_uint64),
                ("sequence", c_uint64), ("vertex_count", c_uint32), ("author", c_char_p)]


class csc_encode_options(_Sized):
    _fields_ = [("struct_size", c_uint32), ("base_version", c_uint64), ("sequence", c_uint64),
                ("author", c_char_p), ("position_tolerance", c_double),
                ("position_scale", c_double), ("channel_tolerance", c_double)]
    _defaults_ = {"position_tolerance": 1e-5, "position_scale": 0.0, "channel_tolerance": 1e-4}


class csc_merge_options(_Sized):
    _fields_ = [("struct_size", c_uint32), ("method", _c_enum), ("use_frame", c_uint32),
                ("frame_center", c_float * 3), ("frame_scale", c_float)]
    _defaults_ = {"frame_scale": 1.0}


class csc_merge_timings(_Sized):
    _fields_ = [("struct_size", c_uint32), ("isometry_ms", c_double), ("decompose_ms", c_double),
                ("blend_ms", c_double), ("apply_ms", c_double)]


class csc_session_options(_Sized):
    _fields_ = [("struct_size", c_uint32), ("bind", c_char_p), ("name", c_char_p),
                ("id", c_uint64), ("sync_ms", c_uint32), ("heartbeat_ms", c_uint32),
                ("evasive_ms", c_uint32), ("expired_ms", c_uint32),
                ("position_tolerance", c_double), ("channel_tolerance", c_double),
                ("join_timeout_ms", c_uint32), ("journal_dir", c_char_p)]
    _defaults_ = {"sync_ms": 10, "heartbeat_ms": 200, "evasive_ms": 600, "expired_ms": 1200,
                  "position_tolerance": 1e-5, "channel_tolerance": 1e-4,
                  "join_timeout_ms": 30000}


class csc_session_event(_Sized):
    _fields_ = [("struct_size", c_uint32), ("kind", _c_enum), ("peer", c_uint64),
                ("version", c_uint64), ("epoch", c_uint64), ("message", c_char_p)]
    _defaults_ = {"kind": 7}  # CSC_EVENT_ERROR, as CSC_SESSION_EVENT_INIT


class csc_session_stats(_Sized):
    _fields_ = [("struct_size", c_uint32), ("id", c_uint64), ("version", c_uint64),
                ("epoch", c_uint64), ("merger", c_uint64), ("members", c_uint32),
                ("submits", c_uint64), ("submit_bytes", c_uint64),
                ("strokes_submitted", c_uint64), ("strokes_acknowledged", c_uint64),
                ("versions_applied", c_uint64), ("rebases", c_uint64), ("merges", c_uint64),
                ("merged_strokes", c_uint64), ("conflicting_strokes", c_uint64),
                ("merge_ms_mean", c_double), ("merge_ms_max", c_double),
                ("messages_received", c_uint64), ("messages_dropped", c_uint64),
                ("stale_ignored", c_uint64), ("auth_rejected", c_uint64),
                ("folds_introduced", c_uint64)]


class csc_presence(_Sized):
    _fields_ = [("struct_size", c_uint32), ("peer", c_uint64), ("position", c_float * 3),
                ("radius", c_float), ("active", c_int32), ("visible", c_int32),
                ("rgba", c_uint32), ("age_ms", c_uint32), ("colour", c_float * 3)]


class csc_peer_info(_Sized):
    _fields_ = [("struct_size", c_uint32), ("id", c_uint64), ("name", c_char_p),
                ("state", _c_enum), ("merger", c_int32), ("version", c_uint64),
                ("latency_ms", c_double)]
    _defaults_ = {"latency_ms": -1.0}


# ---- Errors --------------------------------------------------------------------------------


class CsculptError(Exception):
    """A failed library call. `status` is the csc_status, str(error) the library's message."""
    status = Status.ERROR_INTERNAL

    def __init__(self, message: str, status: Optional[int] = None):
        # One positional argument only: OSError/MemoryError bases read two as (errno, strerror).
        super().__init__(message)
        if status is not None and status != type(self).status:
            self.status = status
        self.message = message


class InvalidArgument(CsculptError, ValueError):
    status = Status.ERROR_INVALID_ARGUMENT


class InvalidInput(CsculptError, ValueError):
    status = Status.ERROR_INVALID_INPUT


class IoError(CsculptError, OSError):
    status = Status.ERROR_IO


class UnknownBaseVersion(CsculptError):
    status = Status.ERROR_UNKNOWN_BASE_VERSION


class OutOfMemory(CsculptError, MemoryError):
    status = Status.ERROR_OUT_OF_MEMORY


class InternalError(CsculptError):
    status = Status.ERROR_INTERNAL


_ERRORS = {cls.status: cls for cls in (InvalidArgument, InvalidInput, IoError,
                                        UnknownBaseVersion, OutOfMemory, InternalError)}


def _error_for(status: int, message: str) -> CsculptError:
    cls = _ERRORS.get(status, CsculptError)
    return cls(message, status)


# ---- Prototypes: every function of csculpt.h ------------------------------------------------

_MeshP = POINTER(csc_mesh)
_HierarchyP = POINTER(csc_hierarchy)
_DiffP = POINTER(csc_diff)
_MergerP = POINTER(csc_merger)
_BytesP = POINTER(csc_bytes)
_SessionP = POINTER(csc_session)
_FloatP = POINTER(c_float)
_U32P = POINTER(c_uint32)
_STATUS = object()  # marks functions returning csc_status: they get an errcheck that raises

# name -> (restype, argtypes), in the header's order.
PROTOTYPES = {
    "csc_version": (c_uint32, []),
    "csc_version_string": (c_char_p, []),
    "csc_wire_protocol_version": (c_uint32, []),
    "csc_status_str": (c_char_p, [_c_enum]),
    "csc_last_error": (c_char_p, []),
    "csc_mesh_create": (_STATUS, [POINTER(_MeshP), POINTER(csc_mesh_desc)]),
    "csc_mesh_add_material_channels": (_STATUS, [_MeshP]),
    "csc_mesh_read": (_STATUS, [POINTER(_MeshP), c_char_p]),
    "csc_mesh_write": (_STATUS, [_MeshP, c_char_p]),
    "csc_mesh_clone": (_STATUS, [POINTER(_MeshP), _MeshP]),
    "csc_mesh_destroy": (None, [_MeshP]),
    "csc_mesh_vertex_count": (c_uint32, [_MeshP]),
    "csc_mesh_triangle_count": (c_uint32, [_MeshP]),
    "csc_mesh_channel_count": (c_uint32, [_MeshP]),
    "csc_mesh_positions": (_FloatP, [_MeshP]),
    "csc_mesh_triangles": (_U32P, [_MeshP]),
    "csc_mesh_channel": (_STATUS, [_MeshP, c_uint32, POINTER(csc_channel_view)]),
    "csc_mesh_find_channel": (c_int32, [_MeshP, c_char_p]),
    "csc_mesh_bbox_diagonal": (c_float, [_MeshP]),
    "csc_hierarchy_build": (_STATUS, [POINTER(_HierarchyP), _MeshP,
                                      POINTER(csc_hierarchy_options)]),
    "csc_hierarchy_destroy": (None, [_HierarchyP]),
    "csc_hierarchy_get_stats": (_STATUS, [_HierarchyP, POINTER(csc_hierarchy_stats)]),
    "csc_hierarchy_digest": (c_uint64, [_HierarchyP]),
    "csc_diff_capture_arrays": (_STATUS, [POINTER(_DiffP), _MeshP, POINTER(csc_vertex_arrays)]),
    "csc_diff_capture": (_STATUS, [POINTER(_DiffP), _MeshP, _MeshP]),
    "csc_diff_destroy": (None, [_DiffP]),
    "csc_mesh_apply_diff": (_STATUS, [_MeshP, _DiffP]),
    "csc_diff_apply_arrays": (_STATUS, [_DiffP, _MeshP, POINTER(csc_vertex_arrays)]),
    "csc_diff_get_info": (_STATUS, [_DiffP, POINTER(csc_diff_info)]),
    "csc_diff_positions": (_STATUS, [_DiffP, POINTER(_U32P), POINTER(_FloatP), _U32P]),
    "csc_diff_channel": (_STATUS, [_DiffP, c_uint32, POINTER(c_char_p), _U32P, POINTER(_U32P),
                                   POINTER(_FloatP), _U32P]),
    "csc_diff_encode": (_STATUS, [POINTER(_BytesP), _DiffP, _MeshP,
                                  POINTER(csc_encode_options)]),
    "csc_bytes_data": (POINTER(c_uint8), [_BytesP]),
    "csc_bytes_size": (c_size_t, [_BytesP]),
    "csc_bytes_destroy": (None, [_BytesP]),
    "csc_diff_peek": (_STATUS, [c_void_p, c_size_t, POINTER(csc_message_info)]),
    "csc_diff_decode": (_STATUS, [POINTER(_DiffP), _MeshP, c_uint64, c_void_p, c_size_t,
                                  POINTER(csc_message_info)]),
    "csc_merge_method_name": (c_char_p, [_c_enum]),
    "csc_merge_method_from_name": (_STATUS, [POINTER(_c_enum), c_char_p]),
    "csc_merger_create": (_STATUS, [POINTER(_MergerP), _HierarchyP]),
    "csc_merger_destroy": (None, [_MergerP]),
    "csc_merger_merge": (_STATUS, [_MergerP, POINTER(_DiffP), _MeshP, POINTER(_DiffP), c_uint32,
                                   POINTER(csc_merge_options)]),
    "csc_merger_last_timings": (_STATUS, [_MergerP, POINTER(csc_merge_timings)]),
    "csc_session_create": (_STATUS, [POINTER(_SessionP), _MeshP,
                                     POINTER(csc_session_options)]),
    "csc_session_join": (_STATUS, [POINTER(_SessionP), c_char_p, POINTER(csc_session_options)]),
    "csc_session_resume": (_STATUS, [POINTER(_SessionP), POINTER(_MeshP), c_char_p,
                                     POINTER(csc_session_options)]),
    "csc_session_leave": (_STATUS, [_SessionP]),
    "csc_session_destroy": (None, [_SessionP]),
    "csc_session_invite": (c_char_p, [_SessionP]),
    "csc_session_id": (c_uint64, [_SessionP]),
    "csc_session_version": (c_uint64, [_SessionP]),
    "csc_session_copy_base": (_STATUS, [POINTER(_MeshP), _SessionP]),
    "csc_session_submit": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), c_uint32,
                                     POINTER(c_int32)]),
    "csc_session_submit_changed": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), _U32P,
                                             c_uint32, c_uint32, POINTER(c_int32)]),
    "csc_session_update": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), _U32P]),
    "csc_session_update_changed": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), _U32P,
                                             c_uint32, _U32P]),
    "csc_session_record_stroke": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), _U32P,
                                            c_uint32, _FloatP]),
    "csc_session_undo": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), POINTER(_U32P), _U32P]),
    "csc_session_redo": (_STATUS, [_SessionP, POINTER(csc_vertex_arrays), POINTER(_U32P), _U32P]),
    "csc_session_undo_depth": (_STATUS, [_SessionP, _U32P, _U32P]),
    "csc_session_poll": (_STATUS, [_SessionP, POINTER(csc_session_event), POINTER(c_int32)]),
    "csc_session_get_stats": (_STATUS, [_SessionP, POINTER(csc_session_stats)]),
    "csc_session_attribution_colors": (_STATUS, [_SessionP, _FloatP, c_uint32]),
    "csc_session_set_presence": (_STATUS, [_SessionP, POINTER(csc_presence)]),
    "csc_session_presence_count": (_STATUS, [_SessionP, _U32P]),
    "csc_session_get_presence": (_STATUS, [_SessionP, c_uint32, POINTER(csc_presence)]),
    "csc_session_peer_count": (_STATUS, [_SessionP, _U32P]),
    "csc_session_get_peer": (_STATUS, [_SessionP, c_uint32, POINTER(csc_peer_info)]),
}

# ---- Loading -------------------------------------------------------------------------------

_SONAME = "libcsculpt.so.0"


def _candidate_paths() -> Sequence[str]:
    explicit = os.environ.get("CSCULPT_LIBRARY")
    if explicit:
        # An explicit choice that fails must say so, not silently load some other build.
        return [explicit]
    here = os.path.dirname(os.path.abspath(__file__))
    prefix = os.path.normpath(os.path.join(here, "..", "..", ".."))
    candidates = [os.path.join(here, _SONAME),
                  os.path.normpath(os.path.join(here, "..", "..", "build", "capi", _SONAME))]
    multiarch = sysconfig.get_config_var("MULTIARCH")
    for libdir in ([os.path.join("lib", multiarch)] if multiarch else []) + ["lib64", "lib"]:
        candidates.append(os.path.join(prefix, libdir, _SONAME))
    found = [c for c in candidates if os.path.exists(c)]
    system = ctypes.util.find_library("csculpt")
    return found + ([system] if system else [])


def _errcheck(status, func, args):
    if status != 0:
        message = _lib.csc_last_error().decode("utf-8", "replace")
        raise _error_for(status, message or _lib.csc_status_str(status).decode())
    return status


def _declare(lib: ctypes.CDLL) -> None:
    for name, (restype, argtypes) in PROTOTYPES.items():
        func = getattr(lib, name)
        func.argtypes = argtypes
        if restype is _STATUS:
            func.restype = _c_enum
            func.errcheck = _errcheck
        else:
            func.restype = restype


def check_version(number: int, string: str, expected: Tuple[int, int] = None,
                  where: str = "") -> Tuple[int, int, int]:
    """Checks a library version (csc_version(), csc_version_string()) against `expected`
    (major, minor; default EXPECTED_VERSION). Returns (major, minor, patch); raises ImportError
    naming both versions when the library is of another major, an older minor, or reports a
    string that disagrees with its number."""
    want_major, want_minor = EXPECTED_VERSION if expected is None else expected
    major, minor, patch = number // 10000, number // 100 % 100, number % 100
    have = f"{major}.{minor}.{patch}"
    source = f" ({where})" if where else ""
    if major != want_major or minor < want_minor:
        raise ImportError(
            f"csculpt: the loaded libcsculpt{source} is version {have}, but this module needs "
            f"{want_major}.{want_minor} or a later {want_major}.x (same major, minor >= "
            f"{want_minor}); install a matching libcsculpt or point CSCULPT_LIBRARY at one")
    if string != have:
        raise ImportError(f"csculpt: the loaded libcsculpt{source} reports version number "
                          f"{number} ({have}) but version string {string!r}; the library is "
                          f"damaged or not libcsculpt")
    return major, minor, patch


def _load() -> Tuple[ctypes.CDLL, str]:
    candidates = _candidate_paths()
    if not candidates:
        raise ImportError("csculpt: libcsculpt.so.0 not found (set CSCULPT_LIBRARY to its full "
                          "path, or install it where ctypes.util.find_library finds it)")
    failures = []
    for path in candidates:
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            failures.append(f"{path}: {e}")
            continue
        try:
            _declare(lib)
        except AttributeError as e:
            raise ImportError(f"csculpt: {path} lacks a function of the C API: {e}") from None
        string = lib.csc_version_string() or b""
        check_version(lib.csc_version(), string.decode("utf-8", "replace"), where=path)
        return lib, path
    raise ImportError("csculpt: could not load libcsculpt: " + "; ".join(failures))


_lib, library_path = _load()


def version() -> Tuple[int, int, int]:
    """(major, minor, patch) of the loaded library."""
    n = _lib.csc_version()
    return n // 10000, n // 100 % 100, n % 100


def version_string() -> str:
    return _lib.csc_version_string().decode()


def wire_protocol_version() -> int:
    """The diff message protocol the library writes (it reads 1 to this)."""
    return _lib.csc_wire_protocol_version()


def status_str(status: int) -> str:
    return _lib.csc_status_str(status).decode()


def merge_method_names() -> Dict[str, MergeMethod]:
    """Every merge method the library knows, by its name ("full", "single-parent", ...)."""
    names = {}
    for m in MergeMethod:
        name = _lib.csc_merge_method_name(m)
        if name is not None:
            names[name.decode()] = m
    return names


# ---- Helpers -------------------------------------------------------------------------------


class _Owner:
    """Owns one C handle; destroys it when the last Python holder (the wrapper, a view, a
    merger) lets go. Destroy functions are bound here so that late garbage collection at
    interpreter exit does not depend on module globals."""
    __slots__ = ("ptr", "_destroy", "deps", "__weakref__")

    def __init__(self, ptr, destroy):
        self.ptr = ptr
        self._destroy = destroy
        # Owners of handles this one refers to: released only after this handle is destroyed,
        # whatever order a garbage-collected cycle finalises its wrappers in.
        self.deps = ()

    def __del__(self):
        ptr, self.ptr = self.ptr, None
        if ptr:
            self._destroy(ptr)


class _Handle:
    _destroy_name = ""
    _kind = "handle"

    def __init__(self, ptr):
        self._owner = _Owner(ptr, getattr(_lib, self._destroy_name))

    @property
    def _ptr(self):
        owner = getattr(self, "_owner", None)
        if owner is None:
            raise InvalidArgument(f"csculpt: this {self._kind} is closed")
        return owner.ptr

    @property
    def closed(self) -> bool:
        return getattr(self, "_owner", None) is None

    def close(self) -> None:
        """Releases the handle now (or, if something still holds it, as soon as that goes).
        Further use of this object raises InvalidArgument; closing twice is harmless."""
        self._owner = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        self._owner = None


def _float_input(values, count: int, what: str) -> np.ndarray:
    """`values` as a C-contiguous float32 array of `count` elements: the same array (so the
    library reads the caller's memory in place) when it already is one, else a converted
    copy."""
    a = np.ascontiguousarray(values, dtype=np.float32)
    if a.size != count:
        raise InvalidArgument(f"csculpt: {what} has {a.size} floats (shape {a.shape}); "
                              f"{count} expected")
    return a


def _float_target(values, count: int, what: str) -> np.ndarray:
    """`values` checked for being written in place: a converted copy would silently drop the
    library's writes, so anything else than a writeable C-contiguous float32 array is
    refused."""
    if not isinstance(values, np.ndarray):
        raise InvalidArgument(f"csculpt: {what} must be a numpy array to be written in place "
                              f"(got {type(values).__name__})")
    if values.dtype != np.float32 or not values.flags.c_contiguous or not values.flags.writeable:
        raise InvalidArgument(f"csculpt: {what} must be a writeable C-contiguous float32 array "
                              f"to be written in place (got {values.dtype}, "
                              f"contiguous={values.flags.c_contiguous}, "
                              f"writeable={values.flags.writeable})")
    if values.size != count:
        raise InvalidArgument(f"csculpt: {what} has {values.size} floats (shape {values.shape}); "
                              f"{count} expected")
    return values


def _fp(a: np.ndarray):
    return a.ctypes.data_as(_FloatP)


def _linearisation(value) -> int:
    if isinstance(value, str):
        try:
            return Linearisation[value.upper()]
        except KeyError:
            raise InvalidArgument(f"csculpt: unknown linearisation {value!r} (identity, square "
                                  f"or srgb)") from None
    return int(value)


def _copy(pointer, count: int, dtype, shape) -> np.ndarray:
    if count == 0:
        return np.zeros(shape, dtype=dtype)
    return np.ctypeslib.as_array(pointer, (count,)).astype(dtype, copy=True).reshape(shape)


def _bytes_arg(data) -> bytes:
    if isinstance(data, bytes):
        return data
    return bytes(memoryview(data).cast("B"))


# ---- Mesh ----------------------------------------------------------------------------------


@dataclasses.dataclass
class Channel:
    """A per-vertex channel: values (vertex_count, width) float32, how they linearise
    ("identity", "square", "srgb") and the (min, max) range merged values are clamped to."""
    values: np.ndarray
    linearisation: str = "identity"
    range: Tuple[float, float] = (-math.inf, math.inf)

    @property
    def width(self) -> int:
        return 1 if self.values.ndim == 1 else self.values.shape[1]


ChannelSpec = Union[Channel, np.ndarray, tuple]


def _channel_from_spec(name: str, spec: ChannelSpec, vertex_count: int) -> Channel:
    if isinstance(spec, Channel):
        values, lin, rng = spec.values, spec.linearisation, spec.range
    elif isinstance(spec, tuple):
        if not 1 <= len(spec) <= 3:
            raise InvalidArgument(f"csculpt: channel {name!r}: expected (values, linearisation, "
                                  f"(min, max)), got a tuple of {len(spec)}")
        values = spec[0]
        lin = spec[1] if len(spec) > 1 else "identity"
        rng = spec[2] if len(spec) > 2 else (-math.inf, math.inf)
    else:
        values, lin, rng = spec, "identity", (-math.inf, math.inf)
    values = np.asarray(values)
    if values.ndim not in (1, 2) or values.shape[0] != vertex_count:
        raise InvalidArgument(f"csculpt: channel {name!r} has shape {values.shape}; "
                              f"({vertex_count},) or ({vertex_count}, width) expected")
    lo, hi = rng
    return Channel(values, lin, (float(lo), float(hi)))


class Mesh(_Handle):
    """A triangle mesh with named per-vertex float channels (csc_mesh). The library keeps its
    own copy of the arrays it is built from."""
    _destroy_name = "csc_mesh_destroy"
    _kind = "mesh"

    def __init__(self, positions, triangles, channels: Optional[Mapping[str,
                                                                         ChannelSpec]] = None):
        """positions (N, 3) float32, triangles (M, 3) uint32 (counter-clockwise), channels
        {name: values | (values, linearisation[, (min, max)]) | Channel} with values (N,) or
        (N, width), width 1 to 4. Anything else convertible is converted."""
        pos = np.ascontiguousarray(positions, dtype=np.float32)
        if pos.ndim != 2 or pos.shape[1] != 3:
            if pos.ndim == 1 and pos.size % 3 == 0:
                pos = pos.reshape(-1, 3)
            else:
                raise InvalidArgument(f"csculpt: positions has shape {pos.shape}; (N, 3) expected")
        tri = np.asarray(triangles)
        if tri.size and tri.dtype.kind not in "iu":
            raise InvalidArgument(f"csculpt: triangles must be integers (got {tri.dtype})")
        if tri.size and (tri.min() < 0 or tri.max() > 0xFFFFFFFF):
            raise InvalidInput("csculpt: triangles has an index outside 0..2^32-1")
        tri = np.ascontiguousarray(tri, dtype=np.uint32)
        if tri.size % 3 != 0 or (tri.ndim == 2 and tri.shape[1] != 3) or tri.ndim > 2:
            raise InvalidArgument(f"csculpt: triangles has shape {tri.shape}; (M, 3) expected")
        n = pos.shape[0]
        specs = [(name, _channel_from_spec(name, spec, n)) for name, spec in (channels or
                                                                              {}).items()]
        descs = (csc_channel_desc * max(len(specs), 1))()
        value_ptrs = (_FloatP * max(len(specs), 1))()
        keep = []  # the arrays and encoded names must live until the library has copied them
        for i, (name, ch) in enumerate(specs):
            encoded = name.encode("utf-8")
            values = np.ascontiguousarray(ch.values, dtype=np.float32)
            keep += [encoded, values]
            descs[i] = csc_channel_desc(encoded, ch.width, _linearisation(ch.linearisation),
                                        ch.range[0], ch.range[1])
            value_ptrs[i] = _fp(values)
        desc = csc_mesh_desc(vertex_count=n, positions=_fp(pos), triangle_count=tri.size // 3,
                             triangles=tri.ctypes.data_as(_U32P), channel_count=len(specs),
                             channels=descs, channel_values=value_ptrs)
        out = _MeshP()
        _lib.csc_mesh_create(ctypes.byref(out), ctypes.byref(desc))
        super().__init__(out)
        self._views = []  # weak references to the buffers of live views

    @classmethod
    def _adopt(cls, ptr) -> "Mesh":
        mesh = cls.__new__(cls)
        _Handle.__init__(mesh, ptr)
        mesh._views = []
        return mesh

    @classmethod
    def read(cls, path: Union[str, os.PathLike]) -> "Mesh":
        """Reads .ply, .obj, .off or .stl (PLY vertex properties become channels)."""
        out = _MeshP()
        _lib.csc_mesh_read(ctypes.byref(out), os.fsencode(path))
        return cls._adopt(out)

    def write(self, path: Union[str, os.PathLike]) -> None:
        """Writes .ply (binary, with channels; reads back bit-identical) or .obj, atomically."""
        _lib.csc_mesh_write(self._ptr, os.fsencode(path))

    def clone(self) -> "Mesh":
        out = _MeshP()
        _lib.csc_mesh_clone(ctypes.byref(out), self._ptr)
        return Mesh._adopt(out)

    @property
    def vertex_count(self) -> int:
        return _lib.csc_mesh_vertex_count(self._ptr)

    @property
    def triangle_count(self) -> int:
        return _lib.csc_mesh_triangle_count(self._ptr)

    @property
    def channel_count(self) -> int:
        return _lib.csc_mesh_channel_count(self._ptr)

    @property
    def bbox_diagonal(self) -> float:
        return _lib.csc_mesh_bbox_diagonal(self._ptr)

    @property
    def positions(self) -> np.ndarray:
        """A copy of the positions, (N, 3) float32."""
        return self.positions_view().copy()

    @property
    def triangles(self) -> np.ndarray:
        """A copy of the triangles, (M, 3) uint32."""
        return self.triangles_view().copy()

    def _view(self, pointer, ctype, count: int, shape) -> np.ndarray:
        buffer = (ctype * count).from_address(ctypes.addressof(pointer.contents)) if count else (
            ctype * 0)()
        buffer._owner = self._owner  # the memory belongs to the handle: keep it alive
        self._views = [r for r in self._views if r() is not None] + [weakref.ref(buffer)]
        view = np.frombuffer(buffer, dtype=np.float32 if ctype is c_float else np.uint32)
        view = view.reshape(shape)
        view.flags.writeable = False
        return view

    def positions_view(self) -> np.ndarray:
        """A read-only view of the library's positions, (N, 3) float32, without copying. It
        keeps the mesh's memory alive (close() is deferred while it exists) and shows the
        values applied later by Diff.apply_to(); add_material_channels() is refused while a
        view exists."""
        n = self.vertex_count
        return self._view(_lib.csc_mesh_positions(self._ptr), c_float, 3 * n, (n, 3))

    def triangles_view(self) -> np.ndarray:
        """A read-only view of the triangles, (M, 3) uint32; see positions_view()."""
        m = self.triangle_count
        return self._view(_lib.csc_mesh_triangles(self._ptr), c_uint32, 3 * m, (m, 3))

    def _channel_view(self, index: int) -> Tuple[str, Channel]:
        view = csc_channel_view()
        _lib.csc_mesh_channel(self._ptr, index, ctypes.byref(view))
        n, w = self.vertex_count, view.desc.width
        values = self._view(view.values, c_float, n * w, (n, w) if w > 1 else (n,))
        lin = Linearisation(view.desc.linearisation).name.lower()
        return view.desc.name.decode("utf-8"), Channel(values, lin, (view.desc.min_value,
                                                                    view.desc.max_value))

    def _channel_layout(self) -> Sequence[Tuple[str, int]]:
        layout = []
        for i in range(self.channel_count):
            view = csc_channel_view()
            _lib.csc_mesh_channel(self._ptr, i, ctypes.byref(view))
            layout.append((view.desc.name.decode("utf-8"), view.desc.width))
        return layout

    @property
    def channel_names(self) -> Tuple[str, ...]:
        return tuple(name for name, _ in self._channel_layout())

    def find_channel(self, name: str) -> int:
        """The index of channel `name`, or -1."""
        return _lib.csc_mesh_find_channel(self._ptr, name.encode("utf-8"))

    def channel(self, name_or_index: Union[str, int], copy: bool = True) -> Channel:
        """A channel; its values are a copy, or with copy=False a read-only view (as
        positions_view())."""
        index = self._channel_index(name_or_index)
        _, ch = self._channel_view(index)
        if copy:
            ch.values = ch.values.copy()
        return ch

    @property
    def channels(self) -> Dict[str, Channel]:
        """Every channel, in the mesh's order, with copied values."""
        result = {}
        for i in range(self.channel_count):
            name, ch = self._channel_view(i)
            ch.values = ch.values.copy()
            result[name] = ch
        return result

    def _channel_index(self, name_or_index: Union[str, int]) -> int:
        if isinstance(name_or_index, str):
            index = self.find_channel(name_or_index)
            if index < 0:
                raise InvalidArgument(f"csculpt: the mesh has no channel {name_or_index!r} "
                                      f"(it has {list(self.channel_names)})")
            return index
        return int(name_or_index)

    def add_material_channels(self) -> None:
        """Adds the built-in material channels (albedo, metallic, roughness) the mesh lacks."""
        ptr = self._ptr
        live = sum(1 for r in self._views if r() is not None)
        if live:
            # The library reallocates every array: a live view would point at freed memory.
            raise InvalidArgument("csculpt: add_material_channels() would invalidate the "
                                  f"{live} array view(s) of this mesh still alive; delete them "
                                  "(or use copies) first")
        _lib.csc_mesh_add_material_channels(ptr)

    def apply(self, diff: "Diff") -> None:
        """Writes `diff`'s values into this mesh (same as diff.apply_to(self))."""
        _lib.csc_mesh_apply_diff(self._ptr, diff._ptr)

    def _vertex_arrays(self, positions, channels, target: bool) -> Tuple[csc_vertex_arrays, list]:
        """csc_vertex_arrays over the host's arrays (in place), with the arrays to keep alive
        during the call; see _host_arrays."""
        return _host_arrays(self.vertex_count, self._channel_layout(), positions, channels,
                            target, lambda: _lib.csc_mesh_positions(self._ptr))


def _host_arrays(n: int, layout: Sequence[Tuple[str, int]], positions, channels, target: bool,
                 base_positions=None) -> Tuple[csc_vertex_arrays, list]:
    """csc_vertex_arrays over the host's arrays (in place) for a mesh of `n` vertices and the
    channels `layout` [(name, width)], with the arrays to keep alive during the call.
    channels: {name: array} or a sequence in the mesh's channel order; channels not given are
    NULL (capture: unchanged; apply: not written). positions None: scratch when `target`, else
    `base_positions()` (the base's own positions: an unchanged copy without copying)."""
    count = len(layout)
    names = [name for name, _ in layout]
    widths = [width for _, width in layout]
    convert = _float_target if target else _float_input
    keep = []
    if positions is None:
        if target:
            # Positions are required by the C struct; applying into scratch drops them.
            pos = np.empty(3 * n, dtype=np.float32)
        else:
            pos_ptr = base_positions()
            pos = None
    else:
        pos = convert(positions, 3 * n, "positions")
    if pos is not None:
        keep.append(pos)
        pos_ptr = _fp(pos)
    given = {}
    if channels is not None:
        if isinstance(channels, Mapping):
            for name, values in channels.items():
                if name not in names:
                    raise InvalidArgument(f"csculpt: the base mesh has no channel {name!r} "
                                          f"(it has {names})")
                given[names.index(name)] = values
        else:
            channels = list(channels)
            if len(channels) != count:
                raise InvalidArgument(f"csculpt: {len(channels)} channel arrays given, the "
                                      f"base mesh has {count} channels")
            given = {i: v for i, v in enumerate(channels) if v is not None}
    ptrs = (_FloatP * max(count, 1))()
    for i, values in given.items():
        a = convert(values, n * widths[i], f"channel {names[i]!r}")
        keep.append(a)
        ptrs[i] = _fp(a)
    arrays = csc_vertex_arrays(vertex_count=n, positions=pos_ptr, channel_count=count,
                               channels=ptrs)
    keep.append(ptrs)
    return arrays, keep


# ---- Hierarchy -----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class HierarchyStats:
    vertices: int
    faces: int
    levels: int
    nodes: int
    node_ratio: float
    mean_level_ratio: float
    top_nodes: int


class Hierarchy(_Handle):
    """The multiresolution vertex hierarchy of a mesh's connectivity (immutable; a pure
    function of the triangles: compare `digest` across peers)."""
    _destroy_name = "csc_hierarchy_destroy"
    _kind = "hierarchy"

    def __init__(self, mesh: Mesh, max_parents: int = 7):
        options = csc_hierarchy_options(max_parents=max_parents)
        out = _HierarchyP()
        _lib.csc_hierarchy_build(ctypes.byref(out), mesh._ptr, ctypes.byref(options))
        super().__init__(out)

    @property
    def stats(self) -> HierarchyStats:
        s = csc_hierarchy_stats()
        _lib.csc_hierarchy_get_stats(self._ptr, ctypes.byref(s))
        return HierarchyStats(s.vertices, s.faces, s.levels, s.nodes, s.node_ratio,
                              s.mean_level_ratio, s.top_nodes)

    @property
    def digest(self) -> int:
        return _lib.csc_hierarchy_digest(self._ptr)


# ---- Diffs ---------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class DiffInfo:
    vertex_count: int
    touched_vertices: int
    position_changes: int
    channel_count: int
    digest: int


@dataclasses.dataclass(frozen=True)
class MessageInfo:
    protocol: int
    base_version: int
    sequence: int
    vertex_count: int
    author: str


def _message_info(m: csc_message_info) -> MessageInfo:
    return MessageInfo(m.protocol, m.base_version, m.sequence, m.vertex_count,
                       (m.author or b"").decode("utf-8", "replace"))


@dataclasses.dataclass(frozen=True)
class Tolerances:
    """Encoding tolerances: position as a fraction of position_scale (0 = the base's bounding
    box diagonal), channel in stored units; 0 is lossless."""
    # The library's defaults (CSC_ENCODE_OPTIONS_INIT), stated once in csc_encode_options.
    position: float = csc_encode_options._defaults_["position_tolerance"]
    channel: float = csc_encode_options._defaults_["channel_tolerance"]
    position_scale: float = csc_encode_options._defaults_["position_scale"]


LOSSLESS = Tolerances(0.0, 0.0)


class Diff(_Handle):
    """A sparse edit of a mesh: the changed vertices of positions and of each channel."""
    _destroy_name = "csc_diff_destroy"
    _kind = "diff"

    def __init__(self):
        raise TypeError("use Diff.capture, Diff.capture_meshes, Diff.decode or Merger.merge")

    @classmethod
    def _adopt(cls, ptr) -> "Diff":
        diff = cls.__new__(cls)
        _Handle.__init__(diff, ptr)
        return diff

    @classmethod
    def capture(cls, base: Mesh, positions=None, channels=None) -> "Diff":
        """The diff from `base` to the host's arrays: positions (N, 3) or (3N,), channels
        {name: (N, width)} or a sequence in the base's channel order (None entries, and
        channels or positions not given, count as unchanged). C-contiguous float32 arrays are
        read in place; others are converted first."""
        arrays, keep = base._vertex_arrays(positions, channels, target=False)
        out = _DiffP()
        _lib.csc_diff_capture_arrays(ctypes.byref(out), base._ptr, ctypes.byref(arrays))
        del keep
        return cls._adopt(out)

    @classmethod
    def capture_meshes(cls, base: Mesh, edited: Mesh) -> "Diff":
        """The diff from `base` to `edited` (same vertex count, triangles and channels)."""
        out = _DiffP()
        _lib.csc_diff_capture(ctypes.byref(out), base._ptr, edited._ptr)
        return cls._adopt(out)

    def apply_to(self, mesh: Mesh) -> None:
        """Writes the diff's values into `mesh` (its base or one of the same layout)."""
        _lib.csc_mesh_apply_diff(mesh._ptr, self._ptr)

    def apply_to_arrays(self, base: Mesh, positions=None, channels=None) -> None:
        """Writes the diff's changed values in place into the host's arrays, which have the
        base's vertex count and channels: positions (N, 3) or (3N,), channels {name: array} or
        a sequence in the base's order. Each must be a writeable C-contiguous float32 array;
        channels (or positions) not given are not written. On failure nothing is written."""
        arrays, keep = base._vertex_arrays(positions, channels, target=True)
        _lib.csc_diff_apply_arrays(self._ptr, base._ptr, ctypes.byref(arrays))
        del keep

    @property
    def info(self) -> DiffInfo:
        i = csc_diff_info()
        _lib.csc_diff_get_info(self._ptr, ctypes.byref(i))
        return DiffInfo(i.vertex_count, i.touched_vertices, i.position_changes, i.channel_count,
                        i.digest)

    @property
    def digest(self) -> int:
        return self.info.digest

    def positions(self) -> Tuple[np.ndarray, np.ndarray]:
        """(indices (k,) uint32 strictly increasing, values (k, 3) float32), copies."""
        indices, values, count = _U32P(), _FloatP(), c_uint32()
        _lib.csc_diff_positions(self._ptr, ctypes.byref(indices), ctypes.byref(values),
                                ctypes.byref(count))
        k = count.value
        return _copy(indices, k, np.uint32, (k,)), _copy(values, 3 * k, np.float32, (k, 3))

    def channel(self, index: int) -> Tuple[str, np.ndarray, np.ndarray]:
        """(name, indices (k,), values (k, width)) of channel `index` (the base's order)."""
        name, width, indices, values, count = c_char_p(), c_uint32(), _U32P(), _FloatP(), c_uint32()
        _lib.csc_diff_channel(self._ptr, index, ctypes.byref(name), ctypes.byref(width),
                              ctypes.byref(indices), ctypes.byref(values), ctypes.byref(count))
        k, w = count.value, width.value
        return (name.value.decode("utf-8"), _copy(indices, k, np.uint32, (k,)),
                _copy(values, k * w, np.float32, (k, w)))

    def channels(self) -> Dict[str, Tuple[np.ndarray, np.ndarray]]:
        """{name: (indices, values)} for every channel the diff carries."""
        result = {}
        for i in range(self.info.channel_count):
            name, indices, values = self.channel(i)
            result[name] = (indices, values)
        return result

    def encode(self, base: Mesh, base_version: int, sequence: int = 0,
               author: Optional[str] = None, tolerances: Optional[Tolerances] = None) -> bytes:
        """A diff message (FlatBuffers DiffMessage) of this diff taken against `base`, the
        agreed version `base_version`. tolerances: Tolerances (default: the library's
        defaults), LOSSLESS, or a tuple (position, channel[, position_scale])."""
        if tolerances is None:
            tolerances = Tolerances()
        elif not isinstance(tolerances, Tolerances):
            tolerances = Tolerances(*tolerances)
        options = csc_encode_options(base_version=base_version, sequence=sequence,
                                     author=None if author is None else author.encode("utf-8"),
                                     position_tolerance=tolerances.position,
                                     position_scale=tolerances.position_scale,
                                     channel_tolerance=tolerances.channel)
        out = _BytesP()
        _lib.csc_diff_encode(ctypes.byref(out), self._ptr, base._ptr, ctypes.byref(options))
        try:
            size = _lib.csc_bytes_size(out)
            return ctypes.string_at(_lib.csc_bytes_data(out), size)
        finally:
            _lib.csc_bytes_destroy(out)

    @classmethod
    def decode(cls, base: Mesh, base_version: int, data) -> Tuple["Diff", MessageInfo]:
        """Verifies and decodes a diff message against `base`, the mesh of `base_version`.
        Raises UnknownBaseVersion if the message names another version, InvalidInput if it
        is corrupt or does not fit `base`."""
        data = _bytes_arg(data)
        info = csc_message_info()
        out = _DiffP()
        _lib.csc_diff_decode(ctypes.byref(out), base._ptr, base_version, data, len(data),
                             ctypes.byref(info))
        diff = cls._adopt(out)
        return diff, _message_info(info)  # author is copied before anything can free it


def peek(data) -> MessageInfo:
    """Verifies a diff message and reads its header without decoding it."""
    data = _bytes_arg(data)
    info = csc_message_info()
    _lib.csc_diff_peek(data, len(data), ctypes.byref(info))
    return _message_info(info)  # author points into `data`, alive here


# ---- Merge ---------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class MergeTimings:
    isometry_ms: float
    decompose_ms: float
    blend_ms: float
    apply_ms: float


def _merge_method(method: Union[str, int]) -> int:
    if isinstance(method, str):
        out = _c_enum()
        _lib.csc_merge_method_from_name(ctypes.byref(out), method.encode("utf-8"))
        return out.value
    return int(method)


class Merger(_Handle):
    """Merges diffs on one hierarchy; reuses its workspace between merges. One merge at a time
    per Merger. Holds `hierarchy` for as long as it lives (the library requires it)."""
    _destroy_name = "csc_merger_destroy"
    _kind = "merger"

    def __init__(self, hierarchy: Hierarchy):
        out = _MergerP()
        _lib.csc_merger_create(ctypes.byref(out), hierarchy._ptr)
        super().__init__(out)
        self.hierarchy = hierarchy
        # The handle, not just the wrapper, holds the hierarchy's handle: closing the
        # Hierarchy wrapper first must not free what the merger refers to.
        self._owner.deps = (hierarchy._owner,)

    def merge(self, base: Mesh, diffs: Iterable[Diff], method: Union[str, int] = "full",
              frame: Optional[Tuple[Sequence[float], float]] = None) -> Diff:
        """Merges 1 to 64 diffs, each taken against `base`, into one diff from `base`; the
        result depends only on `base` and the set of diffs (bitwise, in any order). method: a
        name from merge_method_names() or a MergeMethod. frame: None fits the working frame to
        the base's bounding box on each call; a session passes one (center (3,), scale) so
        every peer merges in the same frame."""
        diffs = list(diffs)
        pointers = (_DiffP * max(len(diffs), 1))(*[d._ptr for d in diffs])
        options = csc_merge_options(method=_merge_method(method))
        if frame is not None:
            center, scale = frame
            center = [float(c) for c in center]
            if len(center) != 3:
                raise InvalidArgument(f"csculpt: frame center has {len(center)} components")
            options.use_frame = 1
            options.frame_center[:] = center
            options.frame_scale = float(scale)
        out = _DiffP()
        _lib.csc_merger_merge(self._ptr, ctypes.byref(out), base._ptr, pointers, len(diffs),
                              ctypes.byref(options))
        return Diff._adopt(out)

    @property
    def last_timings(self) -> MergeTimings:
        t = csc_merge_timings()
        _lib.csc_merger_last_timings(self._ptr, ctypes.byref(t))
        return MergeTimings(t.isometry_ms, t.decompose_ms, t.blend_ms, t.apply_ms)


# ---- Sessions ------------------------------------------------------------------------------

# The options Session.create and Session.join take (csc_session_options' fields), with the
# library's defaults (CSC_SESSION_OPTIONS_INIT); bind None = "tcp://127.0.0.1:*", name None = "",
# id 0 = random, journal_dir None = no journal (docs/journal.md).
SESSION_OPTIONS: Dict[str, object] = {"bind": None, "name": None, "id": 0, "journal_dir": None,
                                      **csc_session_options._defaults_}


def _session_options(options: Mapping[str, object]) -> csc_session_options:
    unknown = sorted(set(options) - set(SESSION_OPTIONS))
    if unknown:
        raise TypeError(f"csculpt: unknown session option(s) {unknown} (valid: "
                        f"{sorted(SESSION_OPTIONS)})")
    o = csc_session_options()
    for name, value in options.items():
        ctype = dict(csc_session_options._fields_)[name]
        if ctype is c_char_p:
            if value is not None:
                if not isinstance(value, str):
                    raise InvalidArgument(f"csculpt: session option {name} must be a str")
                value = value.encode("utf-8")
        elif ctype is c_double:
            value = float(value)
        else:
            # ctypes would wrap an out-of-range integer silently into another valid option.
            bits = 8 * sizeof(ctype)
            if isinstance(value, bool) or int(value) != value or not 0 <= value < 2**bits:
                raise InvalidArgument(f"csculpt: session option {name} must be an integer in "
                                      f"0..2^{bits}-1 (got {value!r})")
            value = int(value)
        setattr(o, name, value)
    return o


def _check_strokes(strokes) -> None:
    if isinstance(strokes, bool) or int(strokes) != strokes or not 0 <= strokes < 2**32:
        raise InvalidArgument(f"csculpt: strokes must be an integer in 0..2^32-1 "
                              f"(got {strokes!r})")


@dataclasses.dataclass(frozen=True)
class SessionEvent:
    """What happened in a session (csc_session_event). kind is an EventKind (a plain int for a
    kind newer than this module); message is a copy of the library's text ("" if none)."""
    kind: Union[EventKind, int]
    peer: int
    version: int
    epoch: int
    message: str


@dataclasses.dataclass(frozen=True)
class SessionStats:
    """csc_session_stats: this peer as author, as merger, and the traffic it saw."""
    id: int
    version: int
    epoch: int
    merger: int
    members: int
    submits: int
    submit_bytes: int
    strokes_submitted: int
    strokes_acknowledged: int
    versions_applied: int
    rebases: int
    merges: int
    merged_strokes: int
    conflicting_strokes: int
    merge_ms_mean: float
    merge_ms_max: float
    messages_received: int
    messages_dropped: int
    stale_ignored: int
    auth_rejected: int
    folds_introduced: int


@dataclasses.dataclass(frozen=True)
class Presence:
    """Another artist's brush cursor (csc_presence): where it is (mesh coordinates), its radius
    (mesh units), whether a stroke is under way and whether it is over the mesh, how long ago it
    came, and the colour to draw it in (RGB in [0, 1])."""
    peer: int
    position: Tuple[float, float, float]
    radius: float
    active: bool
    visible: bool
    rgba: int
    age_ms: int
    colour: Tuple[float, float, float]


@dataclasses.dataclass(frozen=True)
class PeerInfo:
    """Another peer as this one sees it (csc_peer_info); latency_ms is negative until
    measured."""
    id: int
    name: str
    state: Union[PeerState, int]
    merger: bool
    version: int
    latency_ms: float


class Session(_Handle):
    """A serverless editing session over ZeroMQ (csc_session): this peer's share of the
    agreed mesh and its link to the others. Networking runs on the library's own thread; no
    method waits on the network except join().

        with csculpt.Session.create(mesh, sync_ms=250) as s:   # others: Session.join(s.invite)
            while editing:
                s.update(positions, channels)      # merged versions in, host arrays rebased
                ...the artist edits positions / channels in place...
                s.submit(positions, channels, strokes=1)
                for event in s.events(): ...

    The host's arrays are written in place by submit() and update(): positions (N, 3) or
    (3N,) and channels {name: array} or a sequence in the session mesh's channel order, each a
    writeable C-contiguous float32 array (anything else is refused, as a converted copy would
    lose the writes). Channels not given are neither read nor written. Use a Session from one
    thread at a time."""
    _destroy_name = "csc_session_destroy"
    _kind = "session"

    def __init__(self):
        raise TypeError("use Session.create, Session.join or Session.resume")

    @classmethod
    def _adopt(cls, ptr) -> "Session":
        session = cls.__new__(cls)
        _Handle.__init__(session, ptr)
        try:
            # The layout the host's arrays are checked against, read once: it cannot change.
            with session.base() as base:
                session._vertex_count = base.vertex_count
                session._layout = tuple(base._channel_layout())
        except BaseException:
            session.close()
            raise
        return session

    @classmethod
    def create(cls, mesh: Mesh, **options) -> "Session":
        """Starts a session on `mesh` (copied; version 0). options: see SESSION_OPTIONS.
        Raises IoError if `bind` cannot be bound."""
        o = _session_options(options)
        out = _SessionP()
        _lib.csc_session_create(ctypes.byref(out), mesh._ptr, ctypes.byref(o))
        return cls._adopt(out)

    @classmethod
    def join(cls, invite: str, **options) -> "Session":
        """Joins the session of `invite` and waits up to join_timeout_ms for the snapshot.
        Raises InvalidInput for a malformed invite, IoError when no snapshot came."""
        if not isinstance(invite, str):
            raise InvalidArgument(f"csculpt: invite must be a str (got {type(invite).__name__})")
        o = _session_options(options)
        out = _SessionP()
        _lib.csc_session_join(ctypes.byref(out), invite.encode("utf-8"), ctypes.byref(o))
        return cls._adopt(out)

    @classmethod
    def resume(cls, journal_dir: str, **options) -> Tuple["Session", Mesh]:
        """Restarts this peer's session from its journal (docs/journal.md): the session and the
        local mesh to fill the host's arrays from (the agreed mesh plus the unmerged edit,
        already sent again). Raises IoError or InvalidInput naming a missing or corrupt file."""
        if not isinstance(journal_dir, str):
            raise InvalidArgument("csculpt: journal_dir must be a str")
        o = _session_options(options)
        out, local = _SessionP(), _MeshP()
        _lib.csc_session_resume(ctypes.byref(out), ctypes.byref(local),
                                journal_dir.encode("utf-8"), ctypes.byref(o))
        mesh = Mesh._adopt(local)
        return cls._adopt(out), mesh

    @property
    def invite(self) -> str:
        """What others join with (it carries the session's keys: share it only with them)."""
        return _lib.csc_session_invite(self._ptr).decode("utf-8")

    @property
    def id(self) -> int:
        return _lib.csc_session_id(self._ptr)

    @property
    def version(self) -> int:
        """The agreed version update() last applied."""
        return _lib.csc_session_version(self._ptr)

    @property
    def vertex_count(self) -> int:
        return self._vertex_count

    @property
    def channel_names(self) -> Tuple[str, ...]:
        return tuple(name for name, _ in self._layout)

    def base(self) -> Mesh:
        """A copy of the agreed version's mesh (e.g. to fill the host's arrays after join)."""
        out = _MeshP()
        _lib.csc_session_copy_base(ctypes.byref(out), self._ptr)
        return Mesh._adopt(out)

    def _arrays(self, positions, channels):
        ptr = self._ptr  # a closed session says so before the arrays are inspected
        if positions is None:
            # The library reads and writes every position: a scratch array would send garbage.
            raise InvalidArgument("csculpt: the session needs the host's positions")
        arrays, keep = _host_arrays(self._vertex_count, self._layout, positions, channels,
                                    target=True)
        return ptr, arrays, keep

    def submit(self, positions, channels=None, strokes: int = 0) -> bool:
        """Sends the edit from the agreed version to the host's arrays, replacing what was
        sent before for this version; `strokes` counts strokes made since the last submit.
        Changed values are rewritten in place to what the peers receive (within the wire
        tolerance). Returns False when there was nothing new to send: the strokes changed nothing
        the session does not hold (acknowledged at once), or nothing beyond the submit still
        waiting for its version (acknowledged with it)."""
        _check_strokes(strokes)
        ptr, arrays, keep = self._arrays(positions, channels)
        sent = c_int32()
        _lib.csc_session_submit(ptr, ctypes.byref(arrays), strokes, ctypes.byref(sent))
        del keep
        return bool(sent.value)

    def submit_changed(self, positions, changed, channels=None, strokes: int = 0) -> bool:
        """submit() at the cost of the changed vertices: `changed` lists the vertices the host
        changed since its last submit of either kind (any order, repeats allowed). A vertex
        changed but not listed is not sent until a later call lists it. Raises InvalidInput
        naming an index out of range (nothing sent or written)."""
        _check_strokes(strokes)
        ptr, arrays, keep = self._arrays(positions, channels)
        indices = np.ascontiguousarray(changed, dtype=np.uint32).ravel()
        sent = c_int32()
        _lib.csc_session_submit_changed(ptr, ctypes.byref(arrays), indices.ctypes.data_as(_U32P),
                                        indices.size, strokes, ctypes.byref(sent))
        del keep
        return bool(sent.value)

    def update(self, positions, channels=None) -> int:
        """Applies the merged versions received so far and rebases the host's arrays onto
        them, in place (unmerged local edits are kept). Returns the versions applied."""
        ptr, arrays, keep = self._arrays(positions, channels)
        applied = c_uint32()
        _lib.csc_session_update(ptr, ctypes.byref(arrays), ctypes.byref(applied))
        del keep
        return applied.value

    def update_changed(self, positions, changed, channels=None) -> int:
        """update() at the cost of what changed: `changed` lists the vertices the host changed
        since its last submit of either kind, as for submit_changed(). Only those and the
        vertices the session knows differ are compared, and only what the session changed is
        written back. An unlisted change is neither found nor carried over by this call."""
        ptr, arrays, keep = self._arrays(positions, channels)
        indices = np.ascontiguousarray(changed, dtype=np.uint32).ravel()
        applied = c_uint32()
        _lib.csc_session_update_changed(ptr, ctypes.byref(arrays), indices.ctypes.data_as(_U32P),
                                        indices.size, ctypes.byref(applied))
        del keep
        return applied.value

    def record_stroke(self, positions, vertices, before, channels=None) -> None:
        """Records a stroke the host just ended, for undo(): the `vertices` it changed and
        `before`, their values before it (per vertex the position, then every channel's values
        in the session's channel order). `positions`/`channels` hold the values after it."""
        ptr, arrays, keep = self._arrays(positions, channels)
        indices = np.ascontiguousarray(vertices, dtype=np.uint32).ravel()
        values = np.ascontiguousarray(before, dtype=np.float32).ravel()
        stride = 3 + sum(width for _, width in self._layout)
        if values.size != indices.size * stride:
            raise InvalidArgument(f"csculpt: before holds {values.size} values; {indices.size} "
                                  f"vertices need {indices.size * stride} ({stride} per vertex)")
        _lib.csc_session_record_stroke(ptr, ctypes.byref(arrays),
                                       indices.ctypes.data_as(_U32P), indices.size, _fp(values))
        del keep

    def _step(self, function, positions, channels) -> np.ndarray:
        ptr, arrays, keep = self._arrays(positions, channels)
        changed, count = _U32P(), c_uint32()
        function(ptr, ctypes.byref(arrays), ctypes.byref(changed), ctypes.byref(count))
        del keep
        if count.value == 0:
            return np.empty(0, dtype=np.uint32)
        return np.ctypeslib.as_array(changed, shape=(count.value,)).copy()

    def undo(self, positions, channels=None) -> np.ndarray:
        """Undoes this artist's latest recorded stroke in the host's arrays, merged with
        everything that happened since (others' work stays). Returns the changed vertices
        (empty when there was nothing to undo); submit() then sends it like a stroke."""
        return self._step(_lib.csc_session_undo, positions, channels)

    def redo(self, positions, channels=None) -> np.ndarray:
        """Redoes the latest undone stroke the same way."""
        return self._step(_lib.csc_session_redo, positions, channels)

    @property
    def undo_depth(self) -> Tuple[int, int]:
        """(strokes undo() can take back, strokes redo() can put back)."""
        undo, redo = c_uint32(), c_uint32()
        _lib.csc_session_undo_depth(self._ptr, ctypes.byref(undo), ctypes.byref(redo))
        return undo.value, redo.value

    def poll(self) -> Optional[SessionEvent]:
        """The next event, or None. Never blocks."""
        e = csc_session_event()
        has = c_int32()
        _lib.csc_session_poll(self._ptr, ctypes.byref(e), ctypes.byref(has))
        if not has.value:
            return None
        try:
            kind = EventKind(e.kind)
        except ValueError:
            kind = e.kind
        # The message is borrowed until the next poll: decode (copy) it now.
        return SessionEvent(kind, e.peer, e.version, e.epoch,
                            (e.message or b"").decode("utf-8", "replace"))

    def events(self) -> list:
        """Every event waiting, oldest first (drains the queue)."""
        result = []
        while True:
            event = self.poll()
            if event is None:
                return result
            result.append(event)

    @property
    def stats(self) -> SessionStats:
        s = csc_session_stats()
        _lib.csc_session_get_stats(self._ptr, ctypes.byref(s))
        return SessionStats(**{f: getattr(s, f) for f, _ in csc_session_stats._fields_[1:]})

    def attribution_colors(self) -> np.ndarray:
        """Who changed what, as vertex colours (N, 3) float32 in [0, 1]: peers get green,
        blue, red, ... by increasing id, mixed where several edited; light grey where nobody
        did."""
        rgb = np.empty((self._vertex_count, 3), dtype=np.float32)
        _lib.csc_session_attribution_colors(self._ptr, _fp(rgb), self._vertex_count)
        return rgb

    def set_presence(self, position, radius: float, active: bool = False,
                     visible: bool = True, rgba: int = 0) -> None:
        """Sets this peer's brush cursor (as often as you like: the library sends at most 20
        a second). position: 3 floats in mesh coordinates; radius in mesh units; rgba
        0xRRGGBBAA, or 0 to let the others choose. Raises InvalidArgument naming a non-finite
        or negative value."""
        x, y, z = (float(c) for c in position)
        p = csc_presence(radius=float(radius), active=int(bool(active)),
                         visible=int(bool(visible)), rgba=int(rgba))
        p.position[:] = [x, y, z]
        _lib.csc_session_set_presence(self._ptr, ctypes.byref(p))

    def _snapshot(self, count_function, get_function, struct):
        """Takes a snapshot with `count_function` and reads each entry into a new `struct`."""
        count = c_uint32()
        count_function(self._ptr, ctypes.byref(count))
        entries = [struct() for _ in range(count.value)]
        for i, entry in enumerate(entries):
            get_function(self._ptr, i, ctypes.byref(entry))
        return entries

    def presence(self) -> list:
        """The other peers' cursors (a list of Presence)."""
        return [Presence(p.peer, tuple(p.position), p.radius, bool(p.active), bool(p.visible),
                         p.rgba, p.age_ms, tuple(p.colour))
                for p in self._snapshot(_lib.csc_session_presence_count,
                                        _lib.csc_session_get_presence, csc_presence)]

    def peers(self) -> list:
        """The other peers (a list of PeerInfo): members, then the latest that left."""
        result = []
        # Names are borrowed until the next peer_count: decoded (copied) before that.
        for p in self._snapshot(_lib.csc_session_peer_count, _lib.csc_session_get_peer,
                                csc_peer_info):
            try:
                state = PeerState(p.state)
            except ValueError:
                state = p.state
            result.append(PeerInfo(p.id, (p.name or b"").decode("utf-8", "replace"), state,
                                   bool(p.merger), p.version, p.latency_ms))
        return result

    def leave(self) -> None:
        """Tells the others this peer leaves and stops the network thread. Reads (invite, id,
        version, base, events, stats, attribution_colors) still work; submit and update raise
        InvalidArgument."""
        _lib.csc_session_leave(self._ptr)
