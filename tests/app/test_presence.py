"""Presence between two csculpt-app processes: the joiner moves its cursor over the mesh (no
stroke) and the host receives its cursor through the session; the host's cursor stays off the
mesh, and the joiner sees none. The exit line `SESSION ...` ends with presence=<peers whose
cursor was seen over the mesh>: 1 at the host, 0 at the joiner; and peers=<the others' names>,
which each gave with --name.

Xvfb's pointer starts at the screen's centre, over the sphere, and a window mapped under it
takes that position: once the host's window is up the pointer is moved to a corner (xdotool),
so the joiner's window opens off the mesh and only its replay's moves put its cursor there."""
import os
import shutil
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import APP, TEST_SPHERE, Replay, start_host, temp_dir  # noqa: E402


def session_line(out):
    line = next(line for line in out.splitlines() if line.startswith("SESSION "))
    return dict(word.split("=") for word in line.split()[1:])


class Presence(unittest.TestCase):
    def setUp(self):
        if not shutil.which("xdotool"):
            self.skipTest("xdotool is not installed")

    def test_the_host_sees_the_joiners_cursor(self):
        directory = temp_dir(self)
        # Hover across the sphere's front for a while: no press, so nothing is sculpted.
        replay = Replay().wait("session").wait(10)
        for x in range(600, 700, 10):
            replay.lines += [f"move {x} 400", "wait 6"]
        host, invite = start_host(self, *TEST_SPHERE, "--name", "alice", "--exit-after", "8")
        self.assertEqual(host.stdout.readline().strip(), "READY")
        # The bottom-right corner: no mesh and no panel there (moved over a window: Xvfb's
        # bare root does not take the move).
        window = subprocess.run(["xdotool", "search", "--sync", "--name", "^cSculpt$"], check=True,
                                capture_output=True, text=True).stdout.split()[0]
        subprocess.run(["xdotool", "mousemove", "--window", window, "1275", "795"], check=True)
        joiner = subprocess.run([APP, "--join", invite, "--name", "bob", "--replay",
                                 replay.write(directory), "--exit-after", "3"],
                                capture_output=True, text=True, timeout=60)
        self.assertEqual(joiner.returncode, 0, joiner.stderr)
        host_out, host_err = host.communicate(timeout=60)
        self.assertEqual(host.returncode, 0, host_err)
        host_session = session_line(host_out)
        self.assertEqual(host_session["members"], "1", host_out)  # the joiner has left by then
        self.assertEqual(host_session["presence"], "1", host_out)
        self.assertEqual(session_line(joiner.stdout)["presence"], "0", joiner.stdout)
        self.assertEqual(host_session["peers"], "bob", host_out)
        self.assertEqual(session_line(joiner.stdout)["peers"], "alice", joiner.stdout)


if __name__ == "__main__":
    unittest.main()
