"""Files as an artist uses them: an OBJ's vertex colours open as the albedo; a PLY the app
saved opens again with every channel and saves back byte for byte; an OBJ the app saved keeps
the positions bit for bit and the albedo as vertex colours. Meshes are read back from what the
app saves."""
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import TEST_SPHERE, Mesh, Replay, changed_in, moved_vertices, run_app, temp_dir  # noqa: E402

COLOURED_CUBE = "/usr/share/assimp/models/OBJ/cube_with_vertexcolors.obj"
ACROSS = ((560, 400), (720, 400))


def obj_vertices(path):
    """The "v" lines' numbers, one tuple per vertex."""
    with open(path) as f:
        return [tuple(float(w) for w in line.split()[1:]) for line in f if line.startswith("v ")]


class Files(unittest.TestCase):
    def save(self, *args, name="out.ply"):
        path = os.path.join(temp_dir(self), name)
        result = run_app(*args, "--exit-after", "0", "--save", path)
        self.assertNotIn("cannot", result.stderr)
        return path

    @unittest.skipUnless(os.path.exists(COLOURED_CUBE), "assimp-testmodels not installed")
    def test_obj_vertex_colours_open_as_the_albedo(self):
        saved = Mesh(self.save(COLOURED_CUBE))
        expected = obj_vertices(COLOURED_CUBE)
        self.assertEqual(saved.vertex_count, len(expected))
        for v, numbers in enumerate(expected):
            self.assertEqual(saved.position(v), numbers[:3])
            for c, channel in enumerate(("albedo_r", "albedo_g", "albedo_b")):
                self.assertAlmostEqual(saved.columns[channel][v], numbers[3 + c], places=6)
        self.assertIn("roughness", saved.columns)  # the other material channels are added

    def test_saved_ply_reopens_with_every_channel(self):
        directory = temp_dir(self)
        replay = (Replay().key("d").drag(*ACROSS).key("b").drag((600, 360), (680, 440))
                  .key("r").drag((600, 440), (680, 360)).key("m").drag((640, 350), (640, 450)))
        first = self.save(*TEST_SPHERE, "--replay", replay.write(directory))
        again = self.save(first)
        with open(first, "rb") as a, open(again, "rb") as b:
            self.assertEqual(a.read(), b.read())
        mesh = Mesh(first)  # and the strokes are in it
        base = Mesh(self.save(*TEST_SPHERE))
        self.assertTrue(moved_vertices(base, mesh))
        for channel in ("albedo_r", "roughness", "metallic"):
            self.assertTrue(changed_in(base, mesh, channel), channel)

    def test_saved_obj_keeps_positions_and_albedo(self):
        directory = temp_dir(self)
        replay = Replay().key("d").drag(*ACROSS).key("b").drag((600, 360), (680, 440))
        obj = self.save(*TEST_SPHERE, "--replay", replay.write(directory), name="out.obj")
        ply = self.save(*TEST_SPHERE, "--replay", replay.write(directory))  # the same strokes
        reopened, original = Mesh(self.save(obj)), Mesh(ply)
        self.assertEqual(reopened.vertex_count, original.vertex_count)
        for name in ("x", "y", "z", "albedo_r", "albedo_g", "albedo_b"):
            self.assertEqual(reopened.columns[name], original.columns[name], name)
        # the triangles (uchar 3, three ints each) unchanged
        self.assertEqual(reopened.raw[-13 * original.face_count:], original.raw[-13 * original.face_count:])


if __name__ == "__main__":
    unittest.main()
