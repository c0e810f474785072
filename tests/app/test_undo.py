"""Local undo/redo of one's own strokes (Ctrl+Z / Ctrl+Shift+Z): an undone stroke gives back
the mesh bit for bit (positions and every channel) and the same picture; redo puts the stroke
back exactly. The wireframe (W) and flat shading (F) toggles change the picture, not the mesh,
and toggled twice give the picture back. Pictures are compared between runs of this same build, never with committed
images (they differ by Mesa build)."""
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(__file__))
from applib import TEST_SPHERE, Replay, assert_normals_current, run_app, temp_dir  # noqa: E402

STROKE = ((590, 400), (690, 410))


class Undo(unittest.TestCase):
    def run_replay(self, replay):
        """(saved PLY bytes, screenshot PNG bytes) after the replay; panels hidden."""
        directory = temp_dir(self)
        ply, png = os.path.join(directory, "out.ply"), os.path.join(directory, "out.png")
        result = run_app(*TEST_SPHERE, "--replay", replay.write(directory), "--exit-after", "0",
                         "--save", ply, "--screenshot", png)
        assert_normals_current(self, result.stdout)  # after strokes, undo and redo
        with open(ply, "rb") as a, open(png, "rb") as b:
            return a.read(), b.read()

    @classmethod
    def setUpClass(cls):
        cls.untouched = None

    def baseline(self):
        if Undo.untouched is None:
            Undo.untouched = self.run_replay(Replay())
        return Undo.untouched

    def test_undone_stroke_gives_back_mesh_and_picture(self):
        mesh, picture = self.baseline()
        stroked_mesh, stroked_picture = self.run_replay(Replay().key("d").drag(*STROKE))
        self.assertNotEqual(stroked_mesh, mesh)  # the stroke did something
        self.assertNotEqual(stroked_picture, picture)  # and it shows
        undone_mesh, undone_picture = self.run_replay(Replay().key("d").drag(*STROKE).key("z", "ctrl"))
        self.assertEqual(undone_mesh, mesh)
        self.assertEqual(undone_picture, picture)

    def test_redo_puts_the_stroke_back_exactly(self):
        stroked = self.run_replay(Replay().key("d").drag(*STROKE))
        redone = self.run_replay(Replay().key("d").drag(*STROKE).key("z", "ctrl").key("z", "ctrl", "shift"))
        self.assertEqual(redone[0], stroked[0])
        self.assertEqual(redone[1], stroked[1])

    def test_undo_paint_and_sculpt_in_order(self):
        first = Replay().key("b").drag(*STROKE)
        only_paint = self.run_replay(first)
        both_then_undo = self.run_replay(Replay().key("b").drag(*STROKE).key("i").drag((600, 350), (700, 350))
                                         .key("z", "ctrl"))
        self.assertEqual(both_then_undo[0], only_paint[0])
        all_undone = self.run_replay(Replay().key("b").drag(*STROKE).key("i").drag((600, 350), (700, 350))
                                     .key("z", "ctrl").key("z", "ctrl"))
        self.assertEqual(all_undone[0], self.baseline()[0])

    def test_wireframe_and_flat_shading_toggle_the_picture_only(self):
        mesh, picture = self.baseline()
        for key in ("w", "f"):
            on_mesh, on_picture = self.run_replay(Replay().key(key))
            self.assertEqual(on_mesh, mesh, key)
            self.assertNotEqual(on_picture, picture, key)
            self.assertEqual(self.run_replay(Replay().key(key).key(key))[1], picture, key)


if __name__ == "__main__":
    unittest.main()
