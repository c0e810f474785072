"""Drawing on demand: a window nobody touches draws a few frames and then sleeps (with llvmpipe,
drawing the same picture over and over took about 1.5 of the machine's 2 cores), yet whatever
changes on screen is drawn: the pointer's brush ring follows a real pointer (xdotool), and an
idle host shows the strokes a `csculpt peer` process (no window: nothing exposes the host's)
makes in its session. The pictures are read back from
the X server (ImageMagick's `import`), as a person sees the window, not from the app's own
screenshot. The exit line "FRAMES drawn=N" (CSCULPT_APP_COUNT_FRAMES) counts frames drawn."""
import os
import re
import shutil
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import APP, TEST_SPHERE, run_app  # noqa: E402

CLI = os.environ.get("CSCULPT_CLI", os.path.join(os.path.dirname(APP), "..", "cli", "csculpt"))

os.environ["CSCULPT_APP_COUNT_FRAMES"] = "1"


def frames_drawn(stdout):
    return int(re.search(r"^FRAMES drawn=(\d+)", stdout, re.M).group(1))


def xdotool(*args):
    return subprocess.run(["xdotool", *map(str, args)], check=True, capture_output=True,
                          text=True).stdout


def window_pixels(window, x, y, w, h):
    """The window's pixels in a rectangle, as the X server holds them (RGB bytes)."""
    ppm = subprocess.run(["import", "-window", window, "-crop", f"{w}x{h}+{x}+{y}", "ppm:-"],
                         check=True, capture_output=True, timeout=30).stdout
    # P6 header: magic, width, height, maxval, then the pixels.
    fields, pos = [], 0
    while len(fields) < 4:
        while ppm[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while not ppm[pos:pos + 1].isspace():
            pos += 1
        fields.append(ppm[start:pos])
    return ppm[pos + 1:]


def differing_pixels(a, b):
    return sum(1 for i in range(0, min(len(a), len(b)), 3) if a[i:i + 3] != b[i:i + 3])


class DrawOnDemand(unittest.TestCase):
    def setUp(self):
        for tool in ("xdotool", "import"):
            if not shutil.which(tool):
                self.skipTest(f"{tool} is not installed")

    def start(self, *args):
        app = subprocess.Popen([APP, *TEST_SPHERE, *args], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        self.addCleanup(lambda: app.poll() is None and app.kill())
        return app

    def test_an_idle_window_draws_a_few_frames_and_sleeps(self):
        # The pointer off the window: no event reaches it for the whole run.
        result = run_app(*TEST_SPHERE, "--size", "320x240", "--exit-after", "3")
        self.assertLessEqual(frames_drawn(result.stdout), 12, result.stdout)

    def test_the_brush_ring_follows_a_real_pointer(self):
        app = self.start("--exit-after", "8")
        self.assertEqual(app.stdout.readline().strip(), "READY")
        window = xdotool("search", "--sync", "--onlyvisible", "--pid", app.pid).split()[0]
        xdotool("mousemove", "--window", window, 560, 400)
        time.sleep(1.0)
        before = window_pixels(window, 500, 340, 240, 120)
        xdotool("mousemove", "--window", window, 680, 400)
        time.sleep(1.0)
        after = window_pixels(window, 500, 340, 240, 120)
        # The ring (radius 50 px) left one place and circles the other: hundreds of pixels.
        self.assertGreater(differing_pixels(before, after), 200)
        out, err = app.communicate(timeout=60)
        self.assertEqual(app.returncode, 0, err)
        self.assertLess(frames_drawn(out), 200, out)  # a few per event, not every loop

    def test_an_idle_host_shows_a_colleagues_strokes(self):
        host = self.start("--host", "--exit-after", "12")
        invite = host.stdout.readline().strip()
        self.assertTrue(invite.startswith("INVITE "), invite)
        self.assertEqual(host.stdout.readline().strip(), "READY")
        window = xdotool("search", "--sync", "--onlyvisible", "--pid", host.pid).split()[0]
        xdotool("mousemove", "--window", window, 1275, 795)  # off the mesh, then untouched
        time.sleep(1.0)
        whole = (0, 0, 1280, 800)
        before = window_pixels(window, *whole)
        peer = subprocess.run([CLI, "peer", "--join", invite.split(" ", 1)[1], "--seed", "3",
                               "--seconds", "3", "--strokes-per-second", "8", "--linger", "2",
                               "--ignore-stdin"], capture_output=True, text=True, timeout=60)
        self.assertEqual(peer.returncode, 0, peer.stderr)
        time.sleep(1.0)  # the last merged version reaches the host, which nobody touches
        after = window_pixels(window, *whole)
        # The peer's strokes reshaped the sphere where it faces the camera: thousands of pixels.
        self.assertGreater(differing_pixels(before, after), 2000)
        out, err = host.communicate(timeout=60)
        self.assertEqual(host.returncode, 0, err)
        self.assertRegex(out, r"SESSION .*version=[1-9]", out)

if __name__ == "__main__":
    unittest.main()
