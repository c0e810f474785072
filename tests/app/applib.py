"""Helpers for the csculpt-app tests: run the app (under the Xvfb display the test runs in),
write replay files, read the PLY files it saves.

The tests run inside `xvfb-run` (run_under_xvfb.sh); every app started here shares that
display. Mesh statistics come from the saved PLY (csc_mesh_write, binary little endian)."""
import fcntl
import math
import os
import socket
import struct
import subprocess
import tempfile
import zlib

APP = os.environ.get("CSCULPT_APP") or os.path.join(os.getcwd(), "csculpt-app")
# A small sphere keeps the frames fast on llvmpipe; the brushes work the same at any size.
TEST_SPHERE = ["--sphere-faces", "20000"]
# Every app the tests start prints, on exit, how many of its vertex normals differ from a full
# recomputation ("NORMALS stale=N"), and how many BVH boxes differ from an exact refit
# ("bvh_loose=N"): the brushes, undo and the session worker keep both.
os.environ["CSCULPT_APP_CHECK_NORMALS"] = "1"


def assert_normals_current(test, stdout):
    """The app's exit line says its normals are the bits a full recomputation gives, and its
    BVH's boxes those an exact refit gives."""
    test.assertIn("NORMALS stale=0", stdout, "normals left stale (a shading seam)")
    test.assertIn("bvh_loose=0", stdout, "BVH boxes not tight (the brush's hits and region)")


def run_app(*args, timeout=60, check=True):
    """Runs csculpt-app to its exit; returns the CompletedProcess (text stdout/stderr)."""
    result = subprocess.run([APP, *args], capture_output=True, text=True, timeout=timeout)
    if check and result.returncode != 0:
        raise AssertionError(f"csculpt-app {args} exited {result.returncode}:\n{result.stderr}")
    return result


def start_host(test, *args, stderr=subprocess.PIPE):
    """Starts `csculpt-app --host ARGS` (killed at the test's end if still running); returns the
    process and its invite, once it has printed it."""
    host = subprocess.Popen([APP, "--host", *args], stdout=subprocess.PIPE, stderr=stderr, text=True)
    test.addCleanup(lambda: host.poll() is None and (host.kill(), host.wait()))
    test.addCleanup(host.stdout.close)
    line = host.stdout.readline().strip()
    test.assertTrue(line.startswith("INVITE "), line)
    return host, line.split(" ", 1)[1]


def machine_ipv4s():
    """This machine's IPv4 addresses but loopback's (SIOCGIFADDR on each interface)."""
    found = set()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        for _, name in socket.if_nameindex():
            try:
                reply = fcntl.ioctl(s.fileno(), 0x8915, struct.pack("256s", name[:15].encode()))
            except OSError:
                continue  # down, or no IPv4 address
            address = socket.inet_ntoa(reply[20:24])
            if not address.startswith("127."):
                found.add(address)
    return found


class Replay:
    """Builds a --replay file: moves, presses, keys and frame waits."""

    def __init__(self):
        self.lines = ["wait 3"]  # a few frames for the window to settle

    def key(self, name, *mods):
        self.lines += [f"key {name} {' '.join(mods)}".strip(), "wait 1"]
        return self

    def wait(self, what):
        self.lines.append(f"wait {what}")
        return self

    def pressure(self, value):
        self.lines.append(f"pressure {value}")
        return self

    def drag(self, start, end, steps=16, button="left", mods=()):
        """A drag from start to end in `steps` cursor events, one per frame."""
        (x0, y0), (x1, y1) = start, end
        self.lines += [f"move {x0} {y0}", "wait 1", f"press {button} {' '.join(mods)}".strip()]
        for i in range(1, steps + 1):
            t = i / steps
            self.lines += [f"move {x0 + (x1 - x0) * t:.1f} {y0 + (y1 - y0) * t:.1f}", "wait 1"]
        self.lines += [f"release {button}", "wait 2"]
        return self

    def write(self, directory, name="input.replay"):
        path = os.path.join(directory, name)
        with open(path, "w") as f:
            f.write("\n".join(self.lines + ["key tab", "wait 2"]) + "\n")  # hide panels: scene only
        return path


