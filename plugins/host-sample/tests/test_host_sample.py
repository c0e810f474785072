"""The C host sample as a host in a real session: one sample hosts, a second joins with the
invite and a `csculpt peer` joins too; all three make strokes at once and must end on the same
version and the same mesh digest (the sample computes `csculpt peer`'s mesh_digest over its own
arrays, so equal digests mean bit-identical meshes). The joining sample undoes its last stroke
after everybody has it: the undo must converge too, and on the hosting sample (its saved mesh)
the stroke's centre vertex must be back where it was before the stroke. A bad invite must exit 1
with a clear message.

usage: test_host_sample.py HOST_SAMPLE CSCULPT
"""

import os
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest

SAMPLE, CLI = sys.argv[1], sys.argv[2]
os.environ["CSCULPT_CLI"] = CLI
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "..", "..", "tests", "session"))
import sessionlib  # noqa: E402  (drives the `csculpt peer` process)

# The samples' session options are the C ABI's defaults; the peer uses the same.
PEER_TIMING = ["--sync-ms", "250", "--heartbeat-ms", "200", "--evasive-ms", "600",
               "--expired-ms", "1200"]


class Sample:
    """A host-sample process; its stdout lines ("WORD key=value ...") collected by a thread."""

    def __init__(self, *args):
        self.proc = subprocess.Popen([SAMPLE, *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, bufsize=1)
        self.lines, self.cond = [], threading.Condition()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for raw in self.proc.stdout:
            with self.cond:
                self.lines.append(raw.rstrip("\n"))
                self.cond.notify_all()

    def find(self, word):
        return [line for line in self.lines if line.split(" ", 1)[0] == word]

    def wait_line(self, word, timeout):
        deadline = time.time() + timeout
        with self.cond:
            while not self.find(word):
                if time.time() > deadline or self.proc.poll() is not None and not self.find(word):
                    raise AssertionError(f"no {word} line from {self.proc.args} "
                                         f"(exit {self.proc.poll()}): {self.lines[-5:]}")
                self.cond.wait(0.2)
            return self.find(word)[0]

    def finish(self, timeout):
        """Waits for the exit; returns (exit code, fields of the FINAL line, stderr)."""
        try:
            self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            raise AssertionError(f"{self.proc.args} did not finish in {timeout} s: "
                                 f"{self.lines[-5:]}")
        self.reader.join(10)
        err = self.proc.stderr.read()
        self.close()
        final = self.find("FINAL")
        return self.proc.returncode, fields(final[0]) if final else None, err

    def close(self):
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self.reader.join(10)
        for f in (self.proc.stdout, self.proc.stderr):
            f.close()


def fields(line):
    return dict(item.split("=", 1) for item in line.split()[1:] if "=" in item)


def ply_positions(path):
    """The x, y, z of every vertex of a binary little-endian PLY whose vertex properties are
    all floats (what csc_mesh_write writes)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    count, props, in_vertex = 0, [], False
    for line in data[:end].decode().splitlines():
        words = line.split()
        if words[:1] == ["element"]:
            in_vertex = words[1] == "vertex"
            count = int(words[2]) if in_vertex else count
        elif words[:1] == ["property"] and in_vertex:
            assert words[1] == "float", line
            props.append(words[2])
    stride = 4 * len(props)
    xyz = [props.index(n) for n in ("x", "y", "z")]
    return [[struct.unpack_from("<f", data, end + v * stride + 4 * i)[0] for i in xyz]
            for v in range(count)]


class HostSample(unittest.TestCase):
    def test_two_samples_and_a_peer_converge_with_an_undo(self):
        started = time.time()
        tmp = tempfile.mkdtemp(prefix="host_sample_")
        a_out, b_out = os.path.join(tmp, "a.ply"), os.path.join(tmp, "b.ply")
        # A hosts and strokes at once; it leaves after 5 s without a new version.
        a = Sample("--host", "--strokes", "3", "--seconds", "2", "--seed", "1", "--linger", "5",
                   "--out", a_out)
        peer = b = None
        try:
            invite = a.wait_line("INVITE", 30).split(" ", 1)[1]
            # The peer edits for its first 2 s; B strokes over 6 s, so its last stroke (at 4 s)
            # comes after everyone else's, and undoes it once the others have it.
            peer = sessionlib.Peer(7, join=invite, seconds=2.0, rate=3.0, linger=120,
                                   timing=PEER_TIMING)
            b = Sample("--join", invite, "--strokes", "3", "--seconds", "6", "--seed", "2",
                       "--undo-last", "--linger", "2", "--out", b_out)
            b_rc, b_final, b_err = b.finish(60)
            a_rc, a_final, a_err = a.finish(60)
            self.assertEqual((b_rc, b_err), (0, ""), b.lines[-5:])
            self.assertEqual((a_rc, a_err), (0, ""), a.lines[-5:])
            peer.quit()
            p_final = peer.summary(30)
        finally:
            for p in (a, b):
                if p:
                    p.close()
            if peer:
                peer.stop()

        # Everybody edited: 3 strokes per sample, some from the peer, all acknowledged.
        self.assertEqual(len(a.find("STROKE")), 3)
        self.assertEqual(len(b.find("STROKE")), 3)
        self.assertGreater(p_final["strokes"], 0)
        self.assertEqual(p_final["lost_edits"], 0, p_final)
        for f in (a_final, b_final):  # B's undo is sent as a stroke of its own
            self.assertEqual(f["acknowledged"], f["submitted"], f)
        self.assertEqual((a_final["submitted"], b_final["submitted"]), ("3", "4"))
        # Converged: the same version and the same digest in all three processes.
        self.assertEqual(a_final["version"], b_final["version"])
        self.assertEqual(str(p_final["version"]), a_final["version"])
        self.assertEqual(a_final["digest"], b_final["digest"])
        self.assertEqual(p_final["digest"], a_final["digest"])
        self.assertEqual(p_final["digest"], p_final["base_digest"])

        # The undo reached the hosting sample: the centre of B's last stroke is back.
        undo = fields(b.wait_line("UNDO", 0))
        self.assertGreater(int(undo["vertices"]), 0)
        before = [float(x) for x in undo["before"].split(",")]
        after = [float(x) for x in undo["after"].split(",")]
        final = ply_positions(a_out)[int(undo["centre"])]
        moved = max(abs(x - y) for x, y in zip(after, before))
        residual = max(abs(x - y) for x, y in zip(final, before))
        self.assertGreater(moved, 1e-2, undo)
        self.assertLess(residual, 0.02 * moved, (undo, final))
        self.assertEqual(ply_positions(a_out), ply_positions(b_out))
        print(f"[figure] host_sample: version={a_final['version']} digest={a_final['digest']} "
              f"peer_strokes={p_final['strokes']} undo_moved={moved:.4f} "
              f"undo_residual={residual:.2e} seconds={time.time() - started:.1f}", flush=True)

    def test_bad_invite_exits_1_with_a_message(self):
        for invite in ("not-an-invite", "csculpt1:garbage@tcp://127.0.0.1:1"):
            proc = subprocess.run([SAMPLE, "--join", invite], capture_output=True, text=True,
                                  timeout=60)
            self.assertEqual(proc.returncode, 1, proc)
            self.assertIn("host-sample: cannot join the session: ", proc.stderr)
            self.assertNotIn("FINAL", proc.stdout)

    def test_bad_arguments_exit_1(self):
        for args in ([], ["--host", "--join", "x"], ["--frobnicate"]):
            proc = subprocess.run([SAMPLE, *args], capture_output=True, text=True, timeout=30)
            self.assertEqual(proc.returncode, 1, (args, proc))
            self.assertTrue(proc.stderr.startswith("host-sample: "), proc.stderr)


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0], "-v"])
