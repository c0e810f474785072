"""Bad input never stops the artist: a malformed or missing mesh file, a malformed invite and
an invite whose host is gone each give a message (stderr, and the panel) and the app keeps
running on the built-in sphere until --exit-after, exiting 0; a stroke made meanwhile is kept."""
import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import TEST_SPHERE, Mesh, Replay, moved_vertices, run_app, temp_dir  # noqa: E402


class BadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        import tempfile
        cls.dir = tempfile.TemporaryDirectory(prefix="csculpt-app-bad-")
        cls.base_path = os.path.join(cls.dir.name, "base.ply")
        run_app(*TEST_SPHERE, "--exit-after", "0", "--save", cls.base_path)
        with open(cls.base_path, "rb") as f:
            cls.base = f.read()

    @classmethod
    def tearDownClass(cls):
        cls.dir.cleanup()

    def run_kept_alive(self, *args, seconds="1"):
        directory = temp_dir(self)
        saved = os.path.join(directory, "out.ply")
        result = run_app(*TEST_SPHERE, *args, "--exit-after", seconds, "--save", saved, check=False, timeout=120)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn("READY", result.stdout)  # it drew frames
        with open(saved, "rb") as f:
            return result, f.read()

    def test_malformed_mesh_file(self):
        path = os.path.join(temp_dir(self), "broken.ply")
        with open(path, "w") as f:
            f.write("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1 2\n")
        result, saved = self.run_kept_alive(path)
        self.assertIn("cannot open " + path, result.stderr)
        self.assertEqual(saved, self.base)  # it carried on with the built-in sphere

    def test_empty_or_overlong_name(self):
        for name in ("", "x" * 64):
            result = run_app("--name", name, check=False, timeout=30)
            self.assertEqual(result.returncode, 2, result)
            self.assertIn("--name needs a name of 1 to 63 bytes", result.stdout + result.stderr)

    def test_missing_mesh_file(self):
        result, saved = self.run_kept_alive("/nonexistent/mesh.obj")
        self.assertIn("cannot open /nonexistent/mesh.obj", result.stderr)
        self.assertEqual(saved, self.base)

    def test_malformed_invite(self):
        result, saved = self.run_kept_alive("--join", "not-an-invite")
        self.assertIn("cannot join", result.stderr)
        self.assertEqual(saved, self.base)

    def test_invite_of_a_host_that_is_gone(self):
        # A real invite, from a host that exits at once: nobody answers it.
        host = run_app(*TEST_SPHERE, "--host", "--exit-after", "0")
        invite = next(line for line in host.stdout.splitlines() if line.startswith("INVITE ")).split(" ", 1)[1]
        # The artist sculpts while the join waits in the background (the app never blocks).
        replay = Replay().key("d").drag((590, 400), (690, 400)).write(temp_dir(self))
        result, saved = self.run_kept_alive("--join", invite, "--replay", replay, seconds="12")
        self.assertIn("cannot join", result.stderr)
        moved = moved_vertices(Mesh(self.base_path), Mesh(self._last_saved(saved)))
        self.assertGreater(len(moved), 50)

    def _last_saved(self, data):
        path = os.path.join(temp_dir(self), "saved.ply")
        with open(path, "wb") as f:
            f.write(data)
        return path


if __name__ == "__main__":
    unittest.main()