class Mesh:
    """A PLY as csc_mesh_write writes it: float vertex properties, int triangles."""

    def __init__(self, path):
        with open(path, "rb") as f:
            data = f.read()
        end = data.index(b"end_header\n") + len(b"end_header\n")
        header = data[:end].decode().splitlines()
        assert header[1] == "format binary_little_endian 1.0", header[1]
        self.properties, self.vertex_count, self.face_count = [], 0, 0
        element = None
        for line in header:
            words = line.split()
            if words[0] == "element":
                element = words[1]
                if element == "vertex":
                    self.vertex_count = int(words[2])
                elif element == "face":
                    self.face_count = int(words[2])
            elif words[0] == "property" and element == "vertex":
                assert words[1] == "float", line
                self.properties.append(words[2])
        width = len(self.properties)
        values = struct.unpack_from(f"<{self.vertex_count * width}f", data, end)
        self.columns = {name: values[i::width] for i, name in enumerate(self.properties)}
        self.raw = data

    def position(self, v):
        return (self.columns["x"][v], self.columns["y"][v], self.columns["z"][v])

    def radius(self, v):
        return math.sqrt(sum(c * c for c in self.position(v)))


def moved_vertices(before, after):
    """Indices whose position differs."""
    return [v for v in range(before.vertex_count) if before.position(v) != after.position(v)]


def changed_in(before, after, name):
    return [v for v in range(before.vertex_count) if before.columns[name][v] != after.columns[name][v]]


def mean(values):
    values = list(values)
    return sum(values) / len(values) if values else 0.0


class Picture:
    """An 8-bit RGB or RGBA PNG as the app's --screenshot writes it (stb_image_write): its
    pixels, row by row from the top."""

    def __init__(self, path):
        with open(path, "rb") as f:
            data = f.read()
        assert data[:8] == b"\x89PNG\r\n\x1a\n", path
        at, idat = 8, b""
        while at < len(data):
            length, kind = struct.unpack_from(">I4s", data, at)
            body = data[at + 8:at + 8 + length]
            if kind == b"IHDR":
                self.width, self.height, depth, colour = struct.unpack_from(">IIBB", body)
                assert depth == 8 and colour in (2, 6), (depth, colour)
                self.channels = 3 if colour == 2 else 4
            elif kind == b"IDAT":
                idat += body
            at += 12 + length
        raw, stride, n = zlib.decompress(idat), self.width * self.channels, self.channels
        rows, previous = [], bytearray(stride)
        for y in range(self.height):
            kind, row = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
            for i in range(stride):  # the PNG filters: none, sub, up, average, Paeth
                a = row[i - n] if i >= n else 0
                b, c = previous[i], previous[i - n] if i >= n else 0
                if kind == 1:
                    row[i] = (row[i] + a) & 255
                elif kind == 2:
                    row[i] = (row[i] + b) & 255
                elif kind == 3:
                    row[i] = (row[i] + (a + b) // 2) & 255
                elif kind == 4:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
            rows.append(row)
            previous = row
        self.rows = rows

    def rgb(self, x, y):
        at = x * self.channels
        return tuple(self.rows[y][at:at + 3])

    def mean_rgb(self, x0, y0, x1, y1):
        """The mean colour over the pixels x0 <= x < x1, y0 <= y < y1."""
        pixels = [self.rgb(x, y) for y in range(y0, y1) for x in range(x0, x1)]
        return tuple(sum(p[c] for p in pixels) / len(pixels) for c in range(3))


def temp_dir(test):
    directory = tempfile.TemporaryDirectory(prefix="csculpt-app-test-")
    test.addCleanup(directory.cleanup)
    return directory.name
