"""A person at the mouse: xdotool moves the real X pointer over csculpt-app's window under
Xvfb. A left drag across the sphere sculpts it (the saved mesh differs from the untouched one,
outwards, as the draw brush does); a click on the panel's "Host a session" button hosts (the
app prints its INVITE line)."""
import os
import queue
import shutil
import subprocess
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import APP, TEST_SPHERE, Mesh, mean, moved_vertices, run_app, temp_dir  # noqa: E402

HOST_BUTTON = (1030, 63)  # the Session panel's first button (panels are fixed in place)


def xdotool(*args):
    return subprocess.run(["xdotool", *map(str, args)], check=True, capture_output=True, text=True).stdout


class RealPointer(unittest.TestCase):
    def setUp(self):
        if not shutil.which("xdotool"):
            self.skipTest("xdotool is not installed")

    def test_drag_sculpts_and_click_hosts(self):
        directory = temp_dir(self)
        base, edited = os.path.join(directory, "base.ply"), os.path.join(directory, "edited.ply")
        run_app(*TEST_SPHERE, "--exit-after", "0", "--save", base)
        app = subprocess.Popen([APP, *TEST_SPHERE, "--exit-after", "12", "--save", edited],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.addCleanup(lambda: app.poll() is None and app.kill())
        self.addCleanup(app.stderr.close)
        lines = queue.Queue()
        threading.Thread(target=lambda: [lines.put(line.strip()) for line in app.stdout], daemon=True).start()
        self.assertEqual(lines.get(timeout=30), "READY")
        window = xdotool("search", "--sync", "--name", "^cSculpt$").split()[0]

        def move(x, y, pause=0.05):
            xdotool("mousemove", "--window", window, x, y)
            time.sleep(pause)

        # ImGui 1.86 counts a click only if the pointer was over the widget a frame before:
        # every step waits longer than a frame.
        move(590, 400, 0.5)
        xdotool("mousedown", "1")
        time.sleep(0.2)
        for step in range(1, 23):
            move(590 + 5 * step, 400)
        xdotool("mouseup", "1")
        time.sleep(0.5)
        move(*HOST_BUTTON, 0.6)
        xdotool("mousedown", "1")
        time.sleep(0.2)
        xdotool("mouseup", "1")

        invite = lines.get(timeout=10)
        self.assertTrue(invite.startswith("INVITE "), invite)
        self.assertGreater(len(invite), 40)
        self.assertEqual(app.wait(timeout=60), 0, app.stderr.read())
        app.stdout.close()
        before, after = Mesh(base), Mesh(edited)
        moved = moved_vertices(before, after)
        self.assertGreater(len(moved), 50)
        self.assertGreater(mean(after.radius(v) - before.radius(v) for v in moved), 0.005)


if __name__ == "__main__":
    unittest.main()
