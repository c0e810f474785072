"""A person at the mouse: xdotool moves the real X pointer over csculpt-app's window under
Xvfb. A left drag across the sphere sculpts it (the saved mesh differs from the untouched one,
outwards, as the draw brush does); a click on the panel's "Host a session" button hosts (the
app prints its INVITE line); ticking "Pressure -> radius" narrows a light pen's stroke; a
click on Leave takes an app out of its session with the session's mesh kept, and a click on
Host then hosts a session of its own on it. Two apps side by side: host by a click (having
unticked "Other machines can join"), "Copy invite", paste it (Ctrl+V) into the other's invite
field and click "Join": they are in one session, through this machine's loopback address."""
import os
import queue
import shutil
import subprocess
import sys
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import APP, TEST_SPHERE, Mesh, Replay, mean, moved_vertices, run_app, start_host, temp_dir  # noqa: E402

HOST_BUTTON = (1030, 63)  # the Session panel's first button (panels are fixed in place)
PRESSURE_RADIUS_BOX = (112, 289)  # the Brush panel's "Pressure -> radius" box


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


    def test_ticking_pressure_on_radius_narrows_a_light_stroke(self):
        # The box is ticked with the real pointer while a replay waits; the replay then draws
        # with a light pen (replays carry pressure; this machine has no tablet). Unticked, the
        # same replay moves as many vertices as a full-pressure one would: only strength scales.
        directory = temp_dir(self)
        replay = (Replay().pressure(0.3).wait(600).key("d").key("x").drag((590, 400), (690, 400))
                  .write(directory))
        ticked_path, unticked_path = os.path.join(directory, "ticked.ply"), os.path.join(directory, "plain.ply")
        base = os.path.join(directory, "base.ply")
        run_app(*TEST_SPHERE, "--exit-after", "0", "--save", base)
        run_app(*TEST_SPHERE, "--replay", replay, "--exit-after", "0", "--save", unticked_path, timeout=120)
        app = subprocess.Popen([APP, *TEST_SPHERE, "--replay", replay, "--exit-after", "0", "--save", ticked_path],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.addCleanup(lambda: app.poll() is None and app.kill())
        self.assertEqual(app.stdout.readline().strip(), "READY")
        window = xdotool("search", "--sync", "--onlyvisible", "--pid", app.pid).split()[0]
        self.click(window, *PRESSURE_RADIUS_BOX)
        xdotool("mousemove", "--window", window, 640, 760)  # off the panels: the replay draws
        _, err = app.communicate(timeout=120)
        self.assertEqual(app.returncode, 0, err)
        before = Mesh(base)
        ticked = len(moved_vertices(before, Mesh(ticked_path)))
        unticked = len(moved_vertices(before, Mesh(unticked_path)))
        self.assertGreater(ticked, 10)
        self.assertLess(ticked, 0.6 * unticked)

    def test_leave_by_click_keeps_the_mesh_the_host_sees_it_go_and_hosting_again_works(self):
        # 640 px wide: the Session panel starts at x = 330; in a session its first row holds
        # Copy invite and Leave (at x = 451).
        directory = temp_dir(self)
        base, kept = os.path.join(directory, "base.ply"), os.path.join(directory, "kept.ply")
        run_app(*TEST_SPHERE, "--exit-after", "0", "--save", base)
        stroke = Replay().key("d").drag((560, 400), (720, 400)).write(directory)
        host, invite = start_host(self, *TEST_SPHERE, "--replay", stroke, "--exit-after", "10")
        joiner, window = self.start("--join", invite, "--exit-after", "14", "--save", kept)
        xdotool("windowmove", window, 640, 0)
        time.sleep(3)  # joined, the host's stroke in
        self.click(window, 451, 63)  # Leave
        host_out, host_err = host.communicate(timeout=90)
        self.assertEqual(host.returncode, 0, host_err)
        # The joiner was still running when the host quit (10 s against 14), yet no longer a
        # member: it said goodbye.
        host_session = next(line for line in host_out.splitlines() if line.startswith("SESSION "))
        self.assertIn("members=1 ", host_session)
        # Out of the session, it hosts one of its own on the mesh it kept (the copy for it is
        # prepared anew for that mesh's shape).
        self.click(window, 390, 63)  # Host a session
        out, err = joiner.communicate(timeout=90)
        self.assertEqual(joiner.returncode, 0, err)
        self.assertIn("INVITE csculpt1:", out)
        own_session = next(line for line in out.splitlines() if line.startswith("SESSION "))
        self.assertIn("members=1 ", own_session)
        fields = dict(field.split("=", 1) for field in own_session.split()[1:])
        self.assertEqual(fields["merger"], fields["id"])  # its own session: it merges
        self.assertGreater(len(moved_vertices(Mesh(base), Mesh(kept))), 50)  # the session's mesh kept

    def start(self, *args):
        app = subprocess.Popen([APP, *TEST_SPHERE, "--size", "640x800", *args], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        self.addCleanup(lambda: app.poll() is None and app.kill())
        self.addCleanup(app.stderr.close)
        self.addCleanup(app.stdout.close)
        self.assertEqual(app.stdout.readline().strip(), "READY")
        return app, xdotool("search", "--sync", "--onlyvisible", "--pid", app.pid).split()[0]

    def click(self, window, x, y):
        # No window manager under Xvfb: focus by hand (ImGui 1.86 reads the pointer of the
        # focused window only, and keys go to the focused window).
        xdotool("windowfocus", "--sync", window)
        xdotool("mousemove", "--window", window, x, y)
        time.sleep(0.5)  # over the widget for a frame or more before the press
        xdotool("mousedown", "1")
        time.sleep(0.2)
        xdotool("mouseup", "1")
        time.sleep(0.5)

    def test_host_copy_paste_join_by_clicks(self):
        # 640 px wide: the Session panel starts at x = 330; its first button (Host a session,
        # then Copy invite) is at y = 63, the invite field and Join below it at y = 86, the
        # "Other machines can join" box at y = 132.
        host, host_window = self.start("--exit-after", "25")
        joiner, joiner_window = self.start("--exit-after", "20")
        xdotool("windowmove", joiner_window, 640, 0)
        time.sleep(0.5)
        self.click(host_window, 347, 132)  # untick "Other machines can join": this machine only
        self.click(host_window, 390, 63)  # Host a session
        invite = host.stdout.readline()
        self.assertTrue(invite.startswith("INVITE "), invite)
        self.assertIn("@tcp://127.0.0.1:", invite)
        self.click(host_window, 385, 63)  # Copy invite (where Host was)
        self.click(joiner_window, 430, 86)  # the invite field
        # ImGui 1.86 has no input queue: a key pressed and released within a frame is lost,
        # and one held past io.KeyRepeatDelay (0.275 s) repeats: hold V for about 0.15 s.
        for step, pause in ((("keydown", "ctrl"), 0.2), (("keydown", "v"), 0.15), (("keyup", "v"), 0.2),
                            (("keyup", "ctrl"), 0.3)):
            xdotool(*step)
            time.sleep(pause)
        self.click(joiner_window, 558, 86)  # Join
        out, err = joiner.communicate(timeout=90)
        self.assertEqual(joiner.returncode, 0, err)
        session = next((line for line in out.splitlines() if line.startswith("SESSION ")), "")
        self.assertIn("members=2", session, out + err)  # it joined the host's session
        host.communicate(timeout=90)


if __name__ == "__main__":
    unittest.main()
