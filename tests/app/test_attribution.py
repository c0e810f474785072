"""The attribution view (the paper's Fig. 1), toggled with A inside a session: two csculpt-app
processes, each drawing on its own part of the sphere; the hosting app, with the view on,
shows each artist's region in that artist's colour and the untouched surface grey, and a
stroke made with the view on does not show the mesh's own colours through it. Colours are
read from the host's screenshot (panels hidden), compared with each other, never with
committed images."""
import os
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import APP, TEST_SPHERE, Picture, Replay, assert_normals_current, start_host, temp_dir  # noqa: E402

# Above and below the middle: with the default X symmetry each stroke is mirrored to the
# other side, so the two artists' regions differ in height, not side.
HOST_STROKE = ((540, 290), (580, 290))
JOIN_STROKE = ((540, 510), (580, 510))
HOST_REGION = (550, 285, 570, 295)
JOIN_REGION = (550, 505, 570, 515)


def saturation(rgb):
    return max(rgb) - min(rgb)


class Attribution(unittest.TestCase):
    def session_picture(self, host_replay, host_exit_after):
        """The host's screenshot after a session with a joiner who draws JOIN_STROKE."""
        directory = temp_dir(self)
        host_path = host_replay.write(directory, "host.replay")
        join_replay = Replay().wait("session").key("d").drag(*JOIN_STROKE).write(directory, "join.replay")
        png = os.path.join(directory, "host.png")
        host, invite = start_host(self, *TEST_SPHERE, "--replay", host_path, "--exit-after",
                                  host_exit_after, "--screenshot", png)
        joiner = subprocess.run([APP, "--join", invite, "--replay", join_replay,
                                 "--exit-after", "6"], capture_output=True, text=True, timeout=90)
        self.assertEqual(joiner.returncode, 0, joiner.stderr)
        host_out, host_err = host.communicate(timeout=90)
        self.assertEqual(host.returncode, 0, host_err)
        assert_normals_current(self, host_out)
        return Picture(png)

    def test_each_artists_region_in_its_colour(self):
        # The host draws, turns the view on, then waits for the versions that merge both
        # strokes.
        picture = self.session_picture(Replay().wait("session").wait(20).key("d").drag(*HOST_STROKE)
                                       .key("a").wait("version 2").wait(40), "12")
        mine, theirs = picture.mean_rgb(*HOST_REGION), picture.mean_rgb(*JOIN_REGION)
        nobody = picture.mean_rgb(630, 390, 650, 410)
        self.assertLess(saturation(nobody), 12, f"untouched surface not grey: {nobody}")
        self.assertGreater(saturation(mine), 40, f"the host's region not in a colour: {mine}")
        self.assertGreater(saturation(theirs), 40, f"the joiner's region not in a colour: {theirs}")
        # Different artists, different colours: their strongest channels differ.
        self.assertNotEqual(max(range(3), key=lambda c: mine[c]), max(range(3), key=lambda c: theirs[c]),
                            f"both regions in one colour: {mine} {theirs}")

    def test_a_stroke_made_in_the_view_keeps_its_colours(self):
        # With the view on and the joiner's stroke shown, the host draws over it and quits at
        # once (--exit-after 0: when the replay ends), before a version recolours it: the region
        # must still show the view's colours, not the mesh's own through the changed vertices.
        picture = self.session_picture(Replay().wait("session").wait(20).key("a").wait("version 1")
                                       .wait(40).key("d").drag(*JOIN_STROKE), "0")
        over = picture.mean_rgb(*JOIN_REGION)
        self.assertGreater(saturation(over), 40, f"the mesh's own colours show through: {over}")


if __name__ == "__main__":
    unittest.main()
