"""Bad input never stops the artist: a malformed or missing mesh file, a malformed invite, an
invite whose host is gone and an endpoint that cannot be listened on each give a message
(stderr, and the panel) and the app keeps running on the built-in sphere until --exit-after,
exiting 0; a stroke made meanwhile is kept."""
import os
import socket
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import TEST_SPHERE, Mesh, Replay, moved_vertices, run_app, start_host, temp_dir  # noqa: E402


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

    def test_hosting_on_a_port_in_use(self):
        # Another program holds the port: hosting fails with the reason, out of the session,
        # and the artist's own strokes and undo work as if it had never been tried.
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen()
            endpoint = "tcp://127.0.0.1:%d" % taken.getsockname()[1]
            directory = temp_dir(self)
            replay = Replay().key("d").drag((590, 400), (690, 400)).drag((590, 300), (690, 300)) \
                .key("z", "ctrl").write(directory, "two.replay")
            result, saved = self.run_kept_alive("--host", "--bind", endpoint, "--replay", replay)
        self.assertIn("cannot host a session", result.stderr)
        self.assertIn(endpoint, result.stderr)
        self.assertIn("Address already in use", result.stderr)
        self.assertNotIn("INVITE", result.stdout)
        self.assertNotIn("SESSION", result.stdout)  # not left in a session that never was
        one_stroke = os.path.join(directory, "one.ply")
        run_app(*TEST_SPHERE, "--replay", Replay().key("d").drag((590, 400), (690, 400)).write(directory),
                "--exit-after", "0", "--save", one_stroke)
        with open(one_stroke, "rb") as f:
            self.assertEqual(saved, f.read())  # the second stroke undone, the first kept

    def test_joining_from_a_port_in_use(self):
        host, invite = start_host(self, *TEST_SPHERE, "--exit-after", "20")
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen()
            endpoint = "tcp://127.0.0.1:%d" % taken.getsockname()[1]
            result, saved = self.run_kept_alive("--join", invite, "--bind", endpoint)
        self.assertIn("cannot join", result.stderr)
        self.assertIn("Address already in use", result.stderr)
        self.assertEqual(saved, self.base)

    def test_bind_must_be_an_endpoint(self):
        result = run_app("--bind", "192.168.1.5:7000", check=False, timeout=30)
        self.assertEqual(result.returncode, 2, result)
        self.assertIn("--bind needs a tcp:// endpoint", result.stdout + result.stderr)

    def _last_saved(self, data):
        path = os.path.join(temp_dir(self), "saved.ply")
        with open(path, "wb") as f:
            f.write(data)
        return path


if __name__ == "__main__":
    unittest.main()
