"""The session's mesh digest (csculpt::peer::mesh_digest, peer/src/session.cpp) in Python, so
that what Blender, csculpt-app and `csculpt peer` hold can be compared as one 64-bit number:
hash_bytes (sdk/include/csculpt/hash.h) over the positions, then over each channel's name and
values, in the session's channel order. Runs inside Blender and in plain Python (numpy only)."""

import numpy as np

MASK = (1 << 64) - 1
SEED = 0x6a09e667f3bcc908


def _mix(h, w):
    h ^= (w + 0x9e3779b97f4a7c15 + ((h << 6) & MASK) + (h >> 2)) & MASK
    h = (h * 0xff51afd7ed558ccd) & MASK
    return h ^ (h >> 32)


def hash_bytes(h, data):
    data = bytes(data)
    whole = len(data) // 8 * 8
    for w in np.frombuffer(data[:whole], dtype="<u8").tolist():
        h = _mix(h, w)
    tail = len(data)
    for k, byte in enumerate(data[whole:]):
        tail ^= byte << (8 * (k + 1))
    return _mix(h, tail)


def mesh_digest(positions, channels):
    """positions: float32 (n*3); channels: [(name, float32 values, vertex-major)] in the
    session's order. Returns the digest as the peer prints it (16 hex digits)."""
    h = hash_bytes(SEED, np.ascontiguousarray(positions, dtype=np.float32).tobytes())
    for name, values in channels:
        h = hash_bytes(h, name.encode())
        h = hash_bytes(h, np.ascontiguousarray(values, dtype=np.float32).tobytes())
    return f"{h:016x}"


SUFFIXES = ("_r", "_g", "_b", "_a")


def read_ply(path):
    """A PLY as csc_mesh_write writes it (binary little endian, float vertex properties x, y, z
    then each channel's components, name_r/_g/_b/_a for wider ones): (positions (n, 3),
    [(channel name, values (n, width))]) in the file's channel order."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    assert header[1] == "format binary_little_endian 1.0", header[1]
    names, n, element = [], 0, None
    for line in header:
        words = line.split()
        if words[0] == "element":
            element = words[1]
            if element == "vertex":
                n = int(words[2])
        elif words[0] == "property" and element == "vertex":
            assert words[1] == "float", line
            names.append(words[2])
    assert names[:3] == ["x", "y", "z"], names
    table = np.frombuffer(data, dtype="<f4", count=n * len(names), offset=end).reshape(
        n, len(names))
    channels, column = [], 3
    while column < len(names):
        name = names[column]
        if len(name) > 2 and name[-2:] == SUFFIXES[0]:
            base, width = name[:-2], 1
            while (column + width < len(names) and width < len(SUFFIXES) and
                   names[column + width] == base + SUFFIXES[width]):
                width += 1
        else:
            base, width = name, 1
        channels.append((base, np.ascontiguousarray(table[:, column:column + width])))
        column += width
    return np.ascontiguousarray(table[:, :3]), channels


def ply_digest(path):
    positions, channels = read_ply(path)
    return mesh_digest(positions, channels)
